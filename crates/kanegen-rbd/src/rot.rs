//! Joint rotations `R = A' Rot_z(q)` (child → parent) applied without forming `R`.
//!
//! When `A'` is a signed permutation, row `i` of `Rot_z(q)` lands, times a sign `g_i`, in row
//! `A_i` of `R`: `R[A_0] = g_0 (c, −s, 0)`, `R[A_1] = g_1 (s, c, 0)`, `R[A_2] = (0, 0, g_2)`.
//! The six possible `(A_0, A_1, A_2)` are compile-time constants of [`Perm`], selected once per
//! transform by [`RotKind`]; the signed `g_i c`, `g_i s` are formed once per link and call
//! ([`Jr`]). A transform then costs 5 multiplications and 2 additions with no data-dependent
//! indexing. Other rotations ([`RotKind::General`]) use `A'` as a matrix.

use nalgebra::SVector;

use crate::LinkData;
use crate::scalar::{M3, S3, Scalar, V3, add, mat_mul, rot, rot_t, scale, sym_rot, sym_rot_z};

/// How `A'` acts: one of the six signed permutations, named by the rows `(A_0, A_1, A_2)` of
/// `R` that receive rows 0, 1, 2 of `Rot_z`, or a general rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RotKind {
    P012,
    P021,
    P102,
    P120,
    P201,
    P210,
    General,
}

impl RotKind {
    /// The kind for `A_i = rows[i]`.
    pub(crate) fn from_rows(rows: [usize; 3]) -> Self {
        match rows {
            [0, 1, 2] => Self::P012,
            [0, 2, 1] => Self::P021,
            [1, 0, 2] => Self::P102,
            [1, 2, 0] => Self::P120,
            [2, 0, 1] => Self::P201,
            _ => Self::P210,
        }
    }
}

/// Per link and call: `cos q`, `sin q` and the signed `g_0 c`, `g_0 s`, `g_1 c`, `g_1 s`, `g_2`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Jr<T> {
    c: T,
    s: T,
    gc0: T,
    gs0: T,
    gc1: T,
    gs1: T,
    g2: T,
}

/// Position of `(a, b)` in `[xx, xy, xz, yy, yz, zz]`.
pub(crate) const fn sym_index(a: usize, b: usize) -> usize {
    let (i, j) = if a <= b { (a, b) } else { (b, a) };
    match (i, j) {
        (0, 0) => 0,
        (0, 1) => 1,
        (0, 2) => 2,
        (1, 1) => 3,
        (1, 2) => 4,
        _ => 5,
    }
}

/// A signed permutation with compile-time rows `(A0, A1, A2)`.
struct Perm<const A0: usize, const A1: usize, const A2: usize>;

impl<const A0: usize, const A1: usize, const A2: usize> Perm<A0, A1, A2> {
    /// `I[a]`: the row of `Rot_z` that lands in row `a` of `R`.
    const I: [usize; 3] = {
        let mut i = [0; 3];
        i[A0] = 0;
        i[A1] = 1;
        i[A2] = 2;
        i
    };
    /// Entry of `Rot_z J Rot_zᵀ` that lands in each entry `(a, b)` of `R J Rᵀ`.
    const SYM_SRC: [usize; 6] = [
        sym_index(Self::I[0], Self::I[0]),
        sym_index(Self::I[0], Self::I[1]),
        sym_index(Self::I[0], Self::I[2]),
        sym_index(Self::I[1], Self::I[1]),
        sym_index(Self::I[1], Self::I[2]),
        sym_index(Self::I[2], Self::I[2]),
    ];

    #[inline(always)]
    fn up<T: Scalar>(j: &Jr<T>, x: V3<T>) -> V3<T> {
        let mut o = [j.c; 3];
        o[A0] = j.gc0 * x[0] - j.gs0 * x[1];
        o[A1] = j.gs1 * x[0] + j.gc1 * x[1];
        o[A2] = j.g2 * x[2];
        o
    }

    #[inline(always)]
    fn down<T: Scalar>(j: &Jr<T>, x: V3<T>) -> V3<T> {
        [
            j.gc0 * x[A0] + j.gs1 * x[A1],
            j.gc1 * x[A1] - j.gs0 * x[A0],
            j.g2 * x[A2],
        ]
    }

    #[inline(always)]
    fn right<T: Scalar>(j: &Jr<T>, w: &M3<T>) -> M3<T> {
        [
            add(scale(w[A0], j.gc0), scale(w[A1], j.gs1)),
            add(scale(w[A1], j.gc1), scale(w[A0], -j.gs0)),
            scale(w[A2], j.g2),
        ]
    }

    #[inline(always)]
    fn sym<T: Scalar>(j: &Jr<T>, sign: &[T; 6], m: &S3<T>) -> S3<T> {
        let jz = sym_rot_z(m, j.c, j.s);
        let k = Self::SYM_SRC;
        [
            sign[0] * jz[k[0]],
            sign[1] * jz[k[1]],
            sign[2] * jz[k[2]],
            sign[3] * jz[k[3]],
            sign[4] * jz[k[4]],
            sign[5] * jz[k[5]],
        ]
    }
}

/// Dispatches `$f(args)` to the [`Perm`] of `$kind`, or evaluates `$general`.
macro_rules! by_kind {
    ($kind:expr, $f:ident($($arg:expr),*), $general:expr) => {
        match $kind {
            RotKind::P012 => Perm::<0, 1, 2>::$f($($arg),*),
            RotKind::P021 => Perm::<0, 2, 1>::$f($($arg),*),
            RotKind::P102 => Perm::<1, 0, 2>::$f($($arg),*),
            RotKind::P120 => Perm::<1, 2, 0>::$f($($arg),*),
            RotKind::P201 => Perm::<2, 0, 1>::$f($($arg),*),
            RotKind::P210 => Perm::<2, 1, 0>::$f($($arg),*),
            RotKind::General => $general,
        }
    };
}

impl<T: Scalar> LinkData<T> {
    /// The joint rotation at `s = sin q`, `c = cos q`.
    #[inline(always)]
    pub(crate) fn jr(&self, s: T, c: T) -> Jr<T> {
        let [g0, g1, g2] = self.g;
        Jr {
            c,
            s,
            gc0: g0 * c,
            gs0: g0 * s,
            gc1: g1 * c,
            gs1: g1 * s,
            g2,
        }
    }

    /// `R x` (child frame → parent frame).
    #[inline(always)]
    pub(crate) fn up(&self, j: &Jr<T>, x: V3<T>) -> V3<T> {
        by_kind!(
            self.kind,
            up(j, x),
            rot(
                &self.a,
                [j.c * x[0] - j.s * x[1], j.s * x[0] + j.c * x[1], x[2]]
            )
        )
    }

    /// `Rᵀ x` (parent frame → child frame).
    #[inline(always)]
    pub(crate) fn down(&self, j: &Jr<T>, x: V3<T>) -> V3<T> {
        by_kind!(self.kind, down(j, x), {
            let y = rot_t(&self.a, x);
            [j.c * y[0] + j.s * y[1], j.c * y[1] - j.s * y[0], y[2]]
        })
    }

    /// `W R` for a column-stored `W`.
    #[inline(always)]
    pub(crate) fn right(&self, j: &Jr<T>, w: &M3<T>) -> M3<T> {
        by_kind!(self.kind, right(j, w), {
            let x = mat_mul(w, &self.a);
            [
                add(scale(x[0], j.c), scale(x[1], j.s)),
                add(scale(x[1], j.c), scale(x[0], -j.s)),
                x[2],
            ]
        })
    }

    /// `R J Rᵀ` for a symmetric `J`.
    #[inline(always)]
    pub(crate) fn sym_up(&self, j: &Jr<T>, m: &S3<T>) -> S3<T> {
        by_kind!(
            self.kind,
            sym(j, &self.sym_sign, m),
            sym_rot(&self.a, &sym_rot_z(m, j.c, j.s))
        )
    }

    /// The translation `p' (+ A' ẑ q for a prismatic joint)`.
    #[inline(always)]
    pub(crate) fn trans<const N: usize>(&self, q: &SVector<T, N>) -> V3<T> {
        if self.prismatic {
            add(self.p, scale(self.a[2], q[self.speed]))
        } else {
            self.p
        }
    }
}
