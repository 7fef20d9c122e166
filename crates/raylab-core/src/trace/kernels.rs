//! The tracer's SIMD entry points as [`Kernel`]s: each takes this thread's spare [`TileScratch`], lets the
//! backend chosen at run time (`raylab_simd::dispatch`) pick the lane type, and calls the tile walk.

use glam::Vec3;
use raylab_simd::{Kernel, Vf32};

use super::{TileScratch, Tracer};
use crate::edge_width::EdgeWidth;
use crate::ray::{Hit, Ray};
use crate::stats::TraversalStats;

/// [`Tracer::intersect_simd`] as a [`Kernel`], so the backend picks the lane type.
pub(super) struct IntersectSimd<'t, 'a> {
    pub(super) tracer: &'t Tracer<'a>,
    pub(super) rays: &'t [Option<Ray>],
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) out: &'t mut [Option<Hit>],
    pub(super) stats: &'t mut TraversalStats,
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
pub(super) struct OccludedSimd<'t, 'a> {
    pub(super) tracer: &'t Tracer<'a>,
    pub(super) rays: &'t [Option<Ray>],
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) toward: Option<Vec3>,
    pub(super) out: &'t mut [bool],
    pub(super) stats: &'t mut TraversalStats,
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

/// [`Tracer::edge_widths_simd`] as a [`Kernel`].
pub(super) struct EdgeWidthsSimd<'t, 'a> {
    pub(super) tracer: &'t Tracer<'a>,
    pub(super) rays: &'t [Ray],
    pub(super) toward: Option<Vec3>,
    pub(super) states: &'t mut [EdgeWidth],
    pub(super) out: &'t mut [f32],
    pub(super) stats: &'t mut TraversalStats,
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
