//! SIMD value types for raylab's kernels.
//!
//! Kernels are written once, generic over [`Vf32`], and instantiated with a hardware backend and with the
//! portable [`scalar::F32x4`], which has the same API and the same per-lane semantics (including how `min`,
//! `max` and comparisons treat NaN), so tests can run every kernel both ways and compare. Backends are
//! chosen once, when a tracer is set up ([`Backend::detect`], which checks the CPU at run time), never per
//! ray; a kernel runs with a backend's lane type through [`dispatch`].
//!
//! This is the only raylab crate that may use `unsafe`; each block says why it is sound.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Not, Sub};

pub mod scalar;
#[cfg(target_arch = "x86_64")]
pub mod sse;
#[cfg(target_arch = "x86_64")]
mod x16;
#[cfg(target_arch = "x86_64")]
mod x8;

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
    Copy + Debug + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + 'static
{
    /// The mask type of comparisons.
    type Mask: VMask;
    /// Number of lanes.
    const LANES: usize;
    /// `[T; LANES]`: per-lane data kept beside the vectors (a packet's triangle ids, the rays to pack), sized
    /// for this lane type rather than for the widest, so narrow kernels do not fill and copy unused lanes.
    type Array<T: Copy + Debug>: Copy + Debug + AsRef<[T]> + AsMut<[T]>;
    /// The array whose element `i` is `f(i)`.
    fn array_from_fn<T: Copy + Debug>(f: impl FnMut(usize) -> T) -> Self::Array<T>;
    /// The four-lane type of this backend, for work that is four-wide whatever the packet width (MFT's four
    /// frustums): narrower registers make a lighter stack entry and, where wide operations are split into
    /// halves, cheaper steps.
    type Quad: Vf32;
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
    /// Lane-wise square root, correctly rounded as `f32::sqrt` (NaN below zero).
    fn sqrt(self) -> Self;
    /// The four columns of `LANES` four-float rows (`rows[i]` in lane `i`): loads records of four fields
    /// into one vector per field with a register transpose instead of a load per lane and field. `rows` must
    /// hold at least `LANES` rows.
    fn transpose_rows(rows: &[&[f32; 4]]) -> [Self; 4];
    /// Each group of four lanes transposed as a 4x4 matrix: lane `4g + j` of result `i` is lane `4g + i` of
    /// `rows[j]` (the per-ray results of four-wide node tests regrouped per node lane, in MBVH ray streams).
    fn transpose4(rows: [Self; 4]) -> [Self; 4];
    /// `ids` (at least `LANES` of them) in the lane order of [`Vf32::transpose4`]'s results: lane `i` holds
    /// `ids[(LANES / 4) * (i % 4) + i / 4]`. When row `j` of `transpose4`'s input holds the results of ids
    /// `(LANES / 4) * j ..`, one per group of four lanes, lane `i` of every output row then belongs to id `i`
    /// of this array (MBVH ray streams regroup two rays' node tests per child, then push the rays by
    /// [`Vf32::pack_u32`]).
    #[inline(always)]
    fn transpose4_ids(ids: &[u32]) -> Self::Array<u32> {
        let per = Self::LANES / 4;
        let mut out = Self::array_from_fn(|_| 0);
        for (i, slot) in out.as_mut().iter_mut().enumerate() {
            *slot = ids[per * (i % 4) + i / 4];
        }
        out
    }
    /// Left-packs `ids`: writes the entries whose bit is set in `bits` (entry `i` in bit `i`) to the front of
    /// `out` in order and returns how many there are, with one whole-vector store and no branch per entry
    /// (MBVH ray streams push a vector of rays onto a lane's stack at once). `out` must hold at least `LANES`
    /// entries; those past the returned count are left with unspecified values.
    fn pack_u32(ids: &Self::Array<u32>, bits: u32, out: &mut [u32]) -> usize;
    /// The four fields of `LANES / 4` rows, each row's field in every lane of its group of four (`rows[g]`
    /// in lanes `4g..4g + 4`): several rays' records spread for a test against a four-wide node. `rows` must
    /// hold at least `LANES / 4` rows.
    fn splat_rows(rows: &[&[f32; 4]]) -> [Self; 4];
    /// `quad` repeated in every group of four lanes (a four-wide node's planes, once per ray).
    fn repeat4(quad: &[f32; 4]) -> Self;
    /// Quad `quads[g]` in lanes `4g..4g + 4`: four-float rows picked per group (each ray of an MBVH ray
    /// stream's leaf test reads a four-triangle block's coordinates in its own axis order). `quads` must hold
    /// at least `LANES / 4` rows.
    fn from_quads(quads: &[&[f32; 4]]) -> Self;
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
    /// [`Vf32::reduce_min`] of `LANES` vectors at once: lane `i` of the result is the smallest lane of
    /// `rows[i]`. The wide backends fold the rows through a register transpose, in a fraction of the steps
    /// of one reduction per row (the batched culling data of a tile's packets). `rows` must hold at least
    /// `LANES` vectors, none with a NaN lane (what a NaN gives is unspecified).
    #[inline(always)]
    fn reduce_min_each(rows: &[Self]) -> Self {
        let mut out = Self::array_from_fn(|_| 0.0);
        for (o, r) in out.as_mut().iter_mut().zip(&rows[..Self::LANES]) {
            *o = r.reduce_min();
        }
        Self::from_slice(out.as_ref())
    }
    /// [`Vf32::reduce_max`] of `LANES` vectors at once, as [`Vf32::reduce_min_each`].
    #[inline(always)]
    fn reduce_max_each(rows: &[Self]) -> Self {
        let mut out = Self::array_from_fn(|_| 0.0);
        for (o, r) in out.as_mut().iter_mut().zip(&rows[..Self::LANES]) {
            *o = r.reduce_max();
        }
        Self::from_slice(out.as_ref())
    }
}

/// Asks the CPU to start loading every cache line of `values` (MBVH ray streams fetch a leaf's triangles
/// while the leaf waits on the task stack). A hint only: it never faults and changes no result; it does
/// nothing off x86-64.
#[inline(always)]
pub fn prefetch<T>(values: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        let start = values.as_ptr().cast::<i8>();
        for offset in (0..std::mem::size_of_val(values)).step_by(64) {
            // SAFETY: SSE is part of x86-64; a prefetch reads nothing architecturally and never faults, and
            // the address lies inside `values`.
            unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(start.add(offset)) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = values;
}

/// Asks the kernel to back the 2 MiB-aligned stretches of `values` with huge pages (Linux transparent huge
/// pages: `MADV_HUGEPAGE`, then `MADV_COLLAPSE` for memory already touched). A hint only: it changes no value
/// and does nothing elsewhere, on slices without a whole aligned stretch, or where the kernel declines.
/// With 4 KiB pages the physical placement of a structure that fills much of the L2 cache (an MBVH ray
/// stream's per-ray records, about 0.5 MiB for 2^12 rays) differs from run to run, and with it the cache
/// conflicts and the speed.
pub fn huge_pages<T>(values: &[T]) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        const HUGE: usize = 2 << 20;
        let start = values.as_ptr() as usize;
        let (first, end) = (start.next_multiple_of(HUGE), start + std::mem::size_of_val(values));
        if end >= first + HUGE {
            let len = (end - first) / HUGE * HUGE;
            // SAFETY: the range lies inside `values`' allocation and `madvise` with these advice values changes
            // how pages are backed, never their contents; a failure is only an error code, ignored here.
            unsafe {
                libc::madvise(first as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
                libc::madvise(first as *mut libc::c_void, len, libc::MADV_COLLAPSE);
            }
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = values;
}

/// Which hardware path the kernels use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// Portable scalar lanes (any CPU; also the twin the tests compare against).
    Scalar,
    /// SSE2 on x86-64 (always present there): four lanes.
    Sse,
    /// AVX2 and FMA on x86-64 CPUs that have them, with the bit-manipulation sets every such CPU has (BMI1,
    /// BMI2, POPCNT, LZCNT; all checked at run time): eight lanes for the kernels that
    /// take any width (4x2 ray packets, DACRT's filter and leaves) and two rays per four-wide node test in
    /// MBVH ray streams; single-ray MBVH traversal, whose vectors are its four-wide nodes, uses SSE with it.
    Avx2,
    /// AVX-512 (F and VL) with AVX2 and FMA on x86-64 CPUs that have them (checked at run time): sixteen lanes,
    /// 4x4 ray packets, for the kernels that take any width; the kernels written for at most eight lanes (MBVH
    /// ray streams, DACRT) run as under [`Backend::Avx2`] ([`Backend::at_most_eight_lanes`]).
    Avx512,
}

impl Backend {
    /// The fastest backend this CPU supports.
    pub fn detect() -> Self {
        Self::available()[0]
    }

    /// Every backend this CPU can run, fastest first.
    pub fn available() -> Vec<Backend> {
        let mut v = Vec::new();
        #[cfg(target_arch = "x86_64")]
        {
            if avx512_detected() {
                v.push(Backend::Avx512);
            }
            if avx2_detected() {
                v.push(Backend::Avx2);
            }
            v.push(Backend::Sse);
        }
        v.push(Backend::Scalar);
        v
    }

    /// Lanes of [`dispatch`]'s vectors with this backend on this CPU.
    pub fn lanes(self) -> usize {
        struct Lanes;
        impl Kernel for Lanes {
            type Output = usize;
            fn run<V: Vf32>(self) -> usize {
                V::LANES
            }
        }
        dispatch(self, Lanes)
    }

    /// The name shown in reports.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Scalar => "scalar",
            Backend::Sse => "sse2",
            Backend::Avx2 => "avx2",
            Backend::Avx512 => "avx512",
        }
    }

    /// This backend, or [`Backend::Avx2`] in place of [`Backend::Avx512`]: for kernels whose layouts hold at
    /// most eight lanes (one or two rays per four-wide MBVH node test, DACRT's eight-box filter).
    pub fn at_most_eight_lanes(self) -> Self {
        match self {
            Backend::Avx512 => Backend::Avx2,
            b => b,
        }
    }
}

/// A computation written once for any lane type: [`dispatch`] runs it with the type a [`Backend`] picks.
///
/// Generic functions a kernel calls should be `#[inline(always)]`, so that under [`Backend::Avx2`] they are
/// compiled into the AVX2 entry point with it; one compiled on its own is still correct but runs the eight
/// lanes as pairs of SSE instructions.
pub trait Kernel {
    /// What the kernel returns.
    type Output;
    /// Runs the kernel with lane type `V`.
    fn run<V: Vf32>(self) -> Self::Output;
}

/// Runs `k` with the widest vectors `backend` offers on this CPU: sixteen lanes for [`Backend::Avx512`], eight
/// for [`Backend::Avx2`] (a backend the CPU lacks falls back to the next narrower one), four otherwise.
pub fn dispatch<K: Kernel>(backend: Backend, k: K) -> K::Output {
    match backend {
        #[cfg(target_arch = "x86_64")]
        Backend::Avx512 if avx512_detected() => {
            dispatch_log::note(Backend::Avx512);
            // SAFETY: the guard checked that the CPU has AVX-512F/VL, AVX2, FMA and the bit-manipulation sets,
            // every feature `run_avx512` is compiled for.
            unsafe { run_avx512(k) }
        }
        #[cfg(target_arch = "x86_64")]
        Backend::Avx2 | Backend::Avx512 if avx2_detected() => {
            dispatch_log::note(Backend::Avx2);
            // SAFETY: the guard checked that the CPU has AVX2, FMA and the bit-manipulation sets, every feature
            // `run_avx2` is compiled for.
            unsafe { run_avx2(k) }
        }
        #[cfg(target_arch = "x86_64")]
        Backend::Sse | Backend::Avx2 | Backend::Avx512 => {
            dispatch_log::note(Backend::Sse);
            k.run::<sse::F32x4>()
        }
        _ => {
            dispatch_log::note(Backend::Scalar);
            k.run::<scalar::F32x4>()
        }
    }
}

/// Which lanes [`dispatch`] ran, counted per thread when the `dispatch-log` feature is on (tests turn it on);
/// without it counting costs nothing and [`dispatch_log::take`] always returns zeros.
pub mod dispatch_log {
    use super::Backend;

    #[cfg(feature = "dispatch-log")]
    thread_local! {
        static COUNTS: std::cell::Cell<[u64; 4]> = const { std::cell::Cell::new([0; 4]) };
    }

    fn slot(b: Backend) -> usize {
        match b {
            Backend::Scalar => 0,
            Backend::Sse => 1,
            Backend::Avx2 => 2,
            Backend::Avx512 => 3,
        }
    }

    /// Counts one dispatch that ran `lanes`' vectors.
    #[inline(always)]
    pub(crate) fn note(lanes: Backend) {
        #[cfg(feature = "dispatch-log")]
        COUNTS.with(|c| {
            let mut v = c.get();
            v[slot(lanes)] += 1;
            c.set(v);
        });
        #[cfg(not(feature = "dispatch-log"))]
        let _ = slot(lanes);
    }

    /// The dispatches this thread ran since the last call, per lane type: scalar, SSE, AVX2, AVX-512.
    pub fn take() -> [u64; 4] {
        #[cfg(feature = "dispatch-log")]
        return COUNTS.with(|c| c.replace([0; 4]));
        #[cfg(not(feature = "dispatch-log"))]
        [0; 4]
    }
}

/// True when this CPU has AVX-512F and AVX-512VL besides what [`Backend::Avx2`] needs ([`Backend::Avx512`]).
#[cfg(target_arch = "x86_64")]
fn avx512_detected() -> bool {
    is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") && avx2_detected()
}

/// True when this CPU has AVX2 and FMA, and BMI1, BMI2, POPCNT and LZCNT ([`Backend::Avx2`]). Every CPU with
/// AVX2 has the four (Intel from Haswell, AMD from Excavator); compiling the entry points for them turns the
/// kernels' scalar mask work (lane bits, variable shifts, bit counts) into single instructions.
#[cfg(target_arch = "x86_64")]
fn avx2_detected() -> bool {
    is_x86_feature_detected!("avx2")
        && is_x86_feature_detected!("fma")
        && is_x86_feature_detected!("bmi1")
        && is_x86_feature_detected!("bmi2")
        && is_x86_feature_detected!("popcnt")
        && is_x86_feature_detected!("lzcnt")
}

/// Runs `k` with eight lanes, compiled for AVX2, FMA and the bit-manipulation sets, so the kernel's inlined
/// code and [`x8::F32x8`]'s intrinsics become 256-bit instructions. The only place an `F32x8` is created
/// (see the `x8` module).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,popcnt,lzcnt")]
fn run_avx2<K: Kernel>(k: K) -> K::Output {
    k.run::<x8::F32x8>()
}

/// Runs `k` with sixteen lanes, compiled for AVX-512F/VL besides every feature of `run_avx2`, so the kernel's
/// inlined code and [`x16::F32x16`]'s intrinsics become 512-bit instructions. The only place an `F32x16` is
/// created (see the `x16` module).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,bmi1,bmi2,popcnt,lzcnt")]
fn run_avx512<K: Kernel>(k: K) -> K::Output {
    k.run::<x16::F32x16>()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane semantics every backend must share, on every group of four lanes (one, two or four groups).
    struct Semantics;

    impl Kernel for Semantics {
        type Output = ();
        fn run<V: Vf32>(self) {
            let a4 = [1.0, -2.0, f32::NAN, 0.0];
            let b4 = [0.5, 3.0, 1.0, -0.0];
            let (mut a, mut b) = ([0.0f32; 16], [0.0f32; 16]);
            for i in 0..16 {
                a[i] = a4[i % 4];
                b[i] = b4[i % 4];
            }
            let n = V::LANES;
            let (a, b) = (V::from_slice(&a[..n]), V::from_slice(&b[..n]));
            let rep = |bits4: u32| (0..n / 4).fold(0, |m, g| m | bits4 << (4 * g));
            assert_eq!(a.lt(b).bits(), rep(0b0010));
            assert_eq!(a.le(b).bits(), rep(0b1010), "0.0 <= -0.0");
            assert_eq!(a.eq(b).bits(), rep(0b1000));
            let mn = a.min(b);
            for base in (0..n).step_by(4) {
                assert_eq!([mn.lane(base), mn.lane(base + 1), mn.lane(base + 2)], [0.5, -2.0, 1.0], "NaN in a keeps b");
            }
            let mx = b.max(a);
            assert!(mx.lane(2).is_nan() && mx.lane(n - 2).is_nan(), "NaN in the second operand is returned");
            let sel = V::select(V::Mask::from_bits(rep(0b0101)), a, b);
            assert_eq!([sel.lane(0), sel.lane(1), sel.lane(n - 3)], [1.0, 3.0, 3.0]);
            assert_eq!(a.abs().lane(n - 3), 2.0);
            let roots = [2.0f32, 0.25, -1.0, -0.0, 3.0, 1e30, 7.0, 0.5, 9.0, 1e-30, 5.0, 0.0, 2.5, 64.0, 3e3, 1e-3];
            let r = V::from_slice(&roots[..n]).sqrt();
            for (i, x) in roots[..n].iter().enumerate() {
                assert_eq!(r.lane(i).to_bits(), x.sqrt().to_bits(), "sqrt of {x}");
            }
            assert_eq!(a.reduce_min(), -2.0);
            assert_eq!(a.reduce_max(), 1.0);
            assert!(V::splat(f32::NAN).reduce_min().is_nan() && V::splat(f32::NAN).reduce_max().is_nan());
            let mut one = [f32::NAN; 16];
            one[n - 1] = -3.5;
            assert_eq!((V::from_slice(&one[..n]).reduce_min(), V::from_slice(&one[..n]).reduce_max()), (-3.5, -3.5));
            // NaN in any set of lanes is skipped by both reductions, wherever the extremes sit.
            let values = [3.0f32, -1.5, 8.0, 0.25, -7.0, 2.0, 5.5, -0.5, 9.5, 1.0, -3.0, 4.0, 6.0, -2.5, 0.5, 7.5];
            for nan in (0..1u32 << n).step_by(n / 4 * n / 4) {
                let lanes: Vec<f32> = (0..n).map(|i| if nan >> i & 1 == 1 { f32::NAN } else { values[i] }).collect();
                let kept: Vec<f32> = lanes.iter().copied().filter(|x| !x.is_nan()).collect();
                let v = V::from_slice(&lanes);
                if kept.is_empty() {
                    assert!(v.reduce_min().is_nan() && v.reduce_max().is_nan());
                } else {
                    let (lo, hi) =
                        kept.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
                    assert_eq!((v.reduce_min(), v.reduce_max()), (lo, hi), "NaN lanes {nan:#b}");
                }
            }
            // The batched reductions: every row's extremes, wherever they sit, infinities included.
            let rows: Vec<V> = (0..n)
                .map(|r| {
                    let lanes: Vec<f32> = (0..n)
                        .map(|i| match (i + 3 * r) % n {
                            0 if r % 5 == 1 => f32::INFINITY,
                            1 if r % 3 == 2 => f32::NEG_INFINITY,
                            k => values[(k + r) % 16] * (r as f32 + 1.0),
                        })
                        .collect();
                    V::from_slice(&lanes)
                })
                .collect();
            let (lo, hi) = (V::reduce_min_each(&rows), V::reduce_max_each(&rows));
            for (r, row) in rows.iter().enumerate() {
                assert_eq!((lo.lane(r), hi.lane(r)), (row.reduce_min(), row.reduce_max()), "row {r}");
            }
            let mut spread = [1.0f32; 16];
            (spread[1], spread[n - 2]) = (f32::INFINITY, f32::NEG_INFINITY);
            let inf = V::from_slice(&spread[..n]);
            assert_eq!((inf.reduce_min(), inf.reduce_max()), (f32::NEG_INFINITY, f32::INFINITY));
            let mut out = [0.0; 16];
            (a + b).write_to(&mut out[..n]);
            assert_eq!([out[0], out[n - 4]], [1.5, 1.5]);
            assert!((a * b - a / b).lane(1) == -6.0 + 2.0 / 3.0);
            assert!(!V::Mask::from_bits(0).any() && V::Mask::from_bits(0).none());
            let all = (1u32 << n) - 1;
            assert_eq!((!V::Mask::from_bits(0b0001)).bits(), all & !1);
            assert_eq!(V::Mask::from_bits(u32::MAX).bits(), all);
            assert_eq!((V::Mask::from_bits(0b0110) ^ V::Mask::from_bits(0b0011)).bits(), 0b0101);
            assert_eq!(V::splat(2.5).lane(n - 1), 2.5);
            let ids = V::array_from_fn(|i| 10 * i);
            assert_eq!(ids.as_ref(), (0..n).map(|i| 10 * i).collect::<Vec<_>>().as_slice(), "one element per lane");
            let rows: Vec<[f32; 4]> = (0..16).map(|i| [i as f32, 10.0 + i as f32, -(i as f32), f32::NAN]).collect();
            let refs: Vec<&[f32; 4]> = rows.iter().collect();
            let spread = V::splat_rows(&refs);
            let quad = V::repeat4(&[1.0, 2.0, 3.0, 4.0]);
            let quads = V::from_quads(&refs[3..]);
            for i in 0..n {
                let g = i / 4;
                assert_eq!(
                    [spread[0].lane(i), spread[1].lane(i), spread[2].lane(i)],
                    [g as f32, 10.0 + g as f32, -(g as f32)]
                );
                assert!(spread[3].lane(i).is_nan());
                assert_eq!(quad.lane(i), (i % 4 + 1) as f32);
                let row = &rows[3 + g];
                assert_eq!(quads.lane(i).to_bits(), row[i % 4].to_bits(), "from_quads lane {i}");
            }
            let groups = V::transpose4(std::array::from_fn(|j| {
                V::from_slice(&(0..n).map(|i| (100 * j + i) as f32).collect::<Vec<_>>())
            }));
            for (c, col) in groups.iter().enumerate() {
                for i in 0..n {
                    assert_eq!(col.lane(i), (100 * (i % 4) + i - i % 4 + c) as f32, "transpose4 lane {i} of {c}");
                }
            }
            let regrouped = V::transpose4_ids(&(0..n as u32).collect::<Vec<_>>());
            for (i, &id) in regrouped.as_ref().iter().enumerate() {
                assert_eq!(id as usize, (n / 4) * (i % 4) + i / 4, "transpose4_ids lane {i}");
            }
            let ids = V::array_from_fn(|i| 7 + i as u32);
            for bits in [0u32, 1, 0b1010, 0b0110_1001, u32::MAX, 1 << (n - 1)] {
                let mut out = [u32::MAX; 16];
                let kept = V::pack_u32(&ids, bits, &mut out[..n]);
                let want: Vec<u32> =
                    ids.as_ref().iter().enumerate().filter(|(i, _)| bits >> i & 1 == 1).map(|(_, &d)| d).collect();
                assert_eq!(&out[..kept], want.as_slice(), "pack_u32 of {bits:#b}");
            }
            let cols = V::transpose_rows(&refs);
            for i in 0..n {
                assert_eq!(
                    [cols[0].lane(i), cols[1].lane(i), cols[2].lane(i)],
                    [i as f32, 10.0 + i as f32, -(i as f32)]
                );
                assert!(cols[3].lane(i).is_nan());
            }
        }
    }

    #[test]
    fn every_backend_has_the_same_lane_semantics() {
        for b in Backend::available() {
            dispatch(b, Semantics);
        }
    }

    #[test]
    fn huge_page_advice_keeps_every_value() {
        let values: Vec<u32> = (0..3 << 20).collect();
        huge_pages(&values);
        huge_pages(&values[5..7]);
        huge_pages::<u64>(&[]);
        assert!(values.iter().enumerate().all(|(i, &v)| v == i as u32));
    }

    #[test]
    fn backends_are_listed_fastest_first_and_scalar_always() {
        let avail = Backend::available();
        assert_eq!(Backend::detect(), avail[0]);
        assert_eq!(avail.last(), Some(&Backend::Scalar));
        assert_eq!(Backend::Scalar.lanes(), 4);
        #[cfg(target_arch = "x86_64")]
        {
            assert!(avail.contains(&Backend::Sse));
            assert_eq!(Backend::Sse.lanes(), 4);
            let bits = is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("bmi2")
                && is_x86_feature_detected!("popcnt")
                && is_x86_feature_detected!("lzcnt");
            let eight = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") && bits;
            assert_eq!(avail.contains(&Backend::Avx2), eight);
            assert_eq!(Backend::Avx2.lanes(), if eight { 8 } else { 4 }, "without AVX2 the backend falls back");
            let sixteen = eight && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl");
            assert_eq!(avail.contains(&Backend::Avx512), sixteen);
            let wide = if sixteen { 16 } else { Backend::Avx2.lanes() };
            assert_eq!(Backend::Avx512.lanes(), wide, "without AVX-512 the backend falls back");
            assert_eq!(Backend::Avx512.at_most_eight_lanes(), Backend::Avx2);
            assert!(Backend::Avx512.at_most_eight_lanes().lanes() <= 8);
        }
    }
}
