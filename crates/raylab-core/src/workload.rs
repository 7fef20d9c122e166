//! The Embree harness's ray workloads, reproduced bit for bit (`shared/tools/embree-bench/README.md`).
//!
//! Primary rays come from [`crate::scene::CameraRaster`]. Shadow and diffuse rays start from a reference
//! primary pass: `p = o + t d` in `f32`, the geometric normal normalised in `f64` and turned toward the ray,
//! `q = p + eps n` with `eps = 1e-4` times the scene's bounding-box diagonal; shadow rays run from `q` to the
//! light over `(0, |L - q|]`, diffuse rays are cosine-distributed around `n` from a `pcg_hash` sequence,
//! with the orthonormal basis of Duff et al. 2017. The `f32` expressions keep the harness's order of
//! operations so the two tracers are given identical rays.

use std::fmt;
use std::str::FromStr;

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::intersector::Intersector;
use crate::ray::{Hit, Ray};
use crate::scene::{Camera, Scene};
use crate::stats::TraversalStats;

/// The three ray kinds of the harness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    /// Camera rays through every pixel centre.
    #[default]
    Primary,
    /// Hard-shadow rays from every primary hit to the light (any-hit queries).
    Shadow,
    /// One cosine-weighted diffuse bounce from every primary hit (closest-hit queries).
    Diffuse,
}

impl RayKind {
    /// All kinds.
    pub const ALL: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
        }
    }

    /// True for any-hit (occlusion) queries.
    pub fn is_occlusion(self) -> bool {
        self == RayKind::Shadow
    }
}

impl fmt::Display for RayKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for RayKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        RayKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown ray kind '{s}' (valid: primary, shadow, diffuse)"))
    }
}

/// The harness's hash for the diffuse samples.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The rays of one kind for every pixel of an image, in row-major pixel order; `None` where the harness
/// traces no ray (secondary rays of pixels whose primary ray missed).
#[derive(Clone, Debug)]
pub struct Workload {
    /// Ray kind.
    pub kind: RayKind,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// One entry per pixel.
    pub rays: Vec<Option<Ray>>,
    /// The point every ray ends at, when there is one (the light, for shadow rays): frustum methods trace
    /// such rays from that point, as the thesis traces shadow rays from the light.
    pub toward: Option<Vec3>,
}

impl Workload {
    /// Number of rays that are traced.
    pub fn ray_count(&self) -> usize {
        self.rays.iter().filter(|r| r.is_some()).count()
    }
}

/// The reference primary pass from which the secondary rays start.
#[derive(Clone, Debug)]
pub struct PrimaryPass {
    /// Primary rays, row-major.
    pub rays: Vec<Ray>,
    /// Closest hit per pixel.
    pub hits: Vec<Option<Hit>>,
}

impl PrimaryPass {
    /// Traces every primary ray of a `width x height` image with `tracer`.
    pub fn trace(camera: &Camera, width: u32, height: u32, tracer: &dyn Intersector) -> Self {
        let raster = camera.raster(width, height);
        let rays: Vec<Ray> =
            (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| raster.primary(x, y)).collect();
        let mut stats = TraversalStats::default();
        let hits = rays.iter().map(|r| tracer.intersect(r, &mut stats)).collect();
        Self { rays, hits }
    }

    /// Number of pixels whose primary ray hit.
    pub fn hit_count(&self) -> usize {
        self.hits.iter().flatten().count()
    }

    /// Sum of the hit distances, in double precision (the harness's checksum).
    pub fn sum_t(&self) -> f64 {
        self.hits.iter().flatten().map(|h| h.t as f64).sum()
    }
}

/// Builds harness workloads for one scene, camera, light and image size.
pub struct WorkloadBuilder<'a> {
    scene: &'a Scene,
    width: u32,
    height: u32,
    light: Vec3,
    seed: u32,
    pass: PrimaryPass,
}

impl<'a> WorkloadBuilder<'a> {
    /// The harness's default diffuse seed.
    pub const DEFAULT_SEED: u32 = 1;

    /// Runs the reference primary pass with `tracer`.
    pub fn new(
        scene: &'a Scene,
        camera: &Camera,
        light: Vec3,
        width: u32,
        height: u32,
        tracer: &dyn Intersector,
    ) -> Self {
        let pass = PrimaryPass::trace(camera, width, height, tracer);
        Self { scene, width, height, light, seed: Self::DEFAULT_SEED, pass }
    }

    /// Sets the diffuse seed.
    pub fn seed(mut self, seed: u32) -> Self {
        self.seed = seed;
        self
    }

    /// The reference primary pass.
    pub fn primary_pass(&self) -> &PrimaryPass {
        &self.pass
    }

    /// The offset that lifts secondary origins off the surface: `1e-4` times the bounds' diagonal.
    pub fn epsilon(&self) -> f32 {
        let b = self.scene.bounds();
        if b.is_empty() { 0.0 } else { (1e-4 * (b.max.as_dvec3() - b.min.as_dvec3()).length()) as f32 }
    }

    /// The rays of `kind`.
    pub fn build(&self, kind: RayKind) -> Workload {
        let rays = match kind {
            RayKind::Primary => self.pass.rays.iter().map(|r| Some(*r)).collect(),
            RayKind::Shadow | RayKind::Diffuse => {
                let eps = self.epsilon();
                (0..self.pass.rays.len()).map(|i| self.secondary(kind, i, eps)).collect()
            }
        };
        let toward = (kind == RayKind::Shadow).then_some(self.light);
        Workload { kind, width: self.width, height: self.height, rays, toward }
    }

    fn secondary(&self, kind: RayKind, i: usize, eps: f32) -> Option<Ray> {
        let hit = self.pass.hits[i]?;
        let pr = &self.pass.rays[i];
        let ng = self.scene.geometric_normal_unnormalized(hit.tri as usize).as_dvec3();
        let mut n: DVec3 = ng * (1.0 / ng.dot(ng).sqrt());
        if n.dot(pr.dir.as_dvec3()) > 0.0 {
            n = -n;
        }
        let n = n.as_vec3();
        let t = hit.t;
        let p = Vec3::new(pr.origin.x + t * pr.dir.x, pr.origin.y + t * pr.dir.y, pr.origin.z + t * pr.dir.z);
        let q = Vec3::new(p.x + eps * n.x, p.y + eps * n.y, p.z + eps * n.z);
        Some(match kind {
            RayKind::Shadow => {
                let v = self.light - q;
                let dist = (v.x * v.x + v.y * v.y + v.z * v.z).sqrt();
                Ray::segment(q, Vec3::new(v.x / dist, v.y / dist, v.z / dist), 0.0, dist)
            }
            _ => Ray::new(q, self.diffuse_dir(i as u32, n)),
        })
    }

    fn diffuse_dir(&self, i: u32, n: Vec3) -> Vec3 {
        let base = (2u32.wrapping_mul(i)).wrapping_add(self.seed.wrapping_mul(0x9E37_79B9));
        let u1 = (pcg_hash(base) >> 8) as f32 * (1.0 / 16_777_216.0);
        let u2 = (pcg_hash(base.wrapping_add(1)) >> 8) as f32 * (1.0 / 16_777_216.0);
        let r = u1.sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2;
        let (a, b) = (r * phi.cos(), r * phi.sin());
        let c = (1.0 - u1).max(0.0).sqrt();
        let sign = 1.0f32.copysign(n.z);
        let ka = -1.0 / (sign + n.z);
        let kb = n.x * n.y * ka;
        let b1 = Vec3::new(1.0 + sign * n.x * n.x * ka, sign * kb, -sign * n.x);
        let b2 = Vec3::new(kb, sign + n.y * n.y * ka, -n.y);
        let dx = a * b1.x + b * b2.x + c * n.x;
        let dy = a * b1.y + b * b2.y + c * n.y;
        let dz = a * b1.z + b * b2.z + c * n.z;
        let len = (dx * dx + dy * dy + dz * dz).sqrt();
        Vec3::new(dx / len, dy / len, dz / len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_hash_known_values() {
        // Reference values of the PCG hash (Jarzynski and Olano 2020), as the harness computes it.
        assert_eq!(pcg_hash(0), 129_708_002);
        assert_eq!(pcg_hash(1), 2_831_084_092);
    }

    #[test]
    fn kinds_parse() {
        assert_eq!("shadow".parse::<RayKind>(), Ok(RayKind::Shadow));
        assert!("glossy".parse::<RayKind>().unwrap_err().contains("valid"));
    }
}
