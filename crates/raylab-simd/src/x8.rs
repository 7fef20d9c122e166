//! Eight `f32` lanes, the width of AVX registers (thesis 4.1.2 expects packets to widen with the SIMD
//! units; these give the 4x2 packets).
//!
//! The lanes live in a 32-byte-aligned array and every operation is written per lane, with exactly the SSE
//! backend's semantics (`min`/`max` return the second operand when either is NaN). That code is safe on any
//! CPU: compiled on its own it becomes pairs of SSE instructions, and inside [`crate::dispatch`]'s AVX2 entry
//! point (where kernels are inlined) the compiler turns each operation into one 256-bit instruction, so the
//! kernels get AVX2 without any AVX intrinsic that could run on a CPU lacking it.

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

use crate::{VMask, Vf32};

/// Eight `f32` lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct F32x8(pub [f32; 8]);

/// Eight lane masks, all bits set or clear per lane (the layout of SSE/AVX comparison results).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(32))]
pub struct M32x8([i32; 8]);

impl F32x8 {
    // Plain loops rather than `array::from_fn`/`map`, whose helpers are not always inlined: each operation
    // must stay a handful of instructions inside the kernel for the compiler to vectorise it.
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        let mut r = [0.0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            *lane = f(self.0[i]);
        }
        Self(r)
    }

    #[inline(always)]
    fn map2(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        let mut r = [0.0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            *lane = f(self.0[i], o.0[i]);
        }
        Self(r)
    }

    /// Folds the lanes pairwise (halves, then quarters, then the last two), so the steps vectorise; `pick`
    /// must ignore a NaN operand unless both are NaN, as the trait's reductions do.
    #[inline(always)]
    fn reduce(self, pick: impl Fn(f32, f32) -> f32) -> f32 {
        let v = self.0;
        let h = [pick(v[0], v[4]), pick(v[1], v[5]), pick(v[2], v[6]), pick(v[3], v[7])];
        let q = [pick(h[0], h[2]), pick(h[1], h[3])];
        pick(q[0], q[1])
    }

    #[inline(always)]
    fn test(self, o: Self, f: impl Fn(f32, f32) -> bool) -> M32x8 {
        let mut r = [0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            *lane = -(f(self.0[i], o.0[i]) as i32);
        }
        M32x8(r)
    }
}

impl M32x8 {
    #[inline(always)]
    fn map2(self, o: Self, f: impl Fn(i32, i32) -> i32) -> Self {
        let mut r = [0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            *lane = f(self.0[i], o.0[i]);
        }
        Self(r)
    }
}

impl VMask for M32x8 {
    #[inline(always)]
    fn bits(self) -> u32 {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_load_ps, _mm_movemask_ps};
            // SAFETY: SSE2 is part of the x86-64 baseline, so these intrinsics run on every x86-64 CPU; the
            // array is 32-byte aligned, so both 16-byte halves satisfy `_mm_load_ps`'s alignment, and each
            // half holds four readable lanes. Written this way, the AVX2 entry point compiles it to a single
            // `vmovmskps` on the 256-bit register.
            unsafe {
                let lo = _mm_load_ps(self.0.as_ptr().cast::<f32>());
                let hi = _mm_load_ps(self.0.as_ptr().add(4).cast::<f32>());
                (_mm_movemask_ps(lo) | (_mm_movemask_ps(hi) << 4)) as u32
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            (0..8).fold(0, |b, i| b | ((self.0[i] as u32) >> 31) << i)
        }
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        let mut r = [0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            *lane = -((bits >> i & 1) as i32);
        }
        Self(r)
    }
}

impl BitAnd for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        self.map2(o, |a, b| a & b)
    }
}

impl BitOr for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        self.map2(o, |a, b| a | b)
    }
}

impl BitXor for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        self.map2(o, |a, b| a ^ b)
    }
}

impl Not for M32x8 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        self.map2(Self([-1; 8]), |a, b| a ^ b)
    }
}

macro_rules! arith {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for F32x8 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                self.map2(o, |a, b| a $op b)
            }
        }
    };
}

arith!(Add, add, +);
arith!(Sub, sub, -);
arith!(Mul, mul, *);
arith!(Div, div, /);

impl Vf32 for F32x8 {
    type Mask = M32x8;
    const LANES: usize = 8;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self([x; 8])
    }
    #[inline(always)]
    fn from_slice(s: &[f32]) -> Self {
        let mut r = [0.0; 8];
        r.copy_from_slice(&s[..8]);
        Self(r)
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        out[..8].copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.0[i]
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        self.test(o, |a, b| a < b)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x8 {
        self.test(o, |a, b| a <= b)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        self.test(o, |a, b| a == b)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // `minps`: the second operand unless the first is smaller (so NaN in either gives the second).
        self.map2(o, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        self.map2(o, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn select(m: M32x8, a: Self, b: Self) -> Self {
        let mut r = [0.0; 8];
        for (i, lane) in r.iter_mut().enumerate() {
            let keep = m.0[i] as u32;
            *lane = f32::from_bits((a.0[i].to_bits() & keep) | (b.0[i].to_bits() & !keep));
        }
        Self(r)
    }
    #[inline(always)]
    fn reduce_min(self) -> f32 {
        self.reduce(|a, b| if a < b || b.is_nan() { a } else { b })
    }
    #[inline(always)]
    fn reduce_max(self) -> f32 {
        self.reduce(|a, b| if a > b || b.is_nan() { a } else { b })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(|a| f32::from_bits(a.to_bits() & 0x7fff_ffff))
    }
}
