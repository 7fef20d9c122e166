//! The single-ray query interface every structure answers (thesis 2.1: closest hit for camera and secondary
//! rays, any hit for shadow rays).

use crate::ray::{Hit, Ray};
use crate::stats::TraversalStats;

/// Closest-hit and any-hit queries on single rays.
pub trait Intersector: Sync {
    /// The closest hit in `(tmin, tmax]`.
    fn intersect(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit>;
    /// True when anything blocks the ray in `(tmin, tmax]`.
    fn occluded(&self, ray: &Ray, stats: &mut TraversalStats) -> bool;
}
