//! `--headless`: the same UI frames as the window, drawn into an offscreen texture, for machines without a
//! window system. The run ends when the `--frames` automation is done.

use std::sync::Arc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::frontend::{Automation, Frontend};
use crate::gpu::device::Gpu;
use crate::lab::Lab;

/// Target format of the offscreen run.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// How long a headless run may wait for its frames before giving up.
const PATIENCE: Duration = Duration::from_secs(600);
/// The longest sleep between two UI frames when nothing wakes the loop.
const IDLE_FRAME: Duration = Duration::from_millis(100);

/// Runs `automation` offscreen at `size` pixels.
pub fn run(
    make_lab: impl FnOnce(Arc<dyn Fn() + Send + Sync>) -> Lab,
    size: (u32, u32),
    automation: Automation,
) -> Result<(), String> {
    let gpu = Gpu::new(&Gpu::instance(None), None)?;
    let (tx, rx) = mpsc::channel::<()>();
    let tx = std::sync::Mutex::new(tx);
    let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
        if let Ok(t) = tx.lock() {
            // The receiver lives until the run ends.
            let _ = t.send(());
        }
    });
    let mut lab = make_lab(wake);
    lab.gpu_name = gpu.describe();
    let mut front = Frontend::new(gpu, FORMAT);
    let target = front.gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("headless window"),
        size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let started = Instant::now();
    let epoch = Instant::now();
    let mut drawn: Option<Instant> = None;
    loop {
        let raw = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size.0 as f32, size.1 as f32))),
            time: Some(epoch.elapsed().as_secs_f64()),
            ..Default::default()
        };
        let mut frame = front.build(&mut lab, raw, size, 1.0);
        let due = automation.due(&lab, &frame);
        // Nobody looks at the offscreen window between frames: it is drawn when a traced frame arrived, at the
        // end, and at least every IDLE_FRAME, not at every poll of a G-buffer on its way back (on a software
        // driver each draw takes CPU time from the tracer).
        if frame.upload.is_some() || due || drawn.is_none_or(|t| t.elapsed() >= IDLE_FRAME) {
            front.draw(&mut frame, &view, size);
            drawn = Some(Instant::now());
        }
        if due {
            let r = automation.finish(&mut front, &lab, &frame);
            front.finish(&mut lab, frame);
            return r;
        }
        front.finish(&mut lab, frame);
        if started.elapsed() > PATIENCE {
            return Err(format!(
                "--headless: only {} of {} frames traced in {} s",
                lab.readouts.frames(),
                automation.frames,
                PATIENCE.as_secs()
            ));
        }
        // Sleep until the worker has news or the lab wants a redraw (a G-buffer on its way back from the GPU
        // is polled every few milliseconds, as in the window), and at most IDLE_FRAME.
        let sleep = lab.next_redraw().map_or(IDLE_FRAME, |d| d.min(IDLE_FRAME));
        let _ = rx.recv_timeout(sleep);
    }
}
