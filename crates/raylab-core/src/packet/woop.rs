//! The watertight ray/triangle test (Woop, Benthin, Wald 2013) for a packet of rays against one triangle.
//!
//! Every lane performs exactly the `f32` operations of [`crate::triangle::RayShear::intersect`], in the
//! same order: each lane's axis permutation is applied with selects instead of indexing, and lanes whose
//! edge functions hit exactly zero are redone by the scalar test (its double-precision fallback). So a
//! packet lane reports bit-for-bit what single-ray tracing reports for the same ray and triangle.

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{PacketHits, RayPacket};
use crate::triangle::{SCALED_FAR_SLACK, TriangleSoup};

/// Picks component `axis` of `(x, y, z)` per lane, given the lane masks "axis is 0" and "axis is 1".
#[inline(always)]
fn pick<V: Vf32>(is: [V::Mask; 2], x: V, y: V, z: V) -> V {
    V::select(is[0], x, V::select(is[1], y, z))
}

/// Corner `v` relative to origins `org` (already in `(kx, ky, kz)` order), components in that order.
#[inline(always)]
fn rel_uniform<V: Vf32>(org: &[V; 3], v: &Vec3, [kx, ky, kz]: [usize; 3]) -> (V, V, V) {
    // Indexing the corner where it lies loads each component straight from the triangle, with no copy first.
    let v: &[f32; 3] = v.as_ref();
    (V::splat(v[kx]) - org[0], V::splat(v[ky]) - org[1], V::splat(v[kz]) - org[2])
}

/// How a run of watertight tests gets a triangle's corners relative to the packet's origins, in each lane's
/// `(kx, ky, kz)` order: one implementation per way, so that a leaf's loop of tests is compiled for one of
/// them and carries neither the choice nor what the other way needs.
trait Corners<V: Vf32>: Copy {
    /// The corners of `tri`.
    fn of(self, tri: &[Vec3; 3]) -> [(V, V, V); 3];
}

/// Every lane shares the permutation `k`, and `org` holds the origins already in that order: corners by
/// indexing.
#[derive(Clone, Copy)]
struct Indexed<'a, V: Vf32> {
    k: [usize; 3],
    org: &'a [V; 3],
}

impl<V: Vf32> Corners<V> for Indexed<'_, V> {
    #[inline(always)]
    fn of(self, tri: &[Vec3; 3]) -> [(V, V, V); 3] {
        [
            rel_uniform(self.org, &tri[0], self.k),
            rel_uniform(self.org, &tri[1], self.k),
            rel_uniform(self.org, &tri[2], self.k),
        ]
    }
}

/// Lanes with their own permutations: corners by per-lane selects.
#[derive(Clone, Copy)]
struct PerLane<'a, V: Vf32>(&'a RayPacket<V>);

impl<V: Vf32> Corners<V> for PerLane<'_, V> {
    #[inline(always)]
    fn of(self, tri: &[Vec3; 3]) -> [(V, V, V); 3] {
        [rel_permuted(self.0, tri[0]), rel_permuted(self.0, tri[1]), rel_permuted(self.0, tri[2])]
    }
}

/// Corner `v` relative to the packet's origins, permuted per lane into that lane's `(kx, ky, kz)` order.
#[inline(always)]
fn rel_permuted<V: Vf32>(p: &RayPacket<V>, v: Vec3) -> (V, V, V) {
    let q = [V::splat(v.x) - p.org[0], V::splat(v.y) - p.org[1], V::splat(v.z) - p.org[2]];
    let [kx, ky, kz] = p.axis_is;
    (pick::<V>(kx, q[0], q[1], q[2]), pick::<V>(ky, q[0], q[1], q[2]), pick::<V>(kz, q[0], q[1], q[2]))
}

/// The watertight test's arithmetic in every lane: corners relative to the lanes' origins and permuted into
/// their `(kx, ky, kz)` order, sheared by `(S_x, S_y, S_z)`; lanes hit within `(tmin, tmax]`. Shared by the
/// packet test (four rays, one triangle) and [`crate::tri4`] (one ray, four triangles), each lane performing
/// [`crate::triangle::RayShear::intersect`]'s `f32` operations in its order.
#[inline(always)]
pub(crate) fn sheared_test<V: Vf32>(corners: [(V, V, V); 3], shear: [V; 3], tmin: V, tmax: V) -> Sheared<V> {
    edge_functions(corners, shear).distance(tmin, tmax).finish(tmin, tmax)
}

/// The first step of [`sheared_test`]: the three edge functions of the sheared triangle, which decide most
/// lanes. A packet test whose lanes all pass outside an edge here (most tests at a leaf, since a leaf's
/// triangles mostly miss a given packet) skips the distance and the division; the tests of [`crate::tri4`] (one ray, four triangles)
/// take them as they are, where stopping here saved nothing.
#[inline(always)]
fn edge_functions<V: Vf32>(corners: [(V, V, V); 3], [sx, sy, sz]: [V; 3]) -> EdgeFunctions<V> {
    let [(a_x, a_y, a_z), (b_x, b_y, b_z), (c_x, c_y, c_z)] = corners;
    let ax = a_x - sx * a_z;
    let ay = a_y - sy * a_z;
    let bx = b_x - sx * b_z;
    let by = b_y - sy * b_z;
    let cx = c_x - sx * c_z;
    let cy = c_y - sy * c_z;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = V::splat(0.0);
    let exact_zero = u.eq(zero) | v.eq(zero) | w.eq(zero);
    // Both signs among the three: the smallest is negative and the largest positive. A NaN function may make
    // this differ from comparing each one, but such a lane misses anyway (its determinant is NaN).
    let mixed = u.min(v).min(w).lt(zero) & u.max(v).max(w).gt(zero);
    EdgeFunctions { u, v, w, z: [sz * a_z, sz * b_z, sz * c_z], exact_zero, mixed }
}

/// The edge functions of [`edge_functions`] and what the distance needs of the corners.
struct EdgeFunctions<V: Vf32> {
    u: V,
    v: V,
    w: V,
    /// The corners' sheared `z` (`S_z` times their `kz` component).
    z: [V; 3],
    /// Lanes with an edge function of exactly zero.
    exact_zero: V::Mask,
    /// Lanes whose edge functions take both signs: the ray passes outside an edge (unless one is exactly
    /// zero, which the double-precision fallback decides).
    mixed: V::Mask,
}

impl<V: Vf32> EdgeFunctions<V> {
    /// Whether every `active` lane misses, as far as the edges tell: each has edge functions of both signs
    /// and none exactly zero (which the scalar test's double-precision fallback decides). Such a packet test
    /// skips the distance.
    #[inline(always)]
    fn all_miss(&self, active: V::Mask) -> bool {
        (active & !(self.mixed & !self.exact_zero)).none()
    }

    /// The second step of [`sheared_test`]: the scaled distance, which decides every lane but the few that
    /// the division's rounding moves out of `(tmin, tmax]`. A packet test whose lanes all miss here skips
    /// the division and what follows it.
    #[inline(always)]
    fn distance(self, tmin: V, tmax: V) -> Edges<V> {
        let Self { u, v, w, z: [az, bz, cz], exact_zero, mixed } = self;
        let zero = V::splat(0.0);
        let det = u + v + w;
        let t_scaled = u * az + v * bz + w * cz;
        let abs_det = det.abs();
        let t_signed = V::select(det.lt(zero), zero - t_scaled, t_scaled);
        let inside = t_signed.gt(tmin * abs_det) & t_signed.le(tmax * abs_det * V::splat(SCALED_FAR_SLACK));
        let maybe = !(exact_zero | mixed) & !det.eq(zero) & inside;
        Edges { maybe, exact_zero, det, t_scaled, v, w }
    }
}

/// What [`EdgeFunctions::distance`] leaves for the division.
struct Edges<V: Vf32> {
    /// Lanes that hit unless the division's rounding puts `t` outside `(tmin, tmax]`.
    maybe: V::Mask,
    exact_zero: V::Mask,
    det: V,
    t_scaled: V,
    v: V,
    w: V,
}

impl<V: Vf32> Edges<V> {
    /// The distances and barycentrics, and the lanes that hit.
    #[inline(always)]
    fn finish(self, tmin: V, tmax: V) -> Sheared<V> {
        let inv = V::splat(1.0) / self.det;
        let t = self.t_scaled * inv;
        let in_range = t.gt(tmin) & t.le(tmax);
        Sheared { hit: self.maybe & in_range, exact_zero: self.exact_zero, t, u: self.v * inv, v: self.w * inv }
    }
}

/// What [`sheared_test`] finds per lane.
pub(crate) struct Sheared<V: Vf32> {
    /// Lanes hit (never those in `exact_zero`).
    pub hit: V::Mask,
    /// Lanes with an edge function of exactly zero, which the scalar test's double-precision fallback must
    /// decide.
    pub exact_zero: V::Mask,
    /// Distances.
    pub t: V,
    /// Weights of corner 1.
    pub u: V,
    /// Weights of corner 2.
    pub v: V,
}

/// Result of testing one triangle: lanes hit and their distances and barycentrics.
struct LaneHits<V: Vf32> {
    mask: V::Mask,
    t: V,
    u: V,
    v: V,
}

impl<V: Vf32> LaneHits<V> {
    /// No lane hit (the distances are only read where a lane hits).
    #[inline(always)]
    fn none() -> Self {
        let zero = V::splat(0.0);
        LaneHits { mask: V::Mask::from_bits(0), t: zero, u: zero, v: zero }
    }
}

/// A packet set up for a run of triangle tests (the triangles of a leaf): what the watertight test reads of
/// the packet for every triangle, the origins in the lanes' shared `(kx, ky, kz)` order, is fetched once
/// instead of once per triangle, with the permutation's indices known to be in range.
#[derive(Clone, Copy)]
pub struct PacketTester<'a, V: Vf32> {
    p: &'a RayPacket<V>,
    /// The lanes' shared `(kx, ky, kz)` and the origins in that order, when every lane has the same ones.
    uniform: Option<([usize; 3], [V; 3])>,
}

impl<'a, V: Vf32> PacketTester<'a, V> {
    /// Prepares packet `p`.
    #[inline(always)]
    pub fn new(p: &'a RayPacket<V>) -> Self {
        let uniform = match p.uniform_axes {
            Some([kx, ky, kz]) => {
                // `min` tells the compiler what `from_lanes` guarantees, so the tests index without checks.
                let k = [kx.min(2), ky.min(2), kz.min(2)];
                Some((k, [p.org[k[0]], p.org[k[1]], p.org[k[2]]]))
            }
            None => None,
        };
        Self { p, uniform }
    }

    /// Corners of `tri` relative to the origins, permuted into (kx, ky, kz) order: by indexing when every lane
    /// shares the permutation, by per-lane selects otherwise. Both give each lane exactly `v[k] - o[k]`.
    #[inline(always)]
    fn corners(&self, tri: &[Vec3; 3]) -> [(V, V, V); 3] {
        match &self.uniform {
            Some((k, org)) => Indexed { k: *k, org }.of(tri),
            None => PerLane(self.p).of(tri),
        }
    }

    #[inline(always)]
    fn test(&self, tri: &[Vec3; 3], active: V::Mask, tmax: V) -> LaneHits<V> {
        self.test_corners(self.corners(tri), tri, active, tmax)
    }

    /// The watertight test of `tri`, whose corners relative to the origins are `corners`.
    #[inline(always)]
    fn test_corners(&self, corners: [(V, V, V); 3], tri: &[Vec3; 3], active: V::Mask, tmax: V) -> LaneHits<V> {
        let p = self.p;
        let fns = edge_functions(corners, p.shear);
        if fns.all_miss(active) {
            return LaneHits::none();
        }
        let edges = fns.distance(p.tmin, tmax);
        let exact_zero = edges.exact_zero & active;
        if ((edges.maybe | edges.exact_zero) & active).none() {
            // Every lane misses: no division.
            return LaneHits::none();
        }
        let lanes = edges.finish(p.tmin, tmax);
        let mut mask = lanes.hit & active;
        let (mut t, mut bu, mut bv) = (lanes.t, lanes.u, lanes.v);
        if exact_zero.any() {
            // Rare: an edge function is exactly zero, and the paper recomputes it in double precision. Let the
            // scalar test, which does exactly that, decide those lanes.
            let bits = exact_zero.bits();
            let (mut ta, mut ua, mut va) =
                ([0.0f32; super::MAX_LANES], [0.0f32; super::MAX_LANES], [0.0f32; super::MAX_LANES]);
            t.write_to(&mut ta[..V::LANES]);
            bu.write_to(&mut ua[..V::LANES]);
            bv.write_to(&mut va[..V::LANES]);
            let mut hit_bits = mask.bits();
            for i in (0..V::LANES).filter(|i| bits >> i & 1 == 1) {
                let ray = p.ray(i);
                if let Some(h) = crate::triangle::RayShear::new(&ray).intersect(tri, ray.tmin, tmax.lane(i)) {
                    (ta[i], ua[i], va[i]) = (h.t, h.u, h.v);
                    hit_bits |= 1 << i;
                }
            }
            mask = V::Mask::from_bits(hit_bits);
            t = V::from_slice(&ta[..V::LANES]);
            bu = V::from_slice(&ua[..V::LANES]);
            bv = V::from_slice(&va[..V::LANES]);
        }
        LaneHits { mask, t, u: bu, v: bv }
    }

    /// Tests triangle `id` (corners `tri`) against the `active` lanes and keeps closer hits in `hits`,
    /// accepting `tmin < t <= hits.t` per lane as the scalar test does. Returns the lanes that hit it.
    #[inline(always)]
    pub fn intersect(&self, hits: &mut PacketHits<V>, tri: &[Vec3; 3], id: u32, active: V::Mask) -> V::Mask {
        let r = self.test(tri, active, hits.t);
        keep_closer(hits, r, id)
    }

    /// [`PacketTester::intersect`] for each triangle `ids` of `tris`, in order; returns whether some lane's
    /// closest hit changed. The choice between indexed and per-lane permutations is made once for the run
    /// rather than per triangle, which keeps the loop free of it (a leaf's run of tests is the packet
    /// methods' innermost loop).
    #[inline(always)]
    pub fn intersect_each(&self, hits: &mut PacketHits<V>, tris: &TriangleSoup, ids: &[u32], active: V::Mask) -> bool {
        match &self.uniform {
            Some((k, org)) => self.intersect_run(Indexed { k: *k, org }, hits, tris, ids, active),
            None => self.intersect_run(PerLane(self.p), hits, tris, ids, active),
        }
    }

    /// [`PacketTester::intersect_each`] with corners from `corners`.
    #[inline(always)]
    fn intersect_run(
        &self,
        corners: impl Corners<V>,
        hits: &mut PacketHits<V>,
        tris: &TriangleSoup,
        ids: &[u32],
        active: V::Mask,
    ) -> bool {
        let mut changed = V::Mask::from_bits(0);
        for &id in ids {
            let tri = tris.get(id);
            let r = self.test_corners(corners.of(tri), tri, active, hits.t);
            changed = changed | keep_closer(hits, r, id);
        }
        changed.any()
    }

    /// The lanes of `open` that triangles `ids` of `tris` block within `(tmin, tmax]` ([`PacketTester::occlude`]
    /// for each, in order, each test for the lanes still open), and how many tests it took: it stops once
    /// every lane is blocked. The choice of permutation is made once for the run, as in
    /// [`PacketTester::intersect_each`].
    #[inline(always)]
    pub fn occlude_each(&self, tris: &TriangleSoup, ids: &[u32], open: V::Mask) -> (V::Mask, usize) {
        match &self.uniform {
            Some((k, org)) => self.occlude_run(Indexed { k: *k, org }, tris, ids, open),
            None => self.occlude_run(PerLane(self.p), tris, ids, open),
        }
    }

    /// [`PacketTester::occlude_each`] with corners from `corners`.
    #[inline(always)]
    fn occlude_run(
        &self,
        corners: impl Corners<V>,
        tris: &TriangleSoup,
        ids: &[u32],
        open: V::Mask,
    ) -> (V::Mask, usize) {
        let (mut open, mut blocked) = (open, V::Mask::from_bits(0));
        for (n, &id) in ids.iter().enumerate() {
            let tri = tris.get(id);
            blocked = blocked | self.test_corners(corners.of(tri), tri, open, self.p.tmax).mask;
            open = open & !blocked;
            if open.none() {
                return (blocked, n + 1);
            }
        }
        (blocked, ids.len())
    }

    /// The `active` lanes that meet triangle `tri` within `(tmin, tmax]`, and their distances (for edge-width
    /// walks, which want every crossing, not the closest).
    #[inline(always)]
    pub(crate) fn crossing(&self, tri: &[Vec3; 3], active: V::Mask) -> (V::Mask, V) {
        let r = self.test(tri, active, self.p.tmax);
        (r.mask, r.t)
    }

    /// The `active` lanes that triangle `tri` blocks within `(tmin, tmax]`.
    #[inline(always)]
    pub fn occlude(&self, tri: &[Vec3; 3], active: V::Mask) -> V::Mask {
        self.test(tri, active, self.p.tmax).mask
    }
}

/// Keeps the lanes of `r` (a test of triangle `id`) that are closer than `hits`' current ones, or as close
/// with a lower triangle id (`Hit::beats`'s rule; the test already kept only hits no farther than the
/// current ones). Returns the lanes that took it.
#[inline(always)]
fn keep_closer<V: Vf32>(hits: &mut PacketHits<V>, r: LaneHits<V>, id: u32) -> V::Mask {
    let mut mask = r.mask;
    if mask.any() {
        let ties = mask & r.t.eq(hits.t);
        if ties.any() {
            let mut bits = ties.bits();
            let mut keep = mask.bits();
            while bits != 0 {
                let lane = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                if hits.tri.lane(lane).to_bits() < id {
                    keep &= !(1 << lane);
                }
            }
            mask = V::Mask::from_bits(keep);
        }
        hits.t = V::select(mask, r.t, hits.t);
        hits.u = V::select(mask, r.u, hits.u);
        hits.v = V::select(mask, r.v, hits.v);
        hits.tri = V::select(mask, V::splat(f32::from_bits(id)), hits.tri);
        hits.hit = hits.hit | mask;
    }
    mask
}

/// Tests triangle `id` (corners `tri`) against the `active` lanes of `p` and keeps closer hits in `hits`
/// ([`PacketTester::intersect`], for a single test). Returns the lanes that hit it.
#[inline(always)]
pub fn intersect_packet<V: Vf32>(
    p: &RayPacket<V>,
    hits: &mut PacketHits<V>,
    tri: &[Vec3; 3],
    id: u32,
    active: V::Mask,
) -> V::Mask {
    PacketTester::new(p).intersect(hits, tri, id, active)
}

/// The `active` lanes of `p` that triangle `tri` blocks within `(tmin, tmax]` ([`PacketTester::occlude`], for a
/// single test).
#[inline(always)]
pub fn occlude_packet<V: Vf32>(p: &RayPacket<V>, tri: &[Vec3; 3], active: V::Mask) -> V::Mask {
    PacketTester::new(p).occlude(tri, active)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::Ray;
    use crate::triangle::RayShear;

    fn lanes<V: Vf32>() {
        let tri = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        // Mixed directions and origins, an edge hit (exact zero edge function) and an axis-parallel miss.
        let rays = [
            Some(Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0))),
            Some(Ray::new(Vec3::new(0.5, 0.0, -2.0), Vec3::new(0.0, 0.0, 1.0))),
            Some(Ray::new(Vec3::new(-1.0, 0.3, 0.5), Vec3::new(1.2, 0.0, -0.4))),
            Some(Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::X)),
        ];
        let p = RayPacket::<V>::new(&rays);
        let mut hits = PacketHits::new(&p);
        intersect_packet(&p, &mut hits, &tri, 7, p.valid);
        for (i, r) in rays.iter().enumerate() {
            let r = r.unwrap();
            let want = RayShear::new(&r).intersect(&tri, r.tmin, r.tmax);
            let got = hits.get(i);
            assert_eq!(got.map(|h| (h.t, h.u, h.v)), want.map(|h| (h.t, h.u, h.v)), "lane {i}");
            assert_eq!(got.map(|h| h.tri), want.map(|_| 7));
        }
        assert_eq!(occlude_packet(&p, &tri, p.valid).bits(), hits.hit.bits());
    }

    #[test]
    fn packet_lanes_equal_the_scalar_test() {
        lanes::<raylab_simd::scalar::F32x4>();
        #[cfg(target_arch = "x86_64")]
        lanes::<raylab_simd::sse::F32x4>();
    }

    /// A leaf's worth of triangles: a fan around the origin of the xy plane sharing edges and a vertex (exact
    /// zero edge functions for rays through them), a copy of one fan triangle under another id (ties), a
    /// triangle behind the others, and a degenerate one.
    fn leaf() -> TriangleSoup {
        let c = Vec3::new(0.0, 0.0, 5.0);
        let ring: Vec<Vec3> = (0..6)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / 6.0;
                c + Vec3::new(a.cos(), a.sin(), 0.1 * i as f32)
            })
            .collect();
        let mut tris: Vec<[Vec3; 3]> = (0..6).map(|i| [c, ring[i], ring[(i + 1) % 6]]).collect();
        tris.push(tris[2]);
        tris.push([Vec3::new(-3.0, -3.0, 9.0), Vec3::new(3.0, -3.0, 9.0), Vec3::new(0.0, 3.0, 9.0)]);
        tris.push([Vec3::new(0.1, 0.1, 4.0), Vec3::new(0.2, 0.2, 4.0), Vec3::new(0.3, 0.3, 4.0)]);
        TriangleSoup::from_corners(tris)
    }

    /// Runs of tests against every triangle of a leaf equal the single tests, lane by lane and bit for bit,
    /// on packets whose lanes share one permutation (indexed corners) and on packets whose lanes do not
    /// (per-lane selects), for closest hits and for any hit.
    fn runs<V: Vf32>() {
        let tris = leaf();
        let ids: Vec<u32> = (0..9).collect();
        let o = Vec3::ZERO;
        let shared = [
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(1.0, 0.0, 5.0),
            Vec3::new(0.3, 0.4, 5.0),
            Vec3::new(0.5, 0.866_025_4, 5.0),
            Vec3::new(-0.2, 0.1, 5.0),
            Vec3::new(2.5, 2.5, 5.0),
            Vec3::new(0.0, -0.5, 5.0),
            Vec3::new(-0.9, -0.1, 5.0),
        ];
        let mixed = [
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(6.0, 0.2, 5.0),
            Vec3::new(-0.1, 0.1, -5.0),
            Vec3::new(0.3, 7.0, 5.0),
            Vec3::new(0.2, 0.2, 4.5),
            Vec3::new(-8.0, 0.0, 5.0),
            Vec3::new(0.0, -0.4, 5.0),
            Vec3::new(0.1, 0.0, 0.0),
        ];
        // Inside the fan, away from its edges: every lane is blocked before the last triangle.
        let covered = [
            Vec3::new(0.3, 0.1, 5.0),
            Vec3::new(0.1, 0.3, 5.0),
            Vec3::new(-0.2, 0.2, 5.0),
            Vec3::new(-0.3, -0.1, 5.0),
            Vec3::new(0.1, -0.3, 5.0),
            Vec3::new(0.3, -0.1, 5.0),
            Vec3::new(-0.1, 0.25, 5.0),
            Vec3::new(0.2, -0.25, 5.0),
        ];
        for (targets, uniform) in [(shared, true), (mixed, false), (covered, true)] {
            for first in 0..targets.len() {
                let rays: Vec<Option<Ray>> =
                    (0..V::LANES).map(|i| Some(Ray::new(o, targets[(first + i) % targets.len()]))).collect();
                let p = RayPacket::<V>::new(&rays);
                assert_eq!(p.uniform_axes.is_some(), uniform, "lanes from {first}");
                let tester = PacketTester::new(&p);

                let (mut one, mut run) = (PacketHits::new(&p), PacketHits::new(&p));
                let mut changed = false;
                for &id in &ids {
                    changed |= tester.intersect(&mut one, tris.get(id), id, p.valid).any();
                }
                assert_eq!(tester.intersect_each(&mut run, &tris, &ids, p.valid), changed);
                for i in 0..V::LANES {
                    let (a, b) = (one.get(i), run.get(i));
                    assert_eq!(
                        a.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.tri)),
                        b.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.tri)),
                        "lane {i}"
                    );
                }

                let (mut open, mut blocked, mut tests) = (p.valid, V::Mask::from_bits(0), 0);
                for &id in &ids {
                    tests += 1;
                    blocked = blocked | tester.occlude(tris.get(id), open);
                    open = open & !blocked;
                    if open.none() {
                        break;
                    }
                }
                let (got, got_tests) = tester.occlude_each(&tris, &ids, p.valid);
                assert_eq!((got.bits(), got_tests), (blocked.bits(), tests), "lanes from {first}");
                assert!(one.hit.any() && blocked.any(), "lanes from {first}: the packet meets the leaf");
                if targets == covered {
                    assert!(tests < ids.len(), "lanes from {first}: the run stops once all lanes are blocked");
                }
            }
        }
    }

    #[test]
    fn runs_of_tests_equal_single_tests() {
        runs::<raylab_simd::scalar::F32x4>();
        #[cfg(target_arch = "x86_64")]
        runs::<raylab_simd::sse::F32x4>();
    }
}
