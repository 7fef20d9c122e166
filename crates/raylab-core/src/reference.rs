//! The brute-force reference: every ray against every triangle.
//!
//! Slow by design and obviously correct; every traversal method is tested against it ("always keep a
//! reference implementation", Akenine-Moller and Assarsson, Ray Tracing II).

use crate::edge_width::{Crossing, EdgeWidth};
use crate::intersector::Intersector;
use crate::ray::{Hit, Ray};
use crate::scene::Scene;
use crate::stats::TraversalStats;
use crate::triangle::{RayShear, TriangleSoup};

/// Brute-force intersector over a scene's triangles.
#[derive(Clone, Debug)]
pub struct BruteForce {
    tris: TriangleSoup,
}

impl BruteForce {
    /// Prepares the triangles of `scene`.
    pub fn new(scene: &Scene) -> Self {
        Self { tris: TriangleSoup::from_scene(scene) }
    }

    /// Bytes of its triangle copy.
    pub fn bytes(&self) -> usize {
        self.tris.len() * std::mem::size_of::<[crate::Vec3; 3]>()
    }

    /// The closest hit in `(tmin, tmax]`; among hits at the same distance the lowest triangle id wins.
    pub fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        stats.rays += 1;
        stats.packets += 1;
        if !ray.is_valid() {
            return None;
        }
        let shear = RayShear::new(ray);
        let mut best: Option<Hit> = None;
        for (i, tri) in self.tris.as_slice().iter().enumerate() {
            let tmax = best.map_or(ray.tmax, |b| b.t);
            if let Some(h) = shear.intersect(tri, ray.tmin, tmax)
                && best.is_none_or(|b| h.t < b.t)
            {
                best = Some(Hit { t: h.t, tri: i as u32, u: h.u, v: h.v });
            }
        }
        stats.isect_tests += self.tris.len() as u64;
        best
    }

    /// True when any triangle blocks the ray in `(tmin, tmax]`.
    pub fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.occluder(ray, stats).is_some()
    }

    /// The lowest-numbered triangle that blocks the ray in `(tmin, tmax]`.
    pub fn occluder(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        stats.rays += 1;
        stats.packets += 1;
        if !ray.is_valid() {
            return None;
        }
        let shear = RayShear::new(ray);
        stats.isect_tests += self.tris.len() as u64;
        self.tris.as_slice().iter().position(|t| shear.intersect(t, ray.tmin, ray.tmax).is_some()).map(|i| i as u32)
    }

    /// True when triangle `tri` blocks the ray in `(tmin, tmax]`.
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        ray.is_valid() && self.hit_distance(ray, tri).is_some()
    }

    /// The edge-width occlusion of a shadow ray (thesis Listing 5.1) from all its crossings at once: the
    /// answer the kd-tree kernel must reproduce.
    pub fn edge_width(&self, ray: &Ray, state: &mut EdgeWidth, stats: &mut TraversalStats) -> f32 {
        stats.rays += 1;
        stats.packets += 1;
        state.begin();
        if ray.is_valid() {
            let shear = RayShear::new(ray);
            stats.isect_tests += self.tris.len() as u64;
            for (i, c) in self.tris.as_slice().iter().enumerate() {
                if let Some(h) = shear.intersect(c, ray.tmin, ray.tmax) {
                    let n = (c[1] - c[0]).cross(c[2] - c[0]);
                    state.add(Crossing { t: h.t, tri: i as u32, front: n.dot(ray.dir) < 0.0 });
                }
            }
        }
        state.commit(f32::INFINITY, &self.tris);
        state.occlusion()
    }

    /// The distance at which `ray` hits triangle `tri`, if it does (used to check that two methods that
    /// report different triangles at the same distance both report a real hit).
    pub fn hit_distance(&self, ray: &Ray, tri: u32) -> Option<f32> {
        let t = self.tris.as_slice().get(tri as usize)?;
        RayShear::new(ray).intersect(t, ray.tmin, ray.tmax).map(|h| h.t)
    }
}

impl Intersector for BruteForce {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        BruteForce::intersect(self, ray, stats)
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        BruteForce::occluded(self, ray, stats)
    }
}
