//! In-place partitioning of the ray lists, without a branch per element.
//!
//! DACRT divides its ray list at every node, and for incoherent rays which side a ray goes to is close to
//! random: a two-cursor loop then mispredicts a branch on about every other ray (triangles, divided by their
//! centres, come in an order that predicts well, and keep the plain loop, which measured faster for them). Block
//! partitioning (Edelkamp and Weiss, BlockQuicksort, 2016) first collects the offsets of misplaced elements in a
//! block at each end without branching, then swaps misplaced pairs, so each element still moves at most once.

/// A list that can be partitioned: which elements belong in front, and how two are exchanged (together with
/// whatever travels with them).
pub(super) trait Partitioned {
    /// Number of elements.
    fn len(&self) -> usize;
    /// True when element `i` belongs in the front part.
    fn is_front(&self, i: usize) -> bool;
    /// Exchanges elements `a` and `b`.
    fn swap(&mut self, a: usize, b: usize);
}

/// Moves the front elements of `list` before the others and returns how many there are.
pub(super) fn block_partition(list: &mut impl Partitioned) -> usize {
    const BLOCK: usize = 64;
    let (mut l, mut r) = (0, list.len());
    let (mut back_at_l, mut front_at_r) = ([0u8; BLOCK], [0u8; BLOCK]);
    let (mut first_l, mut count_l, mut first_r, mut count_r) = (0, 0, 0, 0);
    while r - l >= 2 * BLOCK {
        if count_l == 0 {
            first_l = 0;
            for i in 0..BLOCK {
                back_at_l[count_l] = i as u8;
                count_l += !list.is_front(l + i) as usize;
            }
        }
        if count_r == 0 {
            first_r = 0;
            for i in 0..BLOCK {
                front_at_r[count_r] = i as u8;
                count_r += list.is_front(r - 1 - i) as usize;
            }
        }
        let pairs = count_l.min(count_r);
        for (&a, &b) in back_at_l[first_l..first_l + pairs].iter().zip(&front_at_r[first_r..first_r + pairs]) {
            list.swap(l + a as usize, r - 1 - b as usize);
        }
        (first_l, count_l, first_r, count_r) = (first_l + pairs, count_l - pairs, first_r + pairs, count_r - pairs);
        if count_l == 0 {
            l += BLOCK;
        }
        if count_r == 0 {
            r -= BLOCK;
        }
    }
    // Blocks still holding misplaced elements lie inside [l, r); their placed elements are checked again.
    loop {
        while l < r && list.is_front(l) {
            l += 1;
        }
        while l < r && !list.is_front(r - 1) {
            r -= 1;
        }
        if l >= r {
            return l;
        }
        list.swap(l, r - 1);
        l += 1;
        r -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Numbers(Vec<u32>, u32);

    impl Partitioned for Numbers {
        fn len(&self) -> usize {
            self.0.len()
        }
        fn is_front(&self, i: usize) -> bool {
            self.0[i].is_multiple_of(self.1)
        }
        fn swap(&mut self, a: usize, b: usize) {
            self.0.swap(a, b);
        }
    }

    /// Every length around the block sizes, with front shares from none to all: the front part holds exactly
    /// the front elements, and nothing is lost or duplicated.
    #[test]
    fn partitions_every_shape() {
        let mut state = 12345u32;
        for len in [0usize, 1, 2, 63, 64, 127, 128, 129, 200, 1000, 4099] {
            for modulus in [1u32, 2, 3, 7, 1 << 30] {
                let values: Vec<u32> = (0..len)
                    .map(|_| {
                        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                        state >> 4
                    })
                    .collect();
                let mut list = Numbers(values.clone(), modulus);
                let k = block_partition(&mut list);
                let want = values.iter().filter(|v| v.is_multiple_of(modulus)).count();
                assert_eq!(k, want, "len {len} modulus {modulus}");
                assert!(
                    list.0[..k].iter().all(|v| v.is_multiple_of(modulus))
                        && list.0[k..].iter().all(|v| !v.is_multiple_of(modulus))
                );
                let (mut a, mut b) = (values, list.0);
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b);
            }
        }
    }
}
