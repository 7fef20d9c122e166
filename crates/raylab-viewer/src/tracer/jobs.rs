//! What the render worker is asked to trace and what it hands back: frame jobs, the hybrid mode's reflection
//! jobs, traced frames, and the scene and structures a frame is traced in.

use std::sync::Arc;
use std::time::Instant;

use raylab_core::method::Method;
use raylab_core::render::{Frame, render};
use raylab_core::scene::{Camera, PointLight, Scene};
use raylab_core::structures::Structures;
use raylab_core::trace::{TraceOptions, Tracer};

use crate::animated::{AnimatedScene, UpdateTimes};
use crate::gpu::hybrid::readback::GBufferImage;
use crate::loader::LoadedScene;
use crate::settings::ViewerSettings;

/// One frame to trace.
#[derive(Clone)]
pub struct Job {
    /// The scene and its tree.
    pub scene: Arc<LoadedScene>,
    /// The camera.
    pub camera: Camera,
    /// The light.
    pub light: PointLight,
    /// The panel's settings.
    pub settings: ViewerSettings,
    /// Render resolution.
    pub size: (u32, u32),
}

/// A traced frame with what it cost.
pub struct Rendered {
    /// The image and counters.
    pub frame: Frame,
    /// Wall-clock seconds of the frame.
    pub wall_s: f64,
    /// The settings it was traced with.
    pub settings: ViewerSettings,
    /// In distribution mode, the paths per pixel accumulated in the image.
    pub paths: Option<u32>,
    /// With the animation on, what bringing the structures up to date cost before this frame.
    pub animation: Option<UpdateTimes>,
    /// In hybrid mode, the R-buffer and what making it cost.
    pub hybrid: Option<Box<HybridFrame>>,
}

/// A G-buffer read back from the GPU, whose reflections the worker traces (hybrid mode).
pub struct ReflectionJob {
    /// The view it was rasterised from (its size is the G-buffer's).
    pub job: Job,
    /// The G-buffer.
    pub gbuffer: GBufferImage,
    /// CPU milliseconds spent recording and submitting the raster pass.
    pub raster_ms: f64,
    /// CPU milliseconds spent reading the G-buffer back: waiting for the GPU (synchronous readback) and
    /// unpacking the staging buffers.
    pub readback_ms: f64,
    /// With the animation on, the animation time the G-buffer shows (the reflections are traced in the
    /// scene posed at the same time).
    pub animation_time: Option<f64>,
}

/// What the hybrid mode's CPU part made of a G-buffer.
#[derive(Clone, Debug)]
pub struct HybridFrame {
    /// R-buffer size (the G-buffer's).
    pub size: (u32, u32),
    /// Linear reflection colour per pixel (black where nothing reflects); rows not traced this frame keep the
    /// previous frame's colours when interlacing.
    pub rbuffer: Vec<[f32; 4]>,
    /// The camera position of the G-buffer.
    pub eye: glam::Vec3,
    /// Pixels that show a reflective surface.
    pub reflective: usize,
    /// Reflection rays traced this frame.
    pub rays: usize,
    /// CPU milliseconds recording and submitting the raster pass.
    pub raster_ms: f64,
    /// CPU milliseconds reading the G-buffer back (waiting, with synchronous readback, and unpacking).
    pub readback_ms: f64,
    /// Milliseconds building, tracing and shading the reflection rays.
    pub trace_ms: f64,
}

/// The scene and structures a frame traces: the loaded ones, or the animated copies.
#[derive(Clone, Copy)]
pub struct Traced<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its structures.
    pub structures: &'a Structures,
}

impl Traced<'_> {
    /// A tracer with `options` over these structures. Every viewer method's structures are built for frames
    /// ([`crate::loader::viewer_methods`]), so only the reference, which the viewer does not offer, is refused.
    pub(crate) fn tracer(&self, options: TraceOptions) -> Tracer<'_> {
        Tracer::new(self.structures, options).expect("the viewer builds every method's structures for frames")
    }
}

impl LoadedScene {
    /// The loaded scene and its structures.
    pub fn traced(&self) -> Traced<'_> {
        Traced { scene: &self.scene, structures: &self.structures }
    }
}

impl AnimatedScene {
    /// The animated scene and its structures.
    pub fn traced(&self) -> Traced<'_> {
        Traced { scene: &self.scene, structures: &self.structures }
    }
}

/// Traces `job` with `method` on the current rayon pool, in the loaded scene.
pub fn trace_frame(job: &Job, method: Method) -> Rendered {
    trace_in(&job.scene.traced(), job, method)
}

/// Traces `job` with `method` in the scene and structures `s`.
pub(crate) fn trace_in(s: &Traced, job: &Job, method: Method) -> Rendered {
    let settings = job.settings.render_settings(job.size.0, job.size.1);
    let tracer = s.tracer(TraceOptions { method, ..job.settings.trace });
    let t0 = Instant::now();
    let frame = render(s.scene, &tracer, &job.camera, job.light, &settings);
    Rendered {
        frame,
        wall_s: t0.elapsed().as_secs_f64(),
        settings: job.settings,
        paths: None,
        animation: None,
        hybrid: None,
    }
}
