//! Stratified samples on a spherical light, as seen from a shaded point (thesis Figures 4.5 and 5.1-5.2).
//!
//! A sphere seen from outside covers the same directions as the disc through its centre facing the viewer,
//! so samples are spread over that disc: one jittered sample per cell of a `gx x gy` grid, mapped to the disc
//! by Shirley and Chiu's concentric map, which keeps the strata compact. The jitter is a hash of a seed
//! (the pixel), so every traversal method shoots exactly the same rays.

use glam::{Vec2, Vec3};

use crate::packet::Disc;

/// The `gx x gy` grid of `n` strata: the most square factorisation with `gx >= gy` (4 -> 2x2, 8 -> 4x2,
/// 16 -> 4x4, 32 -> 8x4).
pub fn stratified_grid(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut gy = (n as f64).sqrt() as u32;
    while gy > 1 && !n.is_multiple_of(gy) {
        gy -= 1;
    }
    (n / gy, gy.max(1))
}

/// Points on a spherical light for one shaded point, laid out as a `width x height` grid (one per stratum).
#[derive(Clone, Debug, Default)]
pub struct LightSamples {
    /// Grid width.
    pub width: u32,
    /// Grid height.
    pub height: u32,
    /// The sample positions, row-major.
    pub points: Vec<Vec3>,
    /// The disc they lie on: the light's face turned toward the shaded point.
    pub disc: Disc,
}

impl LightSamples {
    /// Fills `self` with `n` stratified samples on the light of radius `radius` centred at `center`, seen from
    /// `from`, jittered by `seed`. A radius of zero puts every sample at the centre.
    pub fn generate(&mut self, center: Vec3, radius: f32, from: Vec3, n: u32, seed: u32) {
        let (gx, gy) = stratified_grid(n);
        (self.width, self.height) = (gx, gy);
        self.points.clear();
        let axis = (center - from).normalize_or_zero();
        let axis = if axis == Vec3::ZERO { Vec3::Z } else { axis };
        let (u, v) = axis.any_orthonormal_pair();
        self.disc = Disc { center, normal: axis, radius };
        for j in 0..gy {
            for i in 0..gx {
                let k = j * gx + i;
                let (jx, jy) = jitter(seed, k);
                let cell = Vec2::new((i as f32 + jx) / gx as f32, (j as f32 + jy) / gy as f32);
                let d = concentric_disc(cell) * radius;
                self.points.push(center + u * d.x + v * d.y);
            }
        }
    }
}

/// Shirley and Chiu's concentric map from the unit square to the unit disc.
pub fn concentric_disc(p: Vec2) -> Vec2 {
    let q = p * 2.0 - Vec2::ONE;
    if q == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, phi) = if q.x.abs() > q.y.abs() {
        (q.x, std::f32::consts::FRAC_PI_4 * (q.y / q.x))
    } else {
        (q.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (q.x / q.y))
    };
    Vec2::new(phi.cos(), phi.sin()) * r
}

/// Two numbers in `[0, 1)` from a seed and a sample index (a PCG-style integer hash).
fn jitter(seed: u32, k: u32) -> (f32, f32) {
    let h = hash(seed.wrapping_mul(0x9E37_79B9) ^ hash(k.wrapping_add(0x7F4A_7C15)));
    let g = hash(h ^ 0x85EB_CA6B);
    ((h >> 8) as f32 / (1u32 << 24) as f32, (g >> 8) as f32 / (1u32 << 24) as f32)
}

/// A PCG-style integer hash (also the distribution tracer's random numbers).
pub(crate) fn hash(x: u32) -> u32 {
    let s = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
    (w >> 22) ^ w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_are_the_thesis_sample_counts() {
        assert_eq!(stratified_grid(4), (2, 2));
        assert_eq!(stratified_grid(8), (4, 2));
        assert_eq!(stratified_grid(16), (4, 4));
        assert_eq!(stratified_grid(32), (8, 4));
        assert_eq!(stratified_grid(1024), (32, 32));
        assert_eq!(stratified_grid(7), (7, 1));
        assert_eq!(stratified_grid(0), (1, 1));
    }

    #[test]
    fn samples_lie_on_the_disc_facing_the_point() {
        let mut s = LightSamples::default();
        let (c, r, from) = (Vec3::new(1.0, 5.0, 2.0), 0.5, Vec3::new(0.0, 0.0, 1.0));
        s.generate(c, r, from, 32, 17);
        assert_eq!(s.points.len(), 32);
        let axis = (c - from).normalize();
        for p in &s.points {
            assert!((*p - c).length() <= r * 1.0001);
            assert!((*p - c).dot(axis).abs() < 1e-5);
        }
        let mut again = LightSamples::default();
        again.generate(c, r, from, 32, 17);
        assert_eq!(s.points, again.points, "the same seed gives the same samples");
        again.generate(c, r, from, 32, 18);
        assert_ne!(s.points, again.points);
    }

    #[test]
    fn the_concentric_map_covers_the_disc_uniformly() {
        // The share of a fine grid of square points landing inside radius 0.5 is the area share, 1/4.
        let n = 200;
        let inner = (0..n * n)
            .filter(|k| {
                concentric_disc(Vec2::new((k % n) as f32 + 0.5, (k / n) as f32 + 0.5) / n as f32).length() < 0.5
            })
            .count();
        assert!((inner as f64 / (n * n) as f64 - 0.25).abs() < 0.01);
    }
}
