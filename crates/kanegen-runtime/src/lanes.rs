//! Lane types for batched evaluation: one generated function evaluated at `L` states per call.
//!
//! A generated module's `*_batch` functions (e.g. `mass_matrix_batch(p, pc, &[q; L])`, or the
//! wrapper's `Krang::mass_matrix_batch`) run the *same* straight-line statements as the
//! single-state function, with every state-dependent value a [`Lanes<L>`]: `L` `f64`s, one per
//! state, combined lane by lane. The operators are plain element-wise IEEE operations, and
//! parameters and literals stay `f64` (an `f64` operand is applied to every lane), so lane `l`
//! of every value is computed by exactly the operations, in exactly the order, of the
//! single-state function at state `l`: **the results are the single-state results bit for
//! bit**. The compiler turns the lane loops into vector instructions (two lanes per SSE2
//! instruction, four per AVX2 instruction; the x86-64-v3 copy is chosen by [`crate::isa`]).
//!
//! `L` is a const generic of the batch functions: any `L ≥ 1` works; 4 (one AVX2 register) and
//! 8 are the sizes the benchmarks measure.
//!
//! ```
//! use kanegen_runtime::lanes::Lanes;
//! let a = Lanes([1.0, 2.0, 3.0, 4.0]);
//! let b = 2.0 * a + a * a - 1.0;
//! assert_eq!(b, Lanes([2.0, 7.0, 14.0, 23.0]));
//! assert_eq!(b.0[2], 2.0 * 3.0 + 3.0 * 3.0 - 1.0);
//! ```

use core::ops::{Add, Div, Mul, Neg, Sub};

use nalgebra::{SMatrix, SVector};

/// `L` values of one quantity, one per state of a batch (see the [module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(transparent)]
pub struct Lanes<const L: usize>(pub [f64; L]);

impl<const L: usize> Lanes<L> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: f64) -> Self {
        Lanes([v; L])
    }

    /// Lane `l` is `f(l)`.
    #[inline(always)]
    pub fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Lanes(core::array::from_fn(f))
    }

    /// Lane `l` is entry `i` of `x[l]` (a coordinate, speed or acceleration of state `l`).
    #[inline(always)]
    pub fn gather<const N: usize>(x: &[SVector<f64, N>; L], i: usize) -> Self {
        Lanes(core::array::from_fn(|l| x[l][i]))
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const L: usize> $tr for Lanes<L> {
            type Output = Lanes<L>;
            #[inline(always)]
            fn $f(self, o: Lanes<L>) -> Lanes<L> {
                Lanes(core::array::from_fn(|l| self.0[l] $op o.0[l]))
            }
        }
        impl<const L: usize> $tr<f64> for Lanes<L> {
            type Output = Lanes<L>;
            #[inline(always)]
            fn $f(self, o: f64) -> Lanes<L> {
                Lanes(core::array::from_fn(|l| self.0[l] $op o))
            }
        }
        impl<const L: usize> $tr<Lanes<L>> for f64 {
            type Output = Lanes<L>;
            #[inline(always)]
            fn $f(self, o: Lanes<L>) -> Lanes<L> {
                Lanes(core::array::from_fn(|l| self $op o.0[l]))
            }
        }
    };
}

lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const L: usize> Neg for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn neg(self) -> Lanes<L> {
        Lanes(core::array::from_fn(|l| -self.0[l]))
    }
}

/// A value of a batched function: [`Lanes`], or an `f64` that is the same in every lane (a
/// result entry that depends on parameters only).
pub trait LaneValue<const L: usize>: Copy {
    /// The value in lane `l`.
    fn lane(self, l: usize) -> f64;
}

impl<const L: usize> LaneValue<L> for Lanes<L> {
    #[inline(always)]
    fn lane(self, l: usize) -> f64 {
        self.0[l]
    }
}

impl<const L: usize> LaneValue<L> for f64 {
    #[inline(always)]
    fn lane(self, _l: usize) -> f64 {
        self
    }
}

/// `(sin x, cos x)` lane by lane: [`crate::trig::sin_cos_n`] on the lanes, so bit for bit the
/// values of the single-state functions.
#[inline(always)]
pub fn sin_cos<const L: usize>(x: Lanes<L>) -> (Lanes<L>, Lanes<L>) {
    let (s, c) = crate::trig::sin_cos_n(x.0);
    (Lanes(s), Lanes(c))
}

/// `(sin x, cos x)` of every angle `k` in every lane `l` (`x[k][l]`), in one call of
/// [`crate::trig::sin_cos_slice`]: bit for bit the values of [`crate::trig::sin_cos_n`], which
/// the single-state functions call. The batched functions pass all joint angles of all their
/// states at once (`[q[2].0, q[3].0, …]`).
#[inline(always)]
pub fn sin_cos_n<const N: usize, const L: usize>(
    x: [[f64; L]; N],
) -> ([[f64; L]; N], [[f64; L]; N]) {
    let (mut s, mut c) = ([[0.0; L]; N], [[0.0; L]; N]);
    crate::trig::sin_cos_slice(x.as_flattened(), s.as_flattened_mut(), c.as_flattened_mut());
    (s, c)
}

/// The inputs of a batched function in lane-major order: entry `i` holds coordinate (speed,
/// acceleration) `i` of every state. Written to memory behind an optimisation barrier
/// (`core::hint::black_box`), so that the batched function's loop over the states reads whole
/// lane vectors from consecutive addresses: without it LLVM reads every lane from the states'
/// own (strided) storage and Krang's batched c and τ were not vectorized (1.2 µs instead of
/// 0.6 µs at 4 states). Returned by value, i.e. copied out of the array that passed the
/// barrier (a `memcpy`, 608 bytes for 19 speeds at 4 states): measured, reading the lanes from
/// the array that passed the barrier (which LLVM must then assume the result stores may
/// overwrite) kept the loop from being vectorized (twice the time of c, τ and M at 4 states).
#[inline(always)]
pub fn inputs<const L: usize, const N: usize>(x: &[SVector<f64, N>; L]) -> [Lanes<L>; N] {
    // Plain loops, not `core::array::from_fn`: at L = 8 LLVM left that one out of line
    // (`try_from_fn`: 7 % of Krang's batched c).
    let mut t = [Lanes::splat(0.0); N];
    for (l, x) in x.iter().enumerate() {
        for (t, x) in t.iter_mut().zip(x.iter()) {
            t.0[l] = *x;
        }
    }
    core::hint::black_box(&mut t);
    t
}

/// The result buffer of a batched function: column `c`, row `r`, all lanes together (see
/// [`inputs`] for why lane-major).
pub type Buffer<const L: usize, const R: usize, const C: usize> = [[Lanes<L>; R]; C];

/// An all-zero [`Buffer`].
#[inline(always)]
pub fn buffer<const L: usize, const R: usize, const C: usize>() -> Buffer<L, R, C> {
    [[Lanes::splat(0.0); R]; C]
}

/// `v` in every lane (an `f64` result entry) or `v` itself.
#[inline(always)]
pub fn lanes<const L: usize>(v: impl LaneValue<L>) -> Lanes<L> {
    Lanes::from_fn(|l| v.lane(l))
}

/// The results of the `L` states from a filled [`Buffer`] (read behind an optimisation
/// barrier, so that the stores into the buffer stay whole vectors); `symmetric`: the upper
/// triangle is copied into the lower one.
#[inline(always)]
pub fn results<const L: usize, const R: usize, const C: usize>(
    buf: &mut Buffer<L, R, C>,
    symmetric: bool,
) -> [SMatrix<f64, R, C>; L] {
    core::hint::black_box(&mut *buf);
    let mut out = [SMatrix::<f64, R, C>::zeros(); L];
    for (l, m) in out.iter_mut().enumerate() {
        for c in 0..C {
            for r in 0..R {
                m[(r, c)] = if symmetric && r > c {
                    buf[r][c].0[l]
                } else {
                    buf[c][r].0[l]
                };
            }
        }
    }
    out
}
/// Stores `v`'s lane `l` into entry `(r, c)` of `m[l]`.
#[inline(always)]
pub fn set_matrix<const L: usize, const R: usize, const C: usize>(
    m: &mut [SMatrix<f64, R, C>; L],
    r: usize,
    c: usize,
    v: impl LaneValue<L>,
) {
    for (l, m) in m.iter_mut().enumerate() {
        m[(r, c)] = v.lane(l);
    }
}

/// Stores `v`'s lane `l` into entry `r` of `out[l]`.
#[inline(always)]
pub fn set_vector<const L: usize, const N: usize>(
    out: &mut [SVector<f64, N>; L],
    r: usize,
    v: impl LaneValue<L>,
) {
    for (l, out) in out.iter_mut().enumerate() {
        out[r] = v.lane(l);
    }
}

/// Copies the upper triangle of every `m[l]` into its lower triangle (symmetric results).
#[inline(always)]
pub fn mirror_upper<const L: usize, const N: usize>(m: &mut [SMatrix<f64, N, N>; L]) {
    for m in m.iter_mut() {
        let s = m.as_mut_slice();
        for c in 1..N {
            for r in 0..c {
                s[r * N + c] = s[c * N + r];
            }
        }
    }
}
