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

    /// The child of an inner node a ray meets first: the left one, or the right one where the ray's direction
    /// is negative on the split axis. `signs` holds that per axis as [`KdNode::sign_pattern`] spreads it: the
    /// word's low five bits select its bit directly (a shift by the whole word, which the hardware takes
    /// modulo 32), and the bit is added rather than or-ed in (the sibling follows the even-aligned left
    /// child), so finding the child is a bit test and an add-with-carry after the node's load.
    #[inline(always)]
    pub fn near_child(self, signs: u32) -> usize {
        ((self.word >> 2) + (signs.wrapping_shr(self.word) & 1)) as usize
    }

    /// Per-axis flags (bit `k` of `negative` set when the direction is negative on axis `k`) repeated every
    /// four bits, the form [`KdNode::near_child`] takes: bit `i` is flag `i % 4` (`i % 4 == 3`, a leaf's
    /// code, is never read).
    pub fn sign_pattern(negative: u32) -> u32 {
        (negative & 7) * 0x1111_1111
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
        let signs = KdNode::sign_pattern(0b101);
        for (axis, want) in [(0, 1), (1, 0), (2, 1)] {
            for left in [0, 2, 12344, MAX_INDEX as u32 - 1] {
                assert_eq!(KdNode::inner(axis, 0.5, left).near_child(signs), left as usize + want, "{axis} {left}");
            }
        }
        let l = KdNode::leaf(MAX_INDEX as u32, 7);
        assert!(l.is_leaf());
        assert_eq!(l.leaf_range(), MAX_INDEX..MAX_INDEX + 7);
    }
}
