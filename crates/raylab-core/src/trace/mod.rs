//! Tracing a tile of rays with any method: the one entry point the renderer, the benchmark and the tests
//! share, so every method is driven the same way.
//!
//! Single-ray methods loop over the tile. Packet methods cut it into 2x2 packets. Frustum methods also need
//! the rays to share an origin (camera rays) or an end point (shadow rays toward a light, traced from the
//! light as in the thesis); otherwise they fall back to packets, which is always exact.

mod bundle;
mod kernels;
mod proxy;
mod scratch;

pub use proxy::Proxy;
pub(crate) use scratch::TileScratch;

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{Backend, VMask, Vf32};
use serde::Serialize;

use crate::dacrt::{Dacrt, DacrtParams};
use crate::edge_width::EdgeWidth;
use crate::intersector::Intersector;
use crate::kdtree::KdTree;
use crate::kdtree::mft::Frustum4;
use crate::kdtree::packet::PacketStack;
use crate::mbvh::{Mbvh, StreamLeaves, StreamOptions};
use crate::method::{BundleShape, Method, Purpose, Walk};
use crate::packet::PacketTile;
use crate::ray::{Hit, Ray};
use crate::ray_order::RayOrder;
use crate::reference::BruteForce;
use crate::stats::TraversalStats;
use crate::structures::{MissingStructure, Structures};
use bundle::{Bundled, RayRect, common_origin, cone_from, frustum_from, toward_cone, toward_frustum};
use kernels::{EdgeWidthsSimd, IntersectSimd, OccludedSimd};

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

/// Traces tiles of rays with one method through the [`Structures`] it was made from.
#[derive(Clone, Copy)]
pub struct Tracer<'a> {
    /// The kd-tree the method walks ([`MethodEntry::frame_kd`](crate::method::MethodEntry::frame_kd)); `None` only for the reference and for a
    /// [`Tracer::for_rays`] of a method whose kernel is another structure.
    tree: Option<&'a KdTree>,
    reference: Option<&'a BruteForce>,
    mbvh: Option<&'a Mbvh>,
    dacrt: Option<&'a Dacrt>,
    /// The options.
    pub options: TraceOptions,
}

impl<'a> Tracer<'a> {
    /// A tracer of `options.method` for whole frames: refused when `structures` lack the method's kernel
    /// structure or the kd-tree its frames walk ([`Method::structures`] with [`Purpose::Frames`]).
    pub fn new(structures: &'a Structures, options: TraceOptions) -> Result<Self, MissingStructure> {
        structures.check(options.method, Purpose::Frames)?;
        Ok(Self::from_structures(structures, options))
    }

    /// A tracer of `options.method` for tiles of rays only ([`Tracer::intersect_tile`],
    /// [`Tracer::occluded_tile`], [`Tracer::occluders_tile`]): needs only the method's kernel structure.
    /// Frames' edge-width and sampled-shadow walks need a tracer made with [`Tracer::new`].
    pub fn for_rays(structures: &'a Structures, options: TraceOptions) -> Result<Self, MissingStructure> {
        structures.check(options.method, Purpose::Rays)?;
        Ok(Self::from_structures(structures, options))
    }

    fn from_structures(s: &'a Structures, options: TraceOptions) -> Self {
        Self { tree: s.kd_for(options.method), reference: s.reference(), mbvh: s.mbvh(), dacrt: s.dacrt(), options }
    }

    /// The kd-tree the method walks. Present for every method but the reference when the tracer was made with
    /// [`Tracer::new`]; the reference never asks for it.
    fn tree(&self) -> &'a KdTree {
        self.tree.expect("a kd-tree walk needs a tracer made with Tracer::new (Purpose::Frames)")
    }

    fn dacrt(&self) -> &'a Dacrt {
        self.dacrt.expect("checked by Structures::check: the dacrt method has its preparation")
    }

    fn mbvh(&self) -> &'a Mbvh {
        self.mbvh.expect("checked by Structures::check: the mbvh methods have their MBVH")
    }

    fn reference(&self) -> &'a BruteForce {
        self.reference.expect("checked by Structures::check: the reference method has its brute force")
    }

    /// The kernel of the tracer's method.
    fn walk(&self) -> Walk {
        self.options.method.entry().walk
    }

    fn stream_options(&self) -> StreamOptions {
        StreamOptions { ordered: self.options.stream_order, leaves: self.options.stream_leaves }
    }

    /// The same tracer with another traversal method over the same kd-tree (the brute-force reference stays
    /// the reference): sampled shadows trace their bundles with the packet or frustum kernels.
    pub fn with_method(&self, method: Method) -> Tracer<'a> {
        let method = if self.walk() == Walk::BruteForce { self.options.method } else { method };
        Tracer { options: TraceOptions { method, ..self.options }, ..*self }
    }

    /// The first blocker found along a single ray (for the shadow cache).
    pub fn occluder(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<u32> {
        match self.walk() {
            Walk::BruteForce => self.reference().occluder(ray, stats),
            Walk::MbvhRay | Walk::MbvhStream => self.mbvh().occluder(ray, self.options.backend, stats),
            Walk::DacrtSet => {
                let mut out = [None];
                self.dacrt().occluders(&self.options.dacrt, self.options.backend, &[Some(*ray)], &mut out, stats);
                out[0]
            }
            Walk::KdRay | Walk::KdPacket | Walk::KdBundle(_) => self.tree().occluder(ray, stats),
        }
    }

    /// The first blocker found along each of `rays` (`None` entries and unblocked rays give `None`): one set
    /// for DACRT, ray by ray for the other methods.
    pub fn occluders_tile(&self, rays: &[Option<Ray>], out: &mut [Option<u32>], stats: &mut TraversalStats) {
        assert_eq!(rays.len(), out.len());
        if self.walk() == Walk::DacrtSet {
            self.dacrt().occluders(&self.options.dacrt, self.options.backend, rays, out, stats);
            return;
        }
        for (o, r) in out.iter_mut().zip(rays) {
            *o = r.and_then(|r| self.occluder(&r, stats));
        }
    }

    /// True when triangle `tri` blocks `ray`.
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        match self.walk() {
            Walk::BruteForce => self.reference().blocks(ray, tri),
            Walk::DacrtSet => self.dacrt().blocks(ray, tri),
            Walk::MbvhRay | Walk::MbvhStream => self.mbvh().blocks(ray, tri),
            Walk::KdRay | Walk::KdPacket | Walk::KdBundle(_) => self.tree().blocks(ray, tri),
        }
    }

    /// The edge-width occlusion of a single shadow ray (thesis Listing 5.1): the kd-tree's walk for every
    /// method (also for the MBVH and DACRT methods, which do not visit leaves in distance order, which the
    /// pairing relies on), or the brute-force reference for [`Walk::BruteForce`].
    pub fn edge_width(&self, ray: &Ray, state: &mut EdgeWidth, stats: &mut TraversalStats) -> f32 {
        match self.walk() {
            Walk::BruteForce => self.reference().edge_width(ray, state, stats),
            _ => self.tree().edge_width(ray, state, stats),
        }
    }

    /// The edge-width occlusions of `rays`, written to `out`; `states` holds at least as many states as
    /// there are rays, and at least [`crate::packet::MAX_LANES`], all with the frame's radius and leak-fix
    /// switch. The single-ray kd-tree kernel walks ray by ray (the reference by brute force). The bundled methods
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
        match self.walk() {
            Walk::BruteForce | Walk::KdRay => {
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
        let bundle = self.options.method.entry().bundle();
        let TileScratch { stack, tile, rays: grid, .. } = scratch;
        if let Some(shape) = bundle
            && let Some(toward) = toward.filter(|_| rays.len() >= EDGE_BUNDLE_MIN_RAYS)
        {
            // The rays in packet order: a tile one packet wide whose packets hold consecutive rays.
            let pw = PacketTile::<V>::PACKET_W;
            let height = rays.len().div_ceil(pw);
            grid.clear();
            grid.extend(rays.iter().copied().map(Some));
            grid.resize(pw * height, None);
            tile.refill(grid, pw, height);
            let (tile, grid) = (&*tile, &grid[..]);
            let whole = Bundled {
                tile,
                set: 0..tile.packets.len(),
                rays: RayRect { rays: grid, width: pw, x: 0..pw, y: 0..height },
            };
            let (limit, cull) = (self.options.shadow_spread_limit, self.options.cull);
            // `if let` rather than `Option::map` closures, whose vector code may stay out of line (see `map3`).
            if shape.is_cone() {
                if let Some(c) = toward_cone(&whole, toward, limit) {
                    self.tree().edge_widths_bundle(&c, tile, cull, states, out, stats);
                    return;
                }
            } else if let Some(f) = toward_frustum(&whole, toward, limit) {
                self.tree().edge_widths_bundle(&f, tile, cull, states, out, stats);
                return;
            }
        }
        self.tree().edge_widths::<V>(rays, states, out, stack, stats);
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
        match self.walk() {
            Walk::KdRay => closest_each(self.tree(), rays, out, stats),
            Walk::BruteForce => closest_each(self.reference(), rays, out, stats),
            Walk::MbvhRay => {
                let (mbvh, backend) = (self.mbvh(), self.options.backend);
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.and_then(|r| mbvh.intersect(&r, backend, stats));
                }
            }
            Walk::MbvhStream => self.in_groups(rays, width, height, out, |r, o| {
                self.mbvh().intersect_stream(r, o, self.stream_options(), self.options.backend, stats)
            }),
            Walk::DacrtSet => self.dacrt().intersect(&self.options.dacrt, self.options.backend, rays, out, stats),
            Walk::KdPacket | Walk::KdBundle(_) => raylab_simd::dispatch(
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
        match self.walk() {
            Walk::KdRay => occluded_each(self.tree(), rays, out, stats),
            Walk::BruteForce => occluded_each(self.reference(), rays, out, stats),
            Walk::MbvhRay => {
                let (mbvh, backend) = (self.mbvh(), self.options.backend);
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = r.is_some_and(|r| mbvh.occluded(&r, backend, stats));
                }
            }
            Walk::MbvhStream => self.in_groups(rays, width, height, out, |r, o| {
                self.mbvh().occluded_stream(r, o, self.stream_options(), self.options.backend, stats)
            }),
            Walk::DacrtSet => self.dacrt().occluded(&self.options.dacrt, self.options.backend, rays, out, stats),
            Walk::KdPacket | Walk::KdBundle(_) => raylab_simd::dispatch(
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
        let TileScratch { stack, tile, .. } = scratch;
        tile.refill(rays, width, height);
        let all = 0..tile.packets.len();
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        // Tiles no bundle covers are traced as packets (after the match, so the packet kernel is inlined once).
        let cull = self.options.cull;
        // The rays' common origin, found once for the tile: every bundle of its packets starts there.
        let bundle = self.options.method.entry().bundle();
        let shared = if bundle.is_some() { common_origin(&tile.packets) } else { None };
        if cull && let Some(origin) = shared {
            tile.share_origin(origin);
        }
        let bundled = match (bundle, shared) {
            (Some(BundleShape::Frustum), Some(o)) => {
                let f = frustum_from(o, tile, all.clone());
                if let Some(f) = &f {
                    self.tree().intersect_frustum(f, tile, all, cull, stats);
                }
                f.is_some()
            }
            (Some(BundleShape::Cone), Some(o)) => {
                let c = cone_from(o, tile, all.clone());
                if let Some(c) = &c {
                    self.tree().intersect_frustum(c, tile, all, cull, stats);
                }
                c.is_some()
            }
            (Some(BundleShape::MftFrustums), _) => {
                if let Some((b, sets, _)) = self.quadrants(tile, rays, None, shared, frustum_from, toward_frustum)
                    && let Some(f4) = Frustum4::new(b)
                {
                    self.tree().intersect_mft(&f4, tile, &sets, cull, stats);
                    true
                } else {
                    false
                }
            }
            (Some(BundleShape::MftCones), _) => {
                if let Some((b, sets, _)) = self.quadrants(tile, rays, None, shared, cone_from, toward_cone)
                    && let Some(c4) = Frustum4::new(b)
                {
                    self.tree().intersect_mft(&c4, tile, &sets, cull, stats);
                    true
                } else {
                    false
                }
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
        let tree = self.tree();
        for (p, h) in tile.packets.iter().zip(tile.hits.iter_mut()) {
            tree.intersect_packet(p, h, stack, stats);
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
        let TileScratch { blocked, stack, tile, .. } = scratch;
        tile.refill(rays, width, height);
        blocked.clear();
        blocked.resize(tile.packets.len(), V::Mask::from_bits(0));
        let all = 0..tile.packets.len();
        // The rays' common origin when they have one (camera rays), found once for the tile.
        let bundle = self.options.method.entry().bundle();
        let shared = if bundle.is_some() { common_origin(&tile.packets) } else { None };
        if self.options.cull
            && let Some(origin) = shared
        {
            tile.share_origin(origin);
        }
        let tile = &*tile;
        stats.rays += tile.packets.iter().map(|p| p.valid.bits().count_ones() as u64).sum::<u64>();
        stats.packets += tile.packets.iter().filter(|p| p.valid.bits() != 0).count() as u64;
        // Packets no bundle covers are traced as packets afterwards: all of them, or the quadrants' rest.
        let mut rest: [Range<usize>; 4] = Default::default();
        // A bundle whose apex is not the rays' shared origin was built from `toward`, the segments' far end,
        // and walks far side first.
        let far_first = |apex: Vec3| Some(apex) != shared;
        let cull = self.options.cull;
        match bundle {
            Some(BundleShape::Frustum) => {
                match self.whole(tile, all.clone(), rays, toward, shared, frustum_from, toward_frustum) {
                    Some(f) => self.tree().occluded_frustum(&f, tile, all, cull, far_first(f.origin), blocked, stats),
                    None => rest[0] = all,
                }
            }
            Some(BundleShape::Cone) => {
                match self.whole(tile, all.clone(), rays, toward, shared, cone_from, toward_cone) {
                    Some(c) => {
                        self.tree().occluded_frustum(&c, tile, all, cull, far_first(c.bound.origin), blocked, stats)
                    }
                    None => rest[0] = all,
                }
            }
            Some(BundleShape::MftFrustums) => {
                match self.quadrants(tile, rays, toward, shared, frustum_from, toward_frustum) {
                    Some((b, sets, left)) => {
                        if let Some(f4) = Frustum4::new(b) {
                            self.tree().occluded_mft(&f4, tile, &sets, cull, far_first(f4.origin()), blocked, stats);
                        }
                        rest = left;
                    }
                    None => rest[0] = all,
                }
            }
            Some(BundleShape::MftCones) => match self.quadrants(tile, rays, toward, shared, cone_from, toward_cone) {
                Some((b, sets, left)) => {
                    if let Some(c4) = Frustum4::new(b) {
                        self.tree().occluded_mft(&c4, tile, &sets, cull, far_first(c4.origin()), blocked, stats);
                    }
                    rest = left;
                }
                None => rest[0] = all,
            },
            None => rest[0] = all,
        }
        let tree = self.tree();
        for j in rest.into_iter().flatten() {
            blocked[j] = tree.occluded_packet(&tile.packets[j], stack, stats);
        }
        for (j, b) in blocked.iter().enumerate() {
            let bits = b.bits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = bits >> lane & 1 == 1);
        }
    }
}

/// Closest hits of `rays` one ray at a time, for the single-ray methods.
fn closest_each<I: Intersector>(i: &I, rays: &[Option<Ray>], out: &mut [Option<Hit>], stats: &mut TraversalStats) {
    for (o, r) in out.iter_mut().zip(rays) {
        *o = r.and_then(|r| i.intersect(&r, stats));
    }
}

/// Occlusion of `rays` one ray at a time, for the single-ray methods.
fn occluded_each<I: Intersector>(i: &I, rays: &[Option<Ray>], out: &mut [bool], stats: &mut TraversalStats) {
    for (o, r) in out.iter_mut().zip(rays) {
        *o = r.is_some_and(|r| i.occluded(&r, stats));
    }
}

/// The fewest edge-width segments the bundled methods walk as one bundle; fewer go as packets. A bundle
/// descends more loosely than packets (its frustum holds all the segments) and tests each leaf against every
/// packet that may reach it, which pays only when many packets share the descent. Large frames' tiles hold
/// many coherent segments and gain from bundles; small frames' tiles hold few and scattered ones, which lose.
const EDGE_BUNDLE_MIN_RAYS: usize = 128;

/// Single rays through the tracer's method, each as a tile of one (the method's kernels, backend and options).
impl Intersector for Tracer<'_> {
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        let mut out = [None];
        self.intersect_tile(&[Some(*ray)], 1, 1, &mut out, stats);
        out[0]
    }
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        let mut out = [false];
        self.occluded_tile(&[Some(*ray)], 1, 1, None, &mut out, stats);
        out[0]
    }
}
