//! How much of the light each hit of a layer sees, under the frame's shadow technique ([`Shadows`]).
//!
//! Hard shadows go through the frame's traversal method as one tile of segments ending at the light (so the
//! frustum methods trace them as frustums from the light, as the thesis does); the shadow cache is a
//! single-ray technique (DACRT, which traces sets, consults the cache for a whole layer at once); for edge
//! widths every segment walks the kd-tree, in Morton order over the layer: one ray at a time under the
//! single-ray methods, as one frustum or cone from the light for a tile with many of them under the bundled
//! methods, else in packets; multi-sampling traces each point's samples as one bundle: plain packets
//! (shared by neighbouring points when their samples are fewer than a packet's lanes), a pyramid fitted to
//! them, or a pyramid or cone around the light built before the samples ([`crate::trace::Proxy`]).

use raylab_simd::{Kernel, Vf32};

use crate::edge_width::EdgeWidth;
use crate::method::Walk;
use crate::packet::{MAX_LANES, packet_shape};
use crate::ray::{Hit, Ray};
use crate::scene::{PointLight, Scene};
use crate::shadow::{LightSamples, SampleBound, ShadowCache, Shadows};
use crate::stats::TraversalStats;
use crate::trace::{Proxy, TileScratch, Tracer};

use super::shade::{Surface, shadow_ray};
use crate::ray_order::RayOrder;

/// State of the shadow techniques (the shadow cache, edge-width buffers, light samples), reused from
/// layer to layer and tile to tile ([`ShadowScratch::start_tile`]); one per worker, never shared.
#[derive(Default)]
pub struct ShadowScratch {
    cache: ShadowCache,
    edge: Vec<EdgeWidth>,
    samples: LightSamples,
    pub(super) rays: Vec<Option<Ray>>,
    /// Where each point's rays start in `rays`, and how many there are (`None`: no point, or it faces away).
    starts: Vec<Option<(usize, usize)>>,
    blocked: Vec<bool>,
    /// The edge-width walks' segments, in [`ShadowScratch::gather_walks`]'s order, and their pixels.
    walks: Vec<Ray>,
    walk_pixels: Vec<usize>,
    /// A layer's pixels in Morton order, and the layer size they are for.
    morton: ((usize, usize), Vec<usize>),
    widths: Vec<f32>,
}

/// Traces the shadow rays of hit points under one technique.
pub struct ShadowTracer<'a> {
    /// The tracer (its method traces hard shadows; multi-sampling swaps in the bound's method).
    pub tracer: &'a Tracer<'a>,
    /// The light.
    pub light: PointLight,
    /// The technique.
    pub shadows: Shadows,
    /// How far shadow rays start off the surface, along its geometric normal.
    pub epsilon: f32,
}

impl ShadowScratch {
    /// Starts a new tile: the shadow cache forgets its blocker, which a tile elsewhere in the image found
    /// (kept, it would cost every lit ray of the new tile a test that rarely succeeds).
    pub fn start_tile(&mut self) {
        self.cache = ShadowCache::default();
    }

    /// Fills `walks` and `walk_pixels` with the segments of `rays` (a `width x height` layer) in Morton order,
    /// so that the walks' packets and bundles, which take consecutive segments, hold compact blocks of
    /// pixels rather than strips of rows (a 4x4 block for sixteen lanes), whose segments share more of the
    /// tree than a strip's.
    fn gather_walks(&mut self, width: usize, height: usize) {
        if self.morton.0 != (width, height) {
            let order = RayOrder::Morton.offsets(width as u32, height as u32);
            self.morton = ((width, height), order.iter().map(|&(x, y)| y as usize * width + x as usize).collect());
        }
        self.walks.clear();
        self.walk_pixels.clear();
        for &k in &self.morton.1 {
            if let Some(r) = self.rays[k] {
                self.walks.push(r);
                self.walk_pixels.push(k);
            }
        }
    }
}

impl ShadowTracer<'_> {
    /// Fills `sc.rays` with each surface's segment to the light's centre (`None` where there is no surface
    /// or it faces away): the rays of hard shadows, of the shadow cache over sets and of edge widths.
    fn segments_to_center(&self, surfaces: &[Option<Surface>], sc: &mut ShadowScratch) {
        let center = self.light.position;
        sc.rays.clear();
        sc.rays.extend(surfaces.iter().map(|s| s.as_ref().and_then(|s| shadow_ray(s, center, center, self.epsilon))));
    }

    /// The visibility of the light from the hit `hit` of `ray` alone; `seed` jitters light samples.
    pub fn at_hit(&self, scene: &Scene, ray: &Ray, hit: &Hit, seed: u32, stats: &mut TraversalStats) -> f32 {
        let surface = [Some(Surface::at(scene, ray, hit))];
        self.visibility(&surface, (1, 1), &[seed], stats, &mut ShadowScratch::default())[0]
    }

    /// The visibility in `[0, 1]` of the light from each surface of a `width x height` layer (0 where there is
    /// no surface or it faces away from the light).
    pub fn visibility(
        &self,
        surfaces: &[Option<Surface>],
        (width, height): (usize, usize),
        seeds: &[u32],
        stats: &mut TraversalStats,
        sc: &mut ShadowScratch,
    ) -> Vec<f32> {
        match self.shadows {
            Shadows::None => surfaces.iter().map(|s| if s.is_some() { 1.0 } else { 0.0 }).collect(),
            Shadows::Hard | Shadows::Cached | Shadows::EdgeWidth { .. } => {
                self.segments_to_center(surfaces, sc);
                self.segment_visibility((width, height), stats, sc)
            }
            Shadows::MultiSample { samples, bound } => {
                let mut out = Vec::with_capacity(surfaces.len());
                let kernel = MultiSampled { st: self, surfaces, seeds, samples, bound, stats, sc, out: &mut out };
                if self.tracer.options.method.entry().walk == Walk::BruteForce {
                    kernel.trace_with(&mut ReferenceBundles { tracer: self.tracer });
                } else {
                    raylab_simd::dispatch(self.tracer.options.backend, kernel);
                }
                out
            }
        }
    }

    /// The visibility in `[0, 1]` of the light along the segments in `sc.rays`, a `width x height` layer of
    /// segments from the surfaces to the light's centre (`None`: no surface, or it faces away; it sees
    /// nothing), under the techniques that trace those segments: hard shadows (by the frame's method), the
    /// shadow cache and edge widths. Under the others, whose visibility these segments do not give, every
    /// segment sees the whole light. The plain shading path builds the segments itself
    /// (`super::plain`), so the two paths share this.
    pub(super) fn segment_visibility(
        &self,
        (width, height): (usize, usize),
        stats: &mut TraversalStats,
        sc: &mut ShadowScratch,
    ) -> Vec<f32> {
        let center = self.light.position;
        let seen = |r: &Option<Ray>, blocked: bool| if r.is_some() && !blocked { 1.0 } else { 0.0 };
        match self.shadows {
            Shadows::Hard => {
                sc.blocked.clear();
                sc.blocked.resize(sc.rays.len(), false);
                if sc.rays.iter().any(Option::is_some) {
                    self.tracer.occluded_tile(&sc.rays, width, height, Some(center), &mut sc.blocked, stats);
                }
                sc.rays.iter().zip(&sc.blocked).map(|(r, &b)| seen(r, b)).collect()
            }
            Shadows::Cached if self.tracer.options.method.entry().walk == Walk::DacrtSet => {
                sc.blocked.clear();
                sc.blocked.resize(sc.rays.len(), false);
                sc.cache.occluded_set(self.tracer, &sc.rays, &mut sc.blocked, stats);
                sc.rays.iter().zip(&sc.blocked).map(|(r, &b)| seen(r, b)).collect()
            }
            Shadows::Cached => {
                let (cache, rays) = (&mut sc.cache, &sc.rays);
                rays.iter().map(|r| seen(r, r.is_some_and(|r| cache.occluded(self.tracer, &r, stats)))).collect()
            }
            Shadows::EdgeWidth { radius, leak_fix } => {
                // Every segment walks the tree: one that nothing blocks finds no crossing and sees the whole
                // light. A hard-shadow pass first, to walk only the blocked ones, would trace most segments
                // twice, since most are blocked or graze a blocker.
                // Scratch outlives frames (see `render`), whose edge settings may differ.
                if sc.edge.first().is_none_or(|e| e.settings() != (radius, leak_fix)) {
                    sc.edge.clear();
                }
                sc.gather_walks(width, height);
                let states = sc.walks.len().max(MAX_LANES);
                if sc.edge.len() < states {
                    sc.edge.resize(states, EdgeWidth::new(radius, leak_fix));
                }
                sc.widths.clear();
                sc.widths.resize(sc.walks.len(), 0.0);
                self.tracer.edge_widths(&sc.walks, Some(center), &mut sc.edge, &mut sc.widths, stats);
                let mut visible = vec![0.0; sc.rays.len()];
                for (&k, &w) in sc.walk_pixels.iter().zip(&sc.widths) {
                    visible[k] = 1.0 - w;
                }
                visible
            }
            Shadows::None | Shadows::MultiSample { .. } => sc.rays.iter().map(|r| seen(r, false)).collect(),
        }
    }
}

/// Multi-sampled visibility of a layer's points: each point's samples on the light, traced as one bundle
/// under the technique's bound (plain packets may hold the bundles of several neighbouring points). A
/// [`Kernel`], so that drawing the samples, building the rays and tracing them all run inside one SIMD
/// entry point per layer (drawn outside it, in baseline x86-64 code, the samples took about a seventh of a
/// 16-sample frame), with the tile buffers reused from point to point.
struct MultiSampled<'t, 'a> {
    st: &'t ShadowTracer<'a>,
    surfaces: &'t [Option<Surface<'a>>],
    seeds: &'t [u32],
    samples: u32,
    bound: SampleBound,
    stats: &'t mut TraversalStats,
    sc: &'t mut ShadowScratch,
    out: &'t mut Vec<f32>,
}

/// How [`MultiSampled`] traces one point's bundle (a trait rather than a closure, so that the SIMD
/// kernel's walk is always inlined into its entry point).
trait BundleTracer {
    /// Rays per packet of the walk (1 for ray-by-ray tracers).
    fn lanes(&self) -> usize;

    /// Marks in `blocked` which of `rays` (a `size` grid) something blocks, inside `proxy` where there is one.
    fn trace(
        &mut self,
        proxy: Option<&Proxy>,
        rays: &[Option<Ray>],
        size: (usize, usize),
        blocked: &mut [bool],
        stats: &mut TraversalStats,
    );
}

/// The brute-force reference, ray by ray (proxies are ignored).
struct ReferenceBundles<'t, 'a> {
    tracer: &'t Tracer<'a>,
}

impl BundleTracer for ReferenceBundles<'_, '_> {
    fn lanes(&self) -> usize {
        1
    }

    fn trace(
        &mut self,
        proxy: Option<&Proxy>,
        rays: &[Option<Ray>],
        size: (usize, usize),
        blocked: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        match proxy {
            Some(proxy) => self.tracer.occluded_in_proxy(proxy, rays, size, blocked, stats),
            None => self.tracer.occluded_tile(rays, size.0, size.1, None, blocked, stats),
        }
    }
}

/// The packet kernels with lane type `V`: the proxy's walk, or the bound's method, with buffers reused from
/// point to point.
struct SimdBundles<'a, V: Vf32> {
    tracer: Tracer<'a>,
    scratch: TileScratch<V>,
}

impl<V: Vf32> BundleTracer for SimdBundles<'_, V> {
    #[inline(always)]
    fn lanes(&self) -> usize {
        V::LANES
    }

    #[inline(always)]
    fn trace(
        &mut self,
        proxy: Option<&Proxy>,
        rays: &[Option<Ray>],
        size: (usize, usize),
        blocked: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        match proxy {
            Some(proxy) => self.tracer.occluded_in_proxy_simd(&mut self.scratch, proxy, rays, size, blocked, stats),
            None => self.tracer.occluded_simd(&mut self.scratch, rays, size.0, size.1, None, blocked, stats),
        }
    }
}

impl MultiSampled<'_, '_> {
    /// Fills `out` with each point's lit fraction, tracing its bundle with `tracer`. Plain packets do not
    /// need a point's samples to themselves: where they fill only part of a packet (4 samples in 8 or 16
    /// lanes, 8 in 16), the samples of that many neighbouring points share it.
    #[inline(always)]
    fn trace_with(self, tracer: &mut impl BundleTracer) {
        let Self { st, surfaces, seeds, samples, bound, stats, sc, out } = self;
        let (light, eps) = (&st.light, st.epsilon);
        let center = light.position;
        let (lanes, n) = (tracer.lanes(), samples as usize);
        let shared = bound == SampleBound::Packets && n < lanes && lanes % n == 0;
        let group = if shared { lanes / n } else { 1 };
        for (points, seeds) in surfaces.chunks(group).zip(seeds.chunks(group)) {
            sc.rays.clear();
            sc.starts.clear();
            let mut proxy = None;
            let mut size = (0, 0);
            for (s, &seed) in points.iter().zip(seeds) {
                let Some((s, apex)) = s.as_ref().and_then(|s| Some((s, shadow_ray(s, center, center, eps)?.origin)))
                else {
                    sc.starts.push(None);
                    continue;
                };
                sc.samples.generate(center, light.radius, s.point, samples, seed);
                sc.starts.push(Some((sc.rays.len(), sc.samples.points.len())));
                sc.rays.extend(sc.samples.points.iter().map(|&p| shadow_ray(s, center, p, eps)));
                size = (sc.samples.width as usize, sc.samples.height as usize);
                proxy = bound.proxy(apex, &sc.samples.disc);
            }
            if shared {
                // One packet's rows, in order: the points' samples follow one another along them.
                let (w, h) = packet_shape(lanes);
                sc.rays.resize(sc.rays.len().next_multiple_of(w * h), None);
                size = (w, sc.rays.len() / w);
            }
            sc.blocked.clear();
            sc.blocked.resize(sc.rays.len(), false);
            if !sc.rays.is_empty() {
                tracer.trace(proxy.as_ref(), &sc.rays, size, &mut sc.blocked, stats);
            }
            for start in &sc.starts {
                out.push(start.map_or(0.0, |(k, len)| {
                    let lit = sc.rays[k..k + len].iter().zip(&sc.blocked[k..]).filter(|(r, b)| r.is_some() && !**b);
                    lit.count() as f32 / len as f32
                }));
            }
        }
    }
}

impl Kernel for MultiSampled<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        let tracer = self.st.tracer.with_method(self.bound.method());
        self.trace_with(&mut SimdBundles::<V> { tracer, scratch: TileScratch::default() });
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// Edge-width walks take every segment of a layer once, in Morton order, and know its pixel.
    #[test]
    fn walks_cover_each_segment_once_in_morton_order() {
        let (width, height) = (5, 3);
        let ray = |k: usize| Ray::new(Vec3::new(k as f32, 0.0, 0.0), Vec3::Y);
        let mut sc = ShadowScratch {
            rays: (0..width * height).map(|k| (k % 4 != 1).then(|| ray(k))).collect(),
            ..ShadowScratch::default()
        };
        for (w, h) in [(width, height), (2, 1), (width, height)] {
            let rays = sc.rays.clone();
            sc.rays.truncate(w * h);
            sc.gather_walks(w, h);
            let want: Vec<usize> = RayOrder::Morton
                .offsets(w as u32, h as u32)
                .iter()
                .map(|&(x, y)| y as usize * w + x as usize)
                .filter(|&k| k % 4 != 1)
                .collect();
            assert_eq!(sc.walk_pixels, want, "{w}x{h}");
            for (r, &k) in sc.walks.iter().zip(&sc.walk_pixels) {
                assert_eq!(r.origin.x, k as f32, "{w}x{h}: the walk of pixel {k} holds another pixel's segment");
            }
            sc.rays = rays;
        }
        assert_eq!(sc.walk_pixels[..4], [0, 6, 2, 3], "two 2x2 blocks, pixels 1 and 5 empty");
    }
}
