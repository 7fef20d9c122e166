//! Occlusion of ray bundles bounded by a proxy known before the rays: a cone or a pyramid around a spherical
//! light, seen from the shaded point (Tsakok 2008, 4.1.6-4.1.9, Figure 4.5, Table 4.6).
//!
//! A frustum fitted to a bundle's rays costs a pass over them (the horizontal minima and maxima of Listing
//! 4.2); a proxy is built from the light alone, in constant time, and the bundle walks the kd-tree as one
//! interval whatever its rays are. The walk tests the bundle's packets at the leaves it reaches, so the
//! answer is exact as long as every ray lies inside the proxy.

use glam::Vec3;
use raylab_simd::{Kernel, VMask, Vf32};

use crate::method::Walk;
use crate::packet::{Cone, Frustum};
use crate::ray::Ray;
use crate::stats::TraversalStats;

use super::{TileScratch, Tracer};

/// A bound on a bundle of rays from one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Proxy {
    /// A pyramid frustum, walked through its extremal rays' per-axis ranges (Listing 4.2).
    Pyramid(Frustum),
    /// A cone frustum (Listings 4.3-4.5).
    Cone(Cone),
}

impl Proxy {
    /// The apex every ray of the bundle must start at.
    pub fn apex(&self) -> Vec3 {
        match self {
            Proxy::Pyramid(f) => f.origin,
            Proxy::Cone(c) => c.bound.origin,
        }
    }
}

impl Tracer<'_> {
    /// Marks in `out` which rays of a `width x height` tile something blocks, walking the kd-tree once with
    /// `proxy`, which must hold every ray's segment (all start at its apex). The brute-force reference
    /// ([`Walk::BruteForce`]) ignores the proxy and tests every ray alone, so the proxies are checked
    /// against it.
    pub fn occluded_in_proxy(
        &self,
        proxy: &Proxy,
        rays: &[Option<Ray>],
        (width, height): (usize, usize),
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        assert!(rays.len() == width * height && out.len() == rays.len());
        if self.options.method.entry().walk == Walk::BruteForce {
            return self.occluded_tile(rays, width, height, None, out, stats);
        }
        raylab_simd::dispatch(
            self.options.backend,
            OccludedInProxy { tracer: self, proxy, rays, size: (width, height), out, stats },
        );
    }
}

/// [`Tracer::occluded_in_proxy`]'s walk as a [`Kernel`], so the backend picks the lane type.
struct OccludedInProxy<'t, 'a> {
    tracer: &'t Tracer<'a>,
    proxy: &'t Proxy,
    rays: &'t [Option<Ray>],
    size: (usize, usize),
    out: &'t mut [bool],
    stats: &'t mut TraversalStats,
}

impl Kernel for OccludedInProxy<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        let Self { tracer, proxy, rays, size, out, stats } = self;
        let mut scratch = TileScratch::<V>::take();
        tracer.occluded_in_proxy_simd::<V>(&mut scratch, proxy, rays, size, out, stats);
        scratch.put_back();
    }
}

impl Tracer<'_> {
    /// [`Tracer::occluded_in_proxy`]'s walk with lane type `V` (not for the reference method): for kernels
    /// that trace many bundles in one dispatch.
    #[inline(always)]
    pub(crate) fn occluded_in_proxy_simd<V: Vf32>(
        &self,
        scratch: &mut TileScratch<V>,
        proxy: &Proxy,
        rays: &[Option<Ray>],
        (width, height): (usize, usize),
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        let TileScratch { blocked, tile, .. } = scratch;
        tile.refill(rays, width, height);
        let tile = &*tile;
        // A plain loop: vector code must be inlined into the SIMD entry point (see `map3`).
        for p in &tile.packets {
            let bits = p.valid.bits();
            stats.rays += bits.count_ones() as u64;
            stats.packets += (bits != 0) as u64;
        }
        // Every packet walks; those without a valid ray are never open at a leaf.
        let all = 0..tile.packets.len();
        blocked.clear();
        blocked.resize(tile.packets.len(), V::Mask::from_bits(0));
        let (tree, cull) = (self.tree(), self.options.cull);
        // The rays start at the apex, by the blockers near their surface point: nearest leaves first.
        match proxy {
            Proxy::Pyramid(f) => tree.occluded_frustum(f, tile, all, cull, false, blocked, stats),
            Proxy::Cone(c) => tree.occluded_frustum(c, tile, all, cull, false, blocked, stats),
        }
        for (j, b) in blocked.iter().enumerate() {
            let bits = b.bits();
            tile.for_each_lane(j, |pixel, lane| out[pixel] = bits >> lane & 1 == 1);
        }
    }
}
