//! The thesis's benchmark shading: one point light, N.L with attenuation, an optional hard shadow
//! (Tsakok 2008, chapter 4 introduction: "a single point light with attenuation and simple shading").
//!
//! With a white material and no attenuation this is exactly the Embree harness's image,
//! `0.12 + 0.88 * max(0, N.L) * visible`, so the two renderers can be compared pixel for pixel.

use glam::Vec3;

use crate::method::Intersector;
use crate::ray::{Hit, Ray};
use crate::scene::{PointLight, Scene};
use crate::stats::TraversalStats;

/// Share of the light that reaches every lit or unlit surface.
pub const AMBIENT: f32 = 0.12;
/// Share of the light scaled by N.L and visibility.
pub const DIRECT: f32 = 1.0 - AMBIENT;

/// Everything the shader reads besides the hit.
pub struct ShadeContext<'a> {
    /// The scene (normals and materials).
    pub scene: &'a Scene,
    /// The tracer used for shadow rays.
    pub tracer: &'a dyn Intersector,
    /// The light.
    pub light: PointLight,
    /// Whether to trace a shadow ray.
    pub shadows: bool,
    /// Offset of shadow-ray origins along the normal (the harness's `1e-4 * diagonal`).
    pub epsilon: f32,
}

impl ShadeContext<'_> {
    /// Linear RGB colour of a primary hit.
    pub fn shade(&self, ray: &Ray, hit: &Hit, stats: &mut TraversalStats) -> Vec3 {
        let mut n = self.scene.shading_normal(hit);
        let mut ng = self.scene.geometric_normal(hit.tri as usize);
        if ng.dot(ray.dir) > 0.0 {
            ng = -ng;
        }
        if n.dot(ng) < 0.0 {
            n = -n;
        }
        let material = &self.scene.materials[self.scene.triangles[hit.tri as usize].material as usize];
        let p = ray.at(hit.t);
        let to_light = self.light.position - p;
        let dist = to_light.length();
        let l = to_light / dist;
        let ndl = n.dot(l).max(0.0);
        let mut direct = ndl * self.light.attenuation(dist);
        if direct > 0.0 && self.shadows {
            let q = p + ng * self.epsilon;
            let v = self.light.position - q;
            let d = v.length();
            if self.tracer.occluded(&Ray::segment(q, v / d, 0.0, d), stats) {
                direct = 0.0;
            }
        }
        material.base_color * (AMBIENT + DIRECT * direct * self.light.color)
    }
}

/// Linear value to an 8-bit display value with the harness's gamma of 2.2.
pub fn to_display(v: f32) -> u8 {
    (255.0 * v.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8
}
