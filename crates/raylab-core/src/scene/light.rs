//! Point lights with distance attenuation and a radius for soft shadows.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A point light (thesis 4.2: "a single point light with attenuation").
///
/// Intensity at distance `d` is `color / (constant + linear * d + quadratic * d^2)`. `radius` is the radius of
/// the spherical light that soft-shadow techniques sample or approximate; hard shadows ignore it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointLight {
    /// Position in world space.
    pub position: Vec3,
    /// Linear RGB intensity.
    pub color: Vec3,
    /// Constant attenuation term.
    pub constant: f32,
    /// Linear attenuation term.
    pub linear: f32,
    /// Quadratic attenuation term.
    pub quadratic: f32,
    /// Radius of the light's sphere, for soft shadows.
    pub radius: f32,
}

impl PointLight {
    /// A white light at `position` with no attenuation (the Embree harness's light) and radius zero.
    pub fn at(position: Vec3) -> Self {
        Self { position, color: Vec3::ONE, constant: 1.0, linear: 0.0, quadratic: 0.0, radius: 0.0 }
    }

    /// Radius soft techniques give a point light (the thesis's Sponza light, thesis Table 4.6).
    pub const DEFAULT_SOFT_RADIUS: f32 = 1.0;

    /// This light, with [`Self::DEFAULT_SOFT_RADIUS`] if it is a point, for techniques that need a sphere to
    /// sample or approximate.
    pub fn soft(self) -> Self {
        if self.radius > 0.0 { self } else { Self { radius: Self::DEFAULT_SOFT_RADIUS, ..self } }
    }

    /// The attenuation factor at distance `d`, clamped to at most 1.
    pub fn attenuation(&self, d: f32) -> f32 {
        let denom = self.constant + self.linear * d + self.quadratic * d * d;
        if denom > 1.0 { 1.0 / denom } else { 1.0 }
    }
}
