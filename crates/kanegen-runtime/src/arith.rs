//! Multiply-add per instruction-set copy: the one operation in which the copies of a generated
//! function differ.
//!
//! A generated function's body is generic over an [`Arith`] implementation and prints its sums of
//! products as chains of [`Arith::mul_add`] (`A::mul_add(x, y, acc)` = `x * y + acc`). The
//! baseline copy is instantiated with [`Plain`], which computes `x * y + acc` with two roundings
//! and gives exactly the bits of the printed sum (`a * b + c * d` and `A::mul_add(c, d, a * b)`
//! are the same IEEE operations: addition is commutative, and the terms are folded in the
//! printed order). The x86-64-v3 copy (see [`crate::isa::dispatch_fused`]) is instantiated with
//! [`Fused`], which rounds once (`f64::mul_add`, one `vfmadd` instruction inside the
//! `#[target_feature(enable = "fma")]` copy): fewer instructions, results that differ from the
//! baseline copy's in the last bits (and are, if anything, more accurate).
//!
//! [`Native`] is the implementation for code compiled without dispatch: [`Fused`] when the crate
//! is compiled with FMA enabled (`-C target-cpu=native`, `x86-64-v3`; aarch64, whose baseline
//! has FMA) and `std` is on, [`Plain`] otherwise.
//!
//! The trait is generic in the value type so that lane types (`crate::lanes::Lanes<L>`) can
//! implement it for both [`Plain`] and [`Fused`] next to their other lane-wise operators.
//!
//! ```
//! use kanegen_runtime::isa::{Arith, Fused, Plain};
//!
//! fn dot<A: Arith<f64>>(x: [f64; 3], y: [f64; 3]) -> f64 {
//!     A::mul_add(x[2], y[2], A::mul_add(x[1], y[1], x[0] * y[0]))
//! }
//! let (x, y) = ([0.1, 0.2, 0.3], [3.0, 2.0, 1.0]);
//! assert_eq!(dot::<Plain>(x, y), 0.1 * 3.0 + 0.2 * 2.0 + 0.3 * 1.0);
//! assert!((dot::<Fused>(x, y) - dot::<Plain>(x, y)).abs() <= 1e-15);
//! ```

/// `x * y + acc` for values of type `T`, in one of the ways of [`Plain`] and [`Fused`].
pub trait Arith<T> {
    /// `x * y + acc`.
    fn mul_add(x: T, y: T, acc: T) -> T;
    /// Whether [`Arith::mul_add`] rounds once (a true fused multiply-add): `true` for
    /// [`Fused`] with `std`, `false` otherwise. Code whose accuracy needs the single rounding
    /// reads it to choose its formulas: the argument reduction of `crate::trig` does.
    const ROUNDS_ONCE: bool = false;
}

/// `x * y + acc` with two roundings (a multiplication, then an addition): the baseline copy,
/// the same bits as the sum written out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Plain;

/// `x * y + acc` with one rounding (a fused multiply-add): the x86-64-v3 copy. Without `std`
/// (`f64::mul_add` is not in `core` yet) it computes what [`Plain`] does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Fused;

/// What code compiled without dispatch uses: [`Fused`] when FMA is part of the compilation
/// target (and `std` is on), [`Plain`] otherwise. See the module docs.
#[cfg(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64")))]
pub type Native = Fused;

/// What code compiled without dispatch uses: [`Fused`] when FMA is part of the compilation
/// target (and `std` is on), [`Plain`] otherwise. See the module docs.
#[cfg(not(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64"))))]
pub type Native = Plain;

/// The two implementations for each floating-point type.
macro_rules! arith {
    ($($t:ty),*) => {$(
        impl Arith<$t> for Plain {
            #[inline(always)]
            fn mul_add(x: $t, y: $t, acc: $t) -> $t {
                x * y + acc
            }
        }

        impl Arith<$t> for Fused {
            const ROUNDS_ONCE: bool = cfg!(feature = "std");
            #[inline(always)]
            fn mul_add(x: $t, y: $t, acc: $t) -> $t {
                #[cfg(feature = "std")]
                {
                    x.mul_add(y, acc)
                }
                #[cfg(not(feature = "std"))]
                {
                    x * y + acc
                }
            }
        }
    )*};
}

arith!(f64, f32);
