//! Two `f64` lanes: what a generated function uses to compute two mirrored subtrees of the
//! model (Krang's two arms) at once, one arm per lane ("arms in lanes").
//!
//! Where a model has two sibling subtrees of the same shape (the same joints, axes and
//! geometry below their first joint, each with its own inertial parameters), the generator
//! pairs every statement of one with the statement of the other that computes the same
//! expression of the mirrored inputs, and prints each pair once, as a statement over
//! [`F64x2`]: `let d275_d7 = lanes.mul_add(-d272_d4, F64x2::new(s_q6l, s_q6r), …);`, left subtree in the low
//! lane, right subtree in the high lane. Both lanes run the IEEE operations of the scalar
//! statements they replace, in the same order, so **every value is the scalar program's bit
//! for bit**: [`Plain`]'s multiply-add is a multiplication and an addition per lane, and
//! [`FusedPair`]'s is one fused multiply-add per lane, as `f64::mul_add` in the scalar
//! `Fused` copy. Values shared by both subtrees (the trunk's, the shared lengths) enter as
//! `f64` operands, applied to both lanes.
//!
//! On x86-64 an [`F64x2`] is one SSE2 register (`__m128d`, part of every x86-64 target's
//! baseline), so the baseline copy of a function computes both arms with one `mulpd`/`addpd`
//! per operation, and the x86-64-v3 copy with one `vfmadd…pd`; elsewhere it is `[f64; 2]`,
//! which the compiler may or may not vectorize. The fused multiply-add needs FMA, which only
//! the x86-64-v3 copy may use: the [`FusedPair`] value that performs it can only be obtained
//! from [`crate::isa::dispatch_pair_with`] (after the CPU was found to have FMA) or
//! [`crate::isa::native_pair`] (when the build enables FMA), so safe code cannot run an FMA
//! instruction on a CPU without it.
//!
//! ```
//! use kanegen_runtime::isa::Plain;
//! use kanegen_runtime::pair::{F64x2, PairArith};
//!
//! let x = F64x2::new(1.5, -2.0);
//! let y = 2.0 * x - 1.0; // an `f64` operand applies to both lanes
//! assert_eq!((y.lo(), y.hi()), (2.0, -5.0));
//! let z = Plain.mul_add(x, y, 0.25); // x * y + 0.25 per lane
//! assert_eq!((z.lo(), z.hi()), (1.5 * 2.0 + 0.25, -2.0 * -5.0 + 0.25));
//! ```

use core::ops::{Add, Div, Mul, Neg, Sub};

use crate::arith::Plain;

/// Two `f64` lanes (`lo`, `hi`) with lane-wise arithmetic; an `f64` operand applies to both
/// lanes. See the module docs.
#[derive(Clone, Copy)]
pub struct F64x2(imp::Repr);

impl F64x2 {
    /// The lanes `lo` and `hi`.
    #[inline(always)]
    pub fn new(lo: f64, hi: f64) -> Self {
        Self(imp::new(lo, hi))
    }

    /// `v` in both lanes.
    #[inline(always)]
    pub fn splat(v: f64) -> Self {
        Self::new(v, v)
    }

    /// The low lane (the first subtree's value).
    #[inline(always)]
    pub fn lo(self) -> f64 {
        imp::lo(self.0)
    }

    /// The high lane (the second subtree's value).
    #[inline(always)]
    pub fn hi(self) -> f64 {
        imp::hi(self.0)
    }

    /// The lanes exchanged: `(hi, lo)`.
    #[inline(always)]
    pub fn swap(self) -> Self {
        Self(imp::swap(self.0))
    }
}

impl From<f64> for F64x2 {
    #[inline(always)]
    fn from(v: f64) -> Self {
        Self::splat(v)
    }
}

impl core::fmt::Debug for F64x2 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("F64x2")
            .field(&self.lo())
            .field(&self.hi())
            .finish()
    }
}

impl PartialEq for F64x2 {
    fn eq(&self, other: &Self) -> bool {
        self.lo() == other.lo() && self.hi() == other.hi()
    }
}

/// `F64x2 op F64x2`, `F64x2 op f64` and `f64 op F64x2`, lane by lane.
macro_rules! lane_op {
    ($($trait:ident $method:ident $f:ident),*) => {$(
        impl $trait for F64x2 {
            type Output = F64x2;
            #[inline(always)]
            fn $method(self, rhs: F64x2) -> F64x2 {
                F64x2(imp::$f(self.0, rhs.0))
            }
        }
        impl $trait<f64> for F64x2 {
            type Output = F64x2;
            #[inline(always)]
            fn $method(self, rhs: f64) -> F64x2 {
                F64x2(imp::$f(self.0, F64x2::splat(rhs).0))
            }
        }
        impl $trait<F64x2> for f64 {
            type Output = F64x2;
            #[inline(always)]
            fn $method(self, rhs: F64x2) -> F64x2 {
                F64x2(imp::$f(F64x2::splat(self).0, rhs.0))
            }
        }
    )*};
}

lane_op!(Add add add, Sub sub sub, Mul mul mul, Div div div);

impl Neg for F64x2 {
    type Output = F64x2;
    #[inline(always)]
    fn neg(self) -> F64x2 {
        F64x2(imp::neg(self.0))
    }
}

/// `x * y + acc` on two lanes, the way of one instruction-set copy: [`Plain`] (a
/// multiplication and an addition per lane, the baseline copy) or [`FusedPair`] (a fused
/// multiply-add per lane, the x86-64-v3 copy). A generated function's paired statements call
/// it on the value its dispatch passes in (`lanes.mul_add(x, y, acc)`); `f64` arguments apply
/// to both lanes.
pub trait PairArith: Copy {
    /// `x * y + acc`, lane by lane.
    fn mul_add(self, x: impl Into<F64x2>, y: impl Into<F64x2>, acc: impl Into<F64x2>) -> F64x2;
}

impl PairArith for Plain {
    #[inline(always)]
    fn mul_add(self, x: impl Into<F64x2>, y: impl Into<F64x2>, acc: impl Into<F64x2>) -> F64x2 {
        x.into() * y.into() + acc.into()
    }
}

/// Fused multiply-adds on two lanes (one rounding per lane, the bits of `f64::mul_add`): the
/// x86-64-v3 copy's [`PairArith`]. Only [`crate::isa::dispatch_pair_with`] and
/// [`crate::isa::native_pair`] make one, where the CPU or the build has FMA.
#[derive(Clone, Copy, Debug)]
pub struct FusedPair {
    _fma_present: (),
}

impl FusedPair {
    /// For [`crate::isa`] only: the caller makes sure that the CPU has FMA (x86-64).
    #[inline(always)]
    pub(crate) const fn new_unchecked() -> Self {
        Self { _fma_present: () }
    }
}

impl PairArith for FusedPair {
    #[inline(always)]
    fn mul_add(self, x: impl Into<F64x2>, y: impl Into<F64x2>, acc: impl Into<F64x2>) -> F64x2 {
        F64x2(imp::fused_mul_add(x.into().0, y.into().0, acc.into().0))
    }
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod imp {
    //! SSE2 intrinsics. SAFETY of every `unsafe` block below except `fused_mul_add`'s: SSE2 is
    //! part of the baseline of every x86-64 target (`x86_64-*` targets enable it and cannot
    //! turn it off), so these instructions execute on every CPU this code runs on; the
    //! intrinsics take and return values only (no memory access).
    use core::arch::x86_64::{
        __m128d, _mm_add_pd, _mm_cvtsd_f64, _mm_div_pd, _mm_mul_pd, _mm_set_pd, _mm_set1_pd,
        _mm_shuffle_pd, _mm_sub_pd, _mm_unpackhi_pd, _mm_xor_pd,
    };

    pub(super) type Repr = __m128d;

    #[inline(always)]
    pub(super) fn new(lo: f64, hi: f64) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_set_pd(hi, lo) }
    }
    #[inline(always)]
    pub(super) fn lo(a: Repr) -> f64 {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_cvtsd_f64(a) }
    }
    #[inline(always)]
    pub(super) fn hi(a: Repr) -> f64 {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_cvtsd_f64(_mm_unpackhi_pd(a, a)) }
    }
    #[inline(always)]
    pub(super) fn swap(a: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_shuffle_pd::<1>(a, a) }
    }
    #[inline(always)]
    pub(super) fn add(a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_add_pd(a, b) }
    }
    #[inline(always)]
    pub(super) fn sub(a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_sub_pd(a, b) }
    }
    #[inline(always)]
    pub(super) fn mul(a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_mul_pd(a, b) }
    }
    #[inline(always)]
    pub(super) fn div(a: Repr, b: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2).
        unsafe { _mm_div_pd(a, b) }
    }
    #[inline(always)]
    pub(super) fn neg(a: Repr) -> Repr {
        // SAFETY: see the module docs (SSE2). Flipping the sign bit is IEEE negation.
        unsafe { _mm_xor_pd(a, _mm_set1_pd(-0.0)) }
    }

    /// One `vfmadd…pd`: compiled with FMA, inlined into the x86-64-v3 copy of the generated
    /// function that calls it (whose features include FMA).
    #[target_feature(enable = "fma")]
    #[inline]
    fn fmadd(a: Repr, b: Repr, c: Repr) -> Repr {
        core::arch::x86_64::_mm_fmadd_pd(a, b, c)
    }

    #[inline(always)]
    pub(super) fn fused_mul_add(a: Repr, b: Repr, c: Repr) -> Repr {
        // SAFETY: called only through `FusedPair`, which exists only where the CPU has FMA:
        // `isa::dispatch_pair_with` makes it after `isa` detected x86-64-v3 (which includes
        // FMA), `isa::native_pair` only in builds compiled with FMA enabled.
        unsafe { fmadd(a, b, c) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    //! Portable lanes.
    pub(super) type Repr = [f64; 2];

    #[inline(always)]
    pub(super) fn new(lo: f64, hi: f64) -> Repr {
        [lo, hi]
    }
    #[inline(always)]
    pub(super) fn lo(a: Repr) -> f64 {
        a[0]
    }
    #[inline(always)]
    pub(super) fn hi(a: Repr) -> f64 {
        a[1]
    }
    #[inline(always)]
    pub(super) fn swap(a: Repr) -> Repr {
        [a[1], a[0]]
    }
    #[inline(always)]
    pub(super) fn add(a: Repr, b: Repr) -> Repr {
        [a[0] + b[0], a[1] + b[1]]
    }
    #[inline(always)]
    pub(super) fn sub(a: Repr, b: Repr) -> Repr {
        [a[0] - b[0], a[1] - b[1]]
    }
    #[inline(always)]
    pub(super) fn mul(a: Repr, b: Repr) -> Repr {
        [a[0] * b[0], a[1] * b[1]]
    }
    #[inline(always)]
    pub(super) fn div(a: Repr, b: Repr) -> Repr {
        [a[0] / b[0], a[1] / b[1]]
    }
    #[inline(always)]
    pub(super) fn neg(a: Repr) -> Repr {
        [-a[0], -a[1]]
    }
    #[inline(always)]
    pub(super) fn fused_mul_add(a: Repr, b: Repr, c: Repr) -> Repr {
        use crate::arith::Arith;
        [
            <crate::arith::Fused as Arith<f64>>::mul_add(a[0], b[0], c[0]),
            <crate::arith::Fused as Arith<f64>>::mul_add(a[1], b[1], c[1]),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values() -> impl Iterator<Item = f64> {
        [0.1, -2.5, 3.0e-17, 7.25, -1.0 / 3.0, 1.0e300, -0.0].into_iter()
    }

    #[test]
    fn lane_operations_give_the_scalar_operations_bits_in_each_lane() {
        for a in values() {
            for b in values() {
                let (x, y) = (F64x2::new(a, b), F64x2::new(b, a));
                let pairs = [
                    (x + y, a + b, b + a),
                    (x - y, a - b, b - a),
                    (x * y, a * b, b * a),
                    (x / y, a / b, b / a),
                    (-x, -a, -b),
                    (x.swap(), b, a),
                    (x * 2.5, a * 2.5, b * 2.5),
                    (2.5 - y, 2.5 - b, 2.5 - a),
                ];
                for (v, lo, hi) in pairs {
                    assert_eq!(v.lo().to_bits(), lo.to_bits(), "{a} {b}");
                    assert_eq!(v.hi().to_bits(), hi.to_bits(), "{a} {b}");
                }
                let p = Plain.mul_add(x, y, 0.3);
                assert_eq!(p.lo().to_bits(), (a * b + 0.3).to_bits());
                assert_eq!(p.hi().to_bits(), (b * a + 0.3).to_bits());
            }
        }
    }
}
