//! Eight `f32` lanes in one AVX register (thesis 4.1.2 expects packets to widen with the SIMD units; these
//! give the 4x2 packets), with exactly the SSE backend's semantics (`min`/`max` return the second operand when
//! either is NaN).
//!
//! The types are private to this crate and only [`crate::dispatch`]'s AVX2 entry point instantiates kernels
//! with them, after checking that the CPU has AVX2 and FMA (and the bit-manipulation sets): no value of them,
//! and so none of the AVX instructions below, can exist on a CPU without those features. Kernels are inlined
//! into that entry point, which is compiled for AVX2, so every operation becomes one 256-bit instruction.

use std::arch::x86_64::*;
use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

use crate::{VMask, Vf32};

/// Evaluates an expression of register-only AVX/AVX2 intrinsics.
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: values of this module's types are only created by kernels that `run_avx2` runs, and it is
        // only called once `is_x86_feature_detected!` has confirmed AVX2 and FMA (see the module docs); these
        // intrinsics only read and write registers.
        unsafe { $e }
    };
}

/// Per 8-bit mask, the lanes whose bits are set, in order, one byte each (zero after them): the lane order
/// that left-packs eight lanes ([`Vf32::pack_u32`]), 2 KiB.
static PACK8: [u64; 256] = {
    let mut table = [0u64; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut lane, mut kept) = (0, 0);
        while lane < 8 {
            if mask >> lane & 1 == 1 {
                table[mask] |= (lane as u64) << (8 * kept);
                kept += 1;
            }
            lane += 1;
        }
        mask += 1;
    }
    table
};

/// Eight `f32` lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F32x8(__m256);

/// Eight lane masks (all bits set or clear per lane), as AVX comparisons produce them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct M32x8(__m256);

impl VMask for M32x8 {
    #[inline(always)]
    fn bits(self) -> u32 {
        avx!(_mm256_movemask_ps(self.0)) as u32
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        avx!({
            let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane_bits);
            Self(_mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bits)))
        })
    }
}

/// `impl $trait for $ty` by one two-operand intrinsic on the registers.
macro_rules! binop {
    ($ty:ident, $trait:ident, $f:ident, $intr:ident) => {
        impl $trait for $ty {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(avx!($intr(self.0, o.0)))
            }
        }
    };
}

binop!(M32x8, BitAnd, bitand, _mm256_and_ps);
binop!(M32x8, BitOr, bitor, _mm256_or_ps);
binop!(M32x8, BitXor, bitxor, _mm256_xor_ps);

impl Not for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(avx!(_mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1)))))
    }
}

binop!(F32x8, Add, add, _mm256_add_ps);
binop!(F32x8, Sub, sub, _mm256_sub_ps);
binop!(F32x8, Mul, mul, _mm256_mul_ps);
binop!(F32x8, Div, div, _mm256_div_ps);

impl F32x8 {
    /// The lanes as an array.
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        let mut a = [0.0; 8];
        self.write_to(&mut a);
        a
    }

    /// Folds the lanes with `op` (a lane-wise min or max) in registers: halves, then quarters, then the last
    /// two. NaN lanes are first replaced by `identity`, so they are ignored; all-NaN input gives NaN.
    #[inline(always)]
    fn reduce(self, identity: f32, op: impl Fn(__m128, __m128) -> __m128) -> f32 {
        avx!({
            let ordered = _mm256_cmp_ps::<_CMP_ORD_Q>(self.0, self.0);
            let v = _mm256_blendv_ps(_mm256_set1_ps(identity), self.0, ordered);
            let m = op(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
            let m = op(m, _mm_movehl_ps(m, m));
            let m = op(m, _mm_movehdup_ps(m));
            if _mm256_movemask_ps(ordered) == 0 { f32::NAN } else { _mm_cvtss_f32(m) }
        })
    }

    /// Lane `i` of the result folds the lanes of `rows[i]` with `op` (a lane-wise min or max), for eight rows:
    /// neighbouring lanes of row pairs, then of row quadruples, then the two halves, 21 instructions in all.
    #[inline(always)]
    fn fold_rows(rows: &[Self], op: impl Fn(__m256, __m256) -> __m256) -> Self {
        let r: &[Self; 8] = rows[..8].try_into().expect("eight rows");
        avx!({
            // Per half: [op(a0, a2), op(b0, b2), op(a1, a3), op(b1, b3)].
            let pair = |a: Self, b: Self| op(_mm256_unpacklo_ps(a.0, b.0), _mm256_unpackhi_ps(a.0, b.0));
            // Per half: each of the four rows folded over the half's lanes.
            let quad = |p: __m256, q: __m256| op(_mm256_shuffle_ps::<0x44>(p, q), _mm256_shuffle_ps::<0xee>(p, q));
            let low = quad(pair(r[0], r[1]), pair(r[2], r[3]));
            let high = quad(pair(r[4], r[5]), pair(r[6], r[7]));
            Self(op(_mm256_permute2f128_ps::<0x20>(low, high), _mm256_permute2f128_ps::<0x31>(low, high)))
        })
    }
}

impl Vf32 for F32x8 {
    type Mask = M32x8;
    const LANES: usize = 8;
    type Array<T: Copy + Debug> = [T; 8];
    type Quad = crate::sse::F32x4;

    #[inline(always)]
    fn array_from_fn<T: Copy + Debug>(f: impl FnMut(usize) -> T) -> [T; 8] {
        std::array::from_fn(f)
    }

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self(avx!(_mm256_set1_ps(x)))
    }
    #[inline(always)]
    fn from_slice(s: &[f32]) -> Self {
        assert!(s.len() >= 8);
        // SAFETY: the assert guarantees eight readable `f32`s and `loadu` has no alignment requirement; AVX is
        // present (see `avx!`).
        Self(unsafe { _mm256_loadu_ps(s.as_ptr()) })
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        assert!(out.len() >= 8);
        // SAFETY: the assert guarantees eight writable `f32`s and `storeu` has no alignment requirement; AVX is
        // present (see `avx!`).
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.to_array()[i]
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(avx!(_mm256_min_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(avx!(_mm256_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn select(m: M32x8, a: Self, b: Self) -> Self {
        Self(avx!(_mm256_blendv_ps(b.0, a.0, m.0)))
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.reduce(f32::INFINITY, |a, b| avx!(_mm_min_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.reduce(f32::NEG_INFINITY, |a, b| avx!(_mm_max_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_min_each(rows: &[Self]) -> Self {
        Self::fold_rows(rows, |a, b| avx!(_mm256_min_ps(a, b)))
    }
    #[inline(always)]
    fn reduce_max_each(rows: &[Self]) -> Self {
        Self::fold_rows(rows, |a, b| avx!(_mm256_max_ps(a, b)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(avx!(_mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff)))))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(avx!(_mm256_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn transpose_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        assert!(rows.len() >= 8);
        // Rows i and i + 4 share a register (low and high half); the 4x4 transpose then runs in both halves.
        let pair = |i: usize| {
            // SAFETY: each row is a reference to four readable `f32`s and `loadu` has no alignment
            // requirement; AVX is present (see `avx!`).
            Self(unsafe { _mm256_loadu2_m128(rows[i + 4].as_ptr(), rows[i].as_ptr()) })
        };
        Self::transpose4([pair(0), pair(1), pair(2), pair(3)])
    }
    #[inline(always)]
    fn transpose4(rows: [Self; 4]) -> [Self; 4] {
        let [a, b, c, d] = rows.map(|r| r.0);
        avx!({
            let (ab_lo, cd_lo) = (_mm256_unpacklo_ps(a, b), _mm256_unpacklo_ps(c, d));
            let (ab_hi, cd_hi) = (_mm256_unpackhi_ps(a, b), _mm256_unpackhi_ps(c, d));
            [
                Self(_mm256_shuffle_ps::<0x44>(ab_lo, cd_lo)),
                Self(_mm256_shuffle_ps::<0xee>(ab_lo, cd_lo)),
                Self(_mm256_shuffle_ps::<0x44>(ab_hi, cd_hi)),
                Self(_mm256_shuffle_ps::<0xee>(ab_hi, cd_hi)),
            ]
        })
    }
    #[inline(always)]
    fn transpose4_ids(ids: &[u32]) -> [u32; 8] {
        let ids: &[u32; 8] = ids[..8].try_into().expect("eight ids");
        let mut out = [0u32; 8];
        // SAFETY: `ids` and `out` are eight `u32`s each and `loadu`/`storeu` have no alignment requirement;
        // AVX2 is present (see `avx!`).
        unsafe {
            let v = _mm256_loadu_si256(ids.as_ptr().cast());
            let order = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
            _mm256_storeu_si256(out.as_mut_ptr().cast(), _mm256_permutevar8x32_epi32(v, order));
        }
        out
    }
    #[inline(always)]
    fn pack_u32(ids: &[u32; 8], bits: u32, out: &mut [u32]) -> usize {
        assert!(out.len() >= 8);
        let keep = (bits & 0xff) as usize;
        // SAFETY: `ids` is eight readable `u32`s and the assert guarantees eight writable ones in `out`;
        // `loadu`/`storeu` have no alignment requirement; AVX2 is present (see `avx!`).
        unsafe {
            let v = _mm256_loadu_si256(ids.as_ptr().cast());
            let order = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(PACK8[keep] as i64));
            _mm256_storeu_si256(out.as_mut_ptr().cast(), _mm256_permutevar8x32_epi32(v, order));
        }
        keep.count_ones() as usize
    }
    #[inline(always)]
    fn splat_rows(rows: &[&[f32; 4]]) -> [Self; 4] {
        assert!(rows.len() >= 2);
        // SAFETY: each row is a reference to four readable `f32`s and `loadu` has no alignment requirement;
        // AVX is present (see `avx!`).
        let r = unsafe { _mm256_loadu2_m128(rows[1].as_ptr(), rows[0].as_ptr()) };
        avx!([
            Self(_mm256_permute_ps::<0x00>(r)),
            Self(_mm256_permute_ps::<0x55>(r)),
            Self(_mm256_permute_ps::<0xaa>(r)),
            Self(_mm256_permute_ps::<0xff>(r)),
        ])
    }
    #[inline(always)]
    fn repeat4(quad: &[f32; 4]) -> Self {
        // SAFETY: `quad` is four readable `f32`s and `loadu` has no alignment requirement; AVX is present (see
        // `avx!`).
        Self(unsafe { _mm256_loadu2_m128(quad.as_ptr(), quad.as_ptr()) })
    }
    #[inline(always)]
    fn from_quads(quads: &[&[f32; 4]]) -> Self {
        assert!(quads.len() >= 2);
        // SAFETY: each quad is a reference to four readable `f32`s and `loadu` has no alignment requirement;
        // AVX is present (see `avx!`).
        Self(unsafe { _mm256_loadu2_m128(quads[1].as_ptr(), quads[0].as_ptr()) })
    }
}
