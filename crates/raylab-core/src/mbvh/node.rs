//! The 4-wide node (MBVH RS paper, section 3.1): the boxes of its four children in structure-of-arrays form,
//! a "box packet" that one SIMD slab test checks at once, and what each child is.

/// Marks an empty lane in [`MbvhNode::child`].
pub const EMPTY: u32 = u32::MAX;

/// One 4-wide node: 128 bytes, two cache lines.
///
/// An empty lane's inverted box (`+inf` below, `-inf` above) fails every slab test, whatever the ray, so the
/// kernels need no separate mask of used lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct MbvhNode {
    /// Per axis, the four children's lower box corners (`min[axis][lane]`); empty lanes hold `+inf`.
    pub min: [[f32; 4]; 3],
    /// Per axis, the four children's upper box corners; empty lanes hold `-inf`.
    pub max: [[f32; 4]; 3],
    /// Per lane: an inner node's index, the first entry of a leaf's triangle-id range, or [`EMPTY`].
    pub child: [u32; 4],
    /// Per lane: the leaf's triangle count, 0 for an inner child or an empty lane.
    pub count: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<MbvhNode>() == 128);

impl MbvhNode {
    /// A node with four empty lanes.
    pub const fn empty() -> Self {
        Self { min: [[f32::INFINITY; 4]; 3], max: [[f32::NEG_INFINITY; 4]; 3], child: [EMPTY; 4], count: [0; 4] }
    }

    /// True when lane `k` holds a leaf.
    #[inline(always)]
    pub fn is_leaf(&self, k: usize) -> bool {
        self.count[k] > 0
    }

    /// True when lane `k` holds nothing.
    #[inline(always)]
    pub fn is_empty(&self, k: usize) -> bool {
        self.child[k] == EMPTY
    }
}
