//! The portable backend: four `f32` lanes in an array, with exactly the SSE backend's semantics.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

use crate::{VMask, Vf32};

/// Four `f32` lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct F32x4(pub [f32; 4]);

/// Four lane flags, one bit each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct M32x4(u32);

impl VMask for M32x4 {
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        Self(bits & 0xf)
    }
}

impl BitAnd for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl BitOr for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl BitXor for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        Self(self.0 ^ o.0)
    }
}

impl Not for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0 & 0xf)
    }
}

macro_rules! lanewise {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for F32x4 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self([self.0[0] $op o.0[0], self.0[1] $op o.0[1], self.0[2] $op o.0[2], self.0[3] $op o.0[3]])
            }
        }
    };
}

lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl F32x4 {
    #[inline(always)]
    fn mask(f: impl Fn(usize) -> bool) -> M32x4 {
        M32x4((0..4).fold(0, |m, i| m | ((f(i) as u32) << i)))
    }
}

impl Vf32 for F32x4 {
    type Mask = M32x4;
    const LANES: usize = 4;
    type Array<T: Copy + Debug> = [T; 4];
    type Quad = Self;

    #[inline(always)]
    fn array_from_fn<T: Copy + Debug>(f: impl FnMut(usize) -> T) -> [T; 4] {
        std::array::from_fn(f)
    }

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self([x; 4])
    }
    #[inline(always)]
    fn from_slice(s: &[f32]) -> Self {
        Self([s[0], s[1], s[2], s[3]])
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        out[..4].copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.0[i]
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x4 {
        Self::mask(|i| self.0[i] < o.0[i])
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x4 {
        Self::mask(|i| self.0[i] <= o.0[i])
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x4 {
        Self::mask(|i| self.0[i] == o.0[i])
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(std::array::from_fn(|i| if self.0[i] < o.0[i] { self.0[i] } else { o.0[i] }))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(std::array::from_fn(|i| if self.0[i] > o.0[i] { self.0[i] } else { o.0[i] }))
    }
    #[inline(always)]
    fn select(m: M32x4, a: Self, b: Self) -> Self {
        Self(std::array::from_fn(|i| if m.0 >> i & 1 == 1 { a.0[i] } else { b.0[i] }))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(self.0.map(f32::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    fn transpose_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        std::array::from_fn(|c| Self(std::array::from_fn(|i| rows[i][c])))
    }
    #[inline(always)]
    fn transpose4(rows: [Self; 4]) -> [Self; 4] {
        std::array::from_fn(|c| Self(std::array::from_fn(|i| rows[i].0[c])))
    }
    #[inline(always)]
    fn pack_u32(ids: &[u32; 4], bits: u32, out: &mut [u32]) -> usize {
        pack4(ids, bits, out)
    }
    #[inline(always)]
    fn splat_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        rows[0].map(Self::splat)
    }
    #[inline(always)]
    fn repeat4(quad: &[f32; 4]) -> Self {
        Self(*quad)
    }
    #[inline(always)]
    fn from_quads(quads: &[&[f32; 4]]) -> Self {
        Self(*quads[0])
    }
}

/// Left-packs four ids ([`Vf32::pack_u32`]) without vector instructions: each id is written at the next free
/// place, which advances only when its bit is set.
#[inline(always)]
pub(crate) fn pack4(ids: &[u32; 4], bits: u32, out: &mut [u32]) -> usize {
    let out = &mut out[..4];
    let mut kept = 0;
    for (i, &id) in ids.iter().enumerate() {
        out[kept] = id;
        kept += (bits >> i & 1) as usize;
    }
    kept
}
