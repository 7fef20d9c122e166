//! A disc in space: the face of a spherical light turned toward a shaded point, on which that point's shadow
//! samples lie (thesis Figure 4.5). Cone and pyramid proxies bound it from the point before any sample is
//! drawn.

use glam::{DVec3, Vec3};

/// A flat disc: centre, unit normal and radius.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Disc {
    /// Centre.
    pub center: Vec3,
    /// Unit normal (the samples' plane is perpendicular to it).
    pub normal: Vec3,
    /// Radius.
    pub radius: f32,
}

/// How a disc spreads as seen from an apex in front of it, measured along its normal, padded for rounding:
/// every point of the disc is at depth at most `depth` along the normal, and its direction, scaled to unit
/// depth, is `center_dir` plus a vector perpendicular to the normal no longer than `reach`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DiscSpan {
    /// The direction to the disc's centre scaled to unit depth (its component along the normal is 1).
    pub center_dir: DVec3,
    /// Largest sideways offset per unit depth.
    pub reach: f64,
    /// Largest depth.
    pub depth: f32,
}

impl Disc {
    /// Widest spread a proxy is built for (sideways offset per unit depth, about 72 degrees): points closer
    /// to the light see it too wide for one bundle to help.
    pub const MAX_REACH: f64 = 3.0;

    /// The disc's spread seen from `apex`; `None` when `apex` is not in front of it (beyond a margin for
    /// rounding), the spread exceeds [`Disc::MAX_REACH`], or an input is not finite.
    pub(crate) fn span_from(&self, apex: Vec3) -> Option<DiscSpan> {
        let n = self.normal.as_dvec3();
        let to = (self.center - apex).as_dvec3();
        // Sample points are rounded to f32 near the centre's magnitude: they may sit off the plane and off
        // the rim by a few ulps of it.
        let err = (self.center.abs().max_element() as f64 + self.radius.abs() as f64) * 4e-7;
        let h = to.dot(n);
        let low = h - err;
        if !(low > 0.0 && to.is_finite() && self.radius.is_finite() && (n.length() - 1.0).abs() < 1e-4) {
            return None;
        }
        let radius = self.radius.max(0.0) as f64 + err;
        // The centre's sideways offset from the normal through the apex (an apex lifted off the surface is a
        // little off the line from the shaded point) adds to the reach.
        let center_dir = to / h;
        let offset = (to - n * h).length();
        let reach = (radius + offset) / low - offset / h;
        if reach.is_nan() || reach > Self::MAX_REACH {
            return None;
        }
        Some(DiscSpan { center_dir, reach: reach * (1.0 + 1e-4) + 1e-6, depth: ((h + err) * (1.0 + 1e-6)) as f32 })
    }
}
