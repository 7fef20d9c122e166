//! SIMD value types for raylab's kernels.
//!
//! Kernels are written once, generic over [`Vf32`], and instantiated with a hardware backend and with the
//! portable [`scalar::F32x4`], which has the same API and the same per-lane semantics (including how `min`,
//! `max` and comparisons treat NaN), so tests can run every kernel both ways and compare. Backends are
//! chosen once, when a tracer is set up ([`Backend::detect`]), never per ray.
//!
//! This is the only raylab crate that may use `unsafe`; each block says why it is sound.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

pub mod scalar;
#[cfg(target_arch = "x86_64")]
pub mod sse;

/// A lane mask produced by comparisons.
pub trait VMask:
    Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + BitXor<Output = Self> + Not<Output = Self>
{
    /// One bit per lane, lane 0 in bit 0.
    fn bits(self) -> u32;
    /// The mask with lanes set where `bits` has ones.
    fn from_bits(bits: u32) -> Self;
    /// True when any lane is set.
    #[inline(always)]
    fn any(self) -> bool {
        self.bits() != 0
    }
    /// True when no lane is set.
    #[inline(always)]
    fn none(self) -> bool {
        self.bits() == 0
    }
}

/// A vector of `f32` lanes.
///
/// `min(a, b)` and `max(a, b)` follow the SSE rule: when either lane is NaN the lane of `b` is returned,
/// so `a.min(b)` with a NaN `a` keeps `b`. Comparisons with NaN are false.
pub trait Vf32:
    Copy + Debug + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// The mask type of comparisons.
    type Mask: VMask;
    /// Number of lanes.
    const LANES: usize;
    /// All lanes set to `x`.
    fn splat(x: f32) -> Self;
    /// Lanes from a slice of exactly `LANES` values.
    fn from_slice(s: &[f32]) -> Self;
    /// Writes the lanes to a slice of exactly `LANES` values.
    fn write_to(self, out: &mut [f32]);
    /// Lane `i`.
    fn lane(self, i: usize) -> f32;
    /// `self < o` per lane.
    fn lt(self, o: Self) -> Self::Mask;
    /// `self <= o` per lane.
    fn le(self, o: Self) -> Self::Mask;
    /// `self > o` per lane.
    #[inline(always)]
    fn gt(self, o: Self) -> Self::Mask {
        o.lt(self)
    }
    /// `self >= o` per lane.
    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        o.le(self)
    }
    /// `self == o` per lane.
    fn eq(self, o: Self) -> Self::Mask;
    /// Lane-wise minimum (SSE NaN rule, see the trait docs).
    fn min(self, o: Self) -> Self;
    /// Lane-wise maximum (SSE NaN rule).
    fn max(self, o: Self) -> Self;
    /// `a` where `m` is set, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Lane-wise absolute value.
    fn abs(self) -> Self;
    /// Smallest lane (NaN lanes are ignored unless all are NaN).
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        (1..Self::LANES).fold(self.lane(0), |m, i| {
            let v = self.lane(i);
            if v < m || m.is_nan() { v } else { m }
        })
    }
    /// Largest lane (NaN lanes are ignored unless all are NaN).
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        (1..Self::LANES).fold(self.lane(0), |m, i| {
            let v = self.lane(i);
            if v > m || m.is_nan() { v } else { m }
        })
    }
}

/// Which hardware path the kernels use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// Portable scalar lanes (any CPU; also the twin the tests compare against).
    Scalar,
    /// SSE2 on x86-64 (always present there).
    Sse,
}

impl Backend {
    /// The fastest backend this CPU supports.
    pub fn detect() -> Self {
        if cfg!(target_arch = "x86_64") { Backend::Sse } else { Backend::Scalar }
    }

    /// Every backend this CPU can run, fastest first.
    pub fn available() -> Vec<Backend> {
        let mut v = Vec::new();
        if cfg!(target_arch = "x86_64") {
            v.push(Backend::Sse);
        }
        v.push(Backend::Scalar);
        v
    }

    /// The name shown in reports.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Scalar => "scalar",
            Backend::Sse => "sse2",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<V: Vf32>() {
        let a = V::from_slice(&[1.0, -2.0, f32::NAN, 0.0][..V::LANES]);
        let b = V::from_slice(&[0.5, 3.0, 1.0, -0.0][..V::LANES]);
        assert_eq!(a.lt(b).bits(), 0b0010);
        assert_eq!(a.le(b).bits(), 0b1010, "0.0 <= -0.0");
        assert_eq!(a.eq(b).bits(), 0b1000);
        let mn = a.min(b);
        assert_eq!([mn.lane(0), mn.lane(1), mn.lane(2)], [0.5, -2.0, 1.0], "NaN in a keeps b");
        let mx = b.max(a);
        assert!(mx.lane(2).is_nan(), "NaN in the second operand is returned");
        assert_eq!(V::select(V::Mask::from_bits(0b0101), a, b).lane(1), 3.0);
        assert_eq!(a.abs().lane(1), 2.0);
        assert_eq!(a.reduce_min(), -2.0);
        assert_eq!(a.reduce_max(), 1.0);
        let mut out = [0.0; 4];
        (a + b).write_to(&mut out[..V::LANES]);
        assert_eq!(out[0], 1.5);
        assert!(!V::Mask::from_bits(0).any() && V::Mask::from_bits(0).none());
        assert_eq!((!V::Mask::from_bits(0b0001)).bits(), 0b1110);
    }

    #[test]
    fn scalar_semantics() {
        check::<scalar::F32x4>();
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse_semantics() {
        check::<sse::F32x4>();
    }
}
