//! What a frame shows: the shaded image, or one of the diagnostic views a ray-tracing lab needs to see where
//! the work goes (heat maps of the counters of [`crate::stats::TraversalStats`]) and what the rays hit.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The picture a frame shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameView {
    /// The benchmark shading with hard shadows (thesis chapter 4 introduction).
    #[default]
    Shaded,
    /// Heat map of kd-tree nodes visited per pixel, primary and shadow rays together. A unit traced as one
    /// (a ray, a packet, a frustum's tile) shares its count evenly among its pixels.
    Nodes,
    /// Heat map of ray/triangle intersection tests per pixel, shared like [`FrameView::Nodes`].
    Isects,
    /// Shading normals turned toward the viewer, as `0.5 + 0.5 n` in RGB.
    Normals,
    /// Hit distance, near white to far black; misses black.
    Depth,
}

impl FrameView {
    /// All views, in menu order.
    pub const ALL: [FrameView; 5] =
        [FrameView::Shaded, FrameView::Nodes, FrameView::Isects, FrameView::Normals, FrameView::Depth];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            FrameView::Shaded => "shaded",
            FrameView::Nodes => "nodes",
            FrameView::Isects => "isects",
            FrameView::Normals => "normals",
            FrameView::Depth => "depth",
        }
    }

    /// True for the heat maps, which need each traced unit's own counters.
    pub fn is_heat_map(self) -> bool {
        matches!(self, FrameView::Nodes | FrameView::Isects)
    }

    /// True for the views whose pixels are a value mapped to colour once the whole frame is known.
    pub fn is_scalar(self) -> bool {
        self.is_heat_map() || self == FrameView::Depth
    }
}

impl fmt::Display for FrameView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for FrameView {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        FrameView::ALL.into_iter().find(|v| v.name() == s).ok_or_else(|| {
            let names: Vec<_> = FrameView::ALL.iter().map(|v| v.name()).collect();
            format!("unknown view '{s}' (valid: {})", names.join(", "))
        })
    }
}

/// Control points of the heat-map palette: dark blue through cyan, green and yellow to red, so that equal
/// steps in work read as equal steps in colour and the hot end stands out.
const PALETTE: [[f32; 3]; 6] = [
    [0.02, 0.02, 0.25],
    [0.05, 0.30, 0.85],
    [0.05, 0.75, 0.80],
    [0.30, 0.85, 0.20],
    [0.98, 0.85, 0.10],
    [0.85, 0.08, 0.05],
];

/// The heat-map colour of `x` in `[0, 1]` (clamped), as display-ready RGBA8.
pub fn heat_color(x: f32) -> [u8; 4] {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let f = x * (PALETTE.len() - 1) as f32;
    let i = (f as usize).min(PALETTE.len() - 2);
    let w = f - i as f32;
    let (a, b) = (PALETTE[i], PALETTE[i + 1]);
    let c = |k: usize| ((a[k] + (b[k] - a[k]) * w) * 255.0).round() as u8;
    [c(0), c(1), c(2), 255]
}

/// The depth view's grey for `x` in `[0, 1]` (0 the nearest hit, 1 the farthest): white fading to a dark grey,
/// so the farthest surfaces stay distinct from misses (black).
pub fn depth_grey(x: f32) -> [u8; 4] {
    let g = super::shade::to_display(1.0 - 0.9 * x.clamp(0.0, 1.0));
    [g, g, g, 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for v in FrameView::ALL {
            assert_eq!(v.name().parse::<FrameView>(), Ok(v));
        }
        assert!("heat".parse::<FrameView>().unwrap_err().contains("nodes"));
    }

    #[test]
    fn palette_ends_and_monotone_red_at_hot_end() {
        assert_eq!(heat_color(0.0), [5, 5, 64, 255]);
        assert_eq!(heat_color(1.0), [217, 20, 13, 255]);
        assert_eq!(heat_color(-3.0), heat_color(0.0));
        assert_eq!(heat_color(f32::NAN), heat_color(0.0));
        assert_eq!(heat_color(7.0), heat_color(1.0));
        // Blue dominates the cold half, red the hot end.
        let cold = heat_color(0.2);
        let hot = heat_color(0.9);
        assert!(cold[2] > cold[0] && hot[0] > hot[2]);
    }
}
