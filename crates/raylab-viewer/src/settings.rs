//! Everything the side panel can change about how frames are traced, in one value that travels to the
//! render worker with each job.

use clap::ValueEnum;
use raylab_core::distribution::DistributionSettings;
use raylab_core::method::Method;
use raylab_core::ray_order::RayOrder;
use raylab_core::render::{FrameView, RenderSettings};
use raylab_core::shadow::Shadows;
use raylab_core::trace::TraceOptions;
use serde::Serialize;

/// How a frame is made.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RenderMode {
    /// Primary rays, shadow rays under the chosen technique, and reflection and refraction rays up to the
    /// chosen depth (Whitted-style, thesis 3.3 and 4.2.1).
    #[default]
    Whitted,
    /// The MBVH RS paper's distribution ray tracer: glossy paths, soft shadows, depth of field, refined
    /// progressively while the view stays still.
    Distribution,
    /// Stokes's G-buffer ray tracing (seed 003): the GPU rasterises a G-buffer, the CPU traces only the
    /// reflection rays of reflective pixels, and a GPU pass composites them into the lit raster image.
    Hybrid,
}

/// The hybrid mode's controls.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HybridControls {
    /// G-buffer (and R-buffer) resolution in percent of the render resolution: 25, 50 or 100.
    pub gbuffer_percent: u32,
    /// Reflection rows traced per frame: every row (1), every second (2) or every fourth (4), in turn.
    pub interlace: u32,
    /// Read the G-buffer back asynchronously (one frame late, no waiting) rather than waiting for it.
    pub async_readback: bool,
    /// The method that traces the reflection rays.
    pub method: Method,
}

impl Default for HybridControls {
    fn default() -> Self {
        Self { gbuffer_percent: 50, interlace: 1, async_readback: true, method: Method::Dacrt }
    }
}

impl HybridControls {
    /// G-buffer resolutions offered, in percent.
    pub const PERCENTS: [u32; 3] = [25, 50, 100];
    /// Interlacing factors offered.
    pub const INTERLACE: [u32; 3] = [1, 2, 4];

    /// The G-buffer size for a render resolution of `width x height` (at least 1x1).
    pub fn gbuffer_size(&self, width: u32, height: u32) -> (u32, u32) {
        let p = self.gbuffer_percent.clamp(1, 100);
        ((width * p).div_ceil(100).max(1), (height * p).div_ceil(100).max(1))
    }
}

/// The distribution ray tracer's controls.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DistributionControls {
    /// Bounces after the primary hit (1 to 7).
    pub bounces: u32,
    /// Paths per pixel added by each pass.
    pub paths_per_pass: u32,
    /// Phong exponent of the glossy lobe.
    pub glossy_exponent: f32,
    /// Every surface glossy (the paper's benchmark) rather than only the reflective materials.
    pub all_glossy: bool,
    /// Lens radius (0: pinhole).
    pub aperture: f32,
    /// Passes after which refinement stops.
    pub max_passes: u32,
}

impl Default for DistributionControls {
    fn default() -> Self {
        Self { bounces: 3, paths_per_pass: 4, glossy_exponent: 64.0, all_glossy: false, aperture: 0.0, max_passes: 256 }
    }
}

impl DistributionControls {
    /// The core settings for a `width x height` frame with tile edge `tile`.
    pub fn settings(&self, width: u32, height: u32, tile: u32) -> DistributionSettings {
        DistributionSettings {
            width,
            height,
            tile,
            spp: self.paths_per_pass.max(1),
            bounces: self.bounces.clamp(1, 7),
            glossy_exponent: self.glossy_exponent,
            all_glossy: self.all_glossy,
        }
    }
}

/// The frame settings the UI controls (and the `--json-stats` file records).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ViewerSettings {
    /// Render mode.
    pub mode: RenderMode,
    /// Traversal method and its switches.
    pub trace: TraceOptions,
    /// Tile edge in pixels.
    pub tile: u32,
    /// Shadow technique and its parameters.
    pub shadows: Shadows,
    /// Reflection and refraction depth after the primary hit.
    pub depth: u32,
    /// Distribution-mode controls.
    pub distribution: DistributionControls,
    /// Hybrid-mode controls.
    pub hybrid: HybridControls,
    /// Pixel order of single-ray methods.
    pub order: RayOrder,
    /// What the traced image shows.
    pub show: FrameView,
    /// Fixed hot end of the heat maps, or `None` for each frame's maximum.
    pub heat_max: Option<f32>,
    /// Render resolution in percent of the window (25-100).
    pub scale: u32,
    /// Trace at a lower scale while the camera flies, when a frame at `scale` would miss the fly budget
    /// ([`crate::camera::fly_scale`]).
    pub fly_scale: bool,
    /// Tracer threads.
    pub threads: usize,
    /// Keep tracing the same view (to read steady FPS) rather than only after a change.
    pub continuous: bool,
    /// Move a spinning mirror and a bouncing ball every frame, updating the structures each frame.
    pub animate: bool,
}

impl ViewerSettings {
    /// Tile edges offered in the panel (thesis Tables 4.1-4.5 use 4-64).
    pub const TILES: [u32; 5] = [4, 8, 16, 32, 64];

    /// The render resolution for a window of `width x height` pixels (at least 1x1).
    pub fn render_size(&self, width: u32, height: u32) -> (u32, u32) {
        let s = self.scale.clamp(25, 100);
        ((width * s).div_ceil(100).max(1), (height * s).div_ceil(100).max(1))
    }

    /// The core renderer's settings for a frame of `width x height` traced pixels.
    pub fn render_settings(&self, width: u32, height: u32) -> RenderSettings {
        RenderSettings {
            width,
            height,
            tile: self.tile,
            order: self.order,
            shadows: self.shadows,
            max_depth: self.depth,
            view: self.show,
            heat_max: self.heat_max,
        }
    }

    /// The method that traces this mode's rays: the reflection method in hybrid mode, else the method.
    pub fn frame_method(&self) -> Method {
        if self.mode == RenderMode::Hybrid { self.hybrid.method } else { self.trace.method }
    }
}
