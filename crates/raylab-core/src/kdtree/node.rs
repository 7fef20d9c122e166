//! The compact traversal node.

/// One kd-tree node in 8 bytes (thesis 3.2.1 describes 14-byte nodes and notes 8 are possible).
///
/// Layout, two little words:
/// - inner node: `word = (left << 2) | axis` with `axis` in 0..=2, `data` = split position as `f32` bits; the
///   right child is `left + 1` (children are adjacent, so one index serves both); `left` is even, so a pair
///   fills one aligned 16-byte block and `left ^ 1` is the sibling;
/// - leaf: `word = (first << 2) | 3`, `data` = triangle count; the leaf's triangle ids are
///   `KdTree::tri_ids[first .. first + count]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct KdNode {
    word: u32,
    data: u32,
}

const _: () = assert!(std::mem::size_of::<KdNode>() == 8);

/// Largest node or triangle-reference index a [`KdNode`] can hold.
pub const MAX_INDEX: usize = (1 << 30) - 1;

impl KdNode {
    /// An inner node splitting `axis` at `split`, with children `left` and `left + 1`.
    pub fn inner(axis: usize, split: f32, left: u32) -> Self {
        debug_assert!(axis < 3 && left as usize <= MAX_INDEX);
        Self { word: (left << 2) | axis as u32, data: split.to_bits() }
    }

    /// A leaf holding `count` triangle ids from `first`.
    pub fn leaf(first: u32, count: u32) -> Self {
        debug_assert!(first as usize <= MAX_INDEX);
        Self { word: (first << 2) | 3, data: count }
    }

    /// True for leaves.
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.word & 3 == 3
    }

    /// Split axis of an inner node.
    #[inline(always)]
    pub fn axis(self) -> usize {
        (self.word & 3) as usize
    }

    /// Split position of an inner node.
    #[inline(always)]
    pub fn split(self) -> f32 {
        f32::from_bits(self.data)
    }

    /// Index of the left child of an inner node (the right child follows it).
    #[inline(always)]
    pub fn left(self) -> usize {
        (self.word >> 2) as usize
    }

    /// The range of `KdTree::tri_ids` a leaf covers.
    #[inline(always)]
    pub fn leaf_range(self) -> std::ops::Range<usize> {
        let first = (self.word >> 2) as usize;
        first..first + self.data as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let n = KdNode::inner(2, -1.5, 12345);
        assert!(!n.is_leaf());
        assert_eq!((n.axis(), n.split(), n.left()), (2, -1.5, 12345));
        let l = KdNode::leaf(MAX_INDEX as u32, 7);
        assert!(l.is_leaf());
        assert_eq!(l.leaf_range(), MAX_INDEX..MAX_INDEX + 7);
    }
}
