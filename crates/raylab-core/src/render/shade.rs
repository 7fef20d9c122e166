//! The thesis's benchmark shading: one point light, N.L with attenuation, an optional hard shadow
//! (Tsakok 2008, chapter 4 introduction: "a single point light with attenuation and simple shading").
//!
//! With a white material and no attenuation this is exactly the Embree harness's image,
//! `0.12 + 0.88 * max(0, N.L) * visible`, so the two renderers can be compared pixel for pixel.

use glam::Vec3;

use crate::ray::{Hit, Ray};
use crate::scene::{PointLight, Scene};

/// Share of the light that reaches every lit or unlit surface.
pub const AMBIENT: f32 = 0.12;
/// Share of the light scaled by N.L and visibility.
pub const DIRECT: f32 = 1.0 - AMBIENT;

/// The shadow ray of a primary hit: from the hit point, lifted by `epsilon` along the geometric normal turned
/// toward the viewer, to the light; `None` where the surface faces away from the light (no shadow ray needed).
pub fn shadow_ray(scene: &Scene, ray: &Ray, hit: &Hit, light: &PointLight, epsilon: f32) -> Option<Ray> {
    let mut ng = scene.geometric_normal(hit.tri as usize);
    if ng.dot(ray.dir) > 0.0 {
        ng = -ng;
    }
    let p = ray.at(hit.t);
    if scene.shading_normal(hit).dot(light.position - p) * scene.shading_normal(hit).dot(ng) <= 0.0 {
        return None;
    }
    let q = p + ng * epsilon;
    let v = light.position - q;
    let d = v.length();
    Some(Ray::segment(q, v / d, 0.0, d))
}

/// Linear RGB colour of a primary hit lit by `light`, `visible` telling whether the shadow ray got through.
pub fn shade(scene: &Scene, ray: &Ray, hit: &Hit, light: &PointLight, visible: bool) -> Vec3 {
    let n = facing_normal(scene, ray, hit);
    let material = &scene.materials[scene.triangles[hit.tri as usize].material as usize];
    let p = ray.at(hit.t);
    let to_light = light.position - p;
    let dist = to_light.length();
    let ndl = n.dot(to_light / dist).max(0.0);
    let direct = if visible { ndl * light.attenuation(dist) } else { 0.0 };
    material.base_color * (AMBIENT + DIRECT * direct * light.color)
}

/// The shading normal of a hit, turned to the side of the surface the ray came from (two-sided shading).
pub fn facing_normal(scene: &Scene, ray: &Ray, hit: &Hit) -> Vec3 {
    let n = scene.shading_normal(hit);
    let mut ng = scene.geometric_normal(hit.tri as usize);
    if ng.dot(ray.dir) > 0.0 {
        ng = -ng;
    }
    if n.dot(ng) < 0.0 { -n } else { n }
}

/// Linear value to an 8-bit display value with the harness's gamma of 2.2.
pub fn to_display(v: f32) -> u8 {
    (255.0 * v.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8
}
