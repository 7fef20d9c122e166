//! Axis-aligned bounding boxes.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// An axis-aligned box given by its minimum and maximum corners.
///
/// The empty box has `min = +inf` and `max = -inf`, so that growing it by any point gives that point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

/// Component `k` of `v`, read as an array element. glam's `Index` matches on `k`, a branch that traversal
/// loops, where `k` is each node's split axis, mispredict often; this is a plain indexed load.
#[inline(always)]
pub fn coord(v: &Vec3, k: usize) -> f32 {
    AsRef::<[f32; 3]>::as_ref(v)[k]
}

/// Mutable component `k` of `v` (see [`coord`]).
#[inline(always)]
pub fn coord_mut(v: &mut Vec3, k: usize) -> &mut f32 {
    &mut AsMut::<[f32; 3]>::as_mut(v)[k]
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (contains nothing; the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The box spanning two corners.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding all `points`.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    /// This box grown to hold `p`.
    pub fn grow(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The smallest box holding both boxes.
    pub fn union(self, o: Aabb) -> Self {
        Self { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// The overlap of both boxes (possibly empty).
    pub fn intersection(self, o: Aabb) -> Self {
        Self { min: self.min.max(o.min), max: self.max.min(o.max) }
    }

    /// True when the box holds no point (some `min > max`).
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Edge lengths (zero for an empty box).
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f32 {
        self.extent().length()
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area, the probability measure of the SAH (thesis Eq. 2.1); zero for an empty box, also one
    /// empty along a single axis (such as the intersection of boxes that do not overlap), whose clamped
    /// extent would otherwise count two of its faces.
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index (0, 1, 2) of the longest axis.
    pub fn longest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// The box grown on every side by `pad` times its diagonal plus `pad` times the largest coordinate
    /// magnitude, so that it also grows for flat boxes and for boxes far from the origin.
    pub fn padded(&self, pad: f32) -> Self {
        let mag = self.min.abs().max(self.max.abs()).max_element();
        let d = pad * (self.diagonal() + mag) + f32::MIN_POSITIVE;
        Self { min: self.min - Vec3::splat(d), max: self.max + Vec3::splat(d) }
    }

    /// The parametric interval `[t0, t1]` in which the ray `origin + t * dir` (given by its inverse direction)
    /// is inside the box, clipped to `[tmin, tmax]`; `None` when the ray misses.
    ///
    /// An axis with an infinite inverse direction (a zero direction component) constrains nothing when the
    /// origin lies within that slab, boundary included, and misses otherwise; this avoids the NaN of `0 * inf`.
    pub fn clip_ray(&self, origin: Vec3, inv_dir: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
        let (lo, hi, o, inv) = (self.min.to_array(), self.max.to_array(), origin.to_array(), inv_dir.to_array());
        let mut t0 = tmin;
        let mut t1 = tmax;
        // Straight-line code per axis (selects, no early return), so the three axes overlap: an axis that
        // misses empties the interval instead of returning. Nothing here is NaN for a valid ray (finite
        // origin, a finite inverse where it is used, non-NaN `tmin` and `tmax`), so plain comparisons give
        // `f32::min`/`max`'s values with one instruction each.
        for k in 0..3 {
            let (enter, exit) = if inv[k].is_infinite() {
                if o[k] < lo[k] || o[k] > hi[k] { (f32::INFINITY, f32::NEG_INFINITY) } else { (t0, t1) }
            } else {
                let ta = (lo[k] - o[k]) * inv[k];
                let tb = (hi[k] - o[k]) * inv[k];
                if ta < tb { (ta, tb) } else { (tb, ta) }
            };
            t0 = if enter > t0 { enter } else { t0 };
            t1 = if exit < t1 { exit } else { t1 };
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_area_and_union() {
        let a = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(a.surface_area(), 2.0 * (2.0 + 6.0 + 3.0));
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let apart = a.intersection(Aabb::new(Vec3::new(5.0, 0.0, 0.0), Vec3::new(6.0, 2.0, 3.0)));
        assert_eq!(apart.surface_area(), 0.0, "disjoint along x only: {apart:?}");
        let b = Aabb::EMPTY.union(a);
        assert_eq!(a, b);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(a.longest_axis(), 2);
    }

    /// The slab test written plainly: an early miss for an axis-parallel ray outside its slab, `f32::min`
    /// and `max` for the others.
    fn clip_reference(b: &Aabb, o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
        let (mut t0, mut t1) = (tmin, tmax);
        for k in 0..3 {
            if inv[k].is_infinite() {
                if o[k] < b.min[k] || o[k] > b.max[k] {
                    return None;
                }
                continue;
            }
            let (ta, tb) = ((b.min[k] - o[k]) * inv[k], (b.max[k] - o[k]) * inv[k]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        (t0 <= t1).then_some((t0, t1))
    }

    #[test]
    fn clip_ray_matches_the_plain_slab_test() {
        let b = Aabb::new(Vec3::new(-1.0, -2.0, 0.5), Vec3::new(3.0, 1.0, 4.0));
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32 * 10.0 - 5.0
        };
        for i in 0..20_000 {
            let o = Vec3::new(next(), next(), next());
            let mut d = Vec3::new(next(), next(), next());
            // Zero components of both signs, and whole axis-parallel rays.
            if i % 5 == 0 {
                d[i % 3] = if i % 2 == 0 { 0.0 } else { -0.0 };
            }
            if i % 17 == 0 {
                d = Vec3::new(0.0, 0.0, 1.0);
            }
            let (tmin, tmax) = if i % 7 == 0 { (next().abs(), next().abs()) } else { (0.0, f32::INFINITY) };
            let inv = Vec3::ONE / d;
            assert_eq!(b.clip_ray(o, inv, tmin, tmax), clip_reference(&b, o, inv, tmin, tmax), "{o} {d} {tmin} {tmax}");
        }
    }

    #[test]
    fn clip_ray_handles_axis_parallel_rays() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let inv = Vec3::new(1.0, f32::INFINITY, f32::INFINITY);
        // Origin on the y = 0 slab plane with a zero y direction: 0 * inf is NaN, treated as inside.
        let r = b.clip_ray(Vec3::new(-1.0, 0.0, 0.5), inv, 0.0, f32::INFINITY);
        assert_eq!(r, Some((1.0, 2.0)));
        // Outside the y slab: miss.
        assert_eq!(b.clip_ray(Vec3::new(-1.0, 2.0, 0.5), inv, 0.0, f32::INFINITY), None);
    }
}
