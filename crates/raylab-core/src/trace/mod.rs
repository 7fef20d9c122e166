//! Tracing a tile of rays with any method: the one entry point the renderer, the benchmark and the tests
//! share, so every method is driven the same way.
//!
//! Single-ray methods loop over the tile. Packet methods cut it into 2x2 packets. Frustum methods also need
//! the rays to share an origin (camera rays) or an end point (shadow rays toward a light, traced from the
//! light as in the thesis); otherwise they fall back to packets, which is always exact.

mod proxy;

pub use proxy::Proxy;

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{Backend, Kernel, VMask, Vf32};
use serde::Serialize;

use crate::dacrt::{Dacrt, DacrtParams};
use crate::kdtree::KdTree;
use crate::kdtree::mft::Frustum4;
use crate::mbvh::Mbvh;
use crate::method::Method;
use crate::packet::{Cone, Cone4};
use crate::packet::{Frustum, PacketTile};
use crate::ray::{Hit, Ray};
use crate::reference::BruteForce;
use crate::render::RayOrder;
use crate::shadow::EdgeWidth;
use crate::stats::TraversalStats;

/// How rays are traced. Serialises into run reports (the backend by its name).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TraceOptions {
    /// Traversal method.
    pub method: Method,
    /// Packet/leaf culling in the frustum methods (thesis 4.1.4).
    pub cull: bool,
    /// SIMD backend of the packet kernels.
    #[serde(serialize_with = "backend_name")]
    pub backend: Backend,
    /// Widest shadow bundle (tangent of the largest angle between a ray and the bundle's mean direction, seen
    /// from the light) that the frustum methods trace as a frustum; wider tiles or quadrants, whose hit points
    /// are spread in depth, are traced as 2x2 packets instead, which is faster for them.
    pub shadow_spread_limit: f32,
    /// Order MBVH RS child tasks by accumulated hit length (the paper's heuristic; off walks them in lane
    /// order, to measure its gain).
    pub stream_order: bool,
    /// DACRT's leaf thresholds and split rule.
    pub dacrt: DacrtParams,
    /// MBVH RS ray-group size: `None` traces each tile as one group; `Some(g)` cuts a tile into groups of `g`
    /// rays along the Z-order curve (square or 2:1 blocks of pixels for powers of two), the paper's 2^4 to
    /// 2^12 sweep independent of the tile size.
    pub stream_group: Option<usize>,
}

fn backend_name<S: serde::Serializer>(b: &Backend, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(b.name())
}

impl TraceOptions {
    /// Default of [`TraceOptions::shadow_spread_limit`], chosen with `raylab-bench compare` on the Sponza view.
    pub const SHADOW_SPREAD_LIMIT: f32 = 0.05;
}

impl Default for TraceOptions {
    fn default() -> Self {
        Self {
            method: Method::Mono,
            cull: true,
            backend: Backend::detect(),
            shadow_spread_limit: Self::SHADOW_SPREAD_LIMIT,
            stream_order: true,
            dacrt: DacrtParams::default(),
            stream_group: None,
        }
    }
}

/// Traces tiles of rays through a kd-tree (or brute force, for [`Method::Reference`]).
pub struct Tracer<'a> {
    tree: &'a KdTree,
    reference: Option<&'a BruteForce>,
    mbvh: Option<&'a Mbvh>,
    dacrt: Option<&'a Dacrt>,
    /// The options.
    pub options: TraceOptions,
}

/// Relative size of the gap between a shadow segment's end and the light beyond which the segments are not
/// taken to end at the light.
const TOWARD_TOLERANCE: f32 = 1e-3;

impl<'a> Tracer<'a> {
    /// A tracer over `tree`; `reference` is needed only for [`Method::Reference`].
    pub fn new(tree: &'a KdTree, reference: Option<&'a BruteForce>, options: TraceOptions) -> Self {
        Self { tree, reference, mbvh: None, dacrt: None, options }
    }

    /// The same tracer with an MBVH over the same scene, needed for [`Method::Mbvh`].
    pub fn with_mbvh(self, mbvh: &'a Mbvh) -> Self {
        Self { mbvh: Some(mbvh), ..self }
    }

    /// The same tracer with the scene prepared for divide-and-conquer tracing, needed for [`Method::Dacrt`].
    pub fn with_dacrt(self, dacrt: &'a Dacrt) -> Self {
        Self { dacrt: Some(dacrt), ..self }
    }

    fn dacrt(&self) -> &'a Dacrt {
        self.dacrt.expect("the dacrt method needs a Dacrt (Tracer::with_dacrt)")
    }

    fn mbvh(&self) -> &'a Mbvh {
        self.mbvh.expect("the mbvh method needs an Mbvh (Tracer::with_mbvh)")
    }

    /// The same tracer with another traversal method (the brute-force reference stays the reference).
    pub fn with_method(&self, method: Method) -> Tracer<'a> {
        let method = if self.options.method == Method::Reference { Method::Reference } else { method };
        Tracer {
            tree: self.tree,
            reference: self.reference,
            mbvh: self.mbvh,
            dacrt: self.dacrt,
            options: TraceOptions { method, ..self.options },
        }
    }

    /// The first blocker found along a single ray (for the shadow cache).
    pub fn occluder(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        match self.options.method {
            Method::Reference => self.reference().occluder(ray, stats),
            Method::Mbvh | Method::MbvhRs => self.mbvh().occluder(ray, stats),
            Method::Dacrt => {
                let mut out = [None];
                self.dacrt().occluders(&self.options.dacrt, &[Some(*ray)], &mut out, stats);
                out[0]
            }
            _ => self.tree.occluder(ray, stats),
        }
    }

    /// The first blocker found along each of `rays` (`None` entries and unblocked rays give `None`): one set
    /// for DACRT, ray by ray for the other methods.
    pub fn occluders_tile(&self, rays: &[Option<Ray>], out: &mut [Option<u32>], stats: &mut TraversalStats) {
        assert_eq!(rays.len(), out.len());
        if self.options.method == Method::Dacrt {
            self.dacrt().occluders(&self.options.dacrt, rays, out, stats);
            return;
        }
        for (o, r) in out.iter_mut().zip(rays) {
            *o = r.and_then(|r| self.occluder(&r, stats));
        }
    }

    /// True when triangle `tri` blocks `ray`.
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        match self.options.method {
            Method::Reference => self.reference().blocks(ray, tri),
            Method::Dacrt => self.dacrt().blocks(ray, tri),
            Method::Mbvh | Method::MbvhRs => self.mbvh().blocks(ray, tri),
            _ => self.tree.blocks(ray, tri),
        }
    }

    /// The edge-width occlusion of a single shadow ray (thesis Listing 5.1): the kd-tree's walk for every
    /// method (also for the MBVH and DACRT methods, which do not visit leaves in distance order, which the
    /// pairing relies on), or the brute-force reference for [`Method::Reference`].
    pub fn edge_width(&self, ray: &Ray, state: &mut EdgeWidth, stats: &mut TraversalStats) -> f32 {
        match self.options.method {
            Method::Reference => self.reference().edge_width(ray, state, stats),
            _ => self.tree.edge_width(ray, state, stats),
        }
    }

    /// The edge-width occlusions of `rays`, written to `out`; `states` holds at least
    /// [`crate::packet::MAX_LANES`] states with the frame's radius and leak-fix switch. The single-ray
    /// methods walk ray by ray (the reference by brute force); the others trace the walks as kd-tree packets
    /// of rays with the same direction signs (see [`KdTree::edge_widths`]), which give the same answers.
    pub fn edge_widths(&self, rays: &[Ray], states: &mut [EdgeWidth], out: &mut [f32], stats: &mut TraversalStats) {
        assert_eq!(rays.len(), out.len());
        assert!(states.len() >= crate::packet::MAX_LANES, "edge_widths needs one state per packet lane");
        match self.options.method {
            Method::Reference | Method::Mono => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self.edge_width(r, &mut states[0], stats);
                }
            }
            _ => raylab_simd::dispatch(
                self.options.backend,
                EdgeWidthsSimd { tree: self.tree, rays, states, out, stats },
            ),
        }
    }

    fn reference(&self) -> &'a BruteForce {
        self.reference.expect("the reference method needs a BruteForce")
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
                let bf = self.reference();
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.and_then(|r| bf.intersect(&r, stats));
                }
            }
            Method::Mbvh => {
                let m = self.mbvh();
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.and_then(|r| m.intersect(&r, stats));
                }
            }
            Method::MbvhRs => self.in_groups(rays, width, height, out, |r, o| {
                self.mbvh().intersect_stream(r, o, self.options.stream_order, stats)
            }),
            Method::Dacrt => self.dacrt().intersect(&self.options.dacrt, rays, out, stats),
            _ => raylab_simd::dispatch(
                self.options.backend,
                IntersectSimd { tracer: self, rays, width, height, out, stats },
            ),
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
                let bf = self.reference();
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.is_some_and(|r| bf.occluded(&r, stats));
                }
            }
            Method::Mbvh => {
                let m = self.mbvh();
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.is_some_and(|r| m.occluded(&r, stats));
                }
            }
            Method::MbvhRs => self.in_groups(rays, width, height, out, |r, o| {
                self.mbvh().occluded_stream(r, o, self.options.stream_order, stats)
            }),
            Method::Dacrt => self.dacrt().occluded(&self.options.dacrt, rays, out, stats),
            _ => raylab_simd::dispatch(
                self.options.backend,
                OccludedSimd { tracer: self, rays, width, height, toward, out, stats },
            ),
        }
    }

    /// Calls `trace(rays, out)` on the whole tile, or on groups of [`TraceOptions::stream_group`] rays taken
    /// along the Z-order curve of the `width x height` tile.
    fn in_groups<T: Copy + Default>(
        &self,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        out: &mut [T],
        mut trace: impl FnMut(&[Option<Ray>], &mut [T]),
    ) {
        let group = self.options.stream_group.unwrap_or(usize::MAX).max(1);
        if rays.len() <= group {
            return trace(rays, out);
        }
        let order: Vec<usize> = RayOrder::Morton
            .offsets(width as u32, height as u32)
            .into_iter()
            .map(|(x, y)| y as usize * width + x as usize)
            .collect();
        let (mut part_rays, mut part_out) = (Vec::with_capacity(group), Vec::with_capacity(group));
        for chunk in order.chunks(group) {
            part_rays.clear();
            part_rays.extend(chunk.iter().map(|&i| rays[i]));
            part_out.clear();
            part_out.resize(chunk.len(), T::default());
            trace(&part_rays, &mut part_out);
            for (&i, &o) in chunk.iter().zip(&part_out) {
                out[i] = o;
            }
        }
    }

    #[inline(always)]
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
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        // Tiles no bundle covers are traced as packets (after the match, so the packet kernel is inlined once).
        let cull = self.options.cull;
        let bundled = match self.options.method {
            Method::Frustum => {
                let f = common_origin_frustum(&tile, &all);
                if let Some(f) = &f {
                    self.tree.intersect_frustum(f, &mut tile, &all, cull, stats);
                }
                f.is_some()
            }
            Method::Cone => {
                let c = common_origin_cone(&tile, &all);
                if let Some(c) = &c {
                    self.tree.intersect_frustum(c, &mut tile, &all, cull, stats);
                }
                c.is_some()
            }
            Method::Mft => {
                let quads = self.quadrants(&tile, rays, None, common_origin_frustum, toward_frustum);
                let f4 = quads.and_then(|(b, sets, _)| Some((Frustum4::new(b)?, sets)));
                if let Some((f4, sets)) = &f4 {
                    self.tree.intersect_mft(f4, &mut tile, sets, cull, stats);
                }
                f4.is_some()
            }
            Method::MftCone => {
                let quads = self.quadrants(&tile, rays, None, common_origin_cone, toward_cone);
                let c4 = quads.and_then(|(b, sets, _)| Some((Cone4::new(b)?, sets)));
                if let Some((c4, sets)) = &c4 {
                    self.tree.intersect_mft(c4, &mut tile, sets, cull, stats);
                }
                c4.is_some()
            }
            _ => false,
        };
        if !bundled {
            self.packets_intersect(&mut tile, stats);
        }
        for (j, hits) in tile.hits.iter().enumerate() {
            let lanes = hits.to_hits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = lanes[lane]);
        }
    }

    #[inline(always)]
    fn packets_intersect<V: Vf32>(&self, tile: &mut PacketTile<V>, stats: &mut TraversalStats) {
        for (p, h) in tile.packets.iter().zip(tile.hits.iter_mut()) {
            self.tree.intersect_packet(p, h, stats);
        }
    }

    #[inline(always)]
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
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        let limit = self.options.shadow_spread_limit;
        // Packets no bundle covers are traced as packets afterwards.
        let mut leftover: Option<Vec<usize>> = None;
        match self.options.method {
            Method::Frustum => {
                let whole = RayRect { rays, width, x: 0..width, y: 0..height };
                match common_origin_frustum(&tile, &all)
                    .or_else(|| toward.and_then(|t| toward_frustum(whole, t, limit)))
                {
                    Some(f) => self.tree.occluded_frustum(&f, &tile, &all, self.options.cull, &mut blocked, stats),
                    None => leftover = Some(all.clone()),
                }
            }
            Method::Cone => {
                let whole = RayRect { rays, width, x: 0..width, y: 0..height };
                match common_origin_cone(&tile, &all).or_else(|| toward.and_then(|t| toward_cone(whole, t, limit))) {
                    Some(c) => self.tree.occluded_frustum(&c, &tile, &all, self.options.cull, &mut blocked, stats),
                    None => leftover = Some(all.clone()),
                }
            }
            Method::Mft => match self.quadrants(&tile, rays, toward, common_origin_frustum, toward_frustum) {
                Some((b, sets, rest)) => {
                    if let Some(f4) = Frustum4::new(b) {
                        self.tree.occluded_mft(&f4, &tile, &sets, self.options.cull, &mut blocked, stats);
                    }
                    leftover = Some(rest);
                }
                None => leftover = Some(all.clone()),
            },
            Method::MftCone => match self.quadrants(&tile, rays, toward, common_origin_cone, toward_cone) {
                Some((b, sets, rest)) => {
                    if let Some(c4) = Cone4::new(b) {
                        self.tree.occluded_mft(&c4, &tile, &sets, self.options.cull, &mut blocked, stats);
                    }
                    leftover = Some(rest);
                }
                None => leftover = Some(all.clone()),
            },
            _ => leftover = Some(all.clone()),
        }
        for j in leftover.unwrap_or_default() {
            blocked[j] = self.tree.occluded_packet(&tile.packets[j], stats);
        }
        for (j, b) in blocked.iter().enumerate() {
            let bits = b.bits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = bits >> lane & 1 == 1);
        }
    }

    /// The four quadrant bundles of a tile (in whole packets) and the packets each bounds; `common` builds a
    /// bundle from packets with one origin, `toward` one from segments that end at a light.
    #[inline(always)]
    fn quadrants<V: Vf32, B: Copy>(
        &self,
        tile: &PacketTile<V>,
        rays: &[Option<Ray>],
        toward: Option<Vec3>,
        common: fn(&PacketTile<V>, &[usize]) -> Option<B>,
        toward_fn: fn(RayRect, Vec3, f32) -> Option<B>,
    ) -> Option<Quadrants<B>> {
        let (pw, ph) = (PacketTile::<V>::PACKET_W, PacketTile::<V>::PACKET_H);
        let (cx, cy) = (tile.cols.div_ceil(2) * pw, tile.rows.div_ceil(2) * ph);
        let (w, h) = (tile.width, tile.height);
        let quads = [(0, 0, cx.min(w), cy.min(h)), (cx, 0, w, cy.min(h)), (0, cy, cx.min(w), h), (cx, cy, w, h)];
        let mut sets: [Vec<usize>; 4] = Default::default();
        let mut bundles = [None; 4];
        let mut rest = Vec::new();
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
                    let rect = RayRect { rays, width: w, x: x0..x1, y: y0..y1 };
                    match toward_fn(rect, t, self.options.shadow_spread_limit) {
                        Some(b) => (b, t),
                        None => {
                            // Too wide (or not ending at the light): its packets go the packet way.
                            rest.extend(set);
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

/// [`Tracer::intersect_simd`] as a [`Kernel`], so the backend picks the lane type.
struct IntersectSimd<'t, 'a> {
    tracer: &'t Tracer<'a>,
    rays: &'t [Option<Ray>],
    width: usize,
    height: usize,
    out: &'t mut [Option<Hit>],
    stats: &'t mut TraversalStats,
}

impl Kernel for IntersectSimd<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        self.tracer.intersect_simd::<V>(self.rays, self.width, self.height, self.out, self.stats);
    }
}

/// [`Tracer::occluded_simd`] as a [`Kernel`].
struct OccludedSimd<'t, 'a> {
    tracer: &'t Tracer<'a>,
    rays: &'t [Option<Ray>],
    width: usize,
    height: usize,
    toward: Option<Vec3>,
    out: &'t mut [bool],
    stats: &'t mut TraversalStats,
}

impl Kernel for OccludedSimd<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        self.tracer.occluded_simd::<V>(self.rays, self.width, self.height, self.toward, self.out, self.stats);
    }
}

/// [`KdTree::edge_widths`] as a [`Kernel`].
struct EdgeWidthsSimd<'t> {
    tree: &'t KdTree,
    rays: &'t [Ray],
    states: &'t mut [EdgeWidth],
    out: &'t mut [f32],
    stats: &'t mut TraversalStats,
}

impl Kernel for EdgeWidthsSimd<'_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        self.tree.edge_widths::<V>(self.rays, self.states, self.out, self.stats);
    }
}

/// The origin shared by every valid ray of packets `set`, if there is one.
#[inline(always)]
fn common_origin<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Vec3> {
    // A plain loop rather than `find_map`, so the vector code stays inlined (see `map3`).
    let mut found = None;
    for &j in set {
        let p = &tile.packets[j];
        let first = p.valid.bits().trailing_zeros() as usize;
        if first < V::LANES {
            found = Some(p.ray(first).origin);
            break;
        }
    }
    let origin = found?;
    let o = [V::splat(origin.x), V::splat(origin.y), V::splat(origin.z)];
    let mut elsewhere = 0;
    for &j in set {
        let p = &tile.packets[j];
        let at_origin = p.org[0].eq(o[0]) & p.org[1].eq(o[1]) & p.org[2].eq(o[2]);
        elsewhere |= (p.valid & !at_origin).bits();
    }
    (elsewhere == 0).then_some(origin)
}

/// The cone of packets `set` when all their rays start at one point, else `None`.
#[inline(always)]
fn common_origin_cone<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Cone> {
    Cone::from_packets(common_origin(tile, set)?, &tile.packets, set)
}

/// The cone, seen from `toward`, of segments that end there (shadow rays to a light), like
/// [`toward_frustum`].
fn toward_cone(rays: RayRect, toward: Vec3, spread_limit: f32) -> Option<Cone> {
    let (segs, slack) = toward_segments(rays, toward, spread_limit)?;
    let mut c = Cone::bounding(toward, segs.iter().copied())?;
    let scale = toward.abs().max_element() + c.t_max;
    c.origin_slack = slack * 2.0 + scale * 4.0 * f32::EPSILON;
    c.t_max = c.t_max * (1.0 + 4.0 * f32::EPSILON) + c.origin_slack;
    Some(c)
}

/// The frustum of the packets `set` of `tile` when all their rays start at one point, else `None`.
#[inline(always)]
fn common_origin_frustum<V: Vf32>(tile: &PacketTile<V>, set: &[usize]) -> Option<Frustum> {
    Frustum::from_packets(common_origin(tile, set)?, &tile.packets, set)
}

/// A tile's four quadrant bundles (empty quadrants are `None`), the packets each bounds, and the packets left
/// to trace as packets.
type Quadrants<B> = ([Option<B>; 4], [Vec<usize>; 4], Vec<usize>);

/// The rays of the pixel rectangle `x` by `y` of a row-major tile `width` pixels wide.
#[derive(Clone)]
struct RayRect<'a> {
    rays: &'a [Option<Ray>],
    width: usize,
    x: Range<usize>,
    y: Range<usize>,
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
/// [`TraceOptions::shadow_spread_limit`]).
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

/// The frustum, seen from `toward`, of segments that end there (shadow rays to a light): the thesis traces
/// shadow rays from the light toward the surface points. `None` when some segment does not end near it.
fn toward_frustum(rays: RayRect, toward: Vec3, spread_limit: f32) -> Option<Frustum> {
    let (segs, slack) = toward_segments(rays, toward, spread_limit)?;
    let mut f = Frustum::bounding(toward, segs)?;
    // Cover the rounding of the segments' ends and of the positions themselves.
    let scale = toward.abs().max_element() + f.t_max;
    f.origin_slack = slack * 2.0 + scale * 4.0 * f32::EPSILON;
    f.t_max = f.t_max * (1.0 + 4.0 * f32::EPSILON) + f.origin_slack;
    Some(f)
}
