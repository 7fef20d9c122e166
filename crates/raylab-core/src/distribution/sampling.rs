//! Random numbers and sample warps for the distribution ray tracer: a counter-based hash generator (so a
//! pixel's samples do not depend on which thread or method traces it), the concentric disc, and Phong lobes.

use glam::{Vec2, Vec3};

pub use crate::shadow::concentric_disc as disc;
use crate::shadow::samples::hash;

/// A small generator seeded from a pixel, a sample and a pass.
pub struct Rng(u32);

impl Rng {
    /// The generator of sample `sample` of pixel `pixel` in pass `pass`.
    pub fn new(pixel: u32, sample: u32, pass: u32) -> Self {
        Self(hash(pixel ^ hash(sample.wrapping_mul(0x9E37_79B9) ^ hash(pass.wrapping_add(0x632B_E5AB)))))
    }

    /// The next number in `[0, 1)`.
    pub fn next(&mut self) -> f32 {
        self.0 = hash(self.0.wrapping_add(0x6D2B_79F5));
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// A direction about unit `axis` with density proportional to `cos^n` of the angle to it (`n = 1`: the
/// cosine-weighted hemisphere), from `u` in the unit square.
pub fn phong_lobe(axis: Vec3, n: f32, u: Vec2) -> Vec3 {
    let cos_t = u.x.powf(1.0 / (n + 1.0));
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    let (a, b) = axis.any_orthonormal_pair();
    (a * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lobes_concentrate_with_the_exponent() {
        let axis = Vec3::new(0.0, 1.0, 1.0).normalize();
        let mean_cos = |n: f32| {
            let mut r = Rng::new(1, 2, 3);
            (0..4000).map(|_| phong_lobe(axis, n, Vec2::new(r.next(), r.next())).dot(axis)).sum::<f32>() / 4000.0
        };
        // E[cos] = (n + 1) / (n + 2) for a cos^n lobe.
        for n in [1.0f32, 10.0, 100.0] {
            assert!((mean_cos(n) - (n + 1.0) / (n + 2.0)).abs() < 0.02, "n {n}: {}", mean_cos(n));
        }
    }

    #[test]
    fn generators_are_reproducible_and_distinct() {
        let (mut a, mut b, mut c) = (Rng::new(5, 1, 0), Rng::new(5, 1, 0), Rng::new(5, 2, 0));
        let (x, y, z) = (a.next(), b.next(), c.next());
        assert_eq!(x, y);
        assert_ne!(x, z);
        assert!((0.0..1.0).contains(&x));
    }
}
