//! Refitting: when triangles move but keep their ids, the MBVH keeps its topology and only its boxes are
//! recomputed, bottom-up (children always follow their parent in the node array). Linear in the nodes and
//! triangles, far cheaper than a build; the tree's quality degrades as the motion tears leaves apart, which is
//! the usual trade for animated scenes (seed 003's dynamic scenes; DACRT needs neither).

use std::time::{Duration, Instant};

use super::Mbvh;
use super::build::put_box;
use crate::aabb::Aabb;
use crate::scene::Scene;
use crate::triangle::TriangleSoup;

/// Why a refit was refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RefitError {
    /// Triangles the MBVH was built over.
    pub built: usize,
    /// Triangles the scene has now.
    pub now: usize,
}

impl std::fmt::Display for RefitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot refit an MBVH built over {} triangles to a scene of {}", self.built, self.now)
    }
}

impl std::error::Error for RefitError {}

impl Mbvh {
    /// Recomputes every box for the current positions of `scene`'s triangles, which must be the ones the MBVH
    /// was built over (same count and ids). Returns how long it took.
    pub fn refit(&mut self, scene: &Scene) -> Result<Duration, RefitError> {
        if scene.triangle_count() != self.slot_of.len() {
            return Err(RefitError { built: self.slot_of.len(), now: scene.triangle_count() });
        }
        let start = Instant::now();
        self.tris = TriangleSoup::gather(scene, &self.tri_ids);
        self.blocks = crate::tri4::blocks_of(&self.tris);
        let mut node_box = vec![Aabb::EMPTY; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let mut total = Aabb::EMPTY;
            for k in 0..4 {
                let node = &self.nodes[i];
                if node.is_empty(k) {
                    continue;
                }
                let (child, count) = (node.child[k] as usize, node.count[k] as usize);
                let b = if node.is_leaf(k) {
                    (child..child + count)
                        .fold(Aabb::EMPTY, |b, s| b.union(Aabb::from_points(*self.tris.get(s as u32))))
                } else {
                    node_box[child]
                };
                put_box(&mut self.nodes[i], k, &b);
                total = total.union(b);
            }
            node_box[i] = total;
        }
        self.bounds = scene.bounds();
        Ok(start.elapsed())
    }
}
