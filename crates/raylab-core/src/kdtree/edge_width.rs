//! Edge-width shadow rays through the kd-tree (Tsakok 2008, Listing 5.1).
//!
//! The walk is the single-ray traversal; only leaves differ. Every triangle of a leaf is tested without
//! culling (entries and exits both matter), its crossings go to the [`EdgeWidth`] state, and the crossings up
//! to the leaf's far end are committed in order. Leaves come front to back, so the walk can stop as soon as a
//! chord reaches the radius.

use crate::ray::Ray;
use crate::shadow::{Crossing, EdgeWidth};
use crate::stats::TraversalStats;
use crate::triangle::RayShear;

use super::KdTree;
use super::mono::{Next, SPLIT_SLACK};

impl KdTree {
    /// Traces an edge-width shadow ray (from the shaded point toward the light) and returns its occlusion in
    /// `[0, 1]`; `state` holds the radius, the leak-fix switch and reusable buffers.
    pub fn edge_width(&self, ray: &Ray, state: &mut EdgeWidth, stats: &mut TraversalStats) -> f32 {
        state.begin();
        let shear = RayShear::new(ray);
        let tris = self.triangles();
        let mut tests = 0u64;
        self.traverse(ray, stats, |ids, _, t_far| {
            for &id in &self.tri_ids()[ids] {
                if state.seen(id) {
                    continue;
                }
                tests += 1;
                let corners = tris.get(id);
                if let Some(h) = shear.intersect(corners, ray.tmin, ray.tmax) {
                    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
                    state.add(Crossing { t: h.t, tri: id, front: n.dot(ray.dir) < 0.0 });
                }
            }
            if state.commit(t_far * (1.0 + SPLIT_SLACK), tris) { Next::Stop } else { Next::Continue(ray.tmax) }
        });
        stats.isect_tests += tests;
        state.commit(f32::INFINITY, tris);
        state.occlusion()
    }
}
