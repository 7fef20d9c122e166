//! Tracing a tile of rays with any method: the one entry point the renderer, the benchmark and the tests
//! share, so every method is driven the same way.
//!
//! Single-ray methods loop over the tile. Packet methods cut it into 2x2 packets. Frustum methods also need
//! the rays to share an origin (camera rays) or an end point (shadow rays toward a light, traced from the
//! light as in the thesis); otherwise they fall back to packets, which is always exact.

mod proxy;

pub use proxy::Proxy;

use std::any::Any;
use std::cell::Cell;
use std::ops::Range;

use glam::Vec3;
use raylab_simd::{Backend, Kernel, VMask, Vf32};
use serde::Serialize;

use crate::dacrt::{Dacrt, DacrtParams};
use crate::kdtree::KdTree;
use crate::kdtree::mft::Frustum4;
use crate::kdtree::packet::PacketStack;
use crate::mbvh::{Mbvh, StreamLeaves, StreamOptions};
use crate::method::Method;
use crate::packet::Cone;
use crate::packet::{Frustum, PacketTile, RayPacket, map3};
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
    /// are spread in depth, are traced as 2x2 packets instead, which is faster for them. The same limit picks
    /// between a bundle walk and packet walks for a tile's edge-width segments.
    pub shadow_spread_limit: f32,
    /// Order MBVH RS child tasks by accumulated hit length (the paper's heuristic; off walks them in lane
    /// order, to measure its gain).
    pub stream_order: bool,
    /// How MBVH RS tests the rays reaching a leaf: the paper's ray packets or ray/triangle-block tests.
    pub stream_leaves: StreamLeaves,
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
            stream_leaves: StreamLeaves::default(),
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

    fn stream_options(&self) -> StreamOptions {
        StreamOptions { ordered: self.options.stream_order, leaves: self.options.stream_leaves }
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

    /// The edge-width occlusions of `rays`, written to `out`; `states` holds at least as many states as
    /// there are rays, and at least [`crate::packet::MAX_LANES`], all with the frame's radius and leak-fix
    /// switch. The single-ray methods walk ray by ray (the reference by brute force). The bundled methods
    /// walk rays that end at `toward` (a light) as one frustum or cone from there, when there are many and
    /// the bundle is narrow enough (see [`KdTree::edge_widths_bundle`]); the others, and few or widely spread
    /// rays, as kd-tree packets of rays with the same direction signs (see [`KdTree::edge_widths`]). All give
    /// the same answers.
    pub fn edge_widths(
        &self,
        rays: &[Ray],
        toward: Option<Vec3>,
        states: &mut [EdgeWidth],
        out: &mut [f32],
        stats: &mut TraversalStats,
    ) {
        assert_eq!(rays.len(), out.len());
        assert!(
            states.len() >= rays.len().max(crate::packet::MAX_LANES),
            "edge_widths needs one state per ray and per packet lane"
        );
        match self.options.method {
            Method::Reference | Method::Mono => {
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self.edge_width(r, &mut states[0], stats);
                }
            }
            _ => raylab_simd::dispatch(
                self.options.backend,
                EdgeWidthsSimd { tracer: self, rays, toward, states, out, stats },
            ),
        }
    }

    /// [`Tracer::edge_widths`] for the packet methods, in vectors of type `V`, with the buffers of `scratch`.
    #[inline(always)]
    fn edge_widths_simd<V: Vf32>(
        &self,
        scratch: &mut TileScratch<V>,
        rays: &[Ray],
        toward: Option<Vec3>,
        states: &mut [EdgeWidth],
        out: &mut [f32],
        stats: &mut TraversalStats,
    ) {
        let method = self.options.method;
        let TileScratch { all, stack, tile, rays: grid, .. } = scratch;
        if let Some(toward) = toward.filter(|_| method.is_bundled() && rays.len() >= EDGE_BUNDLE_MIN_RAYS) {
            // The rays in packet order: a tile one packet wide whose packets hold consecutive rays.
            let pw = PacketTile::<V>::PACKET_W;
            let height = rays.len().div_ceil(pw);
            grid.clear();
            grid.extend(rays.iter().copied().map(Some));
            grid.resize(pw * height, None);
            tile.refill(grid, pw, height);
            all.clear();
            all.extend(0..tile.packets.len());
            let (tile, grid) = (&*tile, &grid[..]);
            let whole = Bundled { tile, set: all, rays: RayRect { rays: grid, width: pw, x: 0..pw, y: 0..height } };
            let (limit, cull) = (self.options.shadow_spread_limit, self.options.cull);
            let walked = match method {
                Method::Cone | Method::MftCone => toward_cone(&whole, toward, limit)
                    .map(|c| self.tree.edge_widths_bundle(&c, tile, cull, states, out, stats)),
                _ => toward_frustum(&whole, toward, limit)
                    .map(|f| self.tree.edge_widths_bundle(&f, tile, cull, states, out, stats)),
            };
            if walked.is_some() {
                return;
            }
        }
        self.tree.edge_widths::<V>(rays, states, out, stack, stats);
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
                self.mbvh().intersect_stream(r, o, self.stream_options(), stats)
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
                self.mbvh().occluded_stream(r, o, self.stream_options(), stats)
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

    /// [`Tracer::intersect_tile`] for the methods that trace packets, with lane type `V` and the buffers of
    /// `scratch`.
    #[inline(always)]
    fn intersect_simd<V: Vf32>(
        &self,
        scratch: &mut TileScratch<V>,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        out: &mut [Option<Hit>],
        stats: &mut TraversalStats,
    ) {
        let TileScratch { all, stack, tile, .. } = scratch;
        tile.refill(rays, width, height);
        all.clear();
        all.extend(0..tile.packets.len());
        let all = &all[..];
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        // Tiles no bundle covers are traced as packets (after the match, so the packet kernel is inlined once).
        let cull = self.options.cull;
        if cull
            && self.options.method.is_bundled()
            && let Some(origin) = common_origin(tile, all)
        {
            tile.share_origin(origin);
        }
        let bundled = match self.options.method {
            Method::Frustum => {
                let f = common_origin_frustum(tile, all);
                if let Some(f) = &f {
                    self.tree.intersect_frustum(f, tile, all, cull, stats);
                }
                f.is_some()
            }
            Method::Cone => {
                let c = common_origin_cone(tile, all);
                if let Some(c) = &c {
                    self.tree.intersect_frustum(c, tile, all, cull, stats);
                }
                c.is_some()
            }
            Method::Mft => {
                let quads = self.quadrants(tile, rays, None, common_origin_frustum, toward_frustum);
                let f4 = quads.and_then(|(b, sets, _)| Some((Frustum4::new(b)?, sets)));
                if let Some((f4, sets)) = &f4 {
                    self.tree.intersect_mft(f4, tile, sets, cull, stats);
                }
                f4.is_some()
            }
            Method::MftCone => {
                let quads = self.quadrants(tile, rays, None, common_origin_cone, toward_cone);
                let c4 = quads.and_then(|(b, sets, _)| Some((Frustum4::new(b)?, sets)));
                if let Some((c4, sets)) = &c4 {
                    self.tree.intersect_mft(c4, tile, sets, cull, stats);
                }
                c4.is_some()
            }
            _ => false,
        };
        if !bundled {
            self.packets_intersect(tile, stack, stats);
        }
        for (j, hits) in tile.hits.iter().enumerate() {
            let lanes = hits.lanes();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = lanes.get(lane));
        }
    }

    #[inline(always)]
    fn packets_intersect<V: Vf32>(
        &self,
        tile: &mut PacketTile<V>,
        stack: &mut PacketStack<V>,
        stats: &mut TraversalStats,
    ) {
        for (p, h) in tile.packets.iter().zip(tile.hits.iter_mut()) {
            self.tree.intersect_packet(p, h, stack, stats);
        }
    }

    /// [`Tracer::occluded_tile`] for the methods that trace packets, with lane type `V` and the buffers of
    /// `scratch`: kernels that trace many small tiles in one dispatch reuse them.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn occluded_simd<V: Vf32>(
        &self,
        scratch: &mut TileScratch<V>,
        rays: &[Option<Ray>],
        width: usize,
        height: usize,
        toward: Option<Vec3>,
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        let TileScratch { all, blocked, stack, tile, .. } = scratch;
        tile.refill(rays, width, height);
        blocked.clear();
        blocked.resize(tile.packets.len(), V::Mask::from_bits(0));
        all.clear();
        all.extend(0..tile.packets.len());
        let all = &all[..];
        if self.options.cull
            && self.options.method.is_bundled()
            && let Some(origin) = common_origin(tile, all)
        {
            tile.share_origin(origin);
        }
        let tile = &*tile;
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        // Packets no bundle covers are traced as packets afterwards: all of them, or the quadrants' rest.
        let mut rest: Option<Vec<usize>> = None;
        let mut all_left = false;
        match self.options.method {
            Method::Frustum => match self.whole(tile, all, rays, toward, common_origin_frustum, toward_frustum) {
                Some(f) => self.tree.occluded_frustum(&f, tile, all, self.options.cull, blocked, stats),
                None => all_left = true,
            },
            Method::Cone => match self.whole(tile, all, rays, toward, common_origin_cone, toward_cone) {
                Some(c) => self.tree.occluded_frustum(&c, tile, all, self.options.cull, blocked, stats),
                None => all_left = true,
            },
            Method::Mft => match self.quadrants(tile, rays, toward, common_origin_frustum, toward_frustum) {
                Some((b, sets, left)) => {
                    if let Some(f4) = Frustum4::new(b) {
                        self.tree.occluded_mft(&f4, tile, &sets, self.options.cull, blocked, stats);
                    }
                    rest = Some(left);
                }
                None => all_left = true,
            },
            Method::MftCone => match self.quadrants(tile, rays, toward, common_origin_cone, toward_cone) {
                Some((b, sets, left)) => {
                    if let Some(c4) = Frustum4::new(b) {
                        self.tree.occluded_mft(&c4, tile, &sets, self.options.cull, blocked, stats);
                    }
                    rest = Some(left);
                }
                None => all_left = true,
            },
            _ => all_left = true,
        }
        let left = if all_left { all } else { rest.as_deref().unwrap_or_default() };
        for &j in left {
            blocked[j] = self.tree.occluded_packet(&tile.packets[j], stack, stats);
        }
        for (j, b) in blocked.iter().enumerate() {
            let bits = b.bits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = bits >> lane & 1 == 1);
        }
    }

    /// The one bundle of a whole tile, packets `all`: `common` builds it from packets with one origin,
    /// `toward_fn` from segments that end at a light (function items rather than `Option::or_else`
    /// closures, whose vector code the compiler may keep out of line).
    #[inline(always)]
    fn whole<V: Vf32, B>(
        &self,
        tile: &PacketTile<V>,
        all: &[usize],
        rays: &[Option<Ray>],
        toward: Option<Vec3>,
        common: fn(&PacketTile<V>, &[usize]) -> Option<B>,
        toward_fn: fn(&Bundled<V>, Vec3, f32) -> Option<B>,
    ) -> Option<B> {
        if let Some(b) = common(tile, all) {
            return Some(b);
        }
        let (w, h) = (tile.width, tile.height);
        let whole = Bundled { tile, set: all, rays: RayRect { rays, width: w, x: 0..w, y: 0..h } };
        toward_fn(&whole, toward?, self.options.shadow_spread_limit)
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
        toward_fn: fn(&Bundled<V>, Vec3, f32) -> Option<B>,
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
                    let rays = RayRect { rays, width: w, x: x0..x1, y: y0..y1 };
                    match toward_fn(&Bundled { tile, set: &set, rays }, t, self.options.shadow_spread_limit) {
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
        let mut scratch = TileScratch::<V>::take();
        self.tracer.intersect_simd::<V>(&mut scratch, self.rays, self.width, self.height, self.out, self.stats);
        scratch.put_back();
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
        let Self { tracer, rays, width, height, toward, out, stats } = self;
        let mut scratch = TileScratch::<V>::take();
        tracer.occluded_simd::<V>(&mut scratch, rays, width, height, toward, out, stats);
        scratch.put_back();
    }
}

/// The buffers of a tile's occlusion walk ([`Tracer::occluded_simd`], [`Tracer::occluded_in_proxy_simd`]),
/// kept by kernels that trace many small tiles (a point's light samples) so that each does not allocate
/// them anew (cut anew, a 16-sample tile's packets cost two thirds as much as its proxy walk;
/// docs/BENCHMARKS.md, shading readings).
pub(crate) struct TileScratch<V: Vf32> {
    /// Indices of the packets that take part in the walk.
    pub all: Vec<usize>,
    /// Per packet, its blocked lanes.
    pub blocked: Vec<V::Mask>,
    /// The stack of packets traced alone.
    pub stack: PacketStack<V>,
    /// The tile of packets, refilled for each bundle ([`PacketTile::refill`]).
    pub tile: PacketTile<V>,
    /// Rays laid out for `tile` (edge-width walks put theirs one packet wide).
    pub rays: Vec<Option<Ray>>,
}

impl<V: Vf32> Default for TileScratch<V> {
    fn default() -> Self {
        Self {
            all: Vec::new(),
            blocked: Vec::new(),
            stack: PacketStack::default(),
            tile: PacketTile::empty(),
            rays: Vec::new(),
        }
    }
}

thread_local! {
    /// Each thread's spare [`TileScratch`], for the lane type it last traced a tile with.
    static SPARE_SCRATCH: Cell<Option<Box<dyn Any>>> = const { Cell::new(None) };
}

impl<V: Vf32> TileScratch<V> {
    /// This thread's spare buffers if they are for lane type `V`, else new ones: the kernels of one-tile calls
    /// ([`Tracer::intersect_tile`], [`Tracer::occluded_tile`], [`Tracer::edge_widths`],
    /// [`Tracer::occluded_in_proxy`]) would otherwise allocate a tile's packets, hits and stack for every call.
    /// A call nested in another finds none spare and allocates its own.
    pub(crate) fn take() -> Box<Self> {
        SPARE_SCRATCH.take().and_then(|spare| spare.downcast::<Self>().ok()).unwrap_or_default()
    }

    /// Leaves these buffers to the thread's next [`TileScratch::take`].
    pub(crate) fn put_back(self: Box<Self>) {
        SPARE_SCRATCH.set(Some(self));
    }
}

/// The fewest edge-width segments the bundled methods walk as one bundle; fewer go as packets. A bundle
/// descends more loosely than packets (its frustum holds all the segments) and tests each leaf against every
/// packet that may reach it, which pays only when many packets share the descent: on the Sponza view at
/// 1280x720 the bundle walks take the shadow stage 0.89x with this limit and with none, while at 512x512,
/// whose tiles hold fewer and less coherent segments, walking every tile as a bundle was 1.02-1.04x slower
/// (both measured when only the blocked segments walked, in row order).
const EDGE_BUNDLE_MIN_RAYS: usize = 128;

/// [`Tracer::edge_widths_simd`] as a [`Kernel`].
struct EdgeWidthsSimd<'t, 'a> {
    tracer: &'t Tracer<'a>,
    rays: &'t [Ray],
    toward: Option<Vec3>,
    states: &'t mut [EdgeWidth],
    out: &'t mut [f32],
    stats: &'t mut TraversalStats,
}

impl Kernel for EdgeWidthsSimd<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        let Self { tracer, rays, toward, states, out, stats } = self;
        let mut scratch = TileScratch::<V>::take();
        tracer.edge_widths_simd::<V>(&mut scratch, rays, toward, states, out, stats);
        scratch.put_back();
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

/// The cone, seen from `toward`, of the rays of `b` when they are segments that end there (shadow rays to a
/// light), like [`toward_frustum`].
fn toward_cone<V: Vf32>(b: &Bundled<V>, toward: Vec3, spread_limit: f32) -> Option<Cone> {
    let (segs, slack) = toward_segments(b.rays.clone(), toward, spread_limit)?;
    let mut c = Cone::bounding(toward, segs.iter().copied())?;
    widen_toward(&mut c.t_max, &mut c.origin_slack, toward, slack);
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

/// The rays a bundle is to bound: packets `set` of `tile`, which hold the valid rays of `rays`.
struct Bundled<'a, V: Vf32> {
    tile: &'a PacketTile<V>,
    set: &'a [usize],
    rays: RayRect<'a>,
}

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

/// The frustum, seen from `toward`, of the rays of `b` (its packets) when they are segments that end
/// there (shadow rays to a light: the thesis traces shadow rays from the light toward the surface points);
/// `None` when some segment does not end near it or the bundle spreads wider than `spread_limit`. A vector
/// of segments at a time, per lane with the operations of [`toward_segments`] and [`Frustum::bounding`] in
/// their order, so the frustum and its slack are theirs to the bit; only the mean direction of the spread
/// test is summed in another order, which can move a bundle right at the spread limit to the packet side.
#[inline(always)]
fn toward_frustum<V: Vf32>(b: &Bundled<V>, toward: Vec3, spread_limit: f32) -> Option<Frustum> {
    let (tile, set) = (b.tile, b.set);
    let (zero, inf, ninf) = (V::splat(0.0), V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
    let tw = [V::splat(toward.x), V::splat(toward.y), V::splat(toward.z)];
    let (mut gap_max, mut t_max) = (zero, ninf);
    let (mut pos_near, mut pos_far, mut neg_near, mut neg_far) = ([inf; 3], [ninf; 3], [ninf; 3], [inf; 3]);
    let (mut any_pos, mut any_neg) = ([false; 3], [false; 3]);
    let mut sum = [zero; 3];
    for p in set.iter().map(|&j| &tile.packets[j]).filter(|p| p.valid.any()) {
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
            let neg = valid & !pos;
            any_pos[k] |= pos.any();
            any_neg[k] |= neg.any();
            pos_near[k] = pos_near[k].min(V::select(pos, inv, inf));
            pos_far[k] = pos_far[k].max(V::select(pos, inv, ninf));
            neg_near[k] = neg_near[k].max(V::select(neg, inv, ninf));
            neg_far[k] = neg_far[k].min(V::select(neg, inv, inf));
            sum[k] = sum[k] + V::select(valid, d[k], zero);
        }
    }
    if !(0..3).any(|k| any_pos[k] || any_neg[k]) {
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
    for p in set.iter().map(|&j| &tile.packets[j]).filter(|p| p.valid.any()) {
        let (d, _, _) = toward_segment(p, &tw);
        let c = dot3(&d, &m);
        let cross = [d[1] * m[2] - m[1] * d[2], d[2] * m[0] - m[2] * d[0], d[0] * m[1] - m[0] * d[1]];
        let tangent = V::select(c.gt(zero), dot3(&cross, &cross).sqrt() / c, inf);
        spread = spread.max(V::select(p.valid, tangent, zero));
    }
    if spread.reduce_max() > spread_limit {
        return None;
    }
    let mut f = Frustum {
        origin: toward,
        pos_near: [0.0; 3],
        pos_far: [0.0; 3],
        neg_near: [0.0; 3],
        neg_far: [0.0; 3],
        t_min: 0.0,
        t_max: t_max.reduce_max(),
        origin_slack: 0.0,
    };
    for k in 0..3 {
        f.pos_near[k] = pos_near[k].reduce_min();
        f.pos_far[k] = pos_far[k].reduce_max();
        f.neg_near[k] = neg_near[k].reduce_max();
        f.neg_far[k] = neg_far[k].reduce_min();
    }
    f.close_sides(any_pos, any_neg);
    widen_toward(&mut f.t_max, &mut f.origin_slack, toward, gap_max.reduce_max());
    Some(f)
}

/// `a . b` per lane, summed in glam's order.
#[inline(always)]
fn dot3<V: Vf32>(a: &[V; 3], b: &[V; 3]) -> V {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
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
            let all: Vec<usize> = (0..tile.packets.len()).collect();
            let rays = RayRect { rays: self.rays, width: self.width, x: 0..self.width, y: 0..height };
            let packets =
                toward_frustum(&Bundled { tile: &tile, set: &all, rays: rays.clone() }, self.light, self.limit);
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
