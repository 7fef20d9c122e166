//! Everything the side panel can change about how frames are traced, in one value that travels to the
//! render worker with each job.

use clap::ValueEnum;
use raylab_core::method::Method;
use raylab_core::render::{FrameView, RayOrder, RenderSettings};
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
    /// Pixel order of single-ray methods.
    pub order: RayOrder,
    /// What the traced image shows.
    pub show: FrameView,
    /// Fixed hot end of the heat maps, or `None` for each frame's maximum.
    pub heat_max: Option<f32>,
    /// Render resolution in percent of the window (25-100).
    pub scale: u32,
    /// Tracer threads.
    pub threads: usize,
    /// Keep tracing the same view (to read steady FPS) rather than only after a change.
    pub continuous: bool,
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

    /// Why `method` cannot be chosen in the current mode, if it cannot.
    pub fn method_unavailable(&self, method: Method) -> Option<&'static str> {
        match method {
            Method::Reference => Some("brute force over every triangle: for tests, far too slow to fly with"),
            _ => None,
        }
    }
}
