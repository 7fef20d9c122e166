//! The interval form of a bundle of rays from one origin (thesis 2.3.2, Listing 4.2): the frustum the
//! frustum walks descend a kd-tree with, and the per-sign bounds it is built from.

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{Disc, RayPacket};
use crate::aabb::coord;

/// A bundle of rays from one origin, seen by the frustum walks only through the range of distances at which
/// its rays cross an axis-aligned plane, which four factors per axis give by the side of the origin the plane
/// lies on (`sign_crossing`): pyramid [`Frustum`]s and [`super::Cone`]s implement it, each through its
/// interval form.
pub trait Bundle {
    /// The bundle's interval form: origin, distance range, origin slack and per-axis factors.
    fn interval(&self) -> &Frustum;

    /// The common origin.
    #[inline(always)]
    fn origin(&self) -> Vec3 {
        self.interval().origin
    }
    /// The range of distances the walk starts with.
    #[inline(always)]
    fn t_range(&self) -> (f32, f32) {
        (self.interval().t_min, self.interval().t_max)
    }
    /// Distance by which the bundle's segments may miss its origin (see [`Frustum::origin_slack`]).
    #[inline(always)]
    fn origin_slack(&self) -> f32 {
        self.interval().origin_slack
    }
    /// Axis `k`'s factors `[pos_near, pos_far, neg_near, neg_far]` (see [`Frustum`]).
    #[inline(always)]
    fn factors(&self, k: usize) -> [f32; 4] {
        let f = self.interval();
        [f.pos_near[k], f.pos_far[k], f.neg_near[k], f.neg_far[k]]
    }
    /// The range of distances at which the bundle crosses the plane `coordinate k = split`; infinite bounds
    /// mean "some ray never crosses in front of the origin".
    #[inline(always)]
    fn crossing(&self, k: usize, split: f32) -> (f32, f32) {
        sign_crossing(split - coord(&self.origin(), k), self.origin_slack(), self.factors(k))
    }
}

impl Bundle for Frustum {
    #[inline(always)]
    fn interval(&self) -> &Frustum {
        self
    }
}

/// Bounds, for every axis, of the parameters at which the rays of a bundle from one common origin cross an
/// axis-aligned plane: the interval form of a frustum (thesis 2.3.2 and Listing 4.2, with the omni-directional
/// changes of 4.1.2). Parameters are each ray's own `t`; an interval `[near, far]` holds every `t` at which
/// some ray of the bundle is inside a cell, so rays need not have unit directions.
///
/// For a plane at signed distance `dist = split - origin[k]`, a ray with direction `u` crosses it at
/// `dist / u_k` when that is positive, and never otherwise. With `dist > 0` only rays with `1/u_k > 0` cross,
/// at `dist * [min, max]` of those inverses, and any ray going the other way makes the far bound infinite;
/// `dist < 0` mirrors this with the negative inverses. So four precomputed factors per axis give both bounds
/// with one multiply each, for any mix of direction signs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// The common origin.
    pub origin: Vec3,
    /// `dist > 0`: near factor (smallest positive inverse, or +inf when no ray goes that way).
    pub pos_near: [f32; 3],
    /// `dist > 0`: far factor (largest positive inverse; +inf when some ray goes the other way).
    pub pos_far: [f32; 3],
    /// `dist < 0`: near factor (negative inverse closest to zero, or -inf when none).
    pub neg_near: [f32; 3],
    /// `dist < 0`: far factor (most negative inverse; -inf when some ray goes the other way).
    pub neg_far: [f32; 3],
    /// Smallest start distance of the rays.
    pub t_min: f32,
    /// Largest end distance of the rays.
    pub t_max: f32,
    /// Distance by which the bundle's segments may miss `origin` (0 for rays that start there). Shadow rays
    /// traced from the light end at `p + d * t_max`, which rounding puts a little off the light; planes
    /// closer than this to the origin are crossed in both directions, and crossing bounds widen by it.
    pub origin_slack: f32,
}

impl Frustum {
    /// The frustum of segments `(direction, start, end)` from `origin`; `None` for an empty bundle.
    pub fn bounding(origin: Vec3, segments: impl IntoIterator<Item = (Vec3, f32, f32)>) -> Option<Self> {
        let mut f = Frustum {
            origin,
            pos_near: [f32::INFINITY; 3],
            pos_far: [f32::NEG_INFINITY; 3],
            neg_near: [f32::NEG_INFINITY; 3],
            neg_far: [f32::INFINITY; 3],
            t_min: f32::INFINITY,
            t_max: f32::NEG_INFINITY,
            origin_slack: 0.0,
        };
        let (mut any_pos, mut any_neg) = ([false; 3], [false; 3]);
        let mut any = false;
        for (dir, t0, t1) in segments {
            any = true;
            f.t_min = f.t_min.min(t0);
            f.t_max = f.t_max.max(t1);
            for k in 0..3 {
                let inv = 1.0 / dir[k];
                if inv > 0.0 {
                    any_pos[k] = true;
                    f.pos_near[k] = f.pos_near[k].min(inv);
                    f.pos_far[k] = f.pos_far[k].max(inv);
                } else {
                    any_neg[k] = true;
                    f.neg_near[k] = f.neg_near[k].max(inv);
                    f.neg_far[k] = f.neg_far[k].min(inv);
                }
            }
        }
        if !any {
            return None;
        }
        f.close_sides(any_pos, any_neg);
        Some(f)
    }

    /// Finishes a frustum whose factors hold the extreme inverses of its rays, `any_pos[k]` and `any_neg[k]`
    /// telling whether some ray goes each way on axis `k`: a far factor becomes infinite where some ray goes
    /// the other way (or none goes this way), and `t_min` starts at zero at the earliest.
    pub(crate) fn close_sides(&mut self, any_pos: [bool; 3], any_neg: [bool; 3]) {
        for k in 0..3 {
            if any_neg[k] || !any_pos[k] {
                self.pos_far[k] = f32::INFINITY;
            }
            if any_pos[k] || !any_neg[k] {
                self.neg_far[k] = f32::NEG_INFINITY;
            }
        }
        self.t_min = self.t_min.max(0.0);
    }

    /// The square pyramid from `apex` around `disc` (the face of a spherical light turned toward a shaded
    /// point), whose sides run along the axes of the samples' strata ([`Vec3::any_orthonormal_pair`] of the
    /// normal): the pyramid counterpart of [`super::Cone::around_disc`], walked through its four corner
    /// (extremal) rays as Listing 4.2 does. Distances are depths along the disc's normal (at most the distance
    /// along a unit direction, so the walk stays conservative). `None` where the cone proxy is `None`.
    pub fn around_disc(apex: Vec3, disc: &Disc) -> Option<Self> {
        let span = disc.span_from(apex)?;
        let (u, v) = disc.normal.any_orthonormal_pair();
        // The corners' range on each axis: the centre direction plus or minus the reach along both sides.
        let half = |k: usize| span.reach * (u[k].abs() as f64 + v[k].abs() as f64) + 1e-6;
        let lo = Vec3::from_array(std::array::from_fn(|k| (span.center_dir[k] - half(k)) as f32));
        let hi = Vec3::from_array(std::array::from_fn(|k| (span.center_dir[k] + half(k)) as f32));
        Self::bounding(apex, [(lo, 0.0, span.depth), (hi, 0.0, span.depth)])
    }

    /// The frustum of the valid rays of `packets`, which must all start at `origin`, from the packets'
    /// inverse directions (no division per ray).
    #[inline(always)]
    pub fn from_packets<V: Vf32>(origin: Vec3, packets: &[RayPacket<V>]) -> Option<Self> {
        let (inf, ninf, zero) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY), V::splat(0.0));
        let mut sides = SignBounds::<V>::new();
        let (mut t_min, mut t_max) = (inf, ninf);
        let mut any = false;
        for p in packets {
            if p.valid.none() {
                continue;
            }
            any = true;
            t_min = V::select(p.valid, p.tmin.min(t_min), t_min);
            t_max = V::select(p.valid, p.tmax.max(t_max), t_max);
            for k in 0..3 {
                let pos = p.valid & p.inv[k].gt(zero);
                sides.add(k, pos, p.valid & !pos, p.inv[k], p.inv[k]);
            }
        }
        if !any {
            return None;
        }
        Some(sides.frustum(origin, t_min.reduce_min(), t_max.reduce_max()))
    }
}

/// Per-lane running bounds of a bundle's inverse directions on each axis, by sign, and the frustum they
/// give: what [`Frustum::from_packets`], the batched frustums of [`super::BatchCull`] and the frustums of
/// shadow segments seen from a light accumulate, each from its own lanes (rays or packets' ranges).
pub(crate) struct SignBounds<V: Vf32> {
    pos_near: [V; 3],
    pos_far: [V; 3],
    neg_near: [V; 3],
    neg_far: [V; 3],
    any_pos: [bool; 3],
    any_neg: [bool; 3],
}

impl<V: Vf32> SignBounds<V> {
    /// No lanes yet.
    #[inline(always)]
    pub fn new() -> Self {
        let (inf, ninf) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        Self {
            pos_near: [inf; 3],
            pos_far: [ninf; 3],
            neg_near: [ninf; 3],
            neg_far: [inf; 3],
            any_pos: [false; 3],
            any_neg: [false; 3],
        }
    }

    /// Adds, on axis `k`, lanes `pos` whose inverse directions are positive and lanes `neg` whose are not,
    /// each lane's inverses lying in `[lo, hi]` (`lo == hi` for a single ray).
    #[inline(always)]
    pub fn add(&mut self, k: usize, pos: V::Mask, neg: V::Mask, lo: V, hi: V) {
        let (inf, ninf) = (V::splat(f32::INFINITY), V::splat(f32::NEG_INFINITY));
        self.any_pos[k] |= pos.any();
        self.any_neg[k] |= neg.any();
        self.pos_near[k] = self.pos_near[k].min(V::select(pos, lo, inf));
        self.pos_far[k] = self.pos_far[k].max(V::select(pos, hi, ninf));
        self.neg_near[k] = self.neg_near[k].max(V::select(neg, hi, ninf));
        self.neg_far[k] = self.neg_far[k].min(V::select(neg, lo, inf));
    }

    /// Whether any lane was added.
    #[inline(always)]
    pub fn any(&self) -> bool {
        (0..3).any(|k| self.any_pos[k] || self.any_neg[k])
    }

    /// The frustum from `origin` with these bounds and distances `[t_min, t_max]`, `t_min` raised to 0 when
    /// negative (the walks start no nearer than the origin).
    #[inline(always)]
    pub fn frustum(&self, origin: Vec3, t_min: f32, t_max: f32) -> Frustum {
        let (pn, pf, nn, nf) = (&self.pos_near, &self.pos_far, &self.neg_near, &self.neg_far);
        let mut f = Frustum {
            origin,
            // Written out: `map3` with `V::reduce_min` as a function item may call a shim that is neither inlined
            // nor compiled for the kernel's instruction set (seen in callgrind as `Fn::call` around `vcmpps`).
            pos_near: [pn[0].reduce_min(), pn[1].reduce_min(), pn[2].reduce_min()],
            pos_far: [pf[0].reduce_max(), pf[1].reduce_max(), pf[2].reduce_max()],
            neg_near: [nn[0].reduce_max(), nn[1].reduce_max(), nn[2].reduce_max()],
            neg_far: [nf[0].reduce_min(), nf[1].reduce_min(), nf[2].reduce_min()],
            t_min,
            t_max,
            origin_slack: 0.0,
        };
        f.close_sides(self.any_pos, self.any_neg);
        f
    }
}

/// The range of distances at which a bundle crosses a plane at signed distance `dist` from its origin, from
/// its axis's four factors `[pos_near, pos_far, neg_near, neg_far]` (see [`Frustum`]); a plane within `slack`
/// of the origin may be crossed at any distance, and the bounds widen by it.
#[inline(always)]
fn sign_crossing(dist: f32, slack: f32, [pos_near, pos_far, neg_near, neg_far]: [f32; 4]) -> (f32, f32) {
    if dist > slack {
        ((dist - slack) * pos_near, (dist + slack) * pos_far)
    } else if dist < -slack {
        ((dist + slack) * neg_near, (dist - slack) * neg_far)
    } else {
        (0.0, f32::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_bounds_every_ray() {
        let o = Vec3::new(0.5, -1.0, 2.0);
        let dirs =
            [Vec3::new(1.0, 0.2, -0.1), Vec3::new(0.8, -0.3, 0.4), Vec3::new(0.9, 0.0, 0.0), Vec3::new(1.0, 0.5, -0.5)]
                .map(|d| d.normalize());
        let f = Frustum::bounding(o, dirs.iter().map(|&d| (d, 0.0, 10.0))).unwrap();
        for k in 0..3 {
            for split in [-3.0f32, -0.7, 0.1, 0.5, 2.0, 4.0] {
                let (lo, hi) = f.crossing(k, split);
                assert!(lo <= hi, "axis {k} split {split}");
                for d in dirs {
                    let t = (split - o[k]) / d[k];
                    if t > 0.0 && t.is_finite() {
                        assert!(
                            t >= lo * (1.0 - 1e-6) && t <= hi * (1.0 + 1e-6),
                            "axis {k} split {split}: {t} not in [{lo}, {hi}]"
                        );
                    }
                }
            }
        }
        // Mixed signs on y: the far bound becomes infinite on both sides of the origin.
        assert_eq!(f.crossing(1, 0.0).1, f32::INFINITY);
        assert_eq!(f.crossing(1, 5.0).1, f32::INFINITY);
    }
}
