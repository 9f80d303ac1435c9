//! The loop form of a generated inverse-dynamics regressor `Y(q, u, u̇)` (`τ = Y π`).
//!
//! Kane's equations give `τ_r = Σ_k [(v_k)_r · F_k + (ω_k)_r · N_k]`: body k's inertia force and
//! moment about its frame origin, dotted with its partial velocities for speed r. Both are
//! linear in the body's ten standard parameters `π_k = (m, MX, MY, MZ, XX, XY, XZ, YY, YZ, ZZ)`
//! (about the frame origin, in the body frame): `(F_k; N_k) = W_k π_k`, a 6×10 matrix of the
//! body's motion (`ω`, `α` and the origin acceleration `a` minus gravity) with 36 structural
//! non-zeros. So the ten entries of row r in body k's columns are `φ_kr · W_k` with
//! `φ_kr = ((ω_k)_r; (v_k)_r)` in body k's frame.
//!
//! A generated function computes, straight-line, every link's motion and joint transform (the
//! [`KIN`] values per link of a `kin` table) and the entries that are not a body's (a wheeled
//! base's wheel columns), then calls [`inverse_dynamics_regressor`] with two constant tables:
//! per link its parent and the result columns of its body's parameters ([`Link`]), and the
//! (row, link) pairs in the order the loop visits them ([`Step`]): per speed, the link its joint
//! moves (the seed: the joint's own partial velocity, a constant) and then that link's
//! descendants, each partial velocity carried one joint down from its parent's. The code that
//! runs per pair is one small loop body instead of one straight line per entry: it stays in the
//! instruction cache (Krang's straight-line regressor is five times its size).
//!
//! Allocation-free and infallible: the scratch arrays are on the stack and an out-of-range
//! table entry (impossible in generated tables) skips its store instead of panicking.

use core::ops::{Add, Mul, Sub};

/// Values per link in the `kin` table, all in the link's own frame: `ω` (0..3), `α` (3..6), the
/// origin acceleration minus gravity `a` (6..9), the rotation `R` of the link relative to its
/// parent, row-major (9..18: a vector `x` of the parent's axes is `Rᵀ x` in the link's), and the
/// link's origin in the parent's frame `P` (18..21). The root's `R` and `P` are not read.
pub const KIN: usize = 21;

/// No result column (a base regressor leaves most of a body's parameters out).
pub const NO_COLUMN: u16 = u16::MAX;

/// One link of the kinematic tree, for [`inverse_dynamics_regressor`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// Index of the parent link (the root's is not read).
    pub parent: u16,
    /// Result column of each of the body's ten parameters `m, MX, MY, MZ, XX, XY, XZ, YY, YZ,
    /// ZZ`, or [`NO_COLUMN`] (a link without a body has none).
    pub columns: [u16; 10],
}

/// One (row, link) pair of [`inverse_dynamics_regressor`]'s loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step<T> {
    /// The speed (result row).
    pub row: u16,
    /// The link whose partial velocity for `row` this step forms (and whose body's columns it
    /// writes).
    pub link: u16,
    /// `Some((ω; v))`: the partial velocity of the link's own joint, in its frame (the first
    /// step of a row); `None`: carried down from the parent's partial velocity for the same row,
    /// which an earlier step formed.
    pub seed: Option<[T; 6]>,
}

/// The arithmetic the kernel needs (`f64` and `f32`).
pub trait Scalar:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
}

impl<T: Copy + Default + Add<Output = T> + Sub<Output = T> + Mul<Output = T>> Scalar for T {}

/// `a × b`.
#[inline(always)]
fn cross<T: Scalar>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn v3<T: Scalar>(x: &[T], at: usize) -> [T; 3] {
    [x[at], x[at + 1], x[at + 2]]
}

/// `Rᵀ x` with `R` row-major at `kin[9..18]`.
#[inline(always)]
fn rot_down<T: Scalar>(kin: &[T; KIN], x: [T; 3]) -> [T; 3] {
    let r = |i: usize, k: usize| kin[9 + 3 * i + k];
    [
        r(0, 0) * x[0] + r(1, 0) * x[1] + r(2, 0) * x[2],
        r(0, 1) * x[0] + r(1, 1) * x[1] + r(2, 1) * x[2],
        r(0, 2) * x[0] + r(1, 2) * x[1] + r(2, 2) * x[2],
    ]
}

/// The partial velocity of a link from its parent's `phi` (parent axes): `ω' = Rᵀ ω`,
/// `v' = Rᵀ (v + ω × P)`.
#[inline(always)]
fn carry<T: Scalar>(phi: &[T; 6], kin: &[T; KIN]) -> [T; 6] {
    let w = v3(phi, 0);
    let v = v3(phi, 3);
    let wxp = cross(w, v3(kin, 18));
    let w2 = rot_down(kin, w);
    let v2 = rot_down(kin, [v[0] + wxp[0], v[1] + wxp[1], v[2] + wxp[2]]);
    [w2[0], w2[1], w2[2], v2[0], v2[1], v2[2]]
}

/// `K = [α]× + [ω]×[ω]×` (row-major): the first moment's part of the inertia force,
/// `F = m a + K MS`.
#[inline(always)]
fn first_moment_matrix<T: Scalar>(kin: &[T; KIN]) -> [T; 9] {
    let w = v3(kin, 0);
    let al = v3(kin, 3);
    let ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    // ω ωᵀ − |ω|² I + [α]×
    [
        w[0] * w[0] - ww,
        w[0] * w[1] - al[2],
        w[0] * w[2] + al[1],
        w[1] * w[0] + al[2],
        w[1] * w[1] - ww,
        w[1] * w[2] - al[0],
        w[2] * w[0] - al[1],
        w[2] * w[1] + al[0],
        w[2] * w[2] - ww,
    ]
}

/// The ten entries `φ · W` of one (row, body) pair: `φ = (w; v)` the body's partial velocity,
/// `kin` its motion, `k` its [`first_moment_matrix`].
#[inline(always)]
fn entries<T: Scalar>(phi: &[T; 6], kin: &[T; KIN], k: &[T; 9]) -> [T; 10] {
    let w = v3(phi, 0);
    let v = v3(phi, 3);
    let om = v3(kin, 0);
    let al = v3(kin, 3);
    let a = v3(kin, 6);
    // m: v · a
    let m = v[0] * a[0] + v[1] * a[1] + v[2] * a[2];
    // MS: Kᵀ v + a × w   (v · K MS and w · (MS × a) = MS · (a × w))
    let axw = cross(a, w);
    let ms = [
        k[0] * v[0] + k[3] * v[1] + k[6] * v[2] + axw[0],
        k[1] * v[0] + k[4] * v[1] + k[7] * v[2] + axw[1],
        k[2] * v[0] + k[5] * v[1] + k[8] * v[2] + axw[2],
    ];
    // J: w · (J α + ω × J ω) = Lᵀ(α) w + Lᵀ(ω) (w × ω), with J x = L(x) (XX, XY, XZ, YY, YZ, ZZ).
    let x = cross(w, om);
    [
        m,
        ms[0],
        ms[1],
        ms[2],
        al[0] * w[0] + om[0] * x[0],
        al[1] * w[0] + al[0] * w[1] + om[1] * x[0] + om[0] * x[1],
        al[2] * w[0] + al[0] * w[2] + om[2] * x[0] + om[0] * x[2],
        al[1] * w[1] + om[1] * x[1],
        al[2] * w[1] + al[1] * w[2] + om[2] * x[1] + om[1] * x[2],
        al[2] * w[2] + om[2] * x[2],
    ]
}

/// Add to the column-major `rows × cols` result `out` the body entries of the inverse-dynamics
/// regressor: for every step of `steps` (in order), the link's partial velocity for the step's
/// row (its seed, or carried down from its parent's), then the ten entries of its body's
/// columns ([`Link::columns`]) in that row. `kin` is every link's motion and joint transform
/// ([`KIN`]). Entries of rows and columns the steps do not reach are left as they are (the
/// generated function starts from zero and stores the other entries itself).
///
/// Flops per call: 23 per link with a body, 42 per carried step and 71 per written step (see
/// a generated function's documentation for a model's total).
#[inline(always)]
pub fn inverse_dynamics_regressor<T: Scalar, const NL: usize>(
    kin: &[[T; KIN]; NL],
    links: &[Link; NL],
    steps: &[Step<T>],
    rows: usize,
    out: &mut [T],
) {
    let z = T::default();
    let mut k = [[z; 9]; NL];
    let mut phi = [[z; 6]; NL];
    inverse_dynamics_regressor_with(kin, links, steps, rows, out, &mut k, &mut phi);
}

/// [`inverse_dynamics_regressor`] with the scratch space passed in (one entry per link each):
/// `k` the bodies' first-moment matrices, `phi` the partial velocities of the current row. For
/// callers whose number of links is not a constant (tests, interpreters).
#[inline(always)]
pub fn inverse_dynamics_regressor_with<T: Scalar>(
    kin: &[[T; KIN]],
    links: &[Link],
    steps: &[Step<T>],
    rows: usize,
    out: &mut [T],
    k: &mut [[T; 9]],
    phi: &mut [[T; 6]],
) {
    for ((k, kin), link) in k.iter_mut().zip(kin).zip(links) {
        if link.columns.iter().any(|&c| c != NO_COLUMN) {
            *k = first_moment_matrix(kin);
        }
    }
    for s in steps {
        let l = s.link as usize;
        let (Some(kl), Some(link), Some(kk)) = (kin.get(l), links.get(l), k.get(l)) else {
            continue;
        };
        let p = match s.seed {
            Some(seed) => seed,
            None => match phi.get(link.parent as usize) {
                Some(parent) => carry(parent, kl),
                None => continue,
            },
        };
        if let Some(slot) = phi.get_mut(l) {
            *slot = p;
        }
        if link.columns.iter().all(|&c| c == NO_COLUMN) {
            continue;
        }
        let y = entries(&p, kl, kk);
        let row = s.row as usize;
        for (&c, y) in link.columns.iter().zip(y) {
            if c != NO_COLUMN {
                if let Some(o) = out.get_mut(c as usize * rows + row) {
                    *o = y;
                }
            }
        }
    }
}
