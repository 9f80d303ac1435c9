//! The block Cholesky factorisation of Krang's mass matrices, arms first ([`BlockCholesky`]; the
//! structure it exploits is described in [the `forward` module](crate::forward)), the error of a
//! matrix that is not positive definite, and the dense fallback [`solve_spd`].
//! Everything is fixed-size nalgebra on the stack; nothing allocates and nothing panics.

use core::fmt;

use kanegen_runtime::isa::Arith;
use kanegen_runtime::pair::{F64x2, FusedPair, PairArith};
use kanegen_runtime::quad::{F64x4, FusedQuad, QuadArith};
use nalgebra::{SMatrix, SVector};

/// The diagonal block whose factorisation broke down.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Block {
    /// The left-arm block `M[5..12, 5..12]` (Krang; `M[3..10, 3..10]` of the fixed-wheel
    /// tree).
    LeftArm,
    /// The right-arm block `M[12..19, 12..19]` (Krang; `M[10..17, 10..17]` of the fixed-wheel
    /// tree).
    RightArm,
    /// The Schur complement onto the trunk block `M[0..5, 0..5]` (Krang; `M[0..3, 0..3]` of
    /// the fixed-wheel tree).
    Trunk,
    /// The whole matrix (dense factorisation, [`solve_spd`]).
    Dense,
}

/// The mass matrix is not (numerically) positive definite.
///
/// With physical parameters M is always symmetric positive definite; this happens with
/// non-physical parameter sets (negative masses, as in the hardware-trained beta vector),
/// or with non-finite `q`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NotPositiveDefinite {
    /// Where the factorisation failed.
    pub block: Block,
}

impl fmt::Display for NotPositiveDefinite {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.block {
            Block::LeftArm => "left-arm block",
            Block::RightArm => "right-arm block",
            Block::Trunk => "trunk Schur complement",
            Block::Dense => "matrix",
        };
        write!(f, "mass matrix is not positive definite ({what})")
    }
}

impl core::error::Error for NotPositiveDefinite {}

// The factors are kept as upper-triangular `U = Lᵀ` in nalgebra's column-major storage, so
// that every inner loop below runs over a contiguous column prefix, with the reciprocals of
// their diagonals: the substitutions multiply instead of dividing.

/// An upper Cholesky factor `U` (`A = Uᵀ U`; its strict lower triangle is zero) and the
/// reciprocals of its diagonal.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Upper<const N: usize> {
    u: SMatrix<f64, N, N>,
    inv_diag: [f64; N],
}

impl<const N: usize> Upper<N> {
    /// The lower triangle of the N×N diagonal block of `a` at `(at, at)`, transposed into the
    /// upper triangle (zeros below), before the first [`step`](Self::step).
    #[inline(always)]
    fn from_lower_at<const M: usize>(a: &SMatrix<f64, M, M>, at: usize) -> Self {
        let mut u = SMatrix::<f64, N, N>::zeros();
        let s = u.as_mut_slice();
        // Column i of `s` holds row i of the block's lower triangle: U(k, i) = s[i N + k], k ≤ i.
        for i in 0..N {
            for k in 0..=i {
                s[i * N + k] = a[(at + i, at + k)];
            }
        }
        Upper {
            u,
            inv_diag: [0.0; N],
        }
    }

    /// Pivot `k` of the right-looking factorisation, in place: the pivot's square root and
    /// reciprocal, the rest of row `k` of `U` scaled, and that row's outer product subtracted
    /// from the trailing block; `false` if the pivot is not positive (or is NaN).
    ///
    /// The updates of a step are independent of each other, so the dependency chain per pivot
    /// is the square root (the reciprocal `√d · (1/d)` is computed beside it, not after it),
    /// one multiply and one multiply-subtract. [`MassMatrixCholesky::new`] calls it for the
    /// trunk's block with literal pivot indices, so that each step indexes with constants (the
    /// arms' blocks are factorised two lanes at a time by the same steps, written for
    /// [`F64x2`] in `BlockCholesky::new_in`).
    #[inline(always)]
    fn step<A: Arith<f64>>(&mut self, k: usize) -> bool {
        let s = self.u.as_mut_slice();
        let d = s[k * N + k];
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let r = nalgebra::ComplexField::sqrt(d); // `f64::sqrt` needs std
        let r_inv = r * (1.0 / d);
        s[k * N + k] = r;
        self.inv_diag[k] = r_inv;
        for i in k + 1..N {
            s[i * N + k] *= r_inv;
        }
        for i in k + 1..N {
            let uki = s[i * N + k];
            for j in k + 1..=i {
                s[i * N + j] = A::mul_add(-s[j * N + k], uki, s[i * N + j]);
            }
        }
        true
    }
}

/// The right-hand sides [`BlockCholesky::solve_columns_mut`] takes side by side, and their
/// arithmetic: two columns per [`F64x2`] in the baseline copy ([`kanegen_runtime::isa::Plain`]:
/// a multiplication and an addition), four per [`F64x4`] in the x86-64-v3 copy ([`FusedQuad`]:
/// fused). A substitution is a chain of dependent multiply-adds, so four columns per chain run
/// half as many chains (Krang's 57 columns of `forward_dynamics_derivatives`, Intel Xeon, Nov
/// 2026: 1,710 → 1,140 ns in the x86-64-v3 copy; the baseline copy's 2,590 ns unchanged).
/// Each lane runs the operations of [`BlockCholesky::solve_mut`] on its column in the same
/// order.
trait ColumnLanes: Copy {
    /// Columns per value.
    const WIDTH: usize;
    /// One value: a row of `WIDTH` columns.
    type V: Copy;
    /// `x` in every lane.
    fn splat(self, x: f64) -> Self::V;
    /// The lanes `x(0)`, …, `x(WIDTH − 1)`.
    fn load(self, x: impl FnMut(usize) -> f64) -> Self::V;
    /// Calls `to(l, lane l)` for every lane.
    fn store(self, v: Self::V, to: impl FnMut(usize, f64));
    /// `a + b`, lane by lane (as are the three below).
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a − b`.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a · b`.
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a · b + c`: rounded twice by [`Plain`](kanegen_runtime::isa::Plain), once by
    /// [`FusedQuad`].
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
}

impl ColumnLanes for kanegen_runtime::isa::Plain {
    const WIDTH: usize = 2;
    type V = F64x2;
    #[inline(always)]
    fn splat(self, x: f64) -> F64x2 {
        F64x2::splat(x)
    }
    #[inline(always)]
    fn load(self, mut x: impl FnMut(usize) -> f64) -> F64x2 {
        F64x2::new(x(0), x(1))
    }
    #[inline(always)]
    fn store(self, v: F64x2, mut to: impl FnMut(usize, f64)) {
        to(0, v.lo());
        to(1, v.hi());
    }
    #[inline(always)]
    fn add(self, a: F64x2, b: F64x2) -> F64x2 {
        a + b
    }
    #[inline(always)]
    fn sub(self, a: F64x2, b: F64x2) -> F64x2 {
        a - b
    }
    #[inline(always)]
    fn mul(self, a: F64x2, b: F64x2) -> F64x2 {
        a * b
    }
    #[inline(always)]
    fn mul_add(self, a: F64x2, b: F64x2, c: F64x2) -> F64x2 {
        PairArith::mul_add(self, a, b, c)
    }
}

impl ColumnLanes for FusedQuad {
    const WIDTH: usize = 4;
    type V = F64x4;
    #[inline(always)]
    fn splat(self, x: f64) -> F64x4 {
        QuadArith::splat(self, x)
    }
    #[inline(always)]
    fn load(self, mut x: impl FnMut(usize) -> f64) -> F64x4 {
        QuadArith::load(self, [x(0), x(1), x(2), x(3)])
    }
    #[inline(always)]
    fn store(self, v: F64x4, mut to: impl FnMut(usize, f64)) {
        for (l, x) in self.lanes(v).into_iter().enumerate() {
            to(l, x);
        }
    }
    #[inline(always)]
    fn add(self, a: F64x4, b: F64x4) -> F64x4 {
        QuadArith::add(self, a, b)
    }
    #[inline(always)]
    fn sub(self, a: F64x4, b: F64x4) -> F64x4 {
        QuadArith::sub(self, a, b)
    }
    #[inline(always)]
    fn mul(self, a: F64x4, b: F64x4) -> F64x4 {
        QuadArith::mul(self, a, b)
    }
    #[inline(always)]
    fn mul_add(self, a: F64x4, b: F64x4, c: F64x4) -> F64x4 {
        QuadArith::mul_add(self, a, b, c)
    }
}

/// Block Cholesky factorisation of Krang's 19×19 mass matrix, arms first (see the
/// [`forward` module docs](crate::forward)): [`BlockCholesky`] with a trunk of 5 speeds.
pub type MassMatrixCholesky = BlockCholesky<5, 19>;

/// Block Cholesky factorisation, arms first (see the [`forward` module docs](crate::forward)), of an `N×N` mass
/// matrix ordered as Krang's models are: `T` trunk speeds, then two 7-speed arms that do not
/// couple to each other (`N = T + 14`, `T ≤ 8`): [`MassMatrixCholesky`] (`T = 5`, Krang) and
/// `BlockCholesky<3, 17>` (the fixed-wheel tree). Fixed size, `Copy`, no heap.
///
/// Reuse one factorisation for several right-hand sides (e.g. `M⁻¹ Jᵀ` in an
/// operational-space controller) with [`solve`](Self::solve).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockCholesky<const T: usize, const N: usize> {
    /// The arms' factors side by side, the left arm's in the low lane and the right arm's in
    /// the high lane of each value: `U_l = L_lᵀ`, `U_r = L_rᵀ` (upper),
    /// `U(k, i) = arm_u[7 i + k]` for `k ≤ i`.
    arm_u: [F64x2; 49],
    /// The reciprocals of their diagonals.
    arm_inv_diag: [F64x2; 7],
    /// `W_l = L_l⁻¹ M[left, trunk]` and `W_r = L_r⁻¹ M[right, trunk]`, `W(i, j) = arm_w[j][i]`.
    arm_w: [[F64x2; 7]; T],
    /// `U_s = L_sᵀ` (upper), the factor of the Schur complement.
    u_trunk: Upper<T>,
}

impl<const T: usize, const N: usize> BlockCholesky<T, N> {
    /// The first speed of the left arm (the trunk's are `0..T`).
    const LEFT: usize = T;
    /// The first speed of the right arm.
    const RIGHT: usize = T + 7;

    /// Factorises `m`, reading its lower triangle only and assuming `M[left, right] = 0`
    /// (exactly true of Krang's generated mass matrices; entries there are ignored).
    ///
    /// # Errors
    /// [`NotPositiveDefinite`] if a pivot is not positive (or is NaN).
    pub fn new(m: &SMatrix<f64, N, N>) -> Result<Self, NotPositiveDefinite> {
        const {
            assert!(N == T + 14, "N is T trunk speeds and two arms of 7");
            assert!(
                T <= 8,
                "the pivots and substitutions are written out for T ≤ 8"
            );
        };
        // Compiled for the baseline and, run when the CPU has it, for x86-64-v3, whose copy
        // fuses every update into one multiply-add (results differ in the last bits).
        kanegen_runtime::isa::dispatch_pair_with(
            m,
            Self::new_in::<kanegen_runtime::isa::Plain, _>,
            Self::new_in::<kanegen_runtime::isa::Fused, _>,
        )
    }

    /// The factorisation with the two arms in the two lanes of [`F64x2`] values (left arm
    /// low, right arm high, "arms in lanes" as in the generated code): their blocks have the
    /// same shape, so each of the arms' pivot steps, substitutions and Schur-complement
    /// products is one two-lane operation (the factorisation in about two thirds of the time
    /// of the two arms factorised one after the other; Intel Xeon, Nov 2026: 308 → 193 ns,
    /// `forward_dynamics` 900 → 770 ns). The trunk's pivots follow, on the Schur complement.
    #[inline(always)]
    fn new_in<A: Arith<f64>, P: PairArith>(
        m: &SMatrix<f64, N, N>,
        lanes: P,
    ) -> Result<Self, NotPositiveDefinite> {
        let (left, right) = (Self::LEFT, Self::RIGHT);
        // U(k, i) = u[7 i + k] (k ≤ i), from the arms' lower triangles.
        let mut u = [F64x2::splat(0.0); 49];
        for i in 0..7 {
            for k in 0..=i {
                u[7 * i + k] = F64x2::new(m[(left + i, left + k)], m[(right + i, right + k)]);
            }
        }
        let mut inv = [F64x2::splat(0.0); 7];
        // W(i, j) = w[j][i]: the arms' rows of the trunk's columns.
        let mut w = [[F64x2::splat(0.0); 7]; T];
        for j in 0..T {
            for i in 0..7 {
                w[j][i] = F64x2::new(m[(left + i, j)], m[(right + i, j)]);
            }
        }
        // Each pivot step written out with its index as a literal, so that it indexes with
        // constants. A pivot that is not positive (or is NaN) names its arm; when both arms'
        // are, at the same step, the left one.
        macro_rules! arm_pivots {
            ($($k:literal)*) => {$({
                let k: usize = $k;
                let d = u[8 * k];
                let (dl, dr) = (d.lo(), d.hi());
                if dl.is_nan() || dl <= 0.0 {
                    return Err(NotPositiveDefinite { block: Block::LeftArm });
                }
                if dr.is_nan() || dr <= 0.0 {
                    return Err(NotPositiveDefinite { block: Block::RightArm });
                }
                let r = F64x2::new(
                    nalgebra::ComplexField::sqrt(dl),
                    nalgebra::ComplexField::sqrt(dr),
                );
                let r_inv = r * (1.0 / d);
                u[8 * k] = r;
                inv[k] = r_inv;
                for i in k + 1..7 {
                    u[7 * i + k] = u[7 * i + k] * r_inv;
                }
                for i in k + 1..7 {
                    let uki = u[7 * i + k];
                    for j in k + 1..=i {
                        u[7 * i + j] = lanes.mul_add(-u[7 * j + k], uki, u[7 * i + j]);
                    }
                }
            })*};
        }
        arm_pivots!(0 1 2 3 4 5 6);
        // W = L⁻¹ M[arm, trunk], column by column.
        for wj in &mut w {
            for i in 0..7 {
                let mut acc = wj[i];
                for k in 0..i {
                    acc = lanes.mul_add(-u[7 * i + k], wj[k], acc);
                }
                wj[i] = acc * inv[i];
            }
        }
        let mut f = Self {
            arm_u: u,
            arm_inv_diag: inv,
            arm_w: w,
            u_trunk: Upper::from_lower_at(m, 0),
        };
        // The Schur complement S = T − W_lᵀ W_l − W_rᵀ W_r: both arms' products in the two
        // lanes, then the lanes' sum.
        let s = f.u_trunk.u.as_mut_slice();
        let w = &f.arm_w;
        for i in 0..T {
            for j in 0..=i {
                let acc = w[i]
                    .iter()
                    .zip(&w[j])
                    .fold(F64x2::splat(0.0), |acc, (a, b)| lanes.mul_add(*a, *b, acc));
                // S(i, j), j ≤ i, is stored as U(j, i).
                s[T * i + j] -= acc.lo() + acc.hi();
            }
        }
        macro_rules! trunk_pivots {
            ($($k:literal)*) => {$(
                if $k < T && !f.u_trunk.step::<A>($k) {
                    return Err(NotPositiveDefinite { block: Block::Trunk });
                }
            )*};
        }
        trunk_pivots!(0 1 2 3 4 5 6 7);
        Ok(f)
    }

    /// `x = M⁻¹ b` from `m` itself, when one right-hand side is all there is (forward
    /// dynamics): [`new`](Self::new) and [`solve_mut`](Self::solve_mut) in one dispatched call,
    /// so the factor stays a local of it instead of being returned and copied (1.7 KB for
    /// Krang; Intel Xeon, Nov 2026: `forward_dynamics` 724–751 → 677–702 ns). The same bits as
    /// `new(m)?.solve(b)`.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn solve_once(
        m: &SMatrix<f64, N, N>,
        b: &SVector<f64, N>,
    ) -> Result<SVector<f64, N>, NotPositiveDefinite> {
        const { assert!(N == T + 14 && T <= 8) };
        kanegen_runtime::isa::dispatch_pair_with(
            (m, *b),
            #[inline(always)]
            |(m, mut b), lanes| {
                let f = Self::new_in::<kanegen_runtime::isa::Plain, _>(m, lanes)?;
                f.solve_one::<kanegen_runtime::isa::Plain, _>(&mut b, lanes);
                Ok(b)
            },
            #[inline(always)]
            |(m, mut b), lanes| {
                let f = Self::new_in::<kanegen_runtime::isa::Fused, _>(m, lanes)?;
                f.solve_one::<kanegen_runtime::isa::Fused, _>(&mut b, lanes);
                Ok(b)
            },
        )
    }

    /// `x = M⁻¹ b`.
    #[inline]
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x = *b;
        self.solve_mut(&mut x);
        x
    }

    /// `b ← M⁻¹ b`, in place, with the two arms in the two lanes of [`F64x2`] values, as the
    /// factor is stored (the trunk's part in `f64`). Each entry gets the bits that
    /// [`solve_columns_mut`](Self::solve_columns_mut) gives `b` as one of its columns (the
    /// same operations in the same order, lane by lane).
    pub fn solve_mut(&self, b: &mut SVector<f64, N>) {
        kanegen_runtime::isa::dispatch_pair_with(
            b,
            #[inline(always)]
            |b, lanes| self.solve_one::<kanegen_runtime::isa::Plain, _>(b, lanes),
            #[inline(always)]
            |b, lanes| self.solve_one::<kanegen_runtime::isa::Fused, _>(b, lanes),
        );
    }

    #[inline(always)]
    fn solve_one<A: Arith<f64>, P: PairArith>(&self, b: &mut SVector<f64, N>, lanes: P) {
        let (left, right) = (Self::LEFT, Self::RIGHT);
        let mut t = [0.0; T];
        t.copy_from_slice(&b.as_slice()[..T]);
        let mut a: [F64x2; 7] = core::array::from_fn(|i| F64x2::new(b[left + i], b[right + i]));
        let (u, inv, w) = (&self.arm_u, &self.arm_inv_diag, &self.arm_w);
        let (ut, inv_t) = (&self.u_trunk.u, &self.u_trunk.inv_diag);
        // Forward: L z = b (the arms, their coupling into the trunk's rows, the trunk).
        each!(i < 7; {
            for k in 0..i {
                a[i] = lanes.mul_add(a[k], -u[7 * i + k], a[i]);
            }
            a[i] = a[i] * inv[i];
        });
        each!(j < T; {
            let mut acc = F64x2::splat(0.0);
            each!(k < 7; { acc = lanes.mul_add(a[k], w[j][k], acc); });
            t[j] -= acc.lo() + acc.hi();
        });
        each!(i < T; {
            for k in 0..i {
                t[i] = A::mul_add(t[k], -ut[(k, i)], t[i]);
            }
            t[i] *= inv_t[i];
        });
        // Backward: Lᵀ x = z (the trunk, its coupling into the arms' rows, the arms).
        each!(r < T; {
            let i = T - 1 - r;
            t[i] *= inv_t[i];
            for k in 0..i {
                t[k] = A::mul_add(t[i], -ut[(k, i)], t[k]);
            }
        });
        each!(k < 7; {
            each!(j < T; { a[k] = lanes.mul_add(F64x2::splat(t[j]), -w[j][k], a[k]); });
        });
        each!(r < 7; {
            let i = 6 - r;
            a[i] = a[i] * inv[i];
            for k in 0..i {
                a[k] = lanes.mul_add(a[i], -u[7 * i + k], a[k]);
            }
        });
        b.as_mut_slice()[..T].copy_from_slice(&t);
        for (i, ai) in a.iter().enumerate() {
            b[left + i] = ai.lo();
            b[right + i] = ai.hi();
        }
    }

    /// `X ← M⁻¹ X` for the `C` columns of `x` at once (e.g. `M⁻¹ ∂τ/∂q`, `M⁻¹ B`, `M⁻¹` itself).
    ///
    /// The columns are taken in groups side by side, one vector per speed (19 registers' worth
    /// for Krang): two per [`F64x2`] in the baseline copy, four per
    /// [`F64x4`] in the x86-64-v3 copy, which also fuses each
    /// `y_i −= l_ik y_k` into one multiply-add (the two copies' results may differ in the last
    /// bits). The block substitutions (the arms' factors, their coupling to the trunk, the
    /// trunk's factor) run on a group with every index a constant, so it stays in registers
    /// from its load to its store; the last group is padded with zero columns. The lanes are
    /// independent, so each column gets the bits [`solve_mut`](Self::solve_mut) gives it alone
    /// (with the same instruction set). Fixed size, on the stack.
    pub fn solve_columns_mut<const C: usize>(&self, x: &mut SMatrix<f64, N, C>) {
        kanegen_runtime::isa::dispatch_pair_with(
            x,
            #[inline(always)]
            |x, lanes| self.solve_columns_in(x, lanes),
            #[inline(always)]
            |x, lanes: FusedPair| self.solve_columns_in(x, lanes.quad()),
        );
    }

    #[inline(always)]
    fn solve_columns_in<L: ColumnLanes, const C: usize>(
        &self,
        x: &mut SMatrix<f64, N, C>,
        lanes: L,
    ) {
        // Column `c` of `x` is `xs[c * N..(c + 1) * N]`: groups of `WIDTH` columns are
        // contiguous. The last, short group is solved padded with zero columns.
        let xs = x.as_mut_slice();
        let mut padded = [[0.0; N]; 4];
        for c in (0..C).step_by(L::WIDTH) {
            let short = C - c < L::WIDTH;
            let g = if short {
                let rest = &xs[c * N..];
                padded.as_flattened_mut()[..rest.len()].copy_from_slice(rest);
                padded.as_flattened_mut()
            } else {
                &mut xs[c * N..(c + L::WIDTH) * N]
            };
            self.solve_group(g, lanes);
            if short {
                let rest = &mut xs[c * N..];
                let n = rest.len();
                rest.copy_from_slice(&padded.as_flattened()[..n]);
            }
        }
    }

    /// `WIDTH` whole columns, `g[l * N + i]` row `i` of column `l`, solved side by side.
    #[inline(always)]
    fn solve_group<L: ColumnLanes>(&self, g: &mut [f64], lanes: L) {
        let g = &mut g[..L::WIDTH * N];
        // (Not `core::array::from_fn`: its closure is not inlined into the x86-64-v3 copy, and
        // the four-lane loads then become calls.)
        let mut y = [lanes.splat(0.0); N];
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = lanes.load(|l| g[l * N + i]);
        }
        self.solve_lanes(&mut y, lanes);
        for (i, yi) in y.iter().enumerate() {
            lanes.store(*yi, |l, v| g[l * N + i] = v);
        }
    }

    /// `y ← M⁻¹ y` for [`ColumnLanes::WIDTH`] right-hand sides side by side: `L z = y`, then
    /// `Lᵀ y = z`, block by block (left arm, right arm, trunk).
    #[inline(always)]
    fn solve_lanes<L: ColumnLanes>(&self, y: &mut [L::V; N], lanes: L) {
        // Every loop whose bound is not a literal is written out with literal indices (`each!`:
        // the triangles' rows, the trunk's `T`), so that after unrolling every index of `y` is a
        // constant and `y` lives in registers: `F64x2` and `F64x4` are one vector register each,
        // which the compiler does not split into scalars as it does `[f64; 4]` lanes (measured:
        // a `Lanes<4>` version of this kernel ran in scalar instructions, 30 % slower than the
        // old row-at-a-time form).
        // y[d] −= y[s] · a (a multiplication and a subtraction, or one fused multiply-add).
        macro_rules! sub {
            ($d:expr, $s:expr, $a:expr) => {
                y[$d] = lanes.mul_add(y[$s], lanes.splat(-$a), y[$d])
            };
        }
        // U⁻ᵀ (= L⁻¹) and U⁻¹ (= L⁻ᵀ) of an upper factor of size `m` (entry `U(k, i)` given
        // by `u`, the reciprocals of its diagonal by `inv`) on `y[at..at + m]`.
        macro_rules! forward {
            ($u:expr, $inv:expr, $m:expr, $at:expr) => {
                each!(i < $m; {
                    for k in 0..i {
                        sub!($at + i, $at + k, $u(k, i));
                    }
                    y[$at + i] = lanes.mul(y[$at + i], lanes.splat($inv(i)));
                })
            };
        }
        macro_rules! backward {
            ($u:expr, $inv:expr, $m:expr, $at:expr) => {
                each!(r < $m; {
                    let i = $m - 1 - r;
                    y[$at + i] = lanes.mul(y[$at + i], lanes.splat($inv(i)));
                    for k in 0..i {
                        sub!($at + k, $at + i, $u(k, i));
                    }
                })
            };
        }
        let (left, right) = (Self::LEFT, Self::RIGHT);
        let (u, inv, w) = (&self.arm_u, &self.arm_inv_diag, &self.arm_w);
        let (ut, inv_t) = (&self.u_trunk.u, &self.u_trunk.inv_diag);
        let u_left = |k: usize, i: usize| u[7 * i + k].lo();
        let u_right = |k: usize, i: usize| u[7 * i + k].hi();
        let (inv_left, inv_right) = (|i: usize| inv[i].lo(), |i: usize| inv[i].hi());
        let (u_trunk, inv_trunk) = (|k: usize, i: usize| ut[(k, i)], |i: usize| inv_t[i]);
        // Forward: the arms, their coupling into the trunk's rows (z_t −= W_lᵀ z_l + W_rᵀ z_r,
        // each arm's products summed before the two sums are added, as `solve_mut` does), then
        // the Schur complement's factor.
        forward!(u_left, inv_left, 7, left);
        forward!(u_right, inv_right, 7, right);
        each!(j < T; {
            let (mut l, mut r) = (lanes.splat(0.0), lanes.splat(0.0));
            each!(k < 7; {
                l = lanes.mul_add(y[left + k], lanes.splat(w[j][k].lo()), l);
                r = lanes.mul_add(y[right + k], lanes.splat(w[j][k].hi()), r);
            });
            y[j] = lanes.sub(y[j], lanes.add(l, r));
        });
        forward!(u_trunk, inv_trunk, T, 0);
        // Backward: the trunk, then each arm (y_arm −= W y_t, then its factor).
        backward!(u_trunk, inv_trunk, T, 0);
        each!(k < 7; {
            each!(j < T; {
                sub!(left + k, j, w[j][k].lo());
                sub!(right + k, j, w[j][k].hi());
            });
        });
        backward!(u_left, inv_left, 7, left);
        backward!(u_right, inv_right, 7, right);
    }

    /// The factor `L` in the original speed order: `M = L Lᵀ` with `L` lower triangular
    /// after the permutation `[left arm, right arm, trunk]` (for inspection and tests).
    pub fn factor(&self) -> SMatrix<f64, N, N> {
        let (left, right) = (Self::LEFT, Self::RIGHT);
        let mut l = SMatrix::<f64, N, N>::zeros();
        for i in 0..7 {
            for k in 0..=i {
                // L(i, k) = U(k, i).
                l[(left + i, left + k)] = self.arm_u[7 * i + k].lo();
                l[(right + i, right + k)] = self.arm_u[7 * i + k].hi();
            }
            for j in 0..T {
                // The trunk's rows: L(j, arm i) = W(i, j).
                l[(j, left + i)] = self.arm_w[j][i].lo();
                l[(j, right + i)] = self.arm_w[j][i].hi();
            }
        }
        l.fixed_view_mut::<T, T>(0, 0)
            .copy_from(&self.u_trunk.u.transpose());
        l
    }

    /// `det M`, the product of the squared diagonal of `L`.
    pub fn determinant(&self) -> f64 {
        let mut d = 1.0;
        for u in self.arm_u.iter().step_by(8) {
            d *= u.lo() * u.hi();
        }
        for i in 0..T {
            d *= self.u_trunk.u[(i, i)];
        }
        d * d
    }
}

/// Generic dense fallback: `x = A⁻¹ b` for a symmetric positive definite `A` (any fixed
/// size) by nalgebra's Cholesky factorisation of the lower triangle, on the stack. Krang's
/// models use [`BlockCholesky`] instead.
///
/// # Errors
/// [`NotPositiveDefinite`] (`block: Block::Dense`) if a pivot is not positive (or is NaN).
pub fn solve_spd<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
) -> Result<SVector<f64, N>, NotPositiveDefinite> {
    let factor = a.cholesky().ok_or(NotPositiveDefinite {
        block: Block::Dense,
    })?;
    Ok(factor.solve(b))
}

#[cfg(test)]
mod tests {
    use kanegen_runtime::isa::Plain;
    use nalgebra::{SMatrix, SVector};

    use super::{BlockCholesky, MassMatrixCholesky};
    use crate::Krang;

    /// Krang's factor at a pose away from zero, and right-hand sides in [−10, 10].
    fn factor_and_columns<const C: usize>(seed: u64) -> (MassMatrixCholesky, SMatrix<f64, 19, C>) {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
        };
        let q = SVector::<f64, 19>::from_fn(|_, _| 0.3 * next());
        let chol = BlockCholesky::new(&Krang::default().mass_matrix(&q)).expect("physical");
        (chol, SMatrix::from_fn(|_, _| next()))
    }

    /// Both copies' many-column solves (two columns per lane pair in the baseline copy, four
    /// per register in the fused one, the last group padded with zero columns), each column
    /// against the single solve of the same copy: the same bits.
    fn check<const C: usize>(seed: u64) {
        let (chol, b) = factor_and_columns::<C>(seed);
        // The baseline copy, called directly (whatever instruction set is selected).
        let mut x = b;
        chol.solve_columns_in(&mut x, Plain);
        for j in 0..C {
            let mut one = b.column(j).into_owned();
            chol.solve_one::<Plain, _>(&mut one, Plain);
            assert_eq!(x.column(j), one, "baseline, {C} columns, column {j}");
        }
        // The dispatched copy (the fused one, four columns per register, on an x86-64-v3 CPU).
        let mut x = b;
        chol.solve_columns_mut(&mut x);
        for j in 0..C {
            assert_eq!(
                x.column(j),
                chol.solve(&b.column(j).into_owned()),
                "dispatched, {C} columns, column {j}"
            );
        }
    }

    #[test]
    fn many_column_solves_give_every_column_the_single_solves_bits_in_both_copies() {
        for seed in 0..20 {
            check::<1>(seed);
            check::<2>(seed);
            check::<3>(seed);
            check::<4>(seed);
            check::<5>(seed);
            check::<23>(seed);
            check::<57>(seed);
        }
    }
}
