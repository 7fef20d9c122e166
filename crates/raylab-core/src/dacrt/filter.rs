//! Ray filtering (Mora 2011): the rays whose current interval overlaps a box are moved, whole, to the front of
//! the ray list (Afra 2012 moves rays rather than indices, so later passes read them linearly).
//!
//! A node classifies its rays against both children's boxes in one pass, loading each ray into SIMD lanes
//! once. The box test runs on four or eight rays at once in SIMD lanes ([`Vf32`], the backend's widest, run
//! through [`raylab_simd::dispatch`]): each axis's entry and exit are taken in
//! the order the direction's sign gives and merged by `max`/`min`, whose SSE rule ignores a NaN first operand, so
//! a zero direction component with the origin on a slab plane (`0 * inf`) leaves that axis unconstrained. Boxes are padded by a
//! few ulps of their coordinates and far distances widened, so rounding never drops a ray that touches a
//! triangle inside: filtering may keep extra rays, never lose one.

use glam::Vec3;
use raylab_simd::{Backend, Kernel, VMask, Vf32};

use super::partition::partition;
use super::records::{RayRecord, row_lanes};
use crate::aabb::Aabb;

/// Relative widening of a box's far distance (pbrt's `1 + 2 gamma(3)`).
const FAR_SLACK: f32 = 2.0 * 3.0 * f32::EPSILON;
/// Relative padding of a box's planes.
const BOX_PAD: f32 = 16.0 * f32::EPSILON;

/// A box padded for conservative filtering.
#[derive(Clone, Copy, Debug)]
pub(super) struct FilterBox {
    min: Vec3,
    max: Vec3,
}

impl FilterBox {
    /// `b` grown by [`BOX_PAD`] of its coordinates' magnitude on every side.
    pub fn new(b: &Aabb) -> Self {
        let pad = (b.min.abs().max(b.max.abs()) * BOX_PAD) + Vec3::splat(f32::MIN_POSITIVE);
        Self { min: b.min - pad, max: b.max + pad }
    }
}

/// Bytes `0..4` of entry `m` are bits `0..4` of `m`: four lanes' mask bits spread into four flag bytes.
const SPREAD: [u32; 16] = {
    let mut t = [0u32; 16];
    let mut m = 0;
    while m < 16 {
        let mut lane = 0;
        while lane < 4 {
            t[m] |= ((m as u32 >> lane) & 1) << (8 * lane);
            lane += 1;
        }
        m += 1;
    }
    t
};

/// Sets bit `k` of `flags[i]` when ray `i` enters `boxes[k]` within its interval (the rays are loaded into
/// lanes once for all `N` boxes), with `backend`'s widest lanes.
pub(super) fn classify<const N: usize>(
    backend: Backend,
    rays: &[RayRecord],
    boxes: &[FilterBox; N],
    flags: &mut Vec<u8>,
) {
    raylab_simd::dispatch(backend.at_most_eight_lanes(), Classify { rays, boxes, flags });
}

/// [`classify_lanes`] as a [`Kernel`].
struct Classify<'a, const N: usize> {
    rays: &'a [RayRecord],
    boxes: &'a [FilterBox; N],
    flags: &'a mut Vec<u8>,
}

impl<const N: usize> Kernel for Classify<'_, N> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        classify_lanes::<V, N>(self.rays, self.boxes, self.flags);
    }
}

/// [`classify`] with lane type `V`.
#[inline(always)]
fn classify_lanes<V: Vf32, const N: usize>(rays: &[RayRecord], boxes: &[FilterBox; N], flags: &mut Vec<u8>) {
    debug_assert!(V::LANES <= 8 && N <= 8);
    let lanes = V::LANES;
    flags.clear();
    flags.resize(rays.len().next_multiple_of(lanes), 0);
    let splat = |v: Vec3| [V::splat(v.x), V::splat(v.y), V::splat(v.z)];
    let corners: [([V; 3], [V; 3]); N] = std::array::from_fn(|k| (splat(boxes[k].min), splat(boxes[k].max)));
    let zero = V::splat(0.0);
    let slack = V::splat(FAR_SLACK);
    for (block, out) in rays.chunks(lanes).zip(flags.chunks_exact_mut(lanes)) {
        let [ox, oy, oz, tmin] = row_lanes::<V>(block, 0);
        let [_, _, _, tmax] = row_lanes::<V>(block, 1);
        let [ix, iy, iz, _] = row_lanes::<V>(block, 2);
        let (org, inv) = ([ox, oy, oz], [ix, iy, iz]);
        let neg = [inv[0].lt(zero), inv[1].lt(zero), inv[2].lt(zero)];
        let mut bytes = 0u64;
        for (k, (bmin, bmax)) in corners.iter().enumerate() {
            let (mut near, mut far) = (tmin, tmax);
            for a in 0..3 {
                let lo = (bmin[a] - org[a]) * inv[a];
                let hi = (bmax[a] - org[a]) * inv[a];
                let enter = V::select(neg[a], hi, lo);
                let leave = V::select(neg[a], lo, hi);
                // `max`/`min` return their second operand when the first is NaN (origin on the plane, zero
                // direction), so such an axis changes nothing.
                near = enter.max(near);
                far = leave.min(far);
            }
            let bits = near.le(far + far.abs() * slack).bits() as usize;
            bytes |= (u64::from(SPREAD[bits & 15]) | u64::from(SPREAD[bits >> 4 & 15]) << 32) << k;
        }
        out.copy_from_slice(&bytes.to_le_bytes()[..lanes]);
    }
}

/// Moves the rays of `rays` that enter `b` to the front and returns how many there are; `flags` is scratch.
pub(super) fn filter(backend: Backend, rays: &mut [RayRecord], b: &FilterBox, flags: &mut Vec<u8>) -> usize {
    classify::<1>(backend, rays, &[*b], flags);
    let n = rays.len();
    partition(rays, &mut flags[..n], |f| f != 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::Ray;

    #[test]
    fn every_backend_keeps_exactly_the_rays_that_enter() {
        for backend in Backend::available() {
            check(backend);
        }
    }

    fn check(backend: Backend) {
        let b = FilterBox::new(&Aabb::new(Vec3::ZERO, Vec3::ONE));
        let cases = [
            (Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z), true),
            (Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::NEG_Z), false),
            (Ray::segment(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, 0.0, 0.5), false),
            (Ray::segment(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, 2.5, 9.0), false),
            // In the plane x = 0 with a zero x component, both signs of zero.
            (Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0)), true),
            (Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::new(-0.0, 0.0, 1.0)), true),
            (Ray::new(Vec3::new(1.0, 1.0, 3.0), Vec3::new(0.0, -0.0, -1.0)), true),
            (Ray::new(Vec3::new(1.5, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0)), false),
            // Grazing an edge, and starting inside.
            (Ray::new(Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)), true),
            (Ray::new(Vec3::splat(0.5), Vec3::new(-0.3, 0.2, 0.9)), true),
        ];
        let mut rays: Vec<RayRecord> =
            cases.iter().enumerate().map(|(i, (r, _))| RayRecord::new(r, i as u32)).collect();
        let mut flags = Vec::new();
        let k = filter(backend, &mut rays, &b, &mut flags);
        let mut kept: Vec<u32> = rays[..k].iter().map(|r| r.id).collect();
        kept.sort_unstable();
        let want: Vec<u32> = cases.iter().enumerate().filter(|c| c.1.1).map(|(i, _)| i as u32).collect();
        assert_eq!(kept, want, "{backend:?}");
        let mut all: Vec<u32> = rays.iter().map(|r| r.id).collect();
        all.sort_unstable();
        assert!(all.iter().copied().eq(0..cases.len() as u32));
    }
}
