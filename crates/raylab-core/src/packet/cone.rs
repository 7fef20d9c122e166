//! Cone frustums (Tsakok 2008, 4.1.6-4.1.8, Eq. 4.8, Listings 4.3-4.5): a bundle bounded by a cone with apex
//! at the common origin, axis `v` and half-angle `alpha`.
//!
//! Distances along a cone are depths along its axis. A ray at angle `theta <= alpha` from `v` has
//! `u_k / cos(theta) = v_k + tan(theta) w_k` with `|w_k| <= sqrt(1 - v_k^2)`, so at depth `tau` its
//! coordinate on axis `k` is `s_k + tau (v_k + tan(theta) w_k)`. Every ray of the cone therefore crosses the
//! plane `x_k = split` at a depth between `dist / (v_k + beta_k)` and `dist / (v_k - beta_k)`, where
//! `dist = split - s_k` and `beta_k = tan(alpha) sqrt(1 - v_k^2)` (Eq. 4.8). The two reciprocals are
//! precomputed per axis (Listing 4.4), so a split costs two multiplies; a negative depth means "never
//! crosses in front" and becomes infinite (the omni-directional rule of 4.1.2). Which of the two is the
//! near and which the far bound, and which becomes infinite, depends only on the signs of `dist` and of
//! `v_k +- beta_k`, so the precomputation also sorts them into the four per-sign factors of a
//! [`super::Frustum`]: a node then costs a cone what it costs a pyramid, one branch on the side of the
//! plane and two multiplies, with the same bounds as Listing 4.3's sorted and corrected products.
//!
//! Depth is at most the distance along a unit direction, so comparing an entry's depth with the rays' hit
//! distances stays conservative.

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{Bundle, Disc, Frustum, RayPacket};

/// A cone bounding a bundle of rays from one origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis.
    pub axis: Vec3,
    /// Tangent of the half-angle.
    pub tan_alpha: f32,
    /// What the walks see of the cone: its apex, depth range and Listing 4.4's per-axis factors sorted by
    /// sign, as a [`Frustum`]'s. For `dist > 0` the near factor is `1 / (v_k + beta_k)` (`precompute[0]`,
    /// +inf where no ray goes toward the plane) and the far one `1 / (v_k - beta_k)` (`precompute[1]`, +inf
    /// where some ray runs parallel to the axis or away); for `dist < 0` the same two swapped, -inf in
    /// their place. Distances are depths along the axis.
    pub bound: Frustum,
}

impl Cone {
    /// The narrowest cone about the mean direction that holds unit directions `dirs` with start and end
    /// distances; `None` when the bundle is empty or spans more than a hemisphere.
    pub fn bounding(origin: Vec3, segments: impl Iterator<Item = (Vec3, f32, f32)> + Clone) -> Option<Self> {
        let axis = segments.clone().fold(Vec3::ZERO, |s, (d, _, _)| s + d).normalize_or_zero();
        if axis == Vec3::ZERO {
            return None;
        }
        // The half-angle from |d x axis| / (d . axis) in double precision: 1 - cos^2 would cancel for the
        // nearly parallel rays of small tiles and give too narrow a cone.
        let a = axis.as_dvec3();
        let (mut tan_max, mut t_min, mut t_max) = (0.0f64, f32::INFINITY, f32::NEG_INFINITY);
        for (d, t0, t1) in segments {
            let d = d.as_dvec3();
            let c = d.dot(a);
            if c <= 0.05 * d.length() || c.is_nan() {
                return None;
            }
            tan_max = tan_max.max(d.cross(a).length() / c);
            t_min = t_min.min(t0);
            t_max = t_max.max(t1);
        }
        Some(Self::with_axis(origin, axis, pad_tan(tan_max), t_min.max(0.0), t_max))
    }

    /// The cone from `apex` around `disc` (the face of a spherical light turned toward a shaded point, where
    /// its samples lie): it holds every ray from `apex` to the disc, so it bounds the point's shadow samples
    /// before any is drawn (the cone proxy of thesis 4.1.9 and Figure 4.5). Its axis is the disc's normal and
    /// depths run from 0 to the disc. `None` when `apex` is not in front of the disc or too close to it (see
    /// [`Disc::MAX_REACH`]).
    pub fn around_disc(apex: Vec3, disc: &Disc) -> Option<Self> {
        let span = disc.span_from(apex)?;
        let tan = (span.center_dir - disc.normal.as_dvec3()).length() + span.reach;
        Some(Self::with_axis(apex, disc.normal, pad_tan(tan), 0.0, span.depth))
    }

    /// The cone about unit `axis` with the per-axis precomputation of Listing 4.4, sorted by sign.
    fn with_axis(origin: Vec3, axis: Vec3, tan_alpha: f32, t_min: f32, t_max: f32) -> Self {
        let beta = axis.to_array().map(|v| tan_alpha * (1.0 - v * v).max(0.0).sqrt());
        let v = axis.to_array();
        // The rays' axis components range over [v - beta, v + beta] (in units of depth).
        let (hi, lo): ([f32; 3], [f32; 3]) =
            (std::array::from_fn(|k| v[k] + beta[k]), std::array::from_fn(|k| v[k] - beta[k]));
        let (inf, ninf) = (f32::INFINITY, f32::NEG_INFINITY);
        let bound = Frustum {
            origin,
            pos_near: std::array::from_fn(|k| if hi[k] > 0.0 { 1.0 / hi[k] } else { inf }),
            pos_far: std::array::from_fn(|k| if lo[k] > 0.0 { 1.0 / lo[k] } else { inf }),
            neg_near: std::array::from_fn(|k| if lo[k] < 0.0 { 1.0 / lo[k] } else { ninf }),
            neg_far: std::array::from_fn(|k| if hi[k] < 0.0 { 1.0 / hi[k] } else { ninf }),
            t_min,
            t_max,
            origin_slack: 0.0,
        };
        Self { axis, tan_alpha, bound }
    }

    /// The cone of the valid rays of `packets`, which all start at `origin`.
    #[inline(always)]
    pub fn from_packets<V: Vf32>(origin: Vec3, packets: &[RayPacket<V>]) -> Option<Self> {
        // The lanes are read out here, in a plain loop, so that no vector code runs inside `bounding`'s
        // iterator, which the compiler may keep out of line (see `map3`).
        let mut segs = Vec::with_capacity(packets.len() * V::LANES);
        for p in packets {
            let bits = p.valid.bits();
            for i in (0..V::LANES).filter(|i| bits >> i & 1 == 1) {
                let r = p.ray(i);
                let len = r.dir.length();
                segs.push((r.dir / len, r.tmin * len, r.tmax * len));
            }
        }
        Self::bounding(origin, segs.into_iter())
    }
}

/// Listing 4.3 with the omni-directional rule: the two edge depths, negative ones made infinite, in order;
/// the per-sign factors of [`Cone::bound`] hold them already sorted.
impl Bundle for Cone {
    #[inline(always)]
    fn interval(&self) -> &Frustum {
        &self.bound
    }
}

/// A half-angle tangent widened for the rounding of unit directions and of the f32 products of a walk.
pub(super) fn pad_tan(tan: f64) -> f32 {
    (tan * (1.0 + 1e-4) + 1e-5) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_crossing_bounds_every_ray() {
        let o = Vec3::new(1.0, 2.0, -0.5);
        let dirs = [
            Vec3::new(1.0, 0.1, 0.05),
            Vec3::new(0.9, -0.1, 0.0),
            Vec3::new(1.0, 0.0, -0.12),
            Vec3::new(0.95, 0.08, 0.1),
        ]
        .map(|d| d.normalize());
        let c = Cone::bounding(o, dirs.iter().map(|&d| (d, 0.0, f32::INFINITY))).unwrap();
        for k in 0..3 {
            for split in [-4.0f32, -0.6, 0.0, 1.5, 2.5, 9.0] {
                let (lo, hi) = c.crossing(k, split);
                assert!(lo <= hi);
                for d in dirs {
                    let t = (split - o[k]) / d[k];
                    if t > 0.0 && t.is_finite() {
                        let depth = t * d.dot(c.axis);
                        assert!(
                            depth >= lo * (1.0 - 1e-5) && depth <= hi * (1.0 + 1e-5),
                            "axis {k} split {split}: {depth} not in [{lo}, {hi}]"
                        );
                    }
                }
            }
        }
        assert!(Cone::bounding(o, [(Vec3::X, 0.0, 1.0), (Vec3::NEG_X, 0.0, 1.0)].into_iter()).is_none());
    }

    /// The per-sign factors give exactly Listing 4.3's bounds: both edge depths `dist / (v_k +- beta_k)`,
    /// negative ones made infinite, sorted; on axes the cone straddles, runs along, or faces either way.
    #[test]
    fn sign_factors_reproduce_listing_4_3() {
        let axes = [Vec3::new(0.3, -0.8, 0.5), Vec3::X, Vec3::new(0.0, 0.6, -0.8), Vec3::new(-0.02, 1.0, 0.01)];
        for axis in axes.map(|a| a.normalize()) {
            for tan in [0.0f32, 0.01, 0.3, 2.0] {
                let c = Cone::with_axis(Vec3::new(1.0, -2.0, 0.5), axis, tan, 0.0, 100.0);
                for k in 0..3 {
                    let v = axis[k];
                    let beta = tan * (1.0 - v * v).max(0.0).sqrt();
                    for split in [-7.0f32, -2.5, -2.0, 0.0, 0.5, 1.0, 3.0] {
                        let dist = split - c.bound.origin[k];
                        let fix = |t: f32| if t < 0.0 || t.is_nan() { f32::INFINITY } else { t };
                        let (a, b) = (fix(dist * (1.0 / (v + beta))), fix(dist * (1.0 / (v - beta))));
                        let want = if dist == 0.0 { (0.0, f32::INFINITY) } else { (a.min(b), a.max(b)) };
                        assert_eq!(c.crossing(k, split), want, "axis {axis} tan {tan} k {k} split {split}");
                    }
                }
            }
        }
    }
}
