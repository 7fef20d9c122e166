//! Leaf triangles four at a time: one ray against a block of four triangles stored side by side (structure of
//! arrays), with the watertight test (Woop, Benthin, Wald 2013) run in the four SIMD lanes.
//!
//! Packet kernels test four rays against one triangle (`crate::packet`); a single ray has no rays to fill the
//! lanes with, so single rays through the MBVH (and the MBVH RS leaves' left-over rays) fill them with
//! triangles instead, as Embree's four-triangle leaves do. The kd-tree's leaves stay one test per triangle:
//! most hold one or two, where the scalar test's early exit on the edge signs is cheaper than a whole block.
//!
//! A structure lays its leaves out in blocks: each leaf starts at a slot that is a multiple of four, so slot
//! `s` is lane `s % 4` of block `s / 4`. Every lane performs exactly the `f32` operations of
//! [`RayShear::intersect`], in the same order, and lanes whose edge functions are exactly zero are redone by
//! that scalar test (its double-precision fallback), so a block reports bit for bit what testing its
//! triangles one by one reports. Unused lanes hold NaN corners, which fail every comparison and never hit.

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};
use rayon::prelude::*;

use crate::packet::{Sheared, sheared_test};
use crate::ray::{Hit, Ray};
use crate::triangle::{RayShear, TriHit, TriangleSoup};

/// Marks a padding slot in a leaf-ordered triangle-id array.
pub const PAD: u32 = u32::MAX;

/// Four triangles' corners in structure-of-arrays form: `v[corner][axis][lane]`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Tri4 {
    v: [[[f32; 4]; 3]; 3],
}

impl Tri4 {
    /// Packs up to four triangles; missing lanes get NaN corners.
    pub fn pack(tris: &[[Vec3; 3]]) -> Self {
        assert!(tris.len() <= 4, "a block holds at most four triangles");
        let mut v = [[[f32::NAN; 4]; 3]; 3];
        for (lane, tri) in tris.iter().enumerate() {
            for (corner, p) in tri.iter().enumerate() {
                for axis in 0..3 {
                    v[corner][axis][lane] = p[axis];
                }
            }
        }
        Self { v }
    }

    /// The corners of lane `lane`'s triangle.
    pub fn triangle(&self, lane: usize) -> [Vec3; 3] {
        std::array::from_fn(|c| Vec3::new(self.v[c][0][lane], self.v[c][1][lane], self.v[c][2][lane]))
    }
}

/// Four-triangle blocks of a leaf-ordered soup (padding slots hold NaN triangles).
pub fn blocks_of(tris: &TriangleSoup) -> Vec<Tri4> {
    tris.as_slice().par_chunks(4).with_min_len(2048).map(Tri4::pack).collect()
}

/// Moves each leaf `(first, count)` of `ids` to a slot that is a multiple of four (keeping the leaves'
/// order), padding with [`PAD`]; returns the padded array and rewrites each leaf's `first`.
pub fn align_leaves(ids: &[u32], leaves: &mut [(&mut u32, u32)]) -> Vec<u32> {
    leaves.sort_unstable_by_key(|(first, _)| **first);
    let mut out = Vec::with_capacity(ids.len() + 3 * leaves.len());
    for (first, count) in leaves.iter_mut() {
        let (start, n) = (**first as usize, *count as usize);
        **first = out.len() as u32;
        out.extend_from_slice(&ids[start..start + n]);
        out.resize(out.len().next_multiple_of(4), PAD);
    }
    out
}

/// Tests the triangles in `slots` (a leaf of `blocks`, whose ids `ids` holds) and keeps a closer hit in
/// `best`, lowering `best_t` to it. Later lanes win ties, as when the triangles are tested one by one.
#[inline(always)]
pub fn closest_in_leaf<V: Vf32>(
    shear: &ShearX4<V>,
    blocks: &[Tri4],
    ids: &[u32],
    slots: Range<usize>,
    tmin: f32,
    best_t: &mut f32,
    best: &mut Option<Hit>,
) {
    for b in slots.start / 4..slots.end.div_ceil(4) {
        let h = shear.test(&blocks[b], tmin, *best_t);
        let mut bits = h.mask.bits();
        while bits != 0 {
            let lane = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            // The block was tested against the best hit before its first lane, so a later lane may lie
            // beyond an earlier one.
            let hit = Hit { t: h.t.lane(lane), tri: ids[4 * b + lane], u: h.u.lane(lane), v: h.v.lane(lane) };
            if hit.beats(*best) {
                *best_t = hit.t;
                *best = Some(hit);
            }
        }
    }
}

/// The first triangle in `slots` (a leaf of `blocks`) found to block `(tmin, tmax]`, and the number of
/// triangles tested until then.
#[inline(always)]
pub fn blocker_in_leaf<V: Vf32>(
    shear: &ShearX4<V>,
    blocks: &[Tri4],
    ids: &[u32],
    slots: Range<usize>,
    tmin: f32,
    tmax: f32,
) -> (Option<u32>, u64) {
    let mut tests = 0;
    for b in slots.start / 4..slots.end.div_ceil(4) {
        tests += (slots.end - 4 * b).min(4) as u64;
        let bits = shear.test(&blocks[b], tmin, tmax).mask.bits();
        if bits != 0 {
            return (Some(ids[4 * b + bits.trailing_zeros() as usize]), tests);
        }
    }
    (None, tests)
}

/// A ray's watertight-test constants splatted across the lanes.
pub struct ShearX4<V: Vf32> {
    scalar: RayShear,
    /// Origin components in the shear's `(kx, ky, kz)` order.
    org: [V; 3],
    /// `(S_x, S_y, S_z)`.
    s: [V; 3],
    /// `(kx, ky, kz)`.
    k: [usize; 3],
}

/// The lanes of a block a ray hits, with their distances and barycentrics.
pub struct BlockHits<V: Vf32> {
    /// Lanes hit within the interval.
    pub mask: V::Mask,
    /// Distances (meaningful in `mask`'s lanes).
    pub t: V,
    /// Weights of corner 1.
    pub u: V,
    /// Weights of corner 2.
    pub v: V,
}

impl<V: Vf32> ShearX4<V> {
    /// Splats `shear`'s constants.
    pub fn new(shear: &RayShear) -> Self {
        let k = shear.axes();
        let o = shear.origin().to_array();
        let s = shear.shear();
        Self { scalar: *shear, org: k.map(|a| V::splat(o[a])), s: s.map(V::splat), k }
    }

    /// Corner `c` of every lane relative to the origin, in `(kx, ky, kz)` order.
    #[inline(always)]
    fn corner(&self, b: &Tri4, c: usize) -> (V, V, V) {
        let [kx, ky, kz] = self.k;
        (
            V::from_slice(&b.v[c][kx]) - self.org[0],
            V::from_slice(&b.v[c][ky]) - self.org[1],
            V::from_slice(&b.v[c][kz]) - self.org[2],
        )
    }

    /// Tests the four triangles of `b`, reporting hits with `tmin < t <= tmax` as [`RayShear::intersect`].
    #[inline(always)]
    pub fn test(&self, b: &Tri4, tmin: f32, tmax: f32) -> BlockHits<V> {
        let corners = [self.corner(b, 0), self.corner(b, 1), self.corner(b, 2)];
        let lanes = sheared_test(corners, self.s, V::splat(tmin), V::splat(tmax));
        with_exact_zeros_redone(lanes, V::splat(tmax), |lane, tmax| {
            self.scalar.intersect(&b.triangle(lane), tmin, tmax)
        })
    }
}

/// The lanes of a block test, with those whose edge functions came out exactly zero decided by `scalar(lane,
/// tmax)` (the scalar test, which recomputes them in double precision), as the block tests of [`ShearX4`] and
/// [`ShearGroups`] do. The vectors go through arrays, so that the cold redo holds no vector code (which, out
/// of line, would be built without the SIMD entry point's instruction set).
#[inline(always)]
fn with_exact_zeros_redone<V: Vf32>(
    lanes: Sheared<V>,
    tmax: V,
    scalar: impl Fn(usize, f32) -> Option<TriHit>,
) -> BlockHits<V> {
    if lanes.exact_zero.none() {
        return BlockHits { mask: lanes.hit, t: lanes.t, u: lanes.u, v: lanes.v };
    }
    let n = V::LANES;
    let (mut limits, mut out) = ([0f32; 16], [[0f32; 16]; 3]);
    tmax.write_to(&mut limits[..n]);
    for (array, lane_values) in out.iter_mut().zip([lanes.t, lanes.u, lanes.v]) {
        lane_values.write_to(&mut array[..n]);
    }
    let bits = redo(lanes.hit.bits(), lanes.exact_zero.bits(), &limits[..n], &mut out, scalar);
    let [t, u, v] = out.map(|a| V::from_slice(&a[..n]));
    BlockHits { mask: V::Mask::from_bits(bits), t, u, v }
}

/// Rare: the lanes in `zero` have an exactly zero edge function. `scalar(lane, tmax[lane])` decides each;
/// `out` holds the lanes' distances and barycentrics and `hit` the lanes hit so far. Returns the lanes hit.
#[cold]
fn redo(
    mut hit: u32,
    zero: u32,
    tmax: &[f32],
    out: &mut [[f32; 16]; 3],
    scalar: impl Fn(usize, f32) -> Option<TriHit>,
) -> u32 {
    for lane in (0..tmax.len()).filter(|i| zero >> i & 1 == 1) {
        if let Some(TriHit { t, u, v }) = scalar(lane, tmax[lane]) {
            (out[0][lane], out[1][lane], out[2][lane]) = (t, u, v);
            hit |= 1 << lane;
        }
    }
    hit
}

/// A ray's leaf-test state in 48 bytes: its watertight-test constants as two rows of four floats, so that a
/// group of four lanes loads them with one broadcast each (the origin in the shear's `(kx, ky, kz)` order and
/// `tmin`, then `(S_x, S_y, S_z)` and the far limit: `tmax`, then the closest hit's distance), the axes, and
/// the closest hit's triangle, so that a closest-hit test decides [`Hit::beats`] from the record alone.
/// Computed once per ray of an MBVH ray stream, whose rays reach many leaves ([`ShearGroups`]).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct ShearRecord {
    rows: [[f32; 4]; 2],
    axes: [u32; 3],
    best: u32,
}

impl ShearRecord {
    /// The constants of `ray` (its direction must not be zero), with its own `tmax` as the far limit and no
    /// hit yet.
    pub fn new(ray: &Ray) -> Self {
        let shear = RayShear::new(ray);
        let (axes, o, s) = (shear.axes(), shear.origin().to_array(), shear.shear());
        Self {
            rows: [[o[axes[0]], o[axes[1]], o[axes[2]], ray.tmin], [s[0], s[1], s[2], ray.tmax]],
            axes: axes.map(|a| a as u32),
            best: u32::MAX,
        }
    }

    /// The far limit hits must not pass (`tmax`, or the closest hit so far).
    pub fn tmax(&self) -> f32 {
        self.rows[1][3]
    }

    /// True when a hit on triangle `tri` at `t` (found within the far limit) beats the closest so far, by
    /// [`Hit::beats`]'s rule: nearer, or as near on a lower triangle id. Any hit beats none (at most `tmax`
    /// away, with an id below `u32::MAX`, which no triangle has).
    #[inline(always)]
    pub fn beaten_by(&self, t: f32, tri: u32) -> bool {
        t < self.tmax() || (t == self.tmax() && tri < self.best)
    }

    /// Records a closest hit: its distance becomes the far limit.
    #[inline(always)]
    pub fn set_best(&mut self, t: f32, tri: u32) {
        self.rows[1][3] = t;
        self.best = tri;
    }
}

/// `V::LANES / 4` rays (one per group of four lanes) against four triangles at once: lane `4g + j` tests ray
/// `g` against lane `j` of a [`Tri4`] block, so eight lanes test two rays and sixteen four, where a packet
/// test ([`crate::packet`]) takes four rays against one triangle. Each group reads the block's coordinates
/// in its own ray's axis order ([`Vf32::from_quads`]), so rays whose shears permute the axes differently
/// share a test without per-lane selects. Every lane performs [`RayShear::intersect`]'s `f32` operations in
/// its order, and exactly zero edge functions are redone by that test, as [`ShearX4`] does for one ray.
pub struct ShearGroups<V: Vf32> {
    org: [V; 3],
    s: [V; 3],
    tmin: V,
    axes: [[u32; 3]; 4],
}

impl<V: Vf32> ShearGroups<V> {
    /// Ray `g`'s constants `records[g]` in group `g`; groups past `V::LANES / 4` are ignored.
    #[inline(always)]
    pub fn new(records: [&ShearRecord; 4]) -> Self {
        let [ox, oy, oz, tmin] = V::splat_rows(&records.map(|r| &r.rows[0]));
        let [sx, sy, sz, _] = V::splat_rows(&records.map(|r| &r.rows[1]));
        Self { org: [ox, oy, oz], s: [sx, sy, sz], tmin, axes: records.map(|r| r.axes) }
    }

    /// The groups' far limits, ray `g`'s [`ShearRecord::tmax`] in group `g`.
    #[inline(always)]
    pub fn limits(records: [&ShearRecord; 4]) -> V {
        V::splat_rows(&records.map(|r| &r.rows[1]))[3]
    }

    /// Corner `c` of every lane's triangle relative to its ray's origin, in that ray's `(kx, ky, kz)` order.
    #[inline(always)]
    fn corner(&self, b: &Tri4, c: usize) -> (V, V, V) {
        let a = &self.axes;
        let at = |g: usize, i: usize| &b.v[c][a[g][i] as usize];
        let pick = |i: usize| V::from_quads(&[at(0, i), at(1, i), at(2, i), at(3, i)]);
        (pick(0) - self.org[0], pick(1) - self.org[1], pick(2) - self.org[2])
    }

    /// Tests every group's ray against the four triangles of `b`, reporting hits with `tmin < t <= tmax`
    /// (`tmax` per lane) as [`RayShear::intersect`] does. `ray(g)` is group `g`'s ray, for the rare lanes
    /// the scalar test must decide.
    #[inline(always)]
    pub fn test(&self, b: &Tri4, tmax: V, ray: impl Fn(usize) -> Ray) -> BlockHits<V> {
        let corners = [self.corner(b, 0), self.corner(b, 1), self.corner(b, 2)];
        let lanes = sheared_test(corners, self.s, self.tmin, tmax);
        with_exact_zeros_redone(lanes, tmax, |lane, tmax| {
            let ray = ray(lane / 4);
            RayShear::new(&ray).intersect(&b.triangle(lane % 4), ray.tmin, tmax)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lanes of a block report bit for bit what the scalar test reports, exact-zero edges included.
    fn lanes<V: Vf32>() {
        let tris = [
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            [Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            [Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.0, 1.0, 0.5), Vec3::new(1.0, 0.0, 0.5)],
        ];
        let block = Tri4::pack(&tris);
        let rays = [
            Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0)),
            // Through the shared edge (exact zero edge functions).
            Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::new(0.0, 0.0, 1.0)),
            Ray::new(Vec3::new(-1.0, 0.3, 0.25), Vec3::new(1.2, 0.0, 0.1)),
            Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::X),
            Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0)),
        ];
        for ray in rays {
            let shear = RayShear::new(&ray);
            let got = ShearX4::<V>::new(&shear).test(&block, ray.tmin, ray.tmax);
            let bits = got.mask.bits();
            assert_eq!(bits & 8, 0, "the empty lane never hits");
            for (lane, tri) in tris.iter().enumerate() {
                let want = shear.intersect(tri, ray.tmin, ray.tmax).map(|h| (h.t, h.u, h.v));
                let have = (bits >> lane & 1 == 1).then(|| (got.t.lane(lane), got.u.lane(lane), got.v.lane(lane)));
                assert_eq!(have, want, "ray {ray:?} lane {lane}");
            }
        }
    }

    /// Every lane of a group test reports bit for bit what the scalar test reports for its ray and
    /// triangle: rays with different axis orders (and an exactly zero edge function) in one test.
    struct Groups;

    impl raylab_simd::Kernel for Groups {
        type Output = ();
        fn run<V: Vf32>(self) {
            let tris = [
                [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
                [Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
                [Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.0, 1.0, 0.5), Vec3::new(1.0, 0.0, 0.5)],
                [Vec3::new(0.3, -1.0, -1.0), Vec3::new(0.3, 2.0, -1.0), Vec3::new(0.3, -1.0, 2.0)],
            ];
            let block = Tri4::pack(&tris);
            let rays = [
                Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0)),
                // Through the shared edge (exact zero edge functions).
                Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::new(0.0, 0.0, 1.0)),
                Ray::new(Vec3::new(-1.0, 0.3, 0.25), Vec3::new(1.2, 0.0, 0.1)),
                Ray::segment(Vec3::new(0.2, 3.0, 0.2), Vec3::new(0.05, -1.0, -0.02), 0.5, 2.9),
                Ray::new(Vec3::new(2.0, 0.2, 0.1), Vec3::new(-1.0, 0.1, 0.0)),
            ];
            let records = rays.map(|r| ShearRecord::new(&r));
            // Every window of four rays, wrapping, so each ray takes every group position.
            let mut hits = 0;
            for first in 0..rays.len() {
                let pick = |g: usize| (first + g) % rays.len();
                let recs = [0, 1, 2, 3].map(|g| &records[pick(g)]);
                let groups = ShearGroups::<V>::new(recs);
                let got = groups.test(&block, ShearGroups::<V>::limits(recs), |g| rays[pick(g)]);
                let bits = got.mask.bits();
                for lane in 0..V::LANES {
                    let ray = rays[pick(lane / 4)];
                    let want =
                        RayShear::new(&ray).intersect(&tris[lane % 4], ray.tmin, ray.tmax).map(|h| (h.t, h.u, h.v));
                    let have = (bits >> lane & 1 == 1).then(|| (got.t.lane(lane), got.u.lane(lane), got.v.lane(lane)));
                    assert_eq!(have, want, "ray {ray:?} lane {lane} of {}", V::LANES);
                    hits += usize::from(have.is_some());
                }
            }
            assert!(hits >= rays.len(), "the rays hit the block ({hits} lane hits)");
        }
    }

    #[test]
    fn group_lanes_equal_the_scalar_test_on_every_backend() {
        for b in raylab_simd::Backend::available() {
            raylab_simd::dispatch(b, Groups);
        }
    }

    #[test]
    fn block_lanes_equal_the_scalar_test() {
        lanes::<raylab_simd::scalar::F32x4>();
        #[cfg(target_arch = "x86_64")]
        lanes::<raylab_simd::sse::F32x4>();
    }
}
