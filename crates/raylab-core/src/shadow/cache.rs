//! The shadow cache (Akenine-Moller and Assarsson, Ray Tracing II, "The Shadow Cache"): any blocker proves a
//! point is in shadow, and neighbouring shadow rays tend to be blocked by the same triangle, so each shadow
//! ray first tests the triangle that blocked the previous one.

use crate::ray::Ray;
use crate::stats::TraversalStats;
use crate::trace::Tracer;

/// The last blocker found by the shadow rays of one tile (one cache per worker task, so no sharing).
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadowCache {
    last: Option<u32>,
}

impl ShadowCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// True when anything blocks `ray`: the cached triangle is tested first (a lookup, and a hit when it
    /// blocks), then the ray is traced, and the blocker it finds becomes the cached triangle.
    pub fn occluded(&mut self, tracer: &Tracer, ray: &Ray, stats: &mut TraversalStats) -> bool {
        if let Some(tri) = self.last {
            stats.cache_lookups += 1;
            stats.isect_tests += 1;
            if tracer.blocks(ray, tri) {
                stats.cache_hits += 1;
                stats.rays += 1;
                stats.packets += 1;
                return true;
            }
        }
        match tracer.occluder(ray, stats) {
            Some(tri) => {
                self.last = Some(tri);
                true
            }
            None => false,
        }
    }

    /// [`ShadowCache::occluded`] for a whole set of rays at once, for methods that trace sets (DACRT): every
    /// ray tests the cached triangle, the others are traced together, and the last blocker they find becomes
    /// the cached triangle. `out` receives the occlusion of each ray (`false` for `None`).
    pub fn occluded_set(
        &mut self,
        tracer: &Tracer,
        rays: &[Option<Ray>],
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        assert_eq!(rays.len(), out.len());
        let mut rest: Vec<Option<Ray>> = Vec::with_capacity(rays.len());
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = false;
            let cached = match (r, self.last) {
                (Some(r), Some(tri)) => {
                    stats.cache_lookups += 1;
                    stats.isect_tests += 1;
                    tracer.blocks(r, tri)
                }
                _ => false,
            };
            if cached {
                stats.cache_hits += 1;
                stats.rays += 1;
                stats.packets += 1;
                *o = true;
            }
            rest.push(if cached { None } else { *r });
        }
        let mut found = vec![None; rest.len()];
        tracer.occluders_tile(&rest, &mut found, stats);
        for (o, f) in out.iter_mut().zip(&found) {
            if let Some(tri) = f {
                *o = true;
                self.last = Some(*tri);
            }
        }
    }
}
