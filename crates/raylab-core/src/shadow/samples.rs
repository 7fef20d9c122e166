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
    #[inline(always)]
    pub fn generate(&mut self, center: Vec3, radius: f32, from: Vec3, n: u32, seed: u32) {
        let (gx, gy) = stratified_grid(n);
        (self.width, self.height) = (gx, gy);
        self.points.clear();
        let axis = (center - from).normalize_or_zero();
        let axis = if axis == Vec3::ZERO { Vec3::Z } else { axis };
        let (u, v) = axis.any_orthonormal_pair();
        self.disc = Disc { center, normal: axis, radius };
        // One flat loop without branches or integer division (the stratum's column and row come from float
        // arithmetic, exact for these small integers), so that the compiler can draw several samples per
        // instruction.
        self.points.resize((gx * gy) as usize, Vec3::ZERO);
        let (cols, scale) = (gx as f32, Vec2::new(1.0 / gx as f32, 1.0 / gy as f32));
        for (k, p) in self.points.iter_mut().enumerate() {
            let (jx, jy) = jitter(seed, k as u32);
            let row = ((k as f32 + 0.5) / cols).floor();
            let stratum = Vec2::new(k as f32 - row * cols, row);
            let d = concentric_disc((stratum + Vec2::new(jx, jy)) * scale) * radius;
            *p = center + u * d.x + v * d.y;
        }
    }
}

/// Shirley and Chiu's concentric map from the unit square to the unit disc.
///
/// The angle of each wedge is a quarter turn at most, `pi/4 * ratio` with `|ratio| <= 1` (the second wedge's
/// `pi/2 - pi/4 * ratio` swaps sine and cosine), so `sin_cos_eighth` computes it: `f32::sin_cos` was a
/// third of the cost of drawing a point's light samples.
#[inline(always)]
pub fn concentric_disc(p: Vec2) -> Vec2 {
    let q = p * 2.0 - Vec2::ONE;
    // The wedge's radius `a` and the other coordinate `b`, selected rather than branched on (see
    // `LightSamples::generate`); the centre (a = 0) has no angle.
    let swap = q.x.abs() <= q.y.abs();
    let (a, b) = if swap { (q.y, q.x) } else { (q.x, q.y) };
    let ratio = if a == 0.0 { 0.0 } else { b / a };
    let (s, c) = sin_cos_eighth(std::f32::consts::FRAC_PI_4 * ratio);
    let (x, y) = if swap { (s, c) } else { (c, s) };
    Vec2::new(x, y) * a
}

/// Sine and cosine of `x` for `|x| <= pi/4`, from their Taylor series up to the `x^7` and `x^8` terms: the
/// first terms left out are below `(pi/4)^9 / 9! < 4e-7` and `(pi/4)^10 / 10! < 3e-8`, about the rounding of
/// an `f32` near 1.
/// The coefficients are products, not quotients, so that the two polynomials cost multiplies and adds
/// only (a division by a constant stays a division).
#[inline(always)]
fn sin_cos_eighth(x: f32) -> (f32, f32) {
    const S: [f32; 3] = [-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0];
    const C: [f32; 4] = [-1.0 / 2.0, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0];
    let x2 = x * x;
    let s = x + x * x2 * (S[0] + x2 * (S[1] + x2 * S[2]));
    let c = 1.0 + x2 * (C[0] + x2 * (C[1] + x2 * (C[2] + x2 * C[3])));
    (s, c)
}

/// Two numbers in `[0, 1)` from a seed and a sample index (a PCG-style integer hash).
#[inline(always)]
fn jitter(seed: u32, k: u32) -> (f32, f32) {
    let h = hash(seed.wrapping_mul(0x9E37_79B9) ^ hash(k.wrapping_add(0x7F4A_7C15)));
    let g = hash(h ^ 0x85EB_CA6B);
    ((h >> 8) as f32 / (1u32 << 24) as f32, (g >> 8) as f32 / (1u32 << 24) as f32)
}

/// A PCG-style integer hash (also the distribution tracer's random numbers).
#[inline(always)]
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
    fn the_eighth_turn_sine_and_cosine_match_std() {
        let quarter = std::f64::consts::FRAC_PI_4;
        for k in -1000..=1000 {
            let x = (quarter * k as f64 / 1000.0) as f32;
            let (s, c) = sin_cos_eighth(x);
            let (es, ec) = (x as f64).sin_cos();
            assert!((s as f64 - es).abs() < 5e-7 && (c as f64 - ec).abs() < 5e-7, "x = {x}: {s} {c}");
        }
    }

    #[test]
    fn the_concentric_map_keeps_its_wedges() {
        // Corners of the square go to the rim at the diagonals, edge midpoints to the axes.
        let close = |a: Vec2, b: Vec2| (a - b).length() < 1e-6;
        let d = std::f32::consts::FRAC_1_SQRT_2;
        assert!(close(concentric_disc(Vec2::new(1.0, 1.0)), Vec2::new(d, d)));
        assert!(close(concentric_disc(Vec2::new(0.0, 0.0)), Vec2::new(-d, -d)));
        assert!(close(concentric_disc(Vec2::new(1.0, 0.5)), Vec2::new(1.0, 0.0)));
        assert!(close(concentric_disc(Vec2::new(0.5, 0.0)), Vec2::new(0.0, -1.0)));
        assert_eq!(concentric_disc(Vec2::splat(0.5)), Vec2::ZERO);
        // Every point stays in the disc, and the rim of the square maps to the rim of the disc.
        for k in 0..=64 {
            let a = k as f32 / 64.0;
            for p in [Vec2::new(a, 0.0), Vec2::new(a, 1.0), Vec2::new(0.0, a), Vec2::new(1.0, a)] {
                assert!((concentric_disc(p).length() - 1.0).abs() < 1e-6, "{p}");
            }
            assert!(concentric_disc(Vec2::new(a, a * 0.7)).length() <= 1.0 + 1e-6);
        }
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
