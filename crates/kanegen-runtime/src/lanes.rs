//! Lane types and helpers for batched evaluation: one generated function evaluated at `L`
//! states per call.
//!
//! A generated module's `*_batch_into` functions (e.g. `mass_matrix_batch_into(p, pc, &[q; L],
//! &mut [SMatrix; L])`, or the wrapper's `Krang::mass_matrix_batch_into`; `*_batch` returns the
//! results by value) run the *same* straight-line statements as the single-state function in
//! a loop over the states, which LLVM's loop vectorizer turns into vector instructions across
//! the states (two per SSE2 register, four per AVX2 register, eight per AVX-512 register; the
//! x86-64-v3 or x86-64-v4 copy is chosen by [`crate::isa`]). Lane `l` is therefore the
//! single-state result at state `l` **bit for bit**, with the same instruction set. Before the
//! loop the inputs are transposed to lane-major order ([`inputs`]) and the sines and cosines of
//! all joint angles of all states are computed in one loop, inline in the batched function's
//! copy ([`sin_cos_n_inline`]; [`sin_cos_n`] is the same as a dispatched call). [`Lanes<L>`] (`L` `f64`s with lane-wise operators, `f64`
//! operands applied to every lane) holds the transposed inputs and forms a dependent (mimic)
//! joint's angle from its master's. The structure-of-arrays forms (`*_batch_soa_into`) take
//! and give every entry as a [`Lanes<L>`] ([`soa`], [`state`]; their inputs are read in place,
//! [`as_lanes`], or copied, [`inputs_soa`]); both forms run one body emitted once per
//! function, which stores each entry through [`LaneStore`].
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
///
/// **Aligned to 64 bytes**, a cache line, whatever `L`: a batched function stores every entry
/// of its result as one vector of `L` lanes, and an 8-lane vector (64 bytes, one AVX-512
/// register) at an address that is not a multiple of 64 straddles two cache lines, which
/// costs a store and a load each a second cache access. With `f64`'s alignment of 8, a
/// caller's `SMatrix<Lanes<8>, 19, 19>` was misaligned seven times in eight; aligned, Krang's
/// batched `M` and Coriolis matrix take 11–17 % less time (Nov 2026, Intel Xeon with AVX-512). The
/// price: `Lanes<L>` for `L < 8` is padded to 64 bytes (`size_of::<Lanes<4>>() == 64`).
/// Rust cannot make a type's alignment depend on a const generic, and 8 lanes is the width the
/// batched functions are fastest at on AVX-512 machines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
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

/// A matrix (or, with `C = 1`, a vector) of lanes with every lane of every entry `0.0`, built
/// in place. `SMatrix::from_element(Lanes::splat(0.0))` gives the same value, but through
/// nalgebra's iterator-based constructor, which LLVM compiles to one spill and reload per entry
/// for the 64-byte-aligned [`Lanes`] (a sixth of Krang's batched forward dynamics).
///
/// ```
/// use kanegen_runtime::lanes::{Lanes, zeros};
/// let m = zeros::<2, 3, 4>();
/// assert!(m.iter().all(|x| *x == Lanes::splat(0.0)));
/// ```
#[inline(always)]
pub fn zeros<const R: usize, const C: usize, const L: usize>() -> SMatrix<Lanes<L>, R, C> {
    Zeros::<R, C, L>::MATRIX
}

/// The constant behind [`zeros`]: copying an all-zero constant compiles to one `memset` into
/// the destination, where the array expression `[[Lanes([0.0; L]); R]; C]` zeroed one column
/// and copied it `C` times (with the 64-byte-aligned [`Lanes`]). An optimised build keeps no
/// copy of the constant (the copy becomes the `memset`); a debug build keeps one per shape
/// used, `R · C · size_of::<Lanes<L>>()` bytes of read-only data (23 KB for Krang's `M` at
/// 8 lanes).
struct Zeros<const R: usize, const C: usize, const L: usize>;

impl<const R: usize, const C: usize, const L: usize> Zeros<R, C, L> {
    const MATRIX: SMatrix<Lanes<L>, R, C> =
        SMatrix::from_array_storage(nalgebra::ArrayStorage([[Lanes([0.0; L]); R]; C]));
}

/// The structure-of-arrays form of `L` states, what the `*_batch_soa` functions take: entry
/// `i` holds entry `i` of every state (`soa(x)[i].0[l] == x[l][i]`). A sampler that builds its
/// states in this form directly skips the copy.
///
/// ```
/// use kanegen_runtime::lanes::{soa, Lanes};
/// use nalgebra::SVector;
/// let x = [SVector::<f64, 2>::new(1.0, 2.0), SVector::<f64, 2>::new(3.0, 4.0)];
/// assert_eq!(soa(&x)[1], Lanes([2.0, 4.0]));
/// ```
#[inline]
pub fn soa<const N: usize, const L: usize>(x: &[SVector<f64, N>; L]) -> SVector<Lanes<L>, N> {
    SVector::from_fn(|i, _| Lanes::gather(x, i))
}

/// State `l` of a structure-of-arrays result (a `*_batch_soa` function's vector or matrix of
/// [`Lanes`]): entry `(r, c)` is lane `l` of entry `(r, c)`. For tests and for reading one
/// sample back; a consumer that works across the states reads the lanes directly.
///
/// ```
/// use kanegen_runtime::lanes::{state, Lanes};
/// use nalgebra::SMatrix;
/// let m = SMatrix::<Lanes<2>, 1, 2>::new(Lanes([1.0, 2.0]), Lanes([3.0, 4.0]));
/// assert_eq!(state(&m, 1), SMatrix::<f64, 1, 2>::new(2.0, 4.0));
/// ```
#[inline]
pub fn state<const R: usize, const C: usize, const L: usize>(
    m: &SMatrix<Lanes<L>, R, C>,
    l: usize,
) -> SMatrix<f64, R, C> {
    m.map(|x| x.0[l])
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

/// [`sin_cos_n`] computed inline, in the caller's copy, with the multiply-adds of `A`: the
/// same values as [`sin_cos_n`] with the instruction set whose copy calls it (the loop of
/// [`crate::trig::sin_cos_slice`]). What the batched functions use: measured on Krang at 8
/// states (x86-64-v4, profile driver, best of three), 3–6 % faster than the dispatched call
/// (c 944 → 884 ns, τ 1026 → 984 ns, g 483 → 460 ns, M 1392 → 1353 ns per call), which needs
/// the zeroed arrays passed to another function and a second dispatch.
#[inline(always)]
pub fn sin_cos_n_inline<A: crate::isa::Arith<f64>, const N: usize, const L: usize>(
    x: [[f64; L]; N],
) -> ([[f64; L]; N], [[f64; L]; N]) {
    let (mut s, mut c) = ([[0.0; L]; N], [[0.0; L]; N]);
    crate::trig::sin_cos_slice_lanes::<A>(
        x.as_flattened(),
        s.as_flattened_mut(),
        c.as_flattened_mut(),
    );
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

/// The structure-of-arrays inputs of a batched function as the body reads them, copied: a
/// local the result stores cannot overwrite (without it LLVM's loop vectorizer needs run-time
/// checks and gives up). For bodies that store their results straight into the caller's
/// result; those that store into local lane buffers read the inputs in place ([`as_lanes`]).
/// The form [`inputs`] gives for an array of states.
#[inline(always)]
pub fn inputs_soa<const L: usize, const N: usize>(x: &SVector<Lanes<L>, N>) -> [Lanes<L>; N] {
    x.data.0[0]
}

/// The structure-of-arrays inputs of a batched function as the body reads them, in place: the
/// caller's storage as an array of lanes, no copy ([`inputs_soa`] copies).
#[inline(always)]
pub fn as_lanes<const L: usize, const N: usize>(x: &SVector<Lanes<L>, N>) -> &[Lanes<L>; N] {
    &x.data.0[0]
}

/// Where the body shared by a generated module's two batched forms of a function
/// (`NAME_batch_body`, inlined into `NAME_batch_into` and `NAME_batch_soa_into`) stores result
/// entry `(r, c)` of state `l` (`c = 0` for a vector): entry `(r, c)` of the `l`-th result of
/// an array of states, or lane `l` of entry `(r, c)` of a structure-of-arrays result. With
/// constant `r`, `c` and `l < L` from the loop over the states, the index checks fold away and
/// the store is what each layout wrote inline before. A body that keeps each loop's entries
/// in a local lane buffer copies them out after the loop with [`LaneStore::set_lanes`], all
/// `L` states of an entry at once (one vector store in the structure-of-arrays layout).
///
/// ```
/// use kanegen_runtime::lanes::{LaneStore, Lanes};
/// use nalgebra::{SMatrix, SVector};
/// let mut states = [SVector::<f64, 2>::zeros(); 3];
/// states.set(1, 0, 2, 5.0);
/// assert_eq!(states[2][1], 5.0);
/// let mut soa = SMatrix::<Lanes<3>, 2, 1>::from_element(Lanes::splat(0.0));
/// soa.set(1, 0, 2, 5.0);
/// assert_eq!(soa[1].0[2], 5.0);
/// states.set_lanes(0, 0, &[1.0, 2.0, 3.0]);
/// soa.set_lanes(0, 0, &[1.0, 2.0, 3.0]);
/// assert_eq!((states[1][0], soa[0].0), (2.0, [1.0, 2.0, 3.0]));
/// ```
pub trait LaneStore<const L: usize> {
    /// Entry `(r, c)` of state `l` becomes `v`.
    fn set(&mut self, r: usize, c: usize, l: usize, v: f64);

    /// Entry `(r, c)` of every state `l` becomes `v[l]`: what the generated bodies call after
    /// each loop over the states, from the loop's local lane buffer.
    #[inline(always)]
    fn set_lanes(&mut self, r: usize, c: usize, v: &[f64; L]) {
        for (l, &x) in v.iter().enumerate() {
            self.set(r, c, l, x);
        }
    }
}

impl<const R: usize, const C: usize, const L: usize> LaneStore<L> for [SMatrix<f64, R, C>; L] {
    #[inline(always)]
    fn set(&mut self, r: usize, c: usize, l: usize, v: f64) {
        self[l][(r, c)] = v;
    }
}

impl<const R: usize, const C: usize, const L: usize> LaneStore<L> for SMatrix<Lanes<L>, R, C> {
    #[inline(always)]
    fn set(&mut self, r: usize, c: usize, l: usize, v: f64) {
        self[(r, c)].0[l] = v;
    }

    /// One whole-entry store.
    #[inline(always)]
    fn set_lanes(&mut self, r: usize, c: usize, v: &[f64; L]) {
        self[(r, c)].0 = *v;
    }
}
