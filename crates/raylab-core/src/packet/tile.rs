//! A tile of rays cut into 2x2 packets (4x2 with eight lanes, 4x4 with sixteen), the unit that frustum kernels
//! trace and cull (thesis 4.1.3-4.1.5).

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{BatchCull, Disc, PacketHits, RayPacket};
use crate::aabb::{Aabb, coord};
use crate::ray::Ray;

/// Width and height in pixels of a packet of `lanes` rays: 2x2 for four lanes, 4x2 for eight, 4x4 for sixteen
/// (as square as the lanes allow, so a packet's rays stay coherent).
pub const fn packet_shape(lanes: usize) -> (usize, usize) {
    let w = if lanes >= 8 { 4 } else { 2 };
    (w, lanes / w)
}

/// The packets of a `width x height` tile, each [`Self::PACKET_W`] (`w`) pixels wide and [`Self::PACKET_H`]
/// (`h`) high; lane `i` holds pixel `(w bx + i % w, h by + i / w)`. Pixels outside the tile leave lanes empty.
///
/// Packets are stored quadrant by quadrant (top left, top right, bottom left, bottom right; the quadrants of
/// MFT, 4.1.5, split at [`Self::quadrant_split`]), row-major inside each, so a quadrant's packets are one run
/// of indices: its packets fill whole chunks of [`Vf32::LANES`] ([`crate::packet::BatchCull`]) when its
/// packet count is a multiple of the lanes, and each chunk of a tile is a compact block of pixels.
pub struct PacketTile<V: Vf32> {
    /// The packets.
    pub packets: Vec<RayPacket<V>>,
    /// Closest hits (or, for occlusion, the per-lane state) of each packet.
    pub hits: Vec<PacketHits<V>>,
    /// Per packet, the farthest current hit distance over its rays (infinite while one has none), widened
    /// by the kd-tree walks' hit slack once hits are found: a leaf that starts beyond it cannot improve any
    /// of the packet's hits. Padded with -inf to whole vectors, so
    /// [`BatchCull`] loads it a vector at a time.
    pub farthest_hit: Vec<f32>,
    /// The batched culling data, once [`PacketTile::share_origin`] has found the rays' common origin.
    pub batch: Option<BatchCull>,
    /// The last batch data, kept for its buffer while the tile holds none.
    spare_batch: Option<BatchCull>,
    /// Index of each packet's lane-0 pixel in the tile, and the tile width, to map lanes back to pixels.
    pub origin_pixel: Vec<(usize, usize)>,
    /// Packet columns and rows.
    pub cols: usize,
    /// Packet rows.
    pub rows: usize,
    /// Tile width in pixels.
    pub width: usize,
    /// Tile height in pixels.
    pub height: usize,
}

impl<V: Vf32> PacketTile<V> {
    /// Packet width in pixels ([`packet_shape`]).
    pub const PACKET_W: usize = packet_shape(V::LANES).0;
    /// Packet height in pixels ([`packet_shape`]).
    pub const PACKET_H: usize = packet_shape(V::LANES).1;

    /// Cuts `rays` (row-major, `width x height`) into packets.
    #[inline(always)]
    pub fn new(rays: &[Option<Ray>], width: usize, height: usize) -> Self {
        let mut tile = Self::empty();
        tile.refill(rays, width, height);
        tile
    }

    /// A tile without packets, to be filled by [`PacketTile::refill`].
    pub fn empty() -> Self {
        Self {
            packets: Vec::new(),
            hits: Vec::new(),
            farthest_hit: Vec::new(),
            batch: None,
            spare_batch: None,
            origin_pixel: Vec::new(),
            cols: 0,
            rows: 0,
            width: 0,
            height: 0,
        }
    }

    /// [`PacketTile::new`] in place, keeping the buffers: kernels that trace many small tiles one after the
    /// other (each point's light samples) would otherwise spend several times as long allocating them as
    /// packing the rays (docs/BENCHMARKS.md, shading readings).
    #[inline(always)]
    pub fn refill(&mut self, rays: &[Option<Ray>], width: usize, height: usize) {
        let (pw, ph) = (Self::PACKET_W, Self::PACKET_H);
        let (cols, rows) = (width.div_ceil(pw), height.div_ceil(ph));
        (self.cols, self.rows, self.width, self.height) = (cols, rows, width, height);
        if let Some(batch) = self.batch.take() {
            self.spare_batch = Some(batch);
        }
        let n = cols * rows;
        let (packets, origin_pixel, hits, farthest_hit) =
            (&mut self.packets, &mut self.origin_pixel, &mut self.hits, &mut self.farthest_hit);
        packets.clear();
        origin_pixel.clear();
        hits.clear();
        farthest_hit.clear();
        packets.reserve(n);
        origin_pixel.reserve(n);
        hits.reserve(n);
        let (sx, sy) = quadrant_split(cols, rows);
        for (xs, ys) in [(0..sx, 0..sy), (sx..cols, 0..sy), (0..sx, sy..rows), (sx..cols, sy..rows)] {
            let (x0, x1) = (pw * xs.start, width.min(pw * xs.end));
            for by in ys.clone() {
                // The next row of packets' rays start loading while this row is packed: a tile's rays (36 KiB
                // at 32x32) come from memory when a whole frame's rays were made before tracing, and packing
                // waited on them (7-8% of a primary MFT 32x32 trace in `perf`, 4-5% with the hint).
                let next = if by + 1 < ys.end { ph * (by + 1)..ph * (by + 2) } else { 0..0 };
                for y in next {
                    if let Some(row) = rays.get(y * width + x0..y * width + x1) {
                        raylab_simd::prefetch(row);
                    }
                }
                for bx in xs.clone() {
                    let p = RayPacket::gather(|i| {
                        let (x, y) = (pw * bx + i % pw, ph * by + i / pw);
                        if x < width && y < height { rays[y * width + x] } else { None }
                    });
                    hits.push(PacketHits::new(&p));
                    farthest_hit.push(V::select(p.valid, p.tmax, V::splat(f32::NEG_INFINITY)).reduce_max());
                    packets.push(p);
                    origin_pixel.push((pw * bx, ph * by));
                }
            }
        }
        farthest_hit.resize(n.div_ceil(V::LANES) * V::LANES, f32::NEG_INFINITY);
    }

    /// Prepares batched packet/leaf culling ([`BatchCull`]) for rays that all start at `origin` (the caller
    /// has checked that they do).
    #[inline(always)]
    pub fn share_origin(&mut self, origin: Vec3) {
        self.batch = Some(match self.spare_batch.take() {
            Some(mut batch) => {
                batch.rebuild(origin, &self.packets);
                batch
            }
            None => BatchCull::new(origin, &self.packets),
        });
    }

    /// Calls `f(pixel_index, lane)` for every lane of packet `j` that holds a ray.
    #[inline(always)]
    pub fn for_each_lane(&self, j: usize, mut f: impl FnMut(usize, usize)) {
        let (x0, y0) = self.origin_pixel[j];
        let bits = self.packets[j].valid.bits();
        let pw = Self::PACKET_W;
        for i in (0..V::LANES).filter(|i| bits >> i & 1 == 1) {
            f((y0 + i / pw) * self.width + x0 + i % pw, i);
        }
    }

    /// The first packet column and row of the right and bottom quadrants: the left and top ones take the
    /// larger half of an odd count.
    #[inline(always)]
    pub fn quadrant_split(&self) -> (usize, usize) {
        quadrant_split(self.cols, self.rows)
    }

    /// Each quadrant's packets (top left, top right, bottom left, bottom right), as the run of indices the
    /// storage order gives it; an empty quadrant (one packet column or row) has an empty run. Runs rather than
    /// lists of indices cost MFT nothing to build per tile.
    #[inline(always)]
    pub fn quadrant_packets(&self) -> [Range<usize>; 4] {
        let (sx, sy) = self.quadrant_split();
        let (cols, rows) = (self.cols, self.rows);
        let ends = [sx * sy, sy * cols, sy * cols + sx * (rows - sy), cols * rows];
        [0..ends[0], ends[0]..ends[1], ends[1]..ends[2], ends[2]..ends[3]]
    }
}

/// The first packet column and row of the right and bottom quadrants of a tile of `cols x rows` packets: the
/// left and top quadrants take the larger half.
#[inline(always)]
const fn quadrant_split(cols: usize, rows: usize) -> (usize, usize) {
    (cols.div_ceil(2), rows.div_ceil(2))
}

/// Per lane, the interval `[t0, t1]` in which the packet's ray is inside box `b`, clipped to `[tmin, tmax]`
/// (empty when `t0 > t1`). A lane with a zero direction component is constrained by that slab only through
/// its origin; the fast path skips that case when no lane has one.
#[inline(always)]
pub fn slab_interval<V: Vf32>(p: &RayPacket<V>, b: &Aabb, tmin: V, tmax: V) -> (V, V) {
    let (mut t0, mut t1) = (tmin, tmax);
    if p.finite_inv {
        for k in 0..3 {
            let ta = (V::splat(b.min[k]) - p.org[k]) * p.inv[k];
            let tb = (V::splat(b.max[k]) - p.org[k]) * p.inv[k];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    } else {
        let inf = V::splat(f32::INFINITY);
        for k in 0..3 {
            let (lo, hi) = (V::splat(b.min[k]), V::splat(b.max[k]));
            let parallel = p.inv[k].abs().eq(inf);
            let outside = p.org[k].lt(lo) | p.org[k].gt(hi);
            let ta = (lo - p.org[k]) * p.inv[k];
            let tb = (hi - p.org[k]) * p.inv[k];
            let enter = V::select(parallel, V::select(outside, inf, V::splat(f32::NEG_INFINITY)), ta.min(tb));
            let exit = V::select(parallel, V::select(outside, V::splat(f32::NEG_INFINITY), inf), ta.max(tb));
            t0 = t0.max(enter);
            t1 = t1.min(exit);
        }
    }
    (t0, t1)
}

/// The lanes of `p` whose ray overlaps box `b` within `(tmin, limit]` (the packet/leaf culling test of
/// thesis 4.1.4), allowing `slack`.
#[inline(always)]
pub fn overlaps_box<V: Vf32>(p: &RayPacket<V>, b: &Aabb, limit: V, slack: f32) -> V::Mask {
    let (t0, t1) = slab_interval(p, b, p.tmin, limit);
    p.valid & (t0 * V::splat(1.0 - slack)).le(t1 * V::splat(1.0 + slack))
}

/// A bundle of rays from one origin, seen by the frustum walks only through the range of distances at which
/// its rays cross an axis-aligned plane, which four factors per axis give by the side of the origin the plane
/// lies on (`sign_crossing`): pyramid [`Frustum`]s and [`super::Cone`]s implement it, each through its
/// interval form.
pub trait Bundle {
    /// The bundle's interval form: origin, distance range, origin slack and per-axis factors.
    fn interval(&self) -> &Frustum;

    /// The common origin.
    #[inline(always)]
    fn origin(&self) -> Vec3 {
        self.interval().origin
    }
    /// The range of distances the walk starts with.
    #[inline(always)]
    fn t_range(&self) -> (f32, f32) {
        (self.interval().t_min, self.interval().t_max)
    }
    /// Distance by which the bundle's segments may miss its origin (see [`Frustum::origin_slack`]).
    #[inline(always)]
    fn origin_slack(&self) -> f32 {
        self.interval().origin_slack
    }
    /// Axis `k`'s factors `[pos_near, pos_far, neg_near, neg_far]` (see [`Frustum`]).
    #[inline(always)]
    fn factors(&self, k: usize) -> [f32; 4] {
        let f = self.interval();
        [f.pos_near[k], f.pos_far[k], f.neg_near[k], f.neg_far[k]]
    }
    /// The range of distances at which the bundle crosses the plane `coordinate k = split`; infinite bounds
    /// mean "some ray never crosses in front of the origin".
    #[inline(always)]
    fn crossing(&self, k: usize, split: f32) -> (f32, f32) {
        sign_crossing(split - coord(&self.origin(), k), self.origin_slack(), self.factors(k))
    }
}

impl Bundle for Frustum {
    #[inline(always)]
    fn interval(&self) -> &Frustum {
        self
    }
}

/// Bounds, for every axis, of the parameters at which the rays of a bundle from one common origin cross an
/// axis-aligned plane: the interval form of a frustum (thesis 2.3.2 and Listing 4.2, with the omni-directional
/// changes of 4.1.2). Parameters are each ray's own `t`; an interval `[near, far]` holds every `t` at which
/// some ray of the bundle is inside a cell, so rays need not have unit directions.
///
/// For a plane at signed distance `dist = split - origin[k]`, a ray with direction `u` crosses it at
/// `dist / u_k` when that is positive, and never otherwise. With `dist > 0` only rays with `1/u_k > 0` cross,
/// at `dist * [min, max]` of those inverses, and any ray going the other way makes the far bound infinite;
/// `dist < 0` mirrors this with the negative inverses. So four precomputed factors per axis give both bounds
/// with one multiply each, for any mix of direction signs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// The common origin.
    pub origin: Vec3,
    /// `dist > 0`: near factor (smallest positive inverse, or +inf when no ray goes that way).
    pub pos_near: [f32; 3],
    /// `dist > 0`: far factor (largest positive inverse; +inf when some ray goes the other way).
    pub pos_far: [f32; 3],
    /// `dist < 0`: near factor (negative inverse closest to zero, or -inf when none).
    pub neg_near: [f32; 3],
    /// `dist < 0`: far factor (most negative inverse; -inf when some ray goes the other way).
    pub neg_far: [f32; 3],
    /// Smallest start distance of the rays.
    pub t_min: f32,
    /// Largest end distance of the rays.
    pub t_max: f32,
    /// Distance by which the bundle's segments may miss `origin` (0 for rays that start there). Shadow rays
    /// traced from the light end at `p + d * t_max`, which rounding puts a little off the light; planes
    /// closer than this to the origin are crossed in both directions, and crossing bounds widen by it.
    pub origin_slack: f32,
}

impl Frustum {
    /// The frustum of segments `(direction, start, end)` from `origin`; `None` for an empty bundle.
    pub fn bounding(origin: Vec3, segments: impl IntoIterator<Item = (Vec3, f32, f32)>) -> Option<Self> {
        let mut f = Frustum {
            origin,
            pos_near: [f32::INFINITY; 3],
            pos_far: [f32::NEG_INFINITY; 3],
            neg_near: [f32::NEG_INFINITY; 3],
            neg_far: [f32::INFINITY; 3],
            t_min: f32::INFINITY,
            t_max: f32::NEG_INFINITY,
            origin_slack: 0.0,
        };
        let (mut any_pos, mut any_neg) = ([false; 3], [false; 3]);
        let mut any = false;
        for (dir, t0, t1) in segments {
            any = true;
            f.t_min = f.t_min.min(t0);
            f.t_max = f.t_max.max(t1);
            for k in 0..3 {
                let inv = 1.0 / dir[k];
                if inv > 0.0 {
                    any_pos[k] = true;
                    f.pos_near[k] = f.pos_near[k].min(inv);
                    f.pos_far[k] = f.pos_far[k].max(inv);
                } else {
                    any_neg[k] = true;
                    f.neg_near[k] = f.neg_near[k].max(inv);
                    f.neg_far[k] = f.neg_far[k].min(inv);
                }
            }
        }
        if !any {
            return None;
        }
        f.close_sides(any_pos, any_neg);
        Some(f)
    }

    /// Finishes a frustum whose factors hold the extreme inverses of its rays, `any_pos[k]` and `any_neg[k]`
    /// telling whether some ray goes each way on axis `k`: a far factor becomes infinite where some ray goes
    /// the other way (or none goes this way), and `t_min` starts at zero at the earliest.
    pub(crate) fn close_sides(&mut self, any_pos: [bool; 3], any_neg: [bool; 3]) {
        for k in 0..3 {
            if any_neg[k] || !any_pos[k] {
                self.pos_far[k] = f32::INFINITY;
            }
            if any_pos[k] || !any_neg[k] {
                self.neg_far[k] = f32::NEG_INFINITY;
            }
        }
        self.t_min = self.t_min.max(0.0);
    }

    /// The square pyramid from `apex` around `disc` (the face of a spherical light turned toward a shaded
    /// point), whose sides run along the axes of the samples' strata ([`Vec3::any_orthonormal_pair`] of the
    /// normal): the pyramid counterpart of [`super::Cone::around_disc`], walked through its four corner
    /// (extremal) rays as Listing 4.2 does. Distances are depths along the disc's normal (at most the distance
    /// along a unit direction, so the walk stays conservative). `None` where the cone proxy is `None`.
    pub fn around_disc(apex: Vec3, disc: &Disc) -> Option<Self> {
        let span = disc.span_from(apex)?;
        let (u, v) = disc.normal.any_orthonormal_pair();
        // The corners' range on each axis: the centre direction plus or minus the reach along both sides.
        let half = |k: usize| span.reach * (u[k].abs() as f64 + v[k].abs() as f64) + 1e-6;
        let lo = Vec3::from_array(std::array::from_fn(|k| (span.center_dir[k] - half(k)) as f32));
        let hi = Vec3::from_array(std::array::from_fn(|k| (span.center_dir[k] + half(k)) as f32));
        Self::bounding(apex, [(lo, 0.0, span.depth), (hi, 0.0, span.depth)])
    }

    /// The frustum of the valid rays of `packets`, which must all start at `origin`, from the packets'
    /// inverse directions (no division per ray).
    #[inline(always)]
    pub fn from_packets<V: Vf32>(origin: Vec3, packets: &[RayPacket<V>]) -> Option<Self> {
        let (inf, ninf, zero) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY), V::splat(0.0));
        let mut sides = SignBounds::<V>::new();
        let (mut t_min, mut t_max) = (inf, ninf);
        let mut any = false;
        for p in packets {
            if p.valid.none() {
                continue;
            }
            any = true;
            t_min = V::select(p.valid, p.tmin.min(t_min), t_min);
            t_max = V::select(p.valid, p.tmax.max(t_max), t_max);
            for k in 0..3 {
                let pos = p.valid & p.inv[k].gt(zero);
                sides.add(k, pos, p.valid & !pos, p.inv[k], p.inv[k]);
            }
        }
        if !any {
            return None;
        }
        Some(sides.frustum(origin, t_min.reduce_min(), t_max.reduce_max()))
    }
}

/// Per-lane running bounds of a bundle's inverse directions on each axis, by sign, and the frustum they
/// give: what [`Frustum::from_packets`], the batched frustums of [`super::BatchCull`] and the frustums of
/// shadow segments seen from a light accumulate, each from its own lanes (rays or packets' ranges).
pub(crate) struct SignBounds<V: Vf32> {
    pos_near: [V; 3],
    pos_far: [V; 3],
    neg_near: [V; 3],
    neg_far: [V; 3],
    any_pos: [bool; 3],
    any_neg: [bool; 3],
}

impl<V: Vf32> SignBounds<V> {
    /// No lanes yet.
    #[inline(always)]
    pub fn new() -> Self {
        let (inf, ninf) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        Self {
            pos_near: [inf; 3],
            pos_far: [ninf; 3],
            neg_near: [ninf; 3],
            neg_far: [inf; 3],
            any_pos: [false; 3],
            any_neg: [false; 3],
        }
    }

    /// Adds, on axis `k`, lanes `pos` whose inverse directions are positive and lanes `neg` whose are not,
    /// each lane's inverses lying in `[lo, hi]` (`lo == hi` for a single ray).
    #[inline(always)]
    pub fn add(&mut self, k: usize, pos: V::Mask, neg: V::Mask, lo: V, hi: V) {
        let (inf, ninf) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        self.any_pos[k] |= pos.any();
        self.any_neg[k] |= neg.any();
        self.pos_near[k] = self.pos_near[k].min(V::select(pos, lo, inf));
        self.pos_far[k] = self.pos_far[k].max(V::select(pos, hi, ninf));
        self.neg_near[k] = self.neg_near[k].max(V::select(neg, hi, ninf));
        self.neg_far[k] = self.neg_far[k].min(V::select(neg, lo, inf));
    }

    /// Whether any lane was added.
    #[inline(always)]
    pub fn any(&self) -> bool {
        (0..3).any(|k| self.any_pos[k] || self.any_neg[k])
    }

    /// The frustum from `origin` with these bounds and distances `[t_min, t_max]`, `t_min` raised to 0 when
    /// negative (the walks start no nearer than the origin).
    #[inline(always)]
    pub fn frustum(&self, origin: Vec3, t_min: f32, t_max: f32) -> Frustum {
        let (pn, pf, nn, nf) = (&self.pos_near, &self.pos_far, &self.neg_near, &self.neg_far);
        let mut f = Frustum {
            origin,
            // Written out: `map3` with `V::reduce_min` as a function item may call a shim that is neither inlined
            // nor compiled for the kernel's instruction set (seen in callgrind as `Fn::call` around `vcmpps`).
            pos_near: [pn[0].reduce_min(), pn[1].reduce_min(), pn[2].reduce_min()],
            pos_far: [pf[0].reduce_max(), pf[1].reduce_max(), pf[2].reduce_max()],
            neg_near: [nn[0].reduce_max(), nn[1].reduce_max(), nn[2].reduce_max()],
            neg_far: [nf[0].reduce_min(), nf[1].reduce_min(), nf[2].reduce_min()],
            t_min,
            t_max,
            origin_slack: 0.0,
        };
        f.close_sides(self.any_pos, self.any_neg);
        f
    }
}

/// The range of distances at which a bundle crosses a plane at signed distance `dist` from its origin, from
/// its axis's four factors `[pos_near, pos_far, neg_near, neg_far]` (see [`Frustum`]); a plane within `slack`
/// of the origin may be crossed at any distance, and the bounds widen by it.
#[inline(always)]
fn sign_crossing(dist: f32, slack: f32, [pos_near, pos_far, neg_near, neg_far]: [f32; 4]) -> (f32, f32) {
    if dist > slack {
        ((dist - slack) * pos_near, (dist + slack) * pos_far)
    } else if dist < -slack {
        ((dist + slack) * neg_near, (dist - slack) * neg_far)
    } else {
        (0.0, f32::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays of a `width x height` tile, some missing, so packets have empty lanes.
    fn tile_rays(width: usize, height: usize, seed: f32) -> Vec<Option<Ray>> {
        (0..width * height)
            .map(|i| {
                let f = i as f32 + seed;
                let dir = Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), 1.0).normalize();
                (i % 7 != 3).then(|| Ray::segment(Vec3::new(seed, 1.0, -2.0), dir, 0.0, 10.0 + f))
            })
            .collect()
    }

    /// A tile refilled after holding a larger and a smaller one equals the tile cut anew from the same rays
    /// (a [`raylab_simd::Kernel`], so every backend's lane type is checked).
    struct RefillEqualsNew;

    impl raylab_simd::Kernel for RefillEqualsNew {
        type Output = ();
        fn run<V: Vf32>(self) {
            let mut kept = PacketTile::<V>::empty();
            for (w, h, seed) in [(16, 16, 0.5), (4, 4, 1.5), (5, 3, 2.5), (0, 0, 3.5), (9, 6, 4.5)] {
                let rays = tile_rays(w, h, seed);
                kept.refill(&rays, w, h);
                kept.share_origin(Vec3::new(seed, 1.0, -2.0));
                kept.refill(&rays, w, h);
                let new = PacketTile::<V>::new(&rays, w, h);
                let dims = |t: &PacketTile<V>| (t.cols, t.rows, t.width, t.height);
                assert_eq!(dims(&kept), dims(&new), "{w}x{h}");
                assert!(kept.batch.is_none(), "{w}x{h}: a refill drops the old batch data");
                assert_eq!(kept.origin_pixel, new.origin_pixel, "{w}x{h}");
                assert_eq!(kept.farthest_hit, new.farthest_hit, "{w}x{h}");
                assert_eq!((kept.packets.len(), kept.hits.len()), (new.packets.len(), new.hits.len()));
                for (j, (a, b)) in kept.packets.iter().zip(&new.packets).enumerate() {
                    assert_eq!(a.valid.bits(), b.valid.bits(), "{w}x{h} packet {j}");
                    for i in (0..V::LANES).filter(|i| a.valid.bits() >> i & 1 == 1) {
                        assert_eq!(a.ray(i), b.ray(i), "{w}x{h} packet {j} lane {i}");
                        assert_eq!(kept.hits[j].t.lane(i), new.hits[j].t.lane(i), "{w}x{h} packet {j} lane {i}");
                    }
                }
            }
        }
    }

    /// Each quadrant's packets are one run of indices, row by row inside it, the runs in quadrant order
    /// covering the tile, whole chunks in even tiles.
    struct QuadrantOrder;

    impl raylab_simd::Kernel for QuadrantOrder {
        type Output = ();
        fn run<V: Vf32>(self) {
            let (pw, ph) = (PacketTile::<V>::PACKET_W, PacketTile::<V>::PACKET_H);
            for (w, h) in [(16, 16), (32, 32), (8, 8), (5, 3), (9, 6), (40, 24), (1, 1), (20, 7)] {
                let t = PacketTile::<V>::new(&tile_rays(w, h, 0.5), w, h);
                assert_eq!(t.packets.len(), t.cols * t.rows, "{w}x{h}");
                let (sx, sy) = t.quadrant_split();
                let (cx, cy) = (sx * pw, sy * ph);
                let mut next = 0;
                let rects = [(0, 0, cx, cy), (cx, 0, w, cy), (0, cy, cx, h), (cx, cy, w, h)];
                for (run, (x0, y0, x1, y1)) in t.quadrant_packets().into_iter().zip(rects) {
                    assert_eq!(run.start, next, "{w}x{h}: quadrant at ({x0}, {y0}) follows the one before");
                    let inside = (y0..y1).step_by(ph).flat_map(|y| (x0..x1).step_by(pw).map(move |x| (x, y)));
                    let want: Vec<_> = inside.collect();
                    let got: Vec<_> = run.clone().map(|j| t.origin_pixel[j]).collect();
                    assert_eq!(got, want, "{w}x{h}: the packets of the quadrant at ({x0}, {y0}), row by row");
                    next = run.end;
                    if t.cols.is_multiple_of(2) && t.rows.is_multiple_of(2) && (sx * sy).is_multiple_of(V::LANES) {
                        assert_eq!(run.start % V::LANES, 0, "{w}x{h}: quadrants of whole chunks");
                    }
                }
                assert_eq!(next, t.packets.len(), "{w}x{h}: the quadrants cover the tile");
            }
        }
    }

    #[test]
    fn packets_are_stored_quadrant_by_quadrant_on_every_backend() {
        for backend in raylab_simd::Backend::available() {
            raylab_simd::dispatch(backend, QuadrantOrder);
        }
    }

    #[test]
    fn refilled_tiles_equal_new_ones_on_every_backend() {
        for backend in raylab_simd::Backend::available() {
            raylab_simd::dispatch(backend, RefillEqualsNew);
        }
    }

    #[test]
    fn crossing_bounds_every_ray() {
        let o = Vec3::new(0.5, -1.0, 2.0);
        let dirs =
            [Vec3::new(1.0, 0.2, -0.1), Vec3::new(0.8, -0.3, 0.4), Vec3::new(0.9, 0.0, 0.0), Vec3::new(1.0, 0.5, -0.5)]
                .map(|d| d.normalize());
        let f = Frustum::bounding(o, dirs.iter().map(|&d| (d, 0.0, 10.0))).unwrap();
        for k in 0..3 {
            for split in [-3.0f32, -0.7, 0.1, 0.5, 2.0, 4.0] {
                let (lo, hi) = f.crossing(k, split);
                assert!(lo <= hi, "axis {k} split {split}");
                for d in dirs {
                    let t = (split - o[k]) / d[k];
                    if t > 0.0 && t.is_finite() {
                        assert!(
                            t >= lo * (1.0 - 1e-6) && t <= hi * (1.0 + 1e-6),
                            "axis {k} split {split}: {t} not in [{lo}, {hi}]"
                        );
                    }
                }
            }
        }
        // Mixed signs on y: the far bound becomes infinite on both sides of the origin.
        assert_eq!(f.crossing(1, 0.0).1, f32::INFINITY);
        assert_eq!(f.crossing(1, 5.0).1, f32::INFINITY);
    }
}
