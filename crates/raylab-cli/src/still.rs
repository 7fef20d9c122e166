//! One still frame exactly as `raylab-bench render` makes it: the scene, view and light from the flags, a
//! method's structures, and the tile renderer on a pool of the given size. The viewer's tests compare its window
//! against this image.

use std::time::Instant;

use raylab_core::method::Purpose;
use raylab_core::render::{Frame, RenderSettings, render};
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::structures::{StructureParams, Structures};
use raylab_core::trace::{TraceOptions, Tracer};

use crate::args::SceneArgs;
use crate::prepare::{build_structures, load_scene};

/// A rendered still and what it took.
pub struct Still {
    /// The scene.
    pub scene: Scene,
    /// The structures its method traced through.
    pub structures: Structures,
    /// The camera the frame was rendered from (the scene's view with the flags' overrides).
    pub camera: Camera,
    /// The light it was lit by.
    pub light: PointLight,
    /// The frame.
    pub frame: Frame,
    /// Seconds spent loading the scene.
    pub load_s: f64,
    /// Seconds spent rendering: the median over the frames rendered.
    pub render_s: f64,
    /// Seconds each rendered frame took, in order.
    pub frame_s: Vec<f64>,
}

/// Renders `scene`'s view with `options` on `threads` threads, `frames` times over (at least once: the later
/// frames find warm caches and buffers, as a viewer's do); `settings` makes the frame settings for the scene's
/// light (the default edge-width radius is the light's radius). Every frame is the same image; the one kept
/// carries the stage times of the median frame.
pub fn render_still(
    scene: &SceneArgs,
    params: &StructureParams,
    options: TraceOptions,
    settings: impl FnOnce(&PointLight) -> RenderSettings,
    threads: usize,
    frames: usize,
) -> Result<Still, String> {
    let (loaded, load_s) = load_scene(&scene.source())?;
    let (camera, light) = scene.camera_and_light(&loaded)?;
    let settings = &settings(&light);
    settings.shadows.validate().map_err(|e| format!("--shadows: {e}"))?;
    let structures = build_structures(&loaded, &[options.method], Purpose::Frames, params, threads)?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| e.to_string())?;
    let tracer = Tracer::new(&structures, options).map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let mut timed = Vec::with_capacity(frames.max(1));
    let mut frame = pool.install(|| render(&loaded, &tracer, &camera, light, settings));
    timed.push((t0.elapsed().as_secs_f64(), frame.stages));
    for _ in 1..frames {
        let t = Instant::now();
        frame = pool.install(|| render(&loaded, &tracer, &camera, light, settings));
        timed.push((t.elapsed().as_secs_f64(), frame.stages));
    }
    let frame_s: Vec<f64> = timed.iter().map(|&(s, _)| s).collect();
    timed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (render_s, stages) = timed[timed.len() / 2];
    frame.stages = stages;
    Ok(Still { scene: loaded, structures, camera, light, frame, load_s, render_s, frame_s })
}

impl Still {
    /// The frame as an image.
    pub fn image(&self) -> Result<image::RgbaImage, String> {
        let f = &self.frame;
        image::RgbaImage::from_raw(f.width, f.height, f.rgba.as_flattened().to_vec())
            .ok_or_else(|| "frame buffer size mismatch".to_string())
    }
}
