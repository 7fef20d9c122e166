//! Tracing a tile of rays with any method: the one entry point the renderer, the benchmark and the tests
//! share, so every method is driven the same way.
//!
//! Single-ray methods loop over the tile. Packet methods cut it into 2x2 packets. Frustum methods also need
//! the rays to share an origin (camera rays) or an end point (shadow rays toward a light, traced from the
//! light as in the thesis); otherwise they fall back to packets, which is always exact.

use glam::Vec3;
use raylab_simd::{Backend, VMask, Vf32};

use crate::kdtree::KdTree;
use crate::kdtree::mft::Frustum4;
use crate::method::Method;
use crate::packet::{Cone, Cone4};
use crate::packet::{Frustum, PacketTile};
use crate::ray::{Hit, Ray};
use crate::reference::BruteForce;
use crate::stats::TraversalStats;

/// How rays are traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceOptions {
    /// Traversal method.
    pub method: Method,
    /// Packet/leaf culling in the frustum methods (thesis 4.1.4).
    pub cull: bool,
    /// SIMD backend of the packet kernels.
    pub backend: Backend,
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self { method: Method::Mono, cull: true, backend: Backend::detect() }
    }
}

/// Traces tiles of rays through a kd-tree (or brute force, for [`Method::Reference`]).
pub struct Tracer<'a> {
    tree: &'a KdTree,
    reference: Option<&'a BruteForce>,
    /// The options.
    pub options: TraceOptions,
}

/// Relative size of the gap between a shadow segment's end and the light beyond which the segments are not
/// taken to end at the light.
const TOWARD_TOLERANCE: f32 = 1e-3;

impl<'a> Tracer<'a> {
    /// A tracer over `tree`; `reference` is needed only for [`Method::Reference`].
    pub fn new(tree: &'a KdTree, reference: Option<&'a BruteForce>, options: TraceOptions) -> Self {
        Self { tree, reference, options }
    }

    /// Closest hits of a `width x height` tile of rays (row-major; `None` where no ray is traced).
    pub fn intersect_tile(
        &self,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        out: &mut [Option<Hit>],
        stats: &mut TraversalStats,
    ) {
        assert!(rays.len() == width * height && out.len() == rays.len());
        match self.options.method {
            Method::Mono => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.and_then(|r| self.tree.intersect(&r, stats));
                }
            }
            Method::Reference => {
                let bf = self.reference.expect("the reference method needs a BruteForce");
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.and_then(|r| bf.intersect(&r, stats));
                }
            }
            _ => match self.options.backend {
                #[cfg(target_arch = "x86_64")]
                Backend::Sse => self.intersect_simd::<raylab_simd::sse::F32x4>(rays, width, height, out, stats),
                _ => self.intersect_simd::<raylab_simd::scalar::F32x4>(rays, width, height, out, stats),
            },
        }
    }

    /// Occlusion of a tile of rays. `toward` is the point all segments end at, if there is one (a light).
    pub fn occluded_tile(
        &self,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        toward: Option<Vec3>,
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        assert!(rays.len() == width * height && out.len() == rays.len());
        match self.options.method {
            Method::Mono => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.is_some_and(|r| self.tree.occluded(&r, stats));
                }
            }
            Method::Reference => {
                let bf = self.reference.expect("the reference method needs a BruteForce");
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.is_some_and(|r| bf.occluded(&r, stats));
                }
            }
            _ => match self.options.backend {
                #[cfg(target_arch = "x86_64")]
                Backend::Sse => self.occluded_simd::<raylab_simd::sse::F32x4>(rays, width, height, toward, out, stats),
                _ => self.occluded_simd::<raylab_simd::scalar::F32x4>(rays, width, height, toward, out, stats),
            },
        }
    }

    fn intersect_simd<V: Vf32>(
        &self,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        out: &mut [Option<Hit>],
        stats: &mut TraversalStats,
    ) {
        let mut tile = PacketTile::<V>::new(rays, width, height);
        let all: Vec<usize> = (0..tile.packets.len()).collect();
        stats.rays += rays.iter().flatten().filter(|r| r.is_valid()).count() as u64;
        stats.packets += tile.packets.len() as u64;
        match self.options.method {
            Method::Frustum => match common_origin_frustum(&tile, &all) {
                Some(f) => self.tree.intersect_frustum(&f, &mut tile, &all, self.options.cull, stats),
                None => self.packets_intersect(&mut tile, stats),
            },
            Method::Mft => match self.quadrants(&tile, rays, None, common_origin_frustum, toward_frustum) {
                Some((b, sets)) => match Frustum4::new(b) {
                    Some(f4) => self.tree.intersect_mft(&f4, &mut tile, &sets, self.options.cull, stats),
                    None => self.packets_intersect(&mut tile, stats),
                },
                None => self.packets_intersect(&mut tile, stats),
            },
            Method::Cone => match common_origin_cone(&tile, &all) {
                Some(c) => self.tree.intersect_frustum(&c, &mut tile, &all, self.options.cull, stats),
                None => self.packets_intersect(&mut tile, stats),
            },
            Method::MftCone => match self.quadrants(&tile, rays, None, common_origin_cone, toward_cone) {
                Some((b, sets)) => match Cone4::new(b) {
                    Some(c4) => self.tree.intersect_mft(&c4, &mut tile, &sets, self.options.cull, stats),
                    None => self.packets_intersect(&mut tile, stats),
                },
                None => self.packets_intersect(&mut tile, stats),
            },
            _ => self.packets_intersect(&mut tile, stats),
        }
        for j in 0..tile.packets.len() {
            tile.for_each_lane(j, |pixel, lane| out[pixel] = tile.hits[j].get(lane));
        }
    }

    fn packets_intersect<V: Vf32>(&self, tile: &mut PacketTile<V>, stats: &mut TraversalStats) {
        for (p, h) in tile.packets.iter().zip(tile.hits.iter_mut()) {
            self.tree.intersect_packet(p, h, stats);
        }
    }

    fn occluded_simd<V: Vf32>(
        &self,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        toward: Option<Vec3>,
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        let tile = PacketTile::<V>::new(rays, width, height);
        let mut blocked = vec![V::Mask::from_bits(0); tile.packets.len()];
        let all: Vec<usize> = (0..tile.packets.len()).collect();
        stats.rays += rays.iter().flatten().filter(|r| r.is_valid()).count() as u64;
        stats.packets += tile.packets.len() as u64;
        let frustum = || common_origin_frustum(&tile, &all).or_else(|| toward.and_then(|t| toward_frustum(rays, t)));
        let traced = match self.options.method {
            Method::Frustum => frustum().map(|f| {
                self.tree.occluded_frustum(&f, &tile, &all, self.options.cull, &mut blocked, stats);
            }),
            Method::Mft => self
                .quadrants(&tile, rays, toward, common_origin_frustum, toward_frustum)
                .and_then(|(b, sets)| Some((Frustum4::new(b)?, sets)))
                .map(|(f4, sets)| self.tree.occluded_mft(&f4, &tile, &sets, self.options.cull, &mut blocked, stats)),
            Method::Cone => common_origin_cone(&tile, &all)
                .or_else(|| toward.and_then(|t| toward_cone(rays, t)))
                .map(|c| self.tree.occluded_frustum(&c, &tile, &all, self.options.cull, &mut blocked, stats)),
            Method::MftCone => self
                .quadrants(&tile, rays, toward, common_origin_cone, toward_cone)
                .and_then(|(b, sets)| Some((Cone4::new(b)?, sets)))
                .map(|(c4, sets)| self.tree.occluded_mft(&c4, &tile, &sets, self.options.cull, &mut blocked, stats)),
            _ => None,
        };
        if traced.is_none() {
            for (p, b) in tile.packets.iter().zip(blocked.iter_mut()) {
                *b = self.tree.occluded_packet(p, stats);
            }
        }
        for (j, b) in blocked.iter().enumerate() {
            let bits = b.bits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = bits >> lane & 1 == 1);
        }
    }

    /// The four quadrant bundles of a tile (in whole packets) and the packets each bounds; `common` builds a
    /// bundle from packets with one origin, `toward` one from segments that end at a light.
    fn quadrants<V: Vf32, B: Copy>(
        &self,
        tile: &PacketTile<V>,
        rays: &[Option<Ray>],
        toward: Option<Vec3>,
        common: fn(&PacketTile<V>, &[usize]) -> Option<B>,
        toward_fn: fn(&[Option<Ray>], Vec3) -> Option<B>,
    ) -> Option<Quadrants<B>> {
        let ph = PacketTile::<V>::PACKET_H;
        let (cx, cy) = (tile.cols.div_ceil(2) * 2, tile.rows.div_ceil(2) * ph);
        let (w, h) = (tile.width, tile.height);
        let quads = [(0, 0, cx.min(w), cy.min(h)), (cx, 0, w, cy.min(h)), (0, cy, cx.min(w), h), (cx, cy, w, h)];
        let mut sets: [Vec<usize>; 4] = Default::default();
        let mut bundles = [None; 4];
        let mut origin = None;
        for (i, &(x0, y0, x1, y1)) in quads.iter().enumerate() {
            if x0 >= x1 || y0 >= y1 {
                continue;
            }
            let set = tile.packets_in(x0, y0, x1, y1);
            if set.iter().all(|&j| tile.packets[j].valid.none()) {
                continue;
            }
            let (b, o) = match common_origin(tile, &set) {
                Some(o) => (common(tile, &set)?, o),
                None => {
                    let t = toward?;
                    let sub: Vec<Option<Ray>> =
                        (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).map(|(x, y)| rays[y * w + x]).collect();
                    (toward_fn(&sub, t)?, t)
                }
            };
            // All four must share one origin.
            if *origin.get_or_insert(o) != o {
                return None;
            }
            bundles[i] = Some(b);
            sets[i] = set;
        }
        Some((bundles, sets))
    }
}

/// The origin shared by every valid ray of packets `set`, if there is one.
fn common_origin<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Vec3> {
    let origin = set
        .iter()
        .find_map(|&j| {
            let p = &tile.packets[j];
            let first = p.valid.bits().trailing_zeros() as usize;
            (first < V::LANES).then(|| p.ray(first))
        })?
        .origin;
    let o = [V::splat(origin.x), V::splat(origin.y), V::splat(origin.z)];
    let same = set.iter().all(|&j| {
        let p = &tile.packets[j];
        let at_origin = p.org[0].eq(o[0]) & p.org[1].eq(o[1]) & p.org[2].eq(o[2]);
        (p.valid & !at_origin).none()
    });
    same.then_some(origin)
}

/// The cone of packets `set` when all their rays start at one point, else `None`.
fn common_origin_cone<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Cone> {
    Cone::from_packets(common_origin(tile, set)?, &tile.packets, set)
}

/// The cone, seen from `toward`, of segments that end there (shadow rays to a light), like
/// [`toward_frustum`].
fn toward_cone(rays: &[Option<Ray>], toward: Vec3) -> Option<Cone> {
    let (segs, slack) = toward_segments(rays, toward)?;
    let mut c = Cone::bounding(toward, segs.iter().copied())?;
    let scale = toward.abs().max_element() + c.t_max;
    c.origin_slack = slack * 2.0 + scale * 4.0 * f32::EPSILON;
    c.t_max = c.t_max * (1.0 + 4.0 * f32::EPSILON) + c.origin_slack;
    Some(c)
}

/// The frustum of the packets `set` of `tile` when all their rays start at one point, else `None`.
fn common_origin_frustum<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Frustum> {
    Frustum::from_packets(common_origin(tile, set)?, &tile.packets, set)
}

/// A tile's four quadrant bundles (empty quadrants are `None`) and the packets each bounds.
type Quadrants<B> = ([Option<B>; 4], [Vec<usize>; 4]);

/// A segment seen from a light: unit direction, start and end distance.
type Segment = (Vec3, f32, f32);

/// The segments of `rays` seen from `toward`, and how far their ends miss it; `None` when some segment does
/// not end near it.
fn toward_segments(rays: &[Option<Ray>], toward: Vec3) -> Option<(Vec<Segment>, f32)> {
    let mut slack = 0.0f32;
    let mut segs = Vec::new();
    for r in rays.iter().flatten().filter(|r| r.is_valid()) {
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
    Some((segs, slack))
}

/// The frustum, seen from `toward`, of segments that end there (shadow rays to a light): the thesis traces
/// shadow rays from the light toward the surface points. `None` when some segment does not end near it.
fn toward_frustum(rays: &[Option<Ray>], toward: Vec3) -> Option<Frustum> {
    let (segs, slack) = toward_segments(rays, toward)?;
    let mut f = Frustum::bounding(toward, segs)?;
    // Cover the rounding of the segments' ends and of the positions themselves.
    let scale = toward.abs().max_element() + f.t_max;
    f.origin_slack = slack * 2.0 + scale * 4.0 * f32::EPSILON;
    f.t_max = f.t_max * (1.0 + 4.0 * f32::EPSILON) + f.origin_slack;
    Some(f)
}
