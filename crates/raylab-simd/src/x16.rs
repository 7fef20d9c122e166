//! Sixteen `f32` lanes in one AVX-512 register (4x4 ray packets on CPUs with AVX-512: thesis 4.1.2 expects
//! packets to widen with the SIMD units), with exactly the other backends' semantics (`min`/`max` return the
//! second operand when either is NaN; comparisons with NaN are false).
//!
//! The types are private to this crate and only [`crate::dispatch`]'s AVX-512 entry point instantiates kernels
//! with them, after checking that the CPU has AVX-512F, AVX-512VL, AVX2 and FMA: no value of them, and so none
//! of the instructions below, can exist on a CPU without those features. Masks are AVX-512 mask registers
//! (`__mmask16`), so a comparison's lanes are its bits with no conversion.

use std::arch::x86_64::*;
use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

use crate::{VMask, Vf32};

/// Evaluates an expression of register-only AVX-512 intrinsics.
macro_rules! avx512 {
    ($e:expr) => {
        // SAFETY: values of this module's types are only created by kernels that `run_avx512` runs, and it is
        // only called once `is_x86_feature_detected!` has confirmed AVX-512F/VL, AVX2 and FMA (see the module
        // docs); these intrinsics only read and write registers.
        unsafe { $e }
    };
}

/// Sixteen `f32` lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F32x16(__m512);

/// Sixteen lane flags, one bit per lane, as AVX-512 comparisons produce them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct M32x16(__mmask16);

impl VMask for M32x16 {
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self.0)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        Self(bits as u16)
    }
}

impl BitAnd for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl BitOr for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl BitXor for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        Self(self.0 ^ o.0)
    }
}

impl Not for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0)
    }
}

/// `impl $trait for F32x16` by one two-operand intrinsic on the registers.
macro_rules! binop {
    ($trait:ident, $f:ident, $intr:ident) => {
        impl $trait for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(avx512!($intr(self.0, o.0)))
            }
        }
    };
}

binop!(Add, add, _mm512_add_ps);
binop!(Sub, sub, _mm512_sub_ps);
binop!(Mul, mul, _mm512_mul_ps);
binop!(Div, div, _mm512_div_ps);

/// Four rows of four floats in the four 128-bit blocks of one register, row `rows[i]` in block `i`.
#[inline(always)]
fn load_blocks(rows: [&[f32; 4]; 4]) -> __m512 {
    // SAFETY: each row is a reference to four readable `f32`s and `loadu` has no alignment requirement;
    // AVX-512F is present (see `avx512!`).
    unsafe {
        let v = _mm512_castps128_ps512(_mm_loadu_ps(rows[0].as_ptr()));
        let v = _mm512_insertf32x4::<1>(v, _mm_loadu_ps(rows[1].as_ptr()));
        let v = _mm512_insertf32x4::<2>(v, _mm_loadu_ps(rows[2].as_ptr()));
        _mm512_insertf32x4::<3>(v, _mm_loadu_ps(rows[3].as_ptr()))
    }
}

impl F32x16 {
    /// Folds the lanes to their minimum or maximum, NaN lanes first replaced by `identity` so that they are
    /// ignored; all-NaN input gives NaN.
    #[inline(always)]
    fn reduce(self, identity: f32, op: impl Fn(__m512) -> f32) -> f32 {
        avx512!({
            let ordered = _mm512_cmp_ps_mask::<_CMP_ORD_Q>(self.0, self.0);
            let v = _mm512_mask_blend_ps(ordered, _mm512_set1_ps(identity), self.0);
            if ordered == 0 { f32::NAN } else { op(v) }
        })
    }
}

impl Vf32 for F32x16 {
    type Mask = M32x16;
    const LANES: usize = 16;
    type Array<T: Copy + Debug> = [T; 16];
    type Quad = crate::sse::F32x4;

    #[inline(always)]
    fn array_from_fn<T: Copy + Debug>(f: impl FnMut(usize) -> T) -> [T; 16] {
        std::array::from_fn(f)
    }

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self(avx512!(_mm512_set1_ps(x)))
    }
    #[inline(always)]
    fn from_slice(s: &[f32]) -> Self {
        assert!(s.len() >= 16);
        // SAFETY: the assert guarantees sixteen readable `f32`s and `loadu` has no alignment requirement;
        // AVX-512F is present (see `avx512!`).
        Self(unsafe { _mm512_loadu_ps(s.as_ptr()) })
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        assert!(out.len() >= 16);
        // SAFETY: the assert guarantees sixteen writable `f32`s and `storeu` has no alignment requirement;
        // AVX-512F is present (see `avx512!`).
        unsafe { _mm512_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        let mut a = [0.0; 16];
        self.write_to(&mut a);
        a[i]
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x16 {
        M32x16(avx512!(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x16 {
        M32x16(avx512!(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x16 {
        M32x16(avx512!(_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(avx512!(_mm512_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(avx512!(_mm512_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn select(m: M32x16, a: Self, b: Self) -> Self {
        Self(avx512!(_mm512_mask_blend_ps(m.0, b.0, a.0)))
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.reduce(f32::INFINITY, |v| avx512!(_mm512_reduce_min_ps(v)))
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.reduce(f32::NEG_INFINITY, |v| avx512!(_mm512_reduce_max_ps(v)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(avx512!(_mm512_abs_ps(self.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(avx512!(_mm512_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn transpose_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        assert!(rows.len() >= 16);
        // Rows i, i + 4, i + 8 and i + 12 share a register, one per 128-bit block; the 4x4 transpose then runs
        // in all four blocks at once.
        let a = load_blocks([rows[0], rows[4], rows[8], rows[12]]);
        let b = load_blocks([rows[1], rows[5], rows[9], rows[13]]);
        let c = load_blocks([rows[2], rows[6], rows[10], rows[14]]);
        let d = load_blocks([rows[3], rows[7], rows[11], rows[15]]);
        Self::transpose4([a, b, c, d].map(Self))
    }
    #[inline(always)]
    fn transpose4(rows: [Self; 4]) -> [Self; 4] {
        let [a, b, c, d] = rows.map(|r| r.0);
        avx512!({
            let (ab_lo, cd_lo) = (_mm512_unpacklo_ps(a, b), _mm512_unpacklo_ps(c, d));
            let (ab_hi, cd_hi) = (_mm512_unpackhi_ps(a, b), _mm512_unpackhi_ps(c, d));
            [
                Self(_mm512_shuffle_ps::<0x44>(ab_lo, cd_lo)),
                Self(_mm512_shuffle_ps::<0xee>(ab_lo, cd_lo)),
                Self(_mm512_shuffle_ps::<0x44>(ab_hi, cd_hi)),
                Self(_mm512_shuffle_ps::<0xee>(ab_hi, cd_hi)),
            ]
        })
    }
    #[inline(always)]
    fn pack_u32(ids: &[u32; 16], bits: u32, out: &mut [u32]) -> usize {
        assert!(out.len() >= 16);
        let keep = bits as u16;
        // SAFETY: `ids` is sixteen readable `u32`s and the assert guarantees sixteen writable ones in `out`;
        // `loadu`/`storeu` have no alignment requirement; AVX-512F is present (see `avx512!`).
        unsafe {
            let v = _mm512_loadu_si512(ids.as_ptr().cast());
            _mm512_storeu_si512(out.as_mut_ptr().cast(), _mm512_maskz_compress_epi32(keep, v));
        }
        keep.count_ones() as usize
    }
    #[inline(always)]
    fn splat_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        assert!(rows.len() >= 4);
        let r = load_blocks([rows[0], rows[1], rows[2], rows[3]]);
        avx512!([
            Self(_mm512_permute_ps::<0x00>(r)),
            Self(_mm512_permute_ps::<0x55>(r)),
            Self(_mm512_permute_ps::<0xaa>(r)),
            Self(_mm512_permute_ps::<0xff>(r)),
        ])
    }
    #[inline(always)]
    fn repeat4(quad: &[f32; 4]) -> Self {
        Self(load_blocks([quad; 4]))
    }
    #[inline(always)]
    fn from_quads(quads: &[&[f32; 4]]) -> Self {
        assert!(quads.len() >= 4);
        Self(load_blocks([quads[0], quads[1], quads[2], quads[3]]))
    }
}
