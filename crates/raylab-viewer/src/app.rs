//! The windowed viewer: a winit event loop that feeds input to the lab and draws each UI frame to the
//! window's surface. Resizing, minimising and a lost surface are handled; only a missing GPU ends the run.

use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::frontend::{Automation, Frontend};
use crate::gpu::device::Gpu;
use crate::lab::{Lab, Shot, timestamped};

/// Shortest time between two UI frames (caps the UI near 60 FPS).
const UI_FRAME: Duration = Duration::from_millis(16);
/// Shortest time between two UI frames that egui asks for by itself (animations, spinners) when there was
/// no input lately: the window stays live without taking CPU time from the tracer.
const IDLE_FRAME: Duration = Duration::from_millis(100);
/// How long after the last input egui's own repaint requests are served at full rate.
const INPUT_LINGER: Duration = Duration::from_millis(500);

/// Woken from other threads: a traced frame or a load is ready.
#[derive(Debug, Clone, Copy)]
pub struct Wake;

/// The window and everything drawn into it.
struct Windowed {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    view_format: wgpu::TextureFormat,
    front: Frontend,
    egui_state: egui_winit::State,
    look: Option<(f64, f64)>,
    last_redraw: Instant,
    last_input: Instant,
    redraw_at: Option<Instant>,
}

impl Windowed {
    /// Asks for a redraw in `delay` (or earlier, if one is already due earlier).
    fn schedule(&mut self, delay: Duration) {
        let t = Instant::now() + delay;
        self.redraw_at = Some(self.redraw_at.map_or(t, |r| r.min(t)));
    }

    /// Asks for a redraw now, in answer to input.
    fn input(&mut self) {
        self.last_input = Instant::now();
        self.schedule(Duration::ZERO);
    }
}

/// The application.
pub struct App {
    lab: Lab,
    redraw_always: bool,
    size: (u32, u32),
    automation: Option<Automation>,
    win: Option<Windowed>,
    /// Set when the run must end with an error.
    pub error: Option<String>,
}

/// Runs the viewer in a window until it is closed (or a `--frames` run ends).
pub fn run(
    make_lab: impl FnOnce(Arc<dyn Fn() + Send + Sync>) -> Lab,
    size: (u32, u32),
    automation: Option<Automation>,
    redraw_always: bool,
) -> Result<(), String> {
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|e| {
        format!("cannot open a window ({e}); is a display available? Use --headless --frames N without one")
    })?;
    let proxy: EventLoopProxy<Wake> = event_loop.create_proxy();
    let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
        // The loop is gone only when the viewer is closing.
        let _ = proxy.send_event(Wake);
    });
    let mut app = App { lab: make_lab(wake), redraw_always, size, automation, win: None, error: None };
    event_loop.run_app(&mut app).map_err(|e| format!("window event loop failed: {e}"))?;
    app.error.map_or(Ok(()), Err)
}

/// The first non-sRGB format the surface offers, or the sRGB one with its linear twin as view format.
fn choose_format(caps: &wgpu::SurfaceCapabilities) -> Option<(wgpu::TextureFormat, wgpu::TextureFormat)> {
    let plain =
        caps.formats.iter().find(|f| matches!(f, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm));
    match plain {
        Some(f) => Some((*f, *f)),
        None => caps.formats.first().map(|f| (*f, f.remove_srgb_suffix())),
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, msg: String) {
        eprintln!("raylab: {msg}");
        self.error = Some(msg);
        event_loop.exit();
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> Result<Windowed, String> {
        let attrs = Window::default_attributes()
            .with_title("raylab")
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(event_loop.create_window(attrs).map_err(|e| format!("cannot create a window: {e}"))?);
        let instance = Gpu::instance(Some(Box::new(event_loop.owned_display_handle())));
        let surface =
            instance.create_surface(Arc::clone(&window)).map_err(|e| format!("cannot draw into the window: {e}"))?;
        let gpu = Gpu::new(&instance, Some(&surface))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let (format, view_format) =
            choose_format(&caps).ok_or_else(|| format!("the window offers no colour format ({})", gpu.describe()))?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: Default::default(),
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format { vec![] } else { vec![view_format] },
        };
        if size.width > 0 && size.height > 0 {
            surface.configure(&gpu.device, &config);
        }
        self.lab.gpu_name = gpu.describe();
        let front = Frontend::new(gpu, view_format);
        let egui_state = egui_winit::State::new(
            front.egui.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            None,
            Some(front.gpu.device.limits().max_texture_dimension_2d as usize),
        );
        Ok(Windowed {
            window,
            surface,
            config,
            view_format,
            front,
            egui_state,
            look: None,
            last_redraw: Instant::now(),
            last_input: Instant::now(),
            redraw_at: None,
        })
    }

    /// Draws one UI frame; returns false when the run must end.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let Some(w) = &mut self.win else { return };
        w.last_redraw = Instant::now();
        let size = w.window.inner_size();
        let raw = w.egui_state.take_egui_input(&w.window);
        let ppp = egui_winit::pixels_per_point(&w.front.egui, &w.window);
        let mut frame = w.front.build(&mut self.lab, raw, (size.width, size.height), ppp);
        w.egui_state.handle_platform_output(&w.window, std::mem::take(&mut frame.platform));
        if size.width == 0 || size.height == 0 {
            // Minimised: nothing to draw into.
            w.front.finish(&mut self.lab, frame);
            return;
        }
        let texture = match w.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => None,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                w.config.width = size.width;
                w.config.height = size.height;
                w.surface.configure(&w.front.gpu.device, &w.config);
                None
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                self.lab.message("the window surface reported a validation error; retrying", true);
                None
            }
        };
        if let Some(texture) = texture {
            let view = texture
                .texture
                .create_view(&wgpu::TextureViewDescriptor { format: Some(w.view_format), ..Default::default() });
            w.front.draw(&mut frame, &view, (w.config.width, w.config.height));
            w.front.gpu.queue.present(texture);
        }
        let done = self.automation.as_ref().filter(|a| a.due(&self.lab, &frame));
        if let Some(a) = done {
            let r = a.finish(&mut w.front, &self.lab, &frame);
            w.front.finish(&mut self.lab, frame);
            if let Err(e) = r {
                self.fail(event_loop, e);
            } else {
                event_loop.exit();
            }
            return;
        }
        if frame.repaint_delay < Duration::MAX {
            let floor = if w.last_input.elapsed() < INPUT_LINGER { Duration::ZERO } else { IDLE_FRAME };
            w.schedule(frame.repaint_delay.max(floor));
        }
        w.front.finish(&mut self.lab, frame);
    }

    fn key(&mut self, code: KeyCode, down: bool) {
        let l = &mut self.lab;
        match code {
            KeyCode::KeyW | KeyCode::ArrowUp => l.set_keys(|k| k.forward = down),
            KeyCode::KeyS | KeyCode::ArrowDown => l.set_keys(|k| k.back = down),
            KeyCode::KeyA | KeyCode::ArrowLeft => l.set_keys(|k| k.left = down),
            KeyCode::KeyD | KeyCode::ArrowRight => l.set_keys(|k| k.right = down),
            KeyCode::KeyE | KeyCode::Space => l.set_keys(|k| k.up = down),
            KeyCode::KeyQ | KeyCode::ControlLeft | KeyCode::ControlRight => l.set_keys(|k| k.down = down),
            KeyCode::ShiftLeft | KeyCode::ShiftRight => l.set_keys(|k| k.fast = down),
            KeyCode::KeyF if down => l.frame_scene(),
            KeyCode::Tab if down => l.panel_visible = !l.panel_visible,
            KeyCode::F12 if down => l.request_shot(Shot::Window(timestamped("raylab-window"))),
            _ => {}
        }
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.win.is_some() {
            return;
        }
        match self.open_window(event_loop) {
            Ok(mut w) => {
                w.schedule(Duration::ZERO);
                self.win = Some(w);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn user_event(&mut self, _event_loop: &ActiveEventLoop, _event: Wake) {
        if let Some(w) = &mut self.win {
            w.schedule(Duration::ZERO);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(w) = &mut self.win else { return };
        let response = w.egui_state.on_window_event(&w.window, &event);
        // egui marks every event as needing a repaint, the redraw itself included; only real input counts.
        if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
            w.input();
        }
        let egui_keys = w.front.egui.egui_wants_keyboard_input();
        let egui_pointer = w.front.egui.is_pointer_over_egui();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if size.width > 0 && size.height > 0 {
                    w.config.width = size.width;
                    w.config.height = size.height;
                    w.surface.configure(&w.front.gpu.device, &w.config);
                }
                w.input();
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::Focused(false) => {
                w.look = None;
                self.lab.release_keys();
            }
            WindowEvent::DroppedFile(path) => self.lab.open(&path.display().to_string()),
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    let down = event.state == ElementState::Pressed;
                    // Releases always reach the camera so no key sticks when egui takes focus.
                    if !egui_keys || !down {
                        self.key(code, down);
                    }
                }
                if let Some(w) = &mut self.win {
                    w.input();
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Right, .. } => {
                w.look = (state == ElementState::Pressed && !egui_pointer).then_some((f64::NAN, f64::NAN));
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = w.look {
                    if x.is_finite() {
                        self.lab.look((position.x - x) as f32, (position.y - y) as f32);
                    }
                    w.look = Some((position.x, position.y));
                    w.input();
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !egui_pointer => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.lab.wheel(lines);
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(w) = &mut self.win else { return };
        if let Some(d) = self.lab.next_redraw() {
            w.schedule(d);
        }
        if self.redraw_always {
            w.schedule(Duration::ZERO);
        }
        match w.redraw_at {
            Some(t) => {
                let due = t.max(w.last_redraw + UI_FRAME);
                if Instant::now() >= due {
                    w.redraw_at = None;
                    w.window.request_redraw();
                    event_loop.set_control_flow(ControlFlow::Wait);
                } else {
                    event_loop.set_control_flow(ControlFlow::WaitUntil(due));
                }
            }
            None => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}
