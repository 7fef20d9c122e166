//! The SSE2 backend (part of every x86-64 CPU, so no run-time detection is needed for it).

use std::arch::x86_64::*;
use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

use crate::{VMask, Vf32};

/// Evaluates an expression of register-only SSE/SSE2 intrinsics.
macro_rules! sse {
    ($e:expr) => {
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline: every x86-64 CPU has them and the compiler
        // enables them by default, and these intrinsics only read and write registers.
        unsafe { $e }
    };
}

/// Four `f32` lanes in an SSE register.
#[derive(Clone, Copy, Debug)]
pub struct F32x4(__m128);

/// Four lane masks (all bits set or clear per lane) in an SSE register.
#[derive(Clone, Copy, Debug)]
pub struct M32x4(__m128);

impl VMask for M32x4 {
    #[inline(always)]
    fn bits(self) -> u32 {
        sse!(_mm_movemask_ps(self.0)) as u32
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        sse!({
            let lane_bits = _mm_setr_epi32(1, 2, 4, 8);
            let set = _mm_and_si128(_mm_set1_epi32(bits as i32), lane_bits);
            Self(_mm_castsi128_ps(_mm_cmpeq_epi32(set, lane_bits)))
        })
    }
}

impl BitAnd for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(sse!(_mm_and_ps(self.0, o.0)))
    }
}

impl BitOr for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(sse!(_mm_or_ps(self.0, o.0)))
    }
}

impl BitXor for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        Self(sse!(_mm_xor_ps(self.0, o.0)))
    }
}

impl Not for M32x4 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(sse!(_mm_xor_ps(self.0, _mm_castsi128_ps(_mm_set1_epi32(-1)))))
    }
}

macro_rules! arith {
    ($trait:ident, $f:ident, $intr:ident) => {
        impl $trait for F32x4 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(sse!($intr(self.0, o.0)))
            }
        }
    };
}

arith!(Add, add, _mm_add_ps);
arith!(Sub, sub, _mm_sub_ps);
arith!(Mul, mul, _mm_mul_ps);
arith!(Div, div, _mm_div_ps);

impl F32x4 {
    /// Folds the lanes with `op` (a lane-wise min or max) in registers: the two halves, then the last two
    /// lanes. NaN lanes are first replaced by `identity`, so they are ignored; all-NaN input gives NaN (the
    /// trait's lane-by-lane default, which stores the register and reloads each lane, cost packet/leaf culling
    /// setup a tenth of an SSE frame).
    #[inline(always)]
    fn reduce(self, identity: f32, op: impl Fn(__m128, __m128) -> __m128) -> f32 {
        sse!({
            let ordered = _mm_cmpord_ps(self.0, self.0);
            let v = Self::select(M32x4(ordered), self, Self::splat(identity)).0;
            let m = op(v, _mm_movehl_ps(v, v));
            let m = op(m, _mm_shuffle_ps::<0b01>(m, m));
            if _mm_movemask_ps(ordered) == 0 { f32::NAN } else { _mm_cvtss_f32(m) }
        })
    }

    /// Lane `i` of the result folds the lanes of `rows[i]` with `op` (a lane-wise min or max), for four rows:
    /// neighbouring lanes of row pairs, then the pairs' halves.
    #[inline(always)]
    fn fold_rows(rows: &[Self], op: impl Fn(__m128, __m128) -> __m128) -> Self {
        let r: &[Self; 4] = rows[..4].try_into().expect("four rows");
        sse!({
            // [op(a0, a2), op(b0, b2), op(a1, a3), op(b1, b3)].
            let pair = |a: Self, b: Self| op(_mm_unpacklo_ps(a.0, b.0), _mm_unpackhi_ps(a.0, b.0));
            let (p, q) = (pair(r[0], r[1]), pair(r[2], r[3]));
            Self(op(_mm_movelh_ps(p, q), _mm_movehl_ps(q, p)))
        })
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
        Self(sse!(_mm_set1_ps(x)))
    }
    #[inline(always)]
    fn from_slice(s: &[f32]) -> Self {
        assert!(s.len() >= 4);
        // SAFETY: the assert guarantees four readable `f32`s; `loadu` has no alignment requirement.
        Self(unsafe { _mm_loadu_ps(s.as_ptr()) })
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        assert!(out.len() >= 4);
        // SAFETY: the assert guarantees four writable `f32`s; `storeu` has no alignment requirement.
        unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        let mut a = [0.0; 4];
        self.write_to(&mut a);
        a[i]
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x4 {
        M32x4(sse!(_mm_cmplt_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x4 {
        M32x4(sse!(_mm_cmple_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x4 {
        M32x4(sse!(_mm_cmpeq_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(sse!(_mm_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(sse!(_mm_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn select(m: M32x4, a: Self, b: Self) -> Self {
        Self(sse!(_mm_or_ps(_mm_and_ps(m.0, a.0), _mm_andnot_ps(m.0, b.0))))
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.reduce(f32::INFINITY, |a, b| sse!(_mm_min_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.reduce(f32::NEG_INFINITY, |a, b| sse!(_mm_max_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_min_each(rows: &[Self]) -> Self {
        Self::fold_rows(rows, |a, b| sse!(_mm_min_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_max_each(rows: &[Self]) -> Self {
        Self::fold_rows(rows, |a, b| sse!(_mm_max_ps(a, b)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(sse!(_mm_and_ps(self.0, _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff)))))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(sse!(_mm_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn transpose_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        // SAFETY: each row is a reference to four readable `f32`s and `loadu` has no alignment requirement.
        let load = |i: usize| Self(unsafe { _mm_loadu_ps(rows[i].as_ptr()) });
        Self::transpose4([load(0), load(1), load(2), load(3)])
    }
    #[inline(always)]
    fn transpose4(rows: [Self; 4]) -> [Self; 4] {
        let [a, b, c, d] = rows.map(|r| r.0);
        sse!({
            let (ab_lo, cd_lo) = (_mm_unpacklo_ps(a, b), _mm_unpacklo_ps(c, d));
            let (ab_hi, cd_hi) = (_mm_unpackhi_ps(a, b), _mm_unpackhi_ps(c, d));
            [
                Self(_mm_movelh_ps(ab_lo, cd_lo)),
                Self(_mm_movehl_ps(cd_lo, ab_lo)),
                Self(_mm_movelh_ps(ab_hi, cd_hi)),
                Self(_mm_movehl_ps(cd_hi, ab_hi)),
            ]
        })
    }
    #[inline(always)]
    fn pack_u32(ids: &[u32; 4], bits: u32, out: &mut [u32]) -> usize {
        // SSE2 has no variable lane shuffle; four scalar writes do it.
        crate::scalar::pack4(ids, bits, out)
    }
    #[inline(always)]
    fn splat_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        // SAFETY: the row is a reference to four readable `f32`s and `loadu` has no alignment requirement.
        let r = unsafe { _mm_loadu_ps(rows[0].as_ptr()) };
        sse!([
            Self(_mm_shuffle_ps::<0x00>(r, r)),
            Self(_mm_shuffle_ps::<0x55>(r, r)),
            Self(_mm_shuffle_ps::<0xaa>(r, r)),
            Self(_mm_shuffle_ps::<0xff>(r, r)),
        ])
    }
    #[inline(always)]
    fn repeat4(quad: &[f32; 4]) -> Self {
        // SAFETY: `quad` is four readable `f32`s and `loadu` has no alignment requirement.
        Self(unsafe { _mm_loadu_ps(quad.as_ptr()) })
    }
    #[inline(always)]
    fn from_quads(quads: &[&[f32; 4]]) -> Self {
        // SAFETY: the quad is a reference to four readable `f32`s and `loadu` has no alignment requirement.
        Self(unsafe { _mm_loadu_ps(quads[0].as_ptr()) })
    }
}
