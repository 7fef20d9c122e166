//! In-place partitioning of the ray and triangle lists, without a branch per element.
//!
//! DACRT divides its ray and triangle lists at every node, and for incoherent rays which side a ray goes to is
//! close to random: a two-cursor loop then mispredicts a branch on about every other ray. Each element's side
//! is read from a byte that travels with it (a ray's filter flags, a triangle's SAH bin), and block
//! partitioning (Edelkamp and Weiss, BlockQuicksort, 2016) first collects the offsets of misplaced elements in
//! a block at each end without branching, then swaps misplaced pairs, so each element still moves at most once.

/// Moves the elements of `items` whose byte in `keys` (which moves with them) satisfies `front` before the
/// others, and returns how many there are.
pub(super) fn partition<T>(items: &mut [T], keys: &mut [u8], front: impl Fn(u8) -> bool) -> usize {
    const BLOCK: usize = 64;
    debug_assert_eq!(items.len(), keys.len());
    let swap = |items: &mut [T], keys: &mut [u8], a: usize, b: usize| {
        items.swap(a, b);
        keys.swap(a, b);
    };
    let (mut l, mut r) = (0, items.len());
    let (mut back_at_l, mut front_at_r) = ([0u8; BLOCK], [0u8; BLOCK]);
    let (mut first_l, mut count_l, mut first_r, mut count_r) = (0, 0, 0, 0);
    while r - l >= 2 * BLOCK {
        if count_l == 0 {
            first_l = 0;
            for (i, &k) in keys[l..l + BLOCK].iter().enumerate() {
                back_at_l[count_l] = i as u8;
                count_l += !front(k) as usize;
            }
        }
        if count_r == 0 {
            first_r = 0;
            for (i, &k) in keys[r - BLOCK..r].iter().rev().enumerate() {
                front_at_r[count_r] = i as u8;
                count_r += front(k) as usize;
            }
        }
        let pairs = count_l.min(count_r);
        for (&a, &b) in back_at_l[first_l..first_l + pairs].iter().zip(&front_at_r[first_r..first_r + pairs]) {
            swap(items, keys, l + a as usize, r - 1 - b as usize);
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
        while l < r && front(keys[l]) {
            l += 1;
        }
        while l < r && !front(keys[r - 1]) {
            r -= 1;
        }
        if l >= r {
            return l;
        }
        swap(items, keys, l, r - 1);
        l += 1;
        r -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every length around the block sizes, with front shares from none to all: the front part holds exactly
    /// the front elements, keys stay with their elements, and nothing is lost or duplicated.
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
                let mut items = values.clone();
                let mut keys: Vec<u8> = values.iter().map(|v| v.is_multiple_of(modulus) as u8).collect();
                let k = partition(&mut items, &mut keys, |key| key == 1);
                let want = values.iter().filter(|v| v.is_multiple_of(modulus)).count();
                assert_eq!(k, want, "len {len} modulus {modulus}");
                assert!(items[..k].iter().all(|v| v.is_multiple_of(modulus)));
                assert!(items[k..].iter().all(|v| !v.is_multiple_of(modulus)));
                assert!(items.iter().zip(&keys).all(|(v, &key)| v.is_multiple_of(modulus) == (key == 1)));
                let (mut a, mut b) = (values, items);
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b);
            }
        }
    }
}
