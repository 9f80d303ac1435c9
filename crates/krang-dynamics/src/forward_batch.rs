//! Batched forward dynamics: `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))` at `L` states per call, for
//! samplers (sampling-based MPC, MPPI and RL rollouts) that step many states at once. Behind
//! the crate's feature `batch`, like the batched functions of the generated modules it builds
//! on (docs/runtime.md, "Build time and features").
//!
//! [`Krang::forward_dynamics_batch_soa_into`] takes and gives structure-of-arrays vectors
//! (`SVector<Lanes<L>, 19>`, lane `l` of every entry being state `l`, as the batched M, c, g and
//! τ do; docs/batched-and-dispatch.md):
//! - `c + g` of every state from one batched inverse-dynamics call at `u̇ = 0`
//!   (`inverse_dynamics_batch_soa_into`), `M` of every state from `mass_matrix_batch_soa_into`;
//! - then [`block_solve_lanes`]: the block Cholesky factorisation of [`BlockCholesky`] (arms
//!   first, no fill-in; see [`crate::forward`]) and its two substitutions, run lane by lane in
//!   one loop over the states that the compiler vectorizes (8 states per AVX-512 instruction
//!   in the x86-64-v4 copy, 4 with AVX2).
//!
//! Every lane performs the operations of [`BlockCholesky::solve_once`] on one state, in the same
//! order, with the same multiply-adds (fused in the x86-64-v3 and x86-64-v4 copies, not in the
//! baseline one), so lane `l` of the result is [`Krang::forward_dynamics`] of state `l` **bit for
//! bit** with the same instruction set (`tests/isa_batch.rs` at the workspace root). A state whose mass matrix is
//! not positive definite, whose inputs are not finite or whose result is not finite gets NaN
//! in every entry, as `forward_dynamics` gives it; the other lanes are unaffected. Nothing
//! allocates; the factorisation and the substitutions have no branch per state (the one test
//! per state, after them, decides whether its lane is filled with NaN).
//!
//! [`Krang::forward_dynamics_batch`] is the array-of-states form (`&[SVector<f64, 19>; L]` in,
//! `[SVector<f64, 19>; L]` out), which copies the states into lanes and back.
//! [`Krang::forward_dynamics_batch_soa_with_mass_matrix`] writes the states' mass matrices into
//! a lane matrix the caller keeps across calls, instead of zeroing a fresh one in every call
//! (23 KB at `L = 8`, about a tenth of the call). The fixed-wheel tree (feature
//! `fixed-wheels`) has the three methods too, with its `BlockCholesky<3, 17>` shape.

use kanegen_runtime::isa::{self, Arith, Fused, Plain};
use kanegen_runtime::lanes::{self, Lanes, soa};
use nalgebra::{SMatrix, SVector};

use crate::Krang;
#[cfg(feature = "fixed-wheels")]
use crate::fixed_wheels::KrangFixedWheels;
#[cfg(doc)]
use crate::forward::BlockCholesky;

/// `b ← M⁻¹ b` for the `L` states in the lanes of `m` and `b`, by the block Cholesky
/// factorisation of [`BlockCholesky<T, N>`] (the same operations, in the same order, as
/// [`BlockCholesky::solve_once`] on each state). Returns, per lane, whether every pivot was
/// positive (`false` also for a NaN pivot: that lane of `b` is then garbage, never a panic).
/// Reads the lower triangles of `m`'s blocks and assumes `M[left, right] = 0`, as
/// [`BlockCholesky::new`] does.
///
/// Compiled for the baseline, x86-64-v3 and x86-64-v4 (`isa::dispatch_fused_wide_with`); the
/// latter two fuse the multiply-adds and give the same bits as each other. Not inlined: it
/// is vectorized across the states in a function of its own (inlined into the batched forward
/// dynamics, it ran 5× slower).
#[inline(never)]
pub fn block_solve_lanes<const T: usize, const N: usize, const L: usize>(
    m: &SMatrix<Lanes<L>, N, N>,
    b: &mut SVector<Lanes<L>, N>,
) -> [bool; L] {
    const {
        assert!(N == T + 14, "N is T trunk speeds and two arms of 7");
        assert!(
            T <= 8,
            "the pivots and substitutions are written out for T ≤ 8"
        );
    };
    isa::dispatch_fused_wide_with(
        b,
        #[inline(always)]
        |b| solve_lanes_in::<Plain, T, N, L>(m, b),
        #[inline(always)]
        |b| solve_lanes_in::<Fused, T, N, L>(m, b),
    )
}

/// The loop over the states of [`block_solve_lanes`], inlined into each instruction set's copy.
///
/// LLVM vectorizes this loop only if its body is straight-line code once inlined, so every loop
/// inside it must be unrolled completely before the vectorizer runs. The rule the helpers below
/// follow (measured with `solve_s8` of the `profile` example, 8 states: about 0.4 µs
/// vectorized, about 1.9 µs when one loop is left rolled): every loop but the innermost is
/// written out (`each!`, literal indices), and the innermost is a plain `for` over an
/// exclusive range (`0..i + 1`, not `0..=i`: an inclusive range was not unrolled). Writing the
/// innermost loops out too gave the same code at 8 times the expansion, which cost about 20 s
/// of type checking in every build of the crate; two nested plain loops were not unrolled.
#[inline(always)]
fn solve_lanes_in<A: Arith<f64>, const T: usize, const N: usize, const L: usize>(
    m: &SMatrix<Lanes<L>, N, N>,
    b: &mut SVector<Lanes<L>, N>,
) -> [bool; L] {
    let mut ok = [true; L];
    for (l, ok) in ok.iter_mut().enumerate() {
        *ok = solve_state::<A, T, N, L>(m, b, l);
    }
    ok
}

/// The pivot steps of `BlockCholesky`'s factorisation (`Upper::step` for pivots 0, 1, …, in
/// order) on a `K×K` block in place, kept as the upper factor `U(k, i) = u[K i + k]` (`k ≤ i`),
/// the reciprocals of its diagonal into `inv`: an arm's block (`K = 7`) and the trunk's Schur
/// complement (`K = T`). Branch-free: `false` if a pivot is not positive (or is NaN).
#[inline(always)]
fn pivot_steps<A: Arith<f64>, const K: usize>(u: &mut [f64], inv: &mut [f64]) -> bool {
    let mut ok = true;
    each!(k < K; {
        let d = u[K * k + k];
        ok &= d > 0.0; // false for NaN too
        let r = nalgebra::ComplexField::sqrt(d);
        let r_inv = r * (1.0 / d);
        u[K * k + k] = r;
        inv[k] = r_inv;
        for i in k + 1..K {
            u[K * i + k] *= r_inv;
        }
        each!(i < K; {
            if i > k {
                let uki = u[K * i + k];
                for j in k + 1..i + 1 {
                    u[K * i + j] = A::mul_add(-u[K * j + k], uki, u[K * i + j]);
                }
            }
        });
    });
    ok
}

/// `y ← (Uᵀ)⁻¹ y` for a factor of [`pivot_steps`] (the forward substitution of `solve_one`).
#[inline(always)]
fn forward_steps<A: Arith<f64>, const K: usize>(u: &[f64], inv: &[f64], y: &mut [f64]) {
    each!(i < K; {
        for k in 0..i {
            y[i] = A::mul_add(y[k], -u[K * i + k], y[i]);
        }
        y[i] *= inv[i];
    });
}

/// `y ← U⁻¹ y` for a factor of [`pivot_steps`] (the backward substitution of `solve_one`).
#[inline(always)]
fn backward_steps<A: Arith<f64>, const K: usize>(u: &[f64], inv: &[f64], y: &mut [f64]) {
    each!(r < K; {
        let i = K - 1 - r;
        y[i] *= inv[i];
        for k in 0..i {
            y[k] = A::mul_add(y[i], -u[K * i + k], y[k]);
        }
    });
}

/// One arm's part of [`BlockCholesky`]'s factorisation for state `l`: its pivot steps and
/// `W = L⁻¹ M[arm, trunk]`, for the arm whose first speed is `at`. Returns `U` (`U(k, i) =
/// u[7 i + k]`, `k ≤ i`), the reciprocals of its diagonal, `W` (`W(i, j) = w[j][i]`) and whether
/// every pivot was positive.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn factor_arm<A: Arith<f64>, const T: usize, const N: usize, const L: usize>(
    m: &SMatrix<Lanes<L>, N, N>,
    l: usize,
    at: usize,
) -> ([f64; 49], [f64; 7], [[f64; 7]; T], bool) {
    let (mut u, mut inv, mut w) = ([0.0; 49], [0.0; 7], [[0.0; 7]; T]);
    each!(i < 7; {
        for k in 0..i + 1 {
            u[7 * i + k] = m[(at + i, at + k)].0[l];
        }
    });
    each!(j < T; {
        for i in 0..7 {
            w[j][i] = m[(at + i, j)].0[l];
        }
    });
    let ok = pivot_steps::<A, 7>(&mut u, &mut inv);
    // W = L⁻¹ M[arm, trunk], column by column.
    each!(j < T; { forward_steps::<A, 7>(&u, &inv, &mut w[j]); });
    (u, inv, w, ok)
}

/// One state (lane `l`): [`BlockCholesky`]'s factorisation (`new_in`) and substitution
/// (`solve_one`), with the two arms one after the other instead of in the two lanes of an
/// `F64x2` (lane by lane the same operations), and branch-free: a pivot that is not positive
/// clears the returned flag instead of returning.
#[inline(always)]
fn solve_state<A: Arith<f64>, const T: usize, const N: usize, const L: usize>(
    m: &SMatrix<Lanes<L>, N, N>,
    b: &mut SVector<Lanes<L>, N>,
    l: usize,
) -> bool {
    let arms = [T, T + 7];
    let (ul, invl, wl, okl) = factor_arm::<A, T, N, L>(m, l, T);
    let (ur, invr, wr, okr) = factor_arm::<A, T, N, L>(m, l, T + 7);
    let (u, inv, w) = ([ul, ur], [invl, invr], [wl, wr]);
    let mut ok = okl & okr;
    // The trunk: U_s(k, i) = s[T i + k] (k ≤ i) from M's lower triangle, minus both arms'
    // products (each arm's sum apart, then the two sums added, as the pair's two lanes are).
    let mut s = [0.0; 64];
    let mut inv_t = [0.0; 8];
    each!(i < T; {
        each!(j < T; {
            if j <= i {
                let mut acc = [0.0; 2];
                each!(a < 2; {
                    for (wik, wjk) in w[a][i].iter().zip(&w[a][j]) {
                        acc[a] = A::mul_add(*wik, *wjk, acc[a]);
                    }
                });
                s[T * i + j] = m[(i, j)].0[l] - (acc[0] + acc[1]);
            }
        });
    });
    // The trunk's pivot steps.
    ok &= pivot_steps::<A, T>(&mut s, &mut inv_t);
    // Forward substitution L z = b: the arms, their coupling into the trunk's rows, the trunk.
    let mut t = [0.0; 8];
    for j in 0..T {
        t[j] = b[j].0[l];
    }
    let mut y = [[0.0; 7]; 2];
    each!(a < 2; {
        for i in 0..7 {
            y[a][i] = b[arms[a] + i].0[l];
        }
        forward_steps::<A, 7>(&u[a], &inv[a], &mut y[a]);
    });
    each!(j < T; {
        let mut acc = [0.0; 2];
        each!(a < 2; {
            for k in 0..7 {
                acc[a] = A::mul_add(y[a][k], w[a][j][k], acc[a]);
            }
        });
        t[j] -= acc[0] + acc[1];
    });
    forward_steps::<A, T>(&s, &inv_t, &mut t);
    // Backward substitution Lᵀ x = z: the trunk, its coupling into the arms' rows, the arms.
    backward_steps::<A, T>(&s, &inv_t, &mut t);
    each!(a < 2; {
        each!(k < 7; {
            for j in 0..T {
                y[a][k] = A::mul_add(t[j], -w[a][j][k], y[a][k]);
            }
        });
        backward_steps::<A, 7>(&u[a], &inv[a], &mut y[a]);
    });
    for j in 0..T {
        b[j].0[l] = t[j];
    }
    each!(a < 2; {
        for i in 0..7 {
            b[arms[a] + i].0[l] = y[a][i];
        }
    });
    ok
}

/// Batched forward dynamics for a model with the block shape of [`BlockCholesky<T, N>`]: `c + g`
/// written into `ud` by `bias_into(q, u, u̇ = 0, ud)` (batched inverse dynamics), `M` by
/// `mass_matrix_into(q, m)` into the caller's `m` (or, for `None`, a fresh zeroed matrix), then
/// [`block_solve_lanes`]; a lane whose pivots, inputs or result are not all good is filled
/// with NaN.
fn block_forward_dynamics_lanes<const T: usize, const N: usize, const L: usize>(
    (q, u, tau): (
        &SVector<Lanes<L>, N>,
        &SVector<Lanes<L>, N>,
        &SVector<Lanes<L>, N>,
    ),
    m: Option<&mut SMatrix<Lanes<L>, N, N>>,
    ud: &mut SVector<Lanes<L>, N>,
    bias_into: impl FnOnce(
        &SVector<Lanes<L>, N>,
        &SVector<Lanes<L>, N>,
        &SVector<Lanes<L>, N>,
        &mut SVector<Lanes<L>, N>,
    ),
    mass_matrix_into: impl FnOnce(&SVector<Lanes<L>, N>, &mut SMatrix<Lanes<L>, N, N>),
) {
    // c + g at u̇ = 0, then the right-hand side τ − c − g, in `ud`.
    bias_into(q, u, &lanes::zeros(), ud);
    for (ud, tau) in ud.iter_mut().zip(tau.iter()) {
        *ud = *tau - *ud;
    }
    // A fresh matrix is zeroed in place, as the solve's argument: built before the `match`
    // and lent, or built by `from_element`, it was zeroed elsewhere and copied (23 KB for
    // Krang at L = 8, a sixth of the call).
    let factor_and_solve = |m: &mut SMatrix<Lanes<L>, N, N>| {
        mass_matrix_into(q, m);
        block_solve_lanes::<T, N, L>(m, ud)
    };
    let pivots = match m {
        Some(m) => factor_and_solve(m),
        None => factor_and_solve(&mut lanes::zeros()),
    };
    // Per lane: every input and result entry finite (`0 · x` is ±0 for a finite `x`, NaN for
    // ±∞ and NaN), summed across the entries lane by lane.
    let mut sum = [0.0; L];
    for v in [q, u, tau, &*ud] {
        for x in v.iter() {
            for (s, x) in sum.iter_mut().zip(&x.0) {
                *s += 0.0 * x;
            }
        }
    }
    for (l, (ok, sum)) in pivots.into_iter().zip(sum).enumerate() {
        if !(ok && sum == 0.0) {
            for x in ud.iter_mut() {
                x.0[l] = f64::NAN;
            }
        }
    }
}

/// The batched forward-dynamics methods of a model type with `N` speeds and a trunk of `T`.
macro_rules! batched_forward_dynamics {
    ($robot:ty, $t:literal, $n:literal, $example:literal) => {
        impl $robot {
            /// Forward dynamics of `L` states per call in the structure-of-arrays form: lane
            /// `l` of `ud` is `forward_dynamics` of lane `l` of `q`, `u`, `tau`, bit for bit
            /// with the same instruction set (NaN in every entry of a lane whose inputs or
            /// result are not finite or whose mass matrix is not positive definite). One
            /// batched `M`, one batched `c + g` and the block Cholesky solve of every state
            /// vectorized across the states (see the [module docs](crate::forward_batch)).
            /// Allocation-free.
            #[doc = $example]
            pub fn forward_dynamics_batch_soa_into<const L: usize>(
                &self,
                q: &SVector<Lanes<L>, $n>,
                u: &SVector<Lanes<L>, $n>,
                tau: &SVector<Lanes<L>, $n>,
                ud: &mut SVector<Lanes<L>, $n>,
            ) {
                self.forward_dynamics_lanes(q, u, tau, None, ud);
            }

            /// [`forward_dynamics_batch_soa_into`](Self::forward_dynamics_batch_soa_into), with
            /// the mass matrices of the `L` states written into `m`, which may hold anything
            /// before (every entry is written): a sampler that keeps `m` across calls saves
            /// zeroing a fresh one in every call, and gets `M` of every state as well.
            pub fn forward_dynamics_batch_soa_with_mass_matrix<const L: usize>(
                &self,
                q: &SVector<Lanes<L>, $n>,
                u: &SVector<Lanes<L>, $n>,
                tau: &SVector<Lanes<L>, $n>,
                m: &mut SMatrix<Lanes<L>, $n, $n>,
                ud: &mut SVector<Lanes<L>, $n>,
            ) {
                self.forward_dynamics_lanes(q, u, tau, Some(m), ud);
            }

            /// Both batched forms: `M` into `m`, or into a fresh zeroed matrix for `None`.
            #[inline(always)]
            fn forward_dynamics_lanes<const L: usize>(
                &self,
                q: &SVector<Lanes<L>, $n>,
                u: &SVector<Lanes<L>, $n>,
                tau: &SVector<Lanes<L>, $n>,
                m: Option<&mut SMatrix<Lanes<L>, $n, $n>>,
                ud: &mut SVector<Lanes<L>, $n>,
            ) {
                block_forward_dynamics_lanes::<$t, $n, L>(
                    (q, u, tau),
                    m,
                    ud,
                    |q, u, ud0, out| self.inverse_dynamics_batch_soa_into(q, u, ud0, out),
                    |q, m| self.mass_matrix_batch_soa_into(q, m),
                );
            }

            /// Forward dynamics of `L` states per call, the array-of-states form:
            /// `[forward_dynamics(q[l], u[l], tau[l]); L]`, bit for bit. The states are copied
            /// into lanes and the results back; a sampler that keeps its states in lanes calls
            /// [`forward_dynamics_batch_soa_into`](Self::forward_dynamics_batch_soa_into) and
            /// skips the copies.
            pub fn forward_dynamics_batch<const L: usize>(
                &self,
                q: &[SVector<f64, $n>; L],
                u: &[SVector<f64, $n>; L],
                tau: &[SVector<f64, $n>; L],
            ) -> [SVector<f64, $n>; L] {
                let mut ud = lanes::zeros::<$n, 1, L>();
                self.forward_dynamics_batch_soa_into(&soa(q), &soa(u), &soa(tau), &mut ud);
                core::array::from_fn(|l| ud.map(|x| x.0[l]))
            }
        }
    };
}

batched_forward_dynamics!(
    Krang,
    5,
    19,
    r"
```
use krang_dynamics::lanes::{Lanes, soa, state};
use krang_dynamics::{Krang, index};
use nalgebra::SVector;

let k = Krang::default();
// Four states that differ in the base pitch.
let q: [SVector<f64, 19>; 4] = core::array::from_fn(|l| {
    let mut q = SVector::zeros();
    q[index::Q_IMU] = 0.1 * l as f64;
    q
});
let (u, tau) = ([SVector::from_element(0.1); 4], [SVector::zeros(); 4]);
let mut ud = SVector::<Lanes<4>, 19>::from_element(Lanes::splat(0.0));
k.forward_dynamics_batch_soa_into(&soa(&q), &soa(&u), &soa(&tau), &mut ud);
assert_eq!(state(&ud, 2), k.forward_dynamics(&q[2], &u[2], &tau[2]));
```"
);

#[cfg(feature = "fixed-wheels")]
batched_forward_dynamics!(
    KrangFixedWheels,
    3,
    17,
    r"
The fixed-wheel tree (17 speeds; its block factor `BlockCholesky<3, 17>`)."
);
