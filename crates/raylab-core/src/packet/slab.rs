//! A packet against an axis-aligned box: the slab test per lane (thesis 2.3.1), and the overlap test that
//! packet/leaf culling uses (thesis 4.1.4).

use raylab_simd::Vf32;

use super::RayPacket;
use crate::aabb::Aabb;

/// Per lane, the interval `[t0, t1]` in which the packet's ray is inside box `b`, clipped to `[tmin, tmax]`
/// (empty when `t0 > t1`). A lane with a zero direction component is constrained by that slab only through
/// its origin; the fast path skips that case when no lane has one.
#[inline(always)]
pub fn slab_interval<V: Vf32>(p: &RayPacket<V>, b: &Aabb, tmin: V, tmax: V) -> (V, V) {
    let (mut t0, mut t1) = (tmin, tmax);
    if p.finite_inv {
        for k in 0..3 {
            let ta = (V::splat(b.min[k]) - p.org[k]) * p.inv[k];
            let tb = (V::splat(b.max[k]) - p.org[k]) * p.inv[k];
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    } else {
        let inf = V::splat(f32::INFINITY);
        for k in 0..3 {
            let (lo, hi) = (V::splat(b.min[k]), V::splat(b.max[k]));
            let parallel = p.inv[k].abs().eq(inf);
            let outside = p.org[k].lt(lo) | p.org[k].gt(hi);
            let ta = (lo - p.org[k]) * p.inv[k];
            let tb = (hi - p.org[k]) * p.inv[k];
            let enter = V::select(parallel, V::select(outside, inf, V::splat(f32::NEG_INFINITY)), ta.min(tb));
            let exit = V::select(parallel, V::select(outside, V::splat(f32::NEG_INFINITY), inf), ta.max(tb));
            t0 = t0.max(enter);
            t1 = t1.min(exit);
        }
    }
    (t0, t1)
}

/// The lanes of `p` whose ray overlaps box `b` within `(tmin, limit]` (the packet/leaf culling test of
/// thesis 4.1.4), allowing `slack`.
#[inline(always)]
pub fn overlaps_box<V: Vf32>(p: &RayPacket<V>, b: &Aabb, limit: V, slack: f32) -> V::Mask {
    let (t0, t1) = slab_interval(p, b, p.tmin, limit);
    p.valid & (t0 * V::splat(1.0 - slack)).le(t1 * V::splat(1.0 + slack))
}
