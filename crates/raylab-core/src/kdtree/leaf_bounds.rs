//! Tight boxes of the kd-tree's non-empty leaves, for packet/leaf culling (thesis 4.1.4).
//!
//! The frustum walks cull packets against a leaf's box. The leaf's cell (the node's box) is looser than it
//! needs to be: what a ray must reach to hit anything in the leaf is the part of its triangles inside the
//! cell, which lies within the cell intersected with the triangles' bounds. Storing that box per leaf also
//! spares the walks from carrying cell boxes down the tree and onto the stack.

use crate::aabb::Aabb;
use crate::triangle::TriangleSoup;

use super::KdNode;

/// The tight box of every non-empty leaf, found through the leaf's first triangle reference: the boxes lie in
/// the order of those references, so a leaf's box is the number of leaves that start before it, counted in a
/// bit set of the starts. That count reads one 16-byte word of a table of about 45 KiB for Sponza (one bit
/// per reference), where an index per reference took a 4-byte entry of a 730 KiB array that the caches held
/// less well.
#[derive(Clone, Debug, Default)]
pub(super) struct LeafBounds {
    /// Per 64 triangle references, which of them start a non-empty leaf and how many leaves start before.
    starts: Vec<StartWord>,
    /// One box per non-empty leaf, in the order of the leaves' first references.
    boxes: Vec<Aabb>,
}

/// 64 references' worth of [`LeafBounds::starts`].
#[derive(Clone, Copy, Debug, Default)]
struct StartWord {
    /// Bit `i` set when reference `64 * word + i` starts a non-empty leaf.
    bits: u64,
    /// Leaves that start at earlier references.
    before: u32,
}

impl LeafBounds {
    /// The boxes of the leaves of a tree whose nodes `visit` enumerates with their cells.
    pub(super) fn new(tri_ids: &[u32], tris: &TriangleSoup, visit: impl FnOnce(&mut dyn FnMut(&Aabb, KdNode))) -> Self {
        let mut leaves: Vec<(usize, Aabb)> = Vec::new();
        visit(&mut |cell, n| {
            if !n.is_leaf() || n.leaf_range().is_empty() {
                return;
            }
            let range = n.leaf_range();
            let start = range.start;
            let extent = Aabb::from_points(tri_ids[range].iter().flat_map(|&t| *tris.get(t)));
            leaves.push((start, extent.intersection(*cell).padded(super::KdTree::ROOT_PADDING)));
        });
        // Non-empty leaves cover disjoint reference ranges, so no two start at the same reference.
        leaves.sort_unstable_by_key(|&(start, _)| start);
        let mut starts = vec![StartWord::default(); tri_ids.len().div_ceil(64)];
        for &(start, _) in &leaves {
            starts[start / 64].bits |= 1 << (start % 64);
        }
        let mut before = 0;
        for word in &mut starts {
            word.before = before;
            before += word.bits.count_ones();
        }
        LeafBounds { starts, boxes: leaves.into_iter().map(|(_, b)| b).collect() }
    }

    /// The tight box of leaf `n`, which must be a non-empty leaf of the tree.
    #[inline(always)]
    pub(super) fn get(&self, n: KdNode) -> Aabb {
        let start = n.leaf_range().start;
        let word = self.starts[start / 64];
        let earlier = word.bits & ((1u64 << (start % 64)) - 1);
        self.boxes[(word.before + earlier.count_ones()) as usize]
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use crate::kdtree::clip::clipped_bounds;
    use crate::kdtree::{KdParams, KdTree};
    use crate::scene::{SceneBuilder, Triangle};

    /// Every leaf's box holds each of its triangles' parts inside the leaf's cell, and lies within the cell
    /// (up to the padding).
    #[test]
    fn leaf_boxes_hold_their_triangles_parts_and_stay_in_their_cells() {
        let mut b = SceneBuilder::new();
        for k in 0..400u32 {
            let f = k as f32;
            let o = Vec3::new((f * 0.37).sin() * 9.0, (f * 0.11).cos() * 5.0, (k % 13) as f32 * 0.7);
            let base = b.positions.len() as u32;
            let (e1, e2) = (Vec3::new(1.3, 0.2 * (f * 0.5).sin(), 0.1), Vec3::new(-0.2, 0.9, 0.4 * (f * 0.3).cos()));
            b.positions.extend([o, o + e1, o + e2]);
            b.triangles.push(Triangle { v: [base, base + 1, base + 2], material: 0 });
        }
        let tree = KdTree::build(&b.build(), &KdParams::default()).unwrap();
        let mut checked = 0;
        tree.visit(|_, cell, n| {
            if !n.is_leaf() || n.leaf_range().is_empty() {
                return;
            }
            let lb = tree.leaf_bounds(n);
            let pad = cell.padded(KdTree::ROOT_PADDING);
            assert!(pad.min.cmple(lb.min).all() && lb.max.cmple(pad.max).all(), "{lb:?} leaves cell {cell:?}");
            for &t in &tree.tri_ids()[n.leaf_range()] {
                if let Some(part) = clipped_bounds(tree.triangles().get(t), cell) {
                    assert!(lb.min.cmple(part.min).all() && part.max.cmple(lb.max).all(), "{part:?} not in {lb:?}");
                    checked += 1;
                }
            }
        });
        assert!(checked > 400, "only {checked} triangle parts checked");
    }
}
