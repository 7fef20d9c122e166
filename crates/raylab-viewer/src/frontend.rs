//! One UI frame, the same for the window and the headless run: advance the lab, upload a newly traced
//! frame, run egui, and draw everything into a target; plus the automation that ends a `--frames` run.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::cpu_clock::{Cost, Stamp};
use crate::gpu::capture::capture;
use crate::gpu::compositor::Compositor;
use crate::gpu::device::Gpu;
use crate::gpu::hybrid::HybridGpu;
use crate::lab::{Lab, StatsReport};
use crate::settings::RenderMode;

/// The GPU side of the viewer.
pub struct Frontend {
    /// Device and queue.
    pub gpu: Gpu,
    /// Pipelines and the frame texture.
    pub compositor: Compositor,
    /// egui's context.
    pub egui: egui::Context,
    /// The hybrid mode's passes, made when the mode is first used.
    hybrid: Option<HybridGpu>,
    last_tick: Instant,
}

/// A UI frame ready to draw.
pub struct UiFrame {
    jobs: Vec<egui::ClippedPrimitive>,
    screen: egui_wgpu::ScreenDescriptor,
    free: Vec<egui::TextureId>,
    /// What egui asks of the window system (cursor, clipboard, links).
    pub platform: egui::PlatformOutput,
    /// When egui wants the next frame (`Duration::ZERO`: at once; `Duration::MAX`: only on input).
    pub repaint_delay: Duration,
    /// Cost of the frame upload, when a new traced frame was uploaded.
    pub upload: Option<Cost>,
    /// Cost of this UI frame so far: running egui, tessellating, encoding and submitting (not the upload, and
    /// not waiting for the window's next image).
    cost: Cost,
}

impl Frontend {
    /// The GPU side for targets of `format`.
    pub fn new(gpu: Gpu, format: wgpu::TextureFormat) -> Self {
        let compositor = Compositor::new(&gpu.device, format);
        Self { gpu, compositor, egui: egui::Context::default(), hybrid: None, last_tick: Instant::now() }
    }

    /// Advances `lab`, uploads its newest traced frame and runs the UI for a target of `size` pixels.
    pub fn build(&mut self, lab: &mut Lab, raw: egui::RawInput, size: (u32, u32), ppp: f32) -> UiFrame {
        let stamp = Stamp::now();
        let started = Instant::now();
        let dt = started.duration_since(self.last_tick).as_secs_f32();
        self.last_tick = started;
        lab.set_window_size(size.0, size.1);
        lab.tick(dt);
        if lab.settings.mode == RenderMode::Hybrid && self.hybrid.is_none() {
            match HybridGpu::new(&self.gpu) {
                Ok(h) => self.hybrid = Some(h),
                Err(e) => {
                    lab.message(e, true);
                    lab.settings.mode = RenderMode::Whitted;
                }
            }
        }
        if let Some(h) = self.hybrid.as_mut().filter(|_| lab.settings.mode == RenderMode::Hybrid) {
            h.step(&self.gpu, lab);
        }
        let fresh = lab.poll().map(|r| (r.hybrid.clone(), r.frame.width, r.frame.height));
        let upload = match fresh {
            Some((Some(h), _, _)) => {
                let s = Stamp::now();
                let shown = self.hybrid.as_mut().and_then(|g| g.show(&self.gpu, &mut self.compositor, &h, lab));
                lab.hybrid_gpu_ms = shown;
                if let Some((upload, composite)) = shown {
                    lab.readouts.push_hybrid_gpu(upload, composite);
                }
                shown.map(|_| s.cost())
            }
            Some((None, w, h)) => {
                let f = lab.latest().map(|r| &r.frame).filter(|f| (f.width, f.height) == (w, h));
                f.map(|f| {
                    let s = Stamp::now();
                    self.compositor.upload(&self.gpu.device, &self.gpu.queue, f.width, f.height, &f.rgba);
                    s.cost()
                })
            }
            None => None,
        };
        let out = self.egui.run_ui(raw, |ui| lab.ui(ui));
        let jobs = self.egui.tessellate(out.shapes, out.pixels_per_point);
        let free = self.compositor.apply_egui_textures(&self.gpu.device, &self.gpu.queue, out.textures_delta);
        let repaint_delay = out.viewport_output.get(&egui::ViewportId::ROOT).map_or(Duration::MAX, |v| v.repaint_delay);
        UiFrame {
            jobs,
            screen: egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point: ppp },
            free,
            platform: out.platform_output,
            repaint_delay,
            upload,
            cost: stamp.cost().minus(upload.unwrap_or_default()),
        }
    }

    /// Draws `frame` into `target` (of `size` pixels) and submits it.
    pub fn draw(&mut self, frame: &mut UiFrame, target: &wgpu::TextureView, size: (u32, u32)) {
        let stamp = Stamp::now();
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("ui") });
        let extra = self.compositor.prepare_egui(device, queue, &mut encoder, &frame.jobs, &frame.screen);
        self.compositor.draw(&self.gpu, &mut encoder, target, size, &frame.screen);
        queue.submit(extra.into_iter().chain([encoder.finish()]));
        frame.cost = frame.cost.plus(stamp.cost());
    }

    /// Saves the window shots `lab` asked for, then lets egui free what it no longer needs, and records the
    /// UI frame's cost.
    pub fn finish(&mut self, lab: &mut Lab, frame: UiFrame) {
        for path in lab.take_window_shots() {
            match self.screenshot(&frame, &path) {
                Ok(()) => lab.message(format!("saved the window to {}", path.display()), false),
                Err(e) => lab.message(e, true),
            }
        }
        self.compositor.free_egui(&frame.free);
        lab.readouts.push_ui(frame.upload, frame.cost);
    }

    /// Draws `frame` offscreen and writes it as PNG.
    pub fn screenshot(&mut self, frame: &UiFrame, path: &std::path::Path) -> Result<(), String> {
        let size = (frame.screen.size_in_pixels[0], frame.screen.size_in_pixels[1]);
        let img = capture(&self.gpu, &mut self.compositor, size, &frame.screen)?;
        img.save(path).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }
}

/// What a `--frames N` run does at the end.
pub struct Automation {
    /// Traced frames to wait for.
    pub frames: u64,
    /// Whole-window screenshot file.
    pub screenshot: Option<PathBuf>,
    /// Traced-frame screenshot file.
    pub traced_screenshot: Option<PathBuf>,
    /// Readouts file.
    pub json_stats: Option<PathBuf>,
}

/// The `--json-stats` file.
#[derive(Serialize)]
struct StatsFile<'a> {
    /// The machine and build, as `raylab-bench`'s JSON reports give them.
    environment: raylab_cli::env::Environment,
    scene: &'a str,
    triangles: usize,
    gpu: &'a str,
    window: [u32; 2],
    render: [u32; 2],
    settings: crate::settings::ViewerSettings,
    /// The side panel's rectangle in pixels (x0, y0, x1, y1), or null when hidden.
    panel_rect: Option<[f32; 4]>,
    /// Everything the UI drew over the traced image (the panel first), in pixels.
    ui_rects: &'a [[f32; 4]],
    /// In distribution mode, the paths per pixel in the last frame.
    paths: Option<u32>,
    /// With the animation on, the last frame's structure updates.
    animation: Option<crate::animated::UpdateTimes>,
    /// In hybrid mode, the last frame's G-buffer and costs.
    hybrid: Option<HybridStats>,
    readouts: StatsReport,
    /// Times egui's output was drawn (the UI layer); the other UI frames reused the previous drawing.
    ui_layer_draws: u64,
}

/// The hybrid mode's part of the `--json-stats` file: the last frame, and medians over all frames.
#[derive(Serialize)]
struct HybridStats {
    medians: Option<crate::lab::HybridReport>,
    gbuffer: [u32; 2],
    reflective_pixels: usize,
    rays: usize,
    raster_ms: f64,
    readback_ms: f64,
    trace_ms: f64,
    upload_ms: Option<f64>,
    composite_ms: Option<f64>,
}

impl Automation {
    /// True once enough frames were traced and the last one is on screen (it was uploaded by `frame`).
    pub fn due(&self, lab: &Lab, frame: &UiFrame) -> bool {
        lab.readouts.frames() as u64 >= self.frames && frame.upload.is_some()
    }

    /// Writes the requested outputs from `frame`; the error names the file.
    pub fn finish(&self, front: &mut Frontend, lab: &Lab, frame: &UiFrame) -> Result<(), String> {
        if let Some(p) = &self.screenshot {
            front.screenshot(frame, p)?;
        }
        if let Some(p) = &self.traced_screenshot {
            lab.save_traced(p)?;
        }
        if let Some(p) = &self.json_stats {
            let latest = lab.latest().ok_or("no frame was traced")?;
            let file = StatsFile {
                environment: raylab_cli::env::Environment::detect(),
                scene: &lab.scene().name,
                triangles: lab.scene().scene.triangle_count(),
                gpu: &lab.gpu_name,
                window: frame.screen.size_in_pixels,
                render: [latest.frame.width, latest.frame.height],
                settings: latest.settings,
                panel_rect: lab.panel_rect,
                ui_rects: &lab.ui_rects,
                paths: latest.paths,
                animation: latest.animation,
                hybrid: latest.hybrid.as_ref().map(|h| HybridStats {
                    medians: lab.readouts.hybrid_report(),
                    gbuffer: [h.size.0, h.size.1],
                    reflective_pixels: h.reflective,
                    rays: h.rays,
                    raster_ms: h.raster_ms,
                    readback_ms: h.readback_ms,
                    trace_ms: h.trace_ms,
                    upload_ms: lab.hybrid_gpu_ms.map(|m| m.0),
                    composite_ms: lab.hybrid_gpu_ms.map(|m| m.1),
                }),
                readouts: lab.readouts.report(),
                ui_layer_draws: front.compositor.ui_draws,
            };
            let json = serde_json::to_string_pretty(&file).map_err(|e| e.to_string())?;
            std::fs::write(p, json).map_err(|e| format!("cannot write {}: {e}", p.display()))?;
        }
        Ok(())
    }
}
