//! Statistics of a finished kd-tree, gathered in a separate pass over the traversal layout.

use serde::{Deserialize, Serialize};

use super::KdTree;

/// Size and quality figures of a kd-tree, as `raylab-bench info` prints them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KdStats {
    /// Build wall time in seconds.
    pub build_seconds: f64,
    /// All nodes.
    pub nodes: usize,
    /// Inner nodes.
    pub inner: usize,
    /// Leaves.
    pub leaves: usize,
    /// Leaves with no triangle.
    pub empty_leaves: usize,
    /// Triangle references held by leaves (a triangle in several leaves counts in each).
    pub tri_refs: usize,
    /// Mean triangles per non-empty leaf.
    pub avg_tris_per_leaf: f64,
    /// Largest triangle count of one leaf.
    pub max_tris_per_leaf: usize,
    /// Deepest leaf (the root has depth 0).
    pub max_depth: u32,
    /// Bytes of nodes plus triangle references (the triangle corners are not counted).
    pub bytes: usize,
    /// SAH cost of the whole tree (Eq. 2.1 applied recursively, relative to the root's area, no empty bonus).
    pub sah_cost: f64,
}

impl KdStats {
    pub(super) fn gather(tree: &KdTree) -> Self {
        let p = tree.params();
        let root_sa = tree.bounds().surface_area() as f64;
        let mut s = KdStats { build_seconds: tree.build_time().as_secs_f64(), ..Default::default() };
        tree.visit(|depth, b, n| {
            s.nodes += 1;
            s.max_depth = s.max_depth.max(depth);
            let w = if root_sa > 0.0 { b.surface_area() as f64 / root_sa } else { 0.0 };
            if n.is_leaf() {
                let c = n.leaf_range().len();
                s.leaves += 1;
                s.tri_refs += c;
                s.max_tris_per_leaf = s.max_tris_per_leaf.max(c);
                if c == 0 {
                    s.empty_leaves += 1;
                }
                s.sah_cost += w * p.c_isect as f64 * c as f64;
            } else {
                s.inner += 1;
                s.sah_cost += w * p.c_trav as f64;
            }
        });
        let full = s.leaves - s.empty_leaves;
        s.avg_tris_per_leaf = if full == 0 { 0.0 } else { s.tri_refs as f64 / full as f64 };
        s.bytes = s.nodes * std::mem::size_of::<super::KdNode>() + s.tri_refs * 4;
        s
    }
}
