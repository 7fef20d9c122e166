//! Bundles of a tile's packets for the frustum methods: one frustum or cone around a whole tile, or four
//! around its quadrants (MFT), built from packets whose rays share an origin (camera rays) or from
//! segments that end at a light (shadow rays, traced from the light as in the thesis, 4.1.5-4.1.9).

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::Tracer;
use crate::packet::{Cone, Frustum, PacketTile, RayPacket, SignBounds, dot3, map3};
use crate::ray::Ray;

/// Relative size of the gap between a shadow segment's end and the light beyond which the segments are not
/// taken to end at the light.
const TOWARD_TOLERANCE: f32 = 1e-3;

impl Tracer<'_> {
    /// The one bundle of a whole tile, packets `all`: `from_origin` builds it when the tile's rays share the
    /// origin `shared` ([`common_origin`], found once per tile by the caller), `toward_fn` from segments that
    /// end at a light (function items rather than `Option::or_else` closures, whose vector code the compiler
    /// may keep out of line).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn whole<V: Vf32, B>(
        &self,
        tile: &PacketTile<V>,
        all: Range<usize>,
        rays: &[Option<Ray>],
        toward: Option<Vec3>,
        shared: Option<Vec3>,
        from_origin: fn(Vec3, &PacketTile<V>, Range<usize>) -> Option<B>,
        toward_fn: fn(&Bundled<V>, Vec3, f32) -> Option<B>,
    ) -> Option<B> {
        if let Some(o) = shared
            && let Some(b) = from_origin(o, tile, all.clone())
        {
            return Some(b);
        }
        let (w, h) = (tile.width, tile.height);
        let whole = Bundled { tile, set: all, rays: RayRect { rays, width: w, x: 0..w, y: 0..h } };
        toward_fn(&whole, toward?, self.options.shadow_spread_limit)
    }

    /// The four quadrant bundles of a tile (in whole packets) and the packets each bounds; `from_origin` builds
    /// a bundle from packets with one origin (`shared`, when the whole tile's rays have one, saves looking for
    /// it per quadrant), `toward` one from segments that end at a light.
    #[inline(always)]
    pub(super) fn quadrants<V: Vf32, B: Copy>(
        &self,
        tile: &PacketTile<V>,
        rays: &[Option<Ray>],
        toward: Option<Vec3>,
        shared: Option<Vec3>,
        from_origin: fn(Vec3, &PacketTile<V>, Range<usize>) -> Option<B>,
        toward_fn: fn(&Bundled<V>, Vec3, f32) -> Option<B>,
    ) -> Option<Quadrants<B>> {
        let (pw, ph) = (PacketTile::<V>::PACKET_W, PacketTile::<V>::PACKET_H);
        let (cx, cy) = tile.quadrant_split();
        let (cx, cy) = (cx * pw, cy * ph);
        let (w, h) = (tile.width, tile.height);
        let rects = [(0, 0, cx.min(w), cy.min(h)), (cx, 0, w, cy.min(h)), (0, cy, cx.min(w), h), (cx, cy, w, h)];
        let runs = tile.quadrant_packets();
        let mut sets: [Range<usize>; 4] = Default::default();
        let mut rest: [Range<usize>; 4] = Default::default();
        let mut bundles = [None; 4];
        let mut origin = None;
        for (i, &(x0, y0, x1, y1)) in rects.iter().enumerate() {
            let set = runs[i].clone();
            if tile.packets[set.clone()].iter().all(|p| p.valid.none()) {
                continue;
            }
            let found = if shared.is_some() { shared } else { common_origin(&tile.packets[set.clone()]) };
            let (b, o) = match found {
                Some(o) => (from_origin(o, tile, set.clone())?, o),
                None => {
                    let t = toward?;
                    let rays = RayRect { rays, width: w, x: x0..x1, y: y0..y1 };
                    match toward_fn(&Bundled { tile, set: set.clone(), rays }, t, self.options.shadow_spread_limit) {
                        Some(b) => (b, t),
                        None => {
                            // Too wide (or not ending at the light): its packets go the packet way.
                            rest[i] = set;
                            continue;
                        }
                    }
                }
            };
            // All four must share one origin.
            if *origin.get_or_insert(o) != o {
                return None;
            }
            bundles[i] = Some(b);
            sets[i] = set;
        }
        Some((bundles, sets, rest))
    }
}

/// The origin shared by every valid ray of `packets`, if there is one.
#[inline(always)]
pub(super) fn common_origin<V: Vf32>(packets: &[RayPacket<V>]) -> Option<Vec3> {
    // A plain loop rather than `find_map`, so the vector code stays inlined (see `map3`).
    let mut found = None;
    for p in packets {
        let first = p.valid.bits().trailing_zeros() as usize;
        if first < V::LANES {
            found = Some(p.ray(first).origin);
            break;
        }
    }
    let origin = found?;
    let o = [V::splat(origin.x), V::splat(origin.y), V::splat(origin.z)];
    let mut elsewhere = 0;
    for p in packets {
        let at_origin = p.org[0].eq(o[0]) & p.org[1].eq(o[1]) & p.org[2].eq(o[2]);
        elsewhere |= (p.valid & !at_origin).bits();
    }
    (elsewhere == 0).then_some(origin)
}

/// The cone of packets `set`, whose rays all start at `origin` ([`common_origin`]); `None` when none is valid.
#[inline(always)]
pub(super) fn cone_from<V: Vf32>(origin: Vec3, tile: &PacketTile<V>, set: Range<usize>) -> Option<Cone> {
    Cone::from_packets(origin, &tile.packets[set])
}

/// The cone, seen from `toward`, of the rays of `b` when they are segments that end there (shadow rays to a
/// light), like [`toward_frustum`].
pub(super) fn toward_cone<V: Vf32>(b: &Bundled<V>, toward: Vec3, spread_limit: f32) -> Option<Cone> {
    let (segs, slack) = toward_segments(b.rays.clone(), toward, spread_limit)?;
    let mut c = Cone::bounding(toward, segs.iter().copied())?;
    widen_toward(&mut c.bound.t_max, &mut c.bound.origin_slack, toward, slack);
    Some(c)
}

/// The frustum of the packets `set` of `tile`, whose rays all start at `origin` ([`common_origin`]); `None`
/// when none is valid.
#[inline(always)]
pub(super) fn frustum_from<V: Vf32>(origin: Vec3, tile: &PacketTile<V>, set: Range<usize>) -> Option<Frustum> {
    // From the batched culling data when the tile has it (the same frustum, a chunk of packets at a time).
    if let Some(batch) = &tile.batch
        && let Some(f) = batch.frustum::<V>(origin, set.clone(), &tile.farthest_hit)
    {
        return Some(f);
    }
    Frustum::from_packets(origin, &tile.packets[set])
}

/// A tile's four quadrant bundles, the run of packets each bounds, and the runs left to trace as packets
/// (quadrants too wide for a bundle). A quadrant without a bundle has an empty run; one without valid rays
/// is in neither.
type Quadrants<B> = ([Option<B>; 4], [Range<usize>; 4], [Range<usize>; 4]);

/// The rays a bundle is to bound: the run of packets `set` of `tile`, which hold the valid rays of `rays`.
pub(super) struct Bundled<'a, V: Vf32> {
    pub(super) tile: &'a PacketTile<V>,
    pub(super) set: Range<usize>,
    pub(super) rays: RayRect<'a>,
}

/// The rays of the pixel rectangle `x` by `y` of a row-major tile `width` pixels wide.
#[derive(Clone)]
pub(super) struct RayRect<'a> {
    pub(super) rays: &'a [Option<Ray>],
    pub(super) width: usize,
    pub(super) x: Range<usize>,
    pub(super) y: Range<usize>,
}

impl<'a> RayRect<'a> {
    /// The valid rays of the rectangle, row by row.
    fn iter(&self) -> impl Iterator<Item = &'a Ray> + use<'a> {
        let (rays, width, x) = (self.rays, self.width, self.x.clone());
        self.y
            .clone()
            .flat_map(move |y| rays[y * width + x.start..y * width + x.end].iter())
            .flatten()
            .filter(|r| r.is_valid())
    }
}

/// A segment seen from a light: unit direction, start and end distance.
type Segment = (Vec3, f32, f32);

/// The segments of `rays` seen from `toward`, and how far their ends miss it; `None` when some segment does
/// not end near it, or when the bundle spreads wider than `spread_limit` (see
/// [`TraceOptions::shadow_spread_limit`](super::TraceOptions::shadow_spread_limit)).
fn toward_segments(rays: RayRect, toward: Vec3, spread_limit: f32) -> Option<(Vec<Segment>, f32)> {
    let mut slack = 0.0f32;
    let mut segs = Vec::with_capacity(rays.x.len() * rays.y.len());
    for r in rays.iter() {
        if !r.tmax.is_finite() {
            return None;
        }
        let start = r.at(r.tmin.max(0.0));
        let end = r.at(r.tmax);
        let v = start - toward;
        let len = v.length();
        let gap = (end - toward).length();
        if gap > TOWARD_TOLERANCE * len.max(f32::MIN_POSITIVE) || len == 0.0 {
            return None;
        }
        slack = slack.max(gap);
        segs.push((v / len, 0.0, len));
    }
    let mean = segs.iter().fold(Vec3::ZERO, |m, s| m + s.0).normalize_or_zero();
    let spread = segs.iter().fold(0.0f32, |m, s| {
        let c = s.0.dot(mean);
        m.max(if c > 0.0 { s.0.cross(mean).length() / c } else { f32::INFINITY })
    });
    (spread <= spread_limit).then_some((segs, slack))
}

/// The frustum, seen from `toward`, of the rays of `b` (its packets) when they are segments that end
/// there (shadow rays to a light: the thesis traces shadow rays from the light toward the surface points);
/// `None` when some segment does not end near it or the bundle spreads wider than `spread_limit`. A vector
/// of segments at a time, per lane with the operations of [`toward_segments`] and [`Frustum::bounding`] in
/// their order, so the frustum and its slack are theirs to the bit; only the mean direction of the spread
/// test is summed in another order, which can move a bundle right at the spread limit to the packet side.
#[inline(always)]
pub(super) fn toward_frustum<V: Vf32>(b: &Bundled<V>, toward: Vec3, spread_limit: f32) -> Option<Frustum> {
    let (tile, set) = (b.tile, b.set.clone());
    let (zero, inf, ninf) = (V::splat(0.0), V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
    let tw = [V::splat(toward.x), V::splat(toward.y), V::splat(toward.z)];
    let (mut gap_max, mut t_max) = (zero, ninf);
    let mut sides = SignBounds::<V>::new();
    let mut sum = [zero; 3];
    for p in tile.packets[set.clone()].iter().filter(|p| p.valid.any()) {
        let valid = p.valid;
        let (d, len, gap) = toward_segment(p, &tw);
        let far_end = !p.tmax.abs().lt(inf);
        let misses = gap.gt(V::splat(TOWARD_TOLERANCE) * len.max(V::splat(f32::MIN_POSITIVE))) | len.eq(zero);
        if ((far_end | misses) & valid).any() {
            return None;
        }
        gap_max = gap_max.max(V::select(valid, gap, zero));
        t_max = t_max.max(V::select(valid, len, ninf));
        for k in 0..3 {
            let inv = V::splat(1.0) / d[k];
            let pos = inv.gt(zero) & valid;
            sides.add(k, pos, valid & !pos, inv, inv);
            sum[k] = sum[k] + V::select(valid, d[k], zero);
        }
    }
    if !sides.any() {
        return None;
    }
    let mut mean = [0.0f32; 3];
    for k in 0..3 {
        for i in 0..V::LANES {
            mean[k] += sum[k].lane(i);
        }
    }
    let mean = Vec3::from_array(mean).normalize_or_zero();
    let m = [V::splat(mean.x), V::splat(mean.y), V::splat(mean.z)];
    let mut spread = zero;
    for p in tile.packets[set].iter().filter(|p| p.valid.any()) {
        let (d, _, _) = toward_segment(p, &tw);
        let c = dot3(&d, &m);
        let cross = [d[1] * m[2] - m[1] * d[2], d[2] * m[0] - m[2] * d[0], d[0] * m[1] - m[0] * d[1]];
        let tangent = V::select(c.gt(zero), dot3(&cross, &cross).sqrt() / c, inf);
        spread = spread.max(V::select(p.valid, tangent, zero));
    }
    if spread.reduce_max() > spread_limit {
        return None;
    }
    let mut f = sides.frustum(toward, 0.0, t_max.reduce_max());
    widen_toward(&mut f.t_max, &mut f.origin_slack, toward, gap_max.reduce_max());
    Some(f)
}

/// Each lane's segment seen from `tw` (a point in every lane), with [`toward_segments`]' operations: unit
/// direction, length, and how far the segment's end misses the point.
#[inline(always)]
fn toward_segment<V: Vf32>(p: &RayPacket<V>, tw: &[V; 3]) -> ([V; 3], V, V) {
    let t0 = p.tmin.max(V::splat(0.0));
    let v = map3([0, 1, 2], |k| p.org[k] + p.dir[k] * t0 - tw[k]);
    let e = map3([0, 1, 2], |k| p.org[k] + p.dir[k] * p.tmax - tw[k]);
    let len = dot3(&v, &v).sqrt();
    (map3([0, 1, 2], |k| v[k] / len), len, dot3(&e, &e).sqrt())
}

/// Widens a bundle seen from `toward` (its end distance and origin slack) to cover the rounding of its
/// segments' ends (`slack`: how far the farthest misses `toward`) and of the positions themselves.
fn widen_toward(t_max: &mut f32, origin_slack: &mut f32, toward: Vec3, slack: f32) {
    let scale = toward.abs().max_element() + *t_max;
    *origin_slack = slack * 2.0 + scale * 4.0 * f32::EPSILON;
    *t_max = *t_max * (1.0 + 4.0 * f32::EPSILON) + *origin_slack;
}

#[cfg(test)]
mod tests {
    use raylab_simd::{Backend, Kernel, dispatch};

    use super::*;

    /// [`toward_frustum`] on one backend's packets, and the scalar segments of the same rays bounded by
    /// [`Frustum::bounding`].
    struct BothWays<'a> {
        rays: &'a [Option<Ray>],
        width: usize,
        light: Vec3,
        limit: f32,
    }

    impl Kernel for BothWays<'_> {
        type Output = (Option<Frustum>, Option<Frustum>);
        fn run<V: Vf32>(self) -> Self::Output {
            let height = self.rays.len() / self.width;
            let tile = PacketTile::<V>::new(self.rays, self.width, height);
            let rays = RayRect { rays: self.rays, width: self.width, x: 0..self.width, y: 0..height };
            let packets = toward_frustum(
                &Bundled { tile: &tile, set: 0..tile.packets.len(), rays: rays.clone() },
                self.light,
                self.limit,
            );
            let scalar = toward_segments(rays, self.light, self.limit).and_then(|(segs, slack)| {
                let mut f = Frustum::bounding(self.light, segs)?;
                widen_toward(&mut f.t_max, &mut f.origin_slack, self.light, slack);
                Some(f)
            });
            (packets, scalar)
        }
    }

    /// Shadow rays from points around `center` (spread `spread`, on the plane y = 0) to `light`, in a 6x5 tile
    /// (partial packets), with a hole and an invalid ray; the first point lies straight below the light when
    /// `below` is set (zero x and z direction components).
    fn shadow_rays(center: Vec3, spread: f32, light: Vec3, below: bool) -> Vec<Option<Ray>> {
        let mut seed = 12345u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        (0..30)
            .map(|i| match i {
                7 => None,
                11 => Some(Ray::segment(Vec3::NAN, Vec3::Y, 0.0, 1.0)),
                _ => {
                    let p = if i == 0 && below {
                        Vec3::new(light.x, 0.0, light.z)
                    } else {
                        center + Vec3::new(next() * spread, 0.0, next() * spread)
                    };
                    let to = light - p;
                    Some(Ray::segment(p, to / to.length(), 1e-3, to.length()))
                }
            })
            .collect()
    }

    #[test]
    fn bundles_from_packets_equal_the_scalar_segments_on_every_backend() {
        let light = Vec3::new(0.3, 11.0, -0.2);
        let wide = shadow_rays(Vec3::ZERO, 30.0, light, true);
        let narrow = shadow_rays(Vec3::new(40.0, 0.0, 35.0), 1.0, light, false);
        let mut short = narrow.clone();
        short[3] = short[3].map(|r| Ray { tmax: r.tmax * 0.5, ..r });
        for backend in Backend::available() {
            let both = |rays: &[Option<Ray>], limit: f32| dispatch(backend, BothWays { rays, width: 6, light, limit });
            let (packets, scalar) = both(&wide, f32::INFINITY);
            assert!(packets.is_some(), "{backend:?}: an unlimited spread takes every bundle");
            assert_eq!(packets, scalar, "{backend:?}: mixed signs and a zero component");
            let (packets, scalar) = both(&narrow, 0.05);
            assert!(packets.is_some(), "{backend:?}: a narrow bundle");
            assert_eq!(packets, scalar, "{backend:?}: narrow bundle");
            assert_eq!(both(&wide, 0.05), (None, None), "{backend:?}: too wide for the limit");
            assert_eq!(both(&short, f32::INFINITY), (None, None), "{backend:?}: a segment that stops short");
        }
    }
}
