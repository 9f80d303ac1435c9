//! Four `f64` lanes with fused multiply-adds: what a solve with many right-hand sides uses in
//! its x86-64-v3 copy to take four columns at a time (one AVX register) instead of the two of
//! an [`F64x2`](crate::pair::F64x2).
//!
//! A triangular substitution is a chain of dependent multiply-adds, so a solve of many columns
//! waits on that chain once per group of columns it takes together: four columns per register
//! run half as many chains as two (`krang_dynamics`' `BlockCholesky::solve_columns_mut`,
//! Krang's 57 columns: 1,710 → 1,140 ns). Every lane runs the operations of the two-lane
//! [`FusedPair`] code in the same order, so each column gets the same bits either way.
//!
//! An [`F64x4`] is made, read and computed with only through a [`FusedQuad`], which only a
//! [`FusedPair`] makes ([`FusedPair::quad`]): a `FusedPair` exists only where the CPU or the
//! build has FMA (see [`crate::pair`]), and FMA implies AVX, which the four-lane instructions
//! need. On x86-64 an `F64x4` is one `__m256d`; elsewhere it is two [`F64x2`](crate::pair::F64x2).
//! (A `[f64; 4]` form of the same solve compiled to scalar instructions, 30 % slower than two
//! lanes.) Keep its uses out of closures the compiler may not inline (`core::array::from_fn`:
//! measured, the loads became calls and the solve took 3.3 µs): the operations inline only
//! into the copy compiled with AVX and FMA.
//!
//! ```
//! use kanegen_runtime::quad::QuadArith;
//!
//! // Where the CPU has FMA (x86-64-v3), `isa::dispatch_pair_with` hands the fused copy a
//! // `FusedPair`; its `quad()` computes four lanes at once.
//! let r = kanegen_runtime::isa::dispatch_pair_with(
//!     [1.0, 2.0, 3.0, 4.0],
//!     |x, _plain| x.map(|v| v * 2.0 + 1.0),
//!     |x, fused| {
//!         let q = fused.quad();
//!         q.lanes(q.mul_add(q.load(x), q.splat(2.0), q.splat(1.0)))
//!     },
//! );
//! assert_eq!(r, [3.0, 5.0, 7.0, 9.0]);
//! ```

use crate::pair::FusedPair;

/// Four `f64` lanes (see the module docs): values of a [`QuadArith`].
#[derive(Clone, Copy)]
pub struct F64x4(imp::Repr);

/// The operations on [`F64x4`] values: lane by lane, a fused multiply-add rounding once per
/// lane as `f64::mul_add`.
pub trait QuadArith: Copy {
    /// `[x; 4]`.
    fn splat(self, x: f64) -> F64x4;
    /// The lanes `x[0]` (lowest) to `x[3]`.
    fn load(self, x: [f64; 4]) -> F64x4;
    /// The lanes, lowest first.
    fn lanes(self, v: F64x4) -> [f64; 4];
    /// `a + b`.
    fn add(self, a: F64x4, b: F64x4) -> F64x4;
    /// `a − b`.
    fn sub(self, a: F64x4, b: F64x4) -> F64x4;
    /// `a · b`.
    fn mul(self, a: F64x4, b: F64x4) -> F64x4;
    /// `a · b + c`, rounded once.
    fn mul_add(self, a: F64x4, b: F64x4, c: F64x4) -> F64x4;
}

/// Four-lane fused arithmetic: the [`QuadArith`] of the copy that has FMA. Made only by
/// [`FusedPair::quad`].
#[derive(Clone, Copy, Debug)]
pub struct FusedQuad {
    pair: FusedPair,
}

impl FusedPair {
    /// The four-lane arithmetic of the same copy (see [`crate::quad`]).
    #[inline(always)]
    pub fn quad(self) -> FusedQuad {
        FusedQuad { pair: self }
    }
}

impl QuadArith for FusedQuad {
    #[inline(always)]
    fn splat(self, x: f64) -> F64x4 {
        F64x4(imp::splat(self.pair, x))
    }
    #[inline(always)]
    fn load(self, x: [f64; 4]) -> F64x4 {
        F64x4(imp::load(self.pair, x))
    }
    #[inline(always)]
    fn lanes(self, v: F64x4) -> [f64; 4] {
        imp::lanes(self.pair, v.0)
    }
    #[inline(always)]
    fn add(self, a: F64x4, b: F64x4) -> F64x4 {
        F64x4(imp::add(self.pair, a.0, b.0))
    }
    #[inline(always)]
    fn sub(self, a: F64x4, b: F64x4) -> F64x4 {
        F64x4(imp::sub(self.pair, a.0, b.0))
    }
    #[inline(always)]
    fn mul(self, a: F64x4, b: F64x4) -> F64x4 {
        F64x4(imp::mul(self.pair, a.0, b.0))
    }
    #[inline(always)]
    fn mul_add(self, a: F64x4, b: F64x4, c: F64x4) -> F64x4 {
        F64x4(imp::mul_add(self.pair, a.0, b.0, c.0))
    }
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod imp {
    //! AVX and FMA intrinsics. SAFETY of every `unsafe` block below: each function takes a
    //! [`FusedPair`], which exists only where the CPU has FMA (`isa::dispatch_pair_with` makes
    //! it after detecting x86-64-v3) or the build enables FMA (`isa::native_pair`); FMA implies
    //! AVX (rustc enables `avx` with `fma`), the features of the `#[target_feature]` functions
    //! called. They take and return values only (no memory access). Called from the
    //! x86-64-v3 copy, whose features include both, they inline into it.
    use core::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd,
        _mm256_storeu_pd, _mm256_sub_pd,
    };

    use crate::pair::FusedPair;

    pub(super) type Repr = __m256d;

    /// The AVX/FMA operations, compiled with the features they need.
    mod avx {
        use super::*;

        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn splat(x: f64) -> Repr {
            _mm256_set1_pd(x)
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn load(x: [f64; 4]) -> Repr {
            // SAFETY: reads the 32 bytes of `x`.
            unsafe { _mm256_loadu_pd(x.as_ptr()) }
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn lanes(v: Repr) -> [f64; 4] {
            let mut x = [0.0; 4];
            // SAFETY: writes the 32 bytes of `x`.
            unsafe { _mm256_storeu_pd(x.as_mut_ptr(), v) };
            x
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn add(a: Repr, b: Repr) -> Repr {
            _mm256_add_pd(a, b)
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn sub(a: Repr, b: Repr) -> Repr {
            _mm256_sub_pd(a, b)
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn mul(a: Repr, b: Repr) -> Repr {
            _mm256_mul_pd(a, b)
        }
        #[target_feature(enable = "avx,fma")]
        #[inline]
        pub(super) fn mul_add(a: Repr, b: Repr, c: Repr) -> Repr {
            _mm256_fmadd_pd(a, b, c)
        }
    }

    #[inline(always)]
    pub(super) fn splat(_: FusedPair, x: f64) -> Repr {
        // SAFETY: see the module docs (AVX and FMA, proven by the `FusedPair`).
        unsafe { avx::splat(x) }
    }
    #[inline(always)]
    pub(super) fn load(_: FusedPair, x: [f64; 4]) -> Repr {
        // SAFETY: see the module docs.
        unsafe { avx::load(x) }
    }
    #[inline(always)]
    pub(super) fn lanes(_: FusedPair, v: Repr) -> [f64; 4] {
        // SAFETY: see the module docs.
        unsafe { avx::lanes(v) }
    }
    #[inline(always)]
    pub(super) fn add(_: FusedPair, a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs.
        unsafe { avx::add(a, b) }
    }
    #[inline(always)]
    pub(super) fn sub(_: FusedPair, a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs.
        unsafe { avx::sub(a, b) }
    }
    #[inline(always)]
    pub(super) fn mul(_: FusedPair, a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs.
        unsafe { avx::mul(a, b) }
    }
    #[inline(always)]
    pub(super) fn mul_add(_: FusedPair, a: Repr, b: Repr, c: Repr) -> Repr {
        // SAFETY: see the module docs.
        unsafe { avx::mul_add(a, b, c) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    //! Two fused pairs.
    use crate::pair::{F64x2, FusedPair, PairArith};

    pub(super) type Repr = [F64x2; 2];

    #[inline(always)]
    pub(super) fn splat(_: FusedPair, x: f64) -> Repr {
        [F64x2::splat(x); 2]
    }
    #[inline(always)]
    pub(super) fn load(_: FusedPair, x: [f64; 4]) -> Repr {
        [F64x2::new(x[0], x[1]), F64x2::new(x[2], x[3])]
    }
    #[inline(always)]
    pub(super) fn lanes(_: FusedPair, v: Repr) -> [f64; 4] {
        [v[0].lo(), v[0].hi(), v[1].lo(), v[1].hi()]
    }
    #[inline(always)]
    pub(super) fn add(_: FusedPair, a: Repr, b: Repr) -> Repr {
        [a[0] + b[0], a[1] + b[1]]
    }
    #[inline(always)]
    pub(super) fn sub(_: FusedPair, a: Repr, b: Repr) -> Repr {
        [a[0] - b[0], a[1] - b[1]]
    }
    #[inline(always)]
    pub(super) fn mul(_: FusedPair, a: Repr, b: Repr) -> Repr {
        [a[0] * b[0], a[1] * b[1]]
    }
    #[inline(always)]
    pub(super) fn mul_add(p: FusedPair, a: Repr, b: Repr, c: Repr) -> Repr {
        [p.mul_add(a[0], b[0], c[0]), p.mul_add(a[1], b[1], c[1])]
    }
}
