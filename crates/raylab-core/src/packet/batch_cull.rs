//! Packet/leaf culling (thesis 4.1.4) for a whole batch of packets at once.
//!
//! When every ray of a tile starts at one origin, a packet is bounded by the range of its rays' inverse
//! directions on each axis, and a leaf box by its two planes' distances from that origin on each axis. The
//! products of those ranges bound the distances at which any of the packet's rays can be inside the box's
//! slabs (interval arithmetic, as in the MFT frustum test), so one SIMD test over `LANES` packets, one packet
//! per lane, rejects most packets that cannot reach a leaf before the per-ray test of
//! [`super::overlaps_box`] runs on the rest. The test is conservative: rounding is monotone, so each bound
//! is at least as wide as the per-ray test's own arithmetic, and a packet it keeps is still culled per ray.

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{Frustum, MAX_LANES, RayPacket, SignBounds};
use crate::aabb::Aabb;

/// The culling data of up to [`MAX_LANES`] packets, one per lane, relative to the tile's common origin.
#[derive(Clone, Copy, Debug)]
struct Chunk {
    /// Smallest inverse direction per axis; NaN where the packet's rays go both ways on the axis or one of
    /// them is parallel to it (the axis then bounds nothing: the SSE min/max rule drops NaN), or where the
    /// lane holds no packet.
    inv_lo: [[f32; MAX_LANES]; 3],
    /// Largest inverse direction per axis (NaN where `inv_lo` is).
    inv_hi: [[f32; MAX_LANES]; 3],
    /// Smallest `tmin` of the packet's rays (+inf for an empty packet or an empty lane).
    tmin: [f32; MAX_LANES],
}

/// Batched culling data of a tile's packets, whose rays all start at `origin`.
#[derive(Clone, Debug)]
pub struct BatchCull {
    origin: Vec3,
    chunks: Vec<Chunk>,
}

impl BatchCull {
    /// The batch data of `packets`, whose valid rays all start at `origin`, in chunks of `V::LANES` packets.
    #[inline(always)]
    pub fn new<V: Vf32>(origin: Vec3, packets: &[RayPacket<V>]) -> Self {
        let mut batch = BatchCull { origin, chunks: Vec::new() };
        batch.rebuild(origin, packets);
        batch
    }

    /// [`BatchCull::new`] in place, keeping the buffer: a tile of a frustum method rebuilds it for every tile.
    #[inline(always)]
    pub fn rebuild<V: Vf32>(&mut self, origin: Vec3, packets: &[RayPacket<V>]) {
        let empty = Chunk {
            inv_lo: [[f32::NAN; MAX_LANES]; 3],
            inv_hi: [[f32::NAN; MAX_LANES]; 3],
            tmin: [f32::INFINITY; MAX_LANES],
        };
        self.origin = origin;
        let chunks = &mut self.chunks;
        chunks.clear();
        chunks.resize(packets.len().div_ceil(V::LANES), empty);
        let (zero, inf, ninf, nan) =
            (V::splat(0.0), V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY), V::splat(f32::NAN));
        // A chunk's packets at a time, one per row, each row's lanes reduced together
        // (`Vf32::reduce_min_each`): a reduction per packet and quantity cost 4% of a primary MFT trace.
        let mut rows = V::array_from_fn(|_| inf);
        for (c, group) in chunks.iter_mut().zip(packets.chunks(V::LANES)) {
            // Invalid lanes, and the rows past a last short chunk, hold the reduction's identity.
            fill_rows(&mut rows, group, inf, |p| p.tmin);
            V::reduce_min_each(rows.as_ref()).write_to(&mut c.tmin[..V::LANES]);
            for k in 0..3 {
                fill_rows(&mut rows, group, inf, |p| p.inv[k]);
                let lo = V::reduce_min_each(rows.as_ref());
                fill_rows(&mut rows, group, ninf, |p| p.inv[k]);
                let hi = V::reduce_max_each(rows.as_ref());
                // A range only where the packet's rays all go one way on the axis, none parallel to it.
                let ranged = (lo.gt(zero) & hi.lt(inf)) | (hi.lt(zero) & lo.gt(ninf));
                V::select(ranged, lo, nan).write_to(&mut c.inv_lo[k][..V::LANES]);
                V::select(ranged, hi, nan).write_to(&mut c.inv_hi[k][..V::LANES]);
            }
        }
    }

    /// Bits (lane `i` for packet `chunk * LANES + i`) of the packets of one chunk that may have a ray inside
    /// box `b` at a distance in `[tmin, limit]`, allowing the relative `slack` of the per-ray test; `limit`
    /// holds the packets' farthest current hits, padded to whole chunks.
    #[inline(always)]
    pub fn maybe_inside<V: Vf32>(&self, chunk: usize, b: &Aabb, limit: &[f32], slack: f32) -> u32 {
        let c = &self.chunks[chunk];
        let mut t0 = V::from_slice(&c.tmin[..V::LANES]);
        let mut t1 = V::from_slice(&limit[chunk * V::LANES..(chunk + 1) * V::LANES]);
        for k in 0..3 {
            let (lo, hi) = (V::from_slice(&c.inv_lo[k][..V::LANES]), V::from_slice(&c.inv_hi[k][..V::LANES]));
            let near = V::splat(b.min[k] - self.origin[k]);
            let far = V::splat(b.max[k] - self.origin[k]);
            let (a, bb, cc, d) = (near * lo, near * hi, far * lo, far * hi);
            // NaN lanes (unbounded axes) leave `t0` and `t1` as they are: `x.max(y)` keeps `y` when `x` is NaN.
            t0 = a.min(bb).min(cc.min(d)).max(t0);
            t1 = a.max(bb).max(cc.max(d)).min(t1);
        }
        (t0 * V::splat(1.0 - slack)).le(t1 * V::splat(1.0 + slack)).bits()
    }

    /// The frustum from `origin` of packets `set`, built from the chunks' per-packet ranges a chunk at a time
    /// instead of from every ray's inverse direction: the bounds of [`Frustum::from_packets`] to the bit (the
    /// minima and maxima of the same inverses). `farthest` holds each packet's largest `tmax` (the tile's
    /// `farthest_hit` before any hit). `None` when the data cannot tell: `origin` is not the batch's, or a
    /// packet of `set` has no range on some axis (rays going both ways or parallel to it, or no valid ray);
    /// the caller then builds the frustum from the packets. MFT builds four frustums a tile, where a pass over
    /// every ray of the packets would be a visible share of the trace.
    #[inline(always)]
    pub fn frustum<V: Vf32>(&self, origin: Vec3, set: Range<usize>, farthest: &[f32]) -> Option<Frustum> {
        if origin != self.origin || set.is_empty() {
            return None;
        }
        let (zero, inf, ninf) = (V::splat(0.0), V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        let mut sides = SignBounds::<V>::new();
        let (mut t_min, mut t_max) = (inf, ninf);
        for chunk in set.start / V::LANES..set.end.div_ceil(V::LANES) {
            let base = chunk * V::LANES;
            let (lo_bit, hi_bit) = (set.start.max(base) - base, set.end.min(base + V::LANES) - base);
            let members = V::Mask::from_bits(((1u32 << hi_bit) - 1) & !((1u32 << lo_bit) - 1));
            let c = &self.chunks[chunk];
            t_min = t_min.min(V::select(members, V::from_slice(&c.tmin[..V::LANES]), inf));
            t_max = t_max.max(V::select(members, V::from_slice(&farthest[base..base + V::LANES]), ninf));
            for k in 0..3 {
                let (lo, hi) = (V::from_slice(&c.inv_lo[k][..V::LANES]), V::from_slice(&c.inv_hi[k][..V::LANES]));
                if (members & !lo.eq(lo)).any() {
                    return None;
                }
                // A ranged packet's inverses on the axis all have the sign of its range.
                sides.add(k, members & lo.gt(zero), members & hi.lt(zero), lo, hi);
            }
        }
        Some(sides.frustum(origin, t_min.reduce_min(), t_max.reduce_max()))
    }
}

/// Row `j` of `rows` is `value(packet j of group)` in its valid lanes and `identity` elsewhere; rows past the
/// group are all `identity`.
#[inline(always)]
fn fill_rows<V: Vf32>(rows: &mut V::Array<V>, group: &[RayPacket<V>], identity: V, value: impl Fn(&RayPacket<V>) -> V) {
    let rows = rows.as_mut();
    for (j, row) in rows.iter_mut().enumerate() {
        *row = match group.get(j) {
            Some(p) => V::select(p.valid, value(p), identity),
            None => identity,
        };
    }
}

#[cfg(test)]
mod tests {
    use raylab_simd::scalar::F32x4;

    use super::*;
    use crate::packet::overlaps_box;
    use crate::ray::Ray;

    /// A small deterministic generator (no dependency for a test).
    fn next(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    /// Packets of random rays from one origin: some all one way on an axis, some mixed, some with a zero
    /// direction component.
    fn packets(origin: Vec3, n: usize, state: &mut u64) -> Vec<RayPacket<F32x4>> {
        (0..n)
            .map(|i| {
                let centre = Vec3::new(next(state), next(state), next(state));
                let rays: Vec<Option<Ray>> = (0..4)
                    .map(|l| {
                        let mut d = centre + 0.2 * Vec3::new(next(state), next(state), next(state));
                        if i % 7 == 3 {
                            d[l % 3] = 0.0;
                        }
                        (i % 5 != 4 || l != 2).then(|| Ray::segment(origin, d, 0.01 * l as f32, 50.0))
                    })
                    .collect();
                RayPacket::new(&rays)
            })
            .collect()
    }

    #[test]
    fn never_culls_a_packet_the_per_ray_test_keeps() {
        let mut state = 7u64;
        let origin = Vec3::new(0.3, -0.2, 0.1);
        let ps = packets(origin, 203, &mut state);
        let batch = BatchCull::new(origin, &ps);
        let mut limit: Vec<f32> =
            ps.iter().map(|p| F32x4::select(p.valid, p.tmax, F32x4::splat(f32::NEG_INFINITY)).reduce_max()).collect();
        limit.resize(ps.len().div_ceil(4) * 4, f32::NEG_INFINITY);
        let (mut kept, mut culled) = (0, 0);
        for i in 0..400 {
            let c = Vec3::new(next(&mut state), next(&mut state), next(&mut state)) * 3.0;
            let e = Vec3::new(next(&mut state), next(&mut state), next(&mut state)).abs() * 0.8;
            // Some boxes touch the origin's planes exactly.
            let b = if i % 11 == 5 { Aabb::new(origin, origin + e) } else { Aabb::new(c - e, c + e) };
            for (j, p) in ps.iter().enumerate() {
                let coarse = batch.maybe_inside::<F32x4>(j / 4, &b, &limit, 1e-5) >> (j % 4) & 1 == 1;
                let exact = overlaps_box(p, &b, p.tmax, 1e-5).any();
                assert!(coarse || !exact, "packet {j} culled but a ray reaches {b:?}");
                if coarse && exact {
                    kept += 1;
                } else if !coarse {
                    culled += 1;
                }
            }
        }
        assert!(kept > 1000 && culled > 20_000, "kept {kept}, culled {culled}");
    }

    /// The frustum built from the batch data is the packets' own to the bit wherever every packet of the run
    /// has a range on every axis, and is declined (so the caller builds it from the packets) elsewhere.
    #[test]
    fn batch_frustums_equal_the_packets_frustums() {
        let mut state = 11u64;
        let origin = Vec3::new(-0.4, 0.25, 0.6);
        // One direction sign per packet and axis (octant `i % 8`), and the mixed and axis-parallel packets of
        // `packets` after them.
        let mut ps: Vec<RayPacket<F32x4>> = (0..64)
            .map(|i| {
                let sign = Vec3::new(
                    if i & 1 == 0 { 1.0 } else { -1.0 },
                    if i & 2 == 0 { 1.0 } else { -1.0 },
                    if i & 4 == 0 { 1.0 } else { -1.0 },
                );
                let rays: Vec<Option<Ray>> = (0..4)
                    .map(|l| {
                        let d =
                            Vec3::new(next(&mut state), next(&mut state), next(&mut state)).abs() + Vec3::splat(0.05);
                        (i % 9 != 4 || l != 1).then(|| Ray::segment(origin, d * sign, 0.02 * l as f32, 20.0 + i as f32))
                    })
                    .collect();
                RayPacket::new(&rays)
            })
            .collect();
        ps.extend(packets(origin, 40, &mut state));
        let batch = BatchCull::new(origin, &ps);
        let mut farthest: Vec<f32> =
            ps.iter().map(|p| F32x4::select(p.valid, p.tmax, F32x4::splat(f32::NEG_INFINITY)).reduce_max()).collect();
        farthest.resize(ps.len().div_ceil(4) * 4, f32::NEG_INFINITY);
        let (mut built, mut declined) = (0, 0);
        for start in 0..ps.len() {
            for len in [1, 2, 3, 5, 8, 13] {
                let set = start..(start + len).min(ps.len());
                let want = Frustum::from_packets(origin, &ps[set.clone()]);
                match batch.frustum::<F32x4>(origin, set.clone(), &farthest) {
                    Some(got) => {
                        built += 1;
                        assert_eq!(Some(got), want, "packets {set:?}");
                    }
                    None => declined += 1,
                }
            }
        }
        // Runs inside the one-sign packets are built; runs that reach the mixed ones are declined.
        assert!(built > 250 && declined > 150, "built {built}, declined {declined}");
        assert!(batch.frustum::<F32x4>(origin + Vec3::X, 0..4, &farthest).is_none(), "another origin");
    }

    #[test]
    fn padding_and_empty_packets_are_culled() {
        let origin = Vec3::ZERO;
        let empty = RayPacket::<F32x4>::new(&[]);
        let one = RayPacket::<F32x4>::new(&[Some(Ray::segment(origin, Vec3::X, 0.0, 10.0))]);
        let ps = [one, empty];
        let batch = BatchCull::new(origin, &ps);
        let limit = [10.0, f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY];
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        assert_eq!(batch.maybe_inside::<F32x4>(0, &b, &limit, 1e-5), 0b0001);
        let behind = Aabb::new(Vec3::new(-3.0, -1.0, -1.0), Vec3::new(-2.0, 1.0, 1.0));
        assert_eq!(batch.maybe_inside::<F32x4>(0, &behind, &limit, 1e-5), 0);
    }
}
