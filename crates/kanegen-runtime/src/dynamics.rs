//! The interface every generated robot implements.

use nalgebra::{RealField, SMatrix, SVector};

use crate::tree_factor::TreeFactor;

/// The dynamics of a robot with `N` generalized coordinates `q` and `N` generalized speeds
/// `u`, in the form `τ = M(q) u̇ + c(q, u) + g(q)`. Implemented by the robot type of every
/// generated module (for its model's parameter set), so that a controller, estimator or
/// simulator can be written once for any generated robot.
///
/// Vectors are ordered as [`COORDINATE_NAMES`](Self::COORDINATE_NAMES) (for `q`) and
/// [`SPEED_NAMES`](Self::SPEED_NAMES) (for `u`, `u̇` and `τ`). The methods do not allocate and
/// cannot fail.
pub trait RobotDynamics<const N: usize> {
    /// The scalar the robot computes in (`f64` or `f32` for generated modules).
    type Scalar: RealField + Copy;

    /// Generalized speed names, in the order of `u` (and of `u̇`, `τ`, and the rows of `M`).
    const SPEED_NAMES: [&'static str; N];

    /// Coordinate names, in the order of `q`.
    const COORDINATE_NAMES: [&'static str; N];

    /// The speeds' parent array `λ` (`λ(i) < i`, `None` for a speed at the root) when the mass
    /// matrix is structurally zero off the tree's ancestor pairs ([`crate::tree_factor`]):
    /// generated modules set it to their `SPEED_PARENTS` where the generator verified the
    /// pattern, and [`forward_dynamics`](Self::forward_dynamics) then factors `M` without
    /// fill-in. `None` (the default): `M` is taken as dense.
    const SPEED_PARENTS: Option<[Option<usize>; N]> = None;

    /// The mass matrix `M(q)`, symmetric positive definite: the kinetic energy is `½ uᵀ M u`,
    /// and `M u̇` is the part of `τ` that depends on `u̇`.
    fn mass_matrix(&self, q: &SVector<Self::Scalar, N>) -> SMatrix<Self::Scalar, N, N>;

    /// The Coriolis and centrifugal vector `c(q, u)` (quadratic in `u`): `τ` at `u̇ = 0` with
    /// gravity off.
    fn coriolis(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
    ) -> SVector<Self::Scalar, N>;

    /// The gravity vector `g(q)`: `τ` at `u = 0`, `u̇ = 0` (the torque that holds the robot
    /// still).
    fn gravity(&self, q: &SVector<Self::Scalar, N>) -> SVector<Self::Scalar, N>;

    /// Inverse dynamics `τ = M(q) u̇ + c(q, u) + g(q)`: the generalized forces that produce the
    /// accelerations `ud` (= `u̇`) at state `(q, u)`. Generated robots compute it in one pass,
    /// cheaper than the three terms apart.
    fn inverse_dynamics(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
        ud: &SVector<Self::Scalar, N>,
    ) -> SVector<Self::Scalar, N>;

    /// Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))`: the accelerations the generalized
    /// forces `tau` produce at state `(q, u)`, for simulation. `c + g` is one inverse-dynamics
    /// pass at `u̇ = 0`. With [`SPEED_PARENTS`](Self::SPEED_PARENTS) `M` is factored along the
    /// tree ([`TreeFactor`](crate::tree_factor::TreeFactor): no fill-in, two legs never
    /// coupled); without, by nalgebra's dense Cholesky, whose factor is then solved by the
    /// runtime's own substitutions (rows in blocks of four: faster than nalgebra's
    /// `Cholesky::solve`). Either on the stack (no heap, `no_std`).
    ///
    /// `None` when `M(q)` is not positive definite (or has a NaN entry): non-physical
    /// parameters, such as a negative mass or an inertia violating the triangle inequalities
    /// (`Params::validate` names the culprit). Inputs that are not finite otherwise give
    /// non-finite accelerations.
    ///
    /// A provided method: every generated robot has it through this trait. `krang-dynamics`'s
    /// `Krang::forward_dynamics` is a faster inherent method for that model (a block Cholesky
    /// that skips the two arms' zero coupling block).
    fn forward_dynamics(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
        tau: &SVector<Self::Scalar, N>,
    ) -> Option<SVector<Self::Scalar, N>> {
        let bias = self.inverse_dynamics(q, u, &SVector::zeros());
        if Self::SPEED_PARENTS.is_some() {
            // Solved where it lies: the factor (N² entries) is not moved out of the `Option`.
            return self
                .mass_matrix_factor(q)
                .as_ref()
                .map(|factor| factor.solve(&(tau - bias)));
        }
        let factor = DenseFactor::new(self.mass_matrix(q))?;
        Some(factor.solve(&(tau - bias)))
    }

    /// `M(q) = Lᵀ D L` along [`SPEED_PARENTS`](Self::SPEED_PARENTS) (without fill-in), or, when
    /// that is `None`, along [`chain_parents`](crate::tree_factor::chain_parents) (a dense
    /// factorisation): what [`forward_dynamics`](Self::forward_dynamics),
    /// [`crate::contact::constrained_forward_dynamics_factored`] and
    /// [`crate::contact::contact_impulse_factored`] solve with. Generated robots override it
    /// with their straight-line kernels (`TREE_KERNELS`). `None` when `M(q)` is not positive
    /// definite.
    fn mass_matrix_factor(
        &self,
        q: &SVector<Self::Scalar, N>,
    ) -> Option<TreeFactor<Self::Scalar, N>> {
        let parents = Self::SPEED_PARENTS.unwrap_or(crate::tree_factor::chain_parents());
        TreeFactor::new(&self.mass_matrix(q), &parents)
    }
}

/// Implemented by generated robots whose module includes the (opt-in) Coriolis matrix.
pub trait CoriolisMatrix<const N: usize>: RobotDynamics<N> {
    /// The Coriolis matrix `C(q, u)`: `c(q, u) = C(q, u) u` (see
    /// [`RobotDynamics::coriolis`]), and `Ṁ − 2C` is skew-symmetric, `Ṁ` being the rate of
    /// change of `M(q)` along the motion (the property passivity-based controllers rely on).
    fn coriolis_matrix(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
    ) -> SMatrix<Self::Scalar, N, N>;
}

/// Implemented by generated robots whose module includes the (opt-in)
/// `inverse_dynamics_derivatives`: the exact partial derivatives of inverse dynamics, and from
/// them ([`forward_dynamics_derivatives`](Self::forward_dynamics_derivatives), provided) those
/// of forward dynamics, which LQR and MPC linearize with.
///
/// ```
/// use kanegen_runtime::{InverseDynamicsDerivatives, RobotDynamics};
/// use nalgebra::{SMatrix, SVector};
///
/// /// `(∂u̇/∂q, ∂u̇/∂u)` at a state, for any generated robot with derivatives.
/// fn jacobians<R: InverseDynamicsDerivatives<N, Scalar = f64>, const N: usize>(
///     robot: &R,
///     q: &SVector<f64, N>,
///     u: &SVector<f64, N>,
///     tau: &SVector<f64, N>,
/// ) -> Option<(SMatrix<f64, N, N>, SMatrix<f64, N, N>)> {
///     robot
///         .forward_dynamics_derivatives(q, u, tau)
///         .map(|d| (d.dud_dq, d.dud_du))
/// }
///
/// /// A point mass `m` on a rod of length `l`, `q` from straight down: `τ = m l² u̇ + m g l sin q`.
/// struct Pendulum { m: f64, l: f64, g: f64 }
///
/// impl RobotDynamics<1> for Pendulum {
///     type Scalar = f64;
///     const SPEED_NAMES: [&'static str; 1] = ["qd"];
///     const COORDINATE_NAMES: [&'static str; 1] = ["q"];
///     fn mass_matrix(&self, _: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
///         SMatrix::from_element(self.m * self.l * self.l)
///     }
///     fn coriolis(&self, _: &SVector<f64, 1>, _: &SVector<f64, 1>) -> SVector<f64, 1> {
///         SVector::zeros()
///     }
///     fn gravity(&self, q: &SVector<f64, 1>) -> SVector<f64, 1> {
///         SVector::from_element(self.m * self.g * self.l * q[0].sin())
///     }
///     fn inverse_dynamics(
///         &self,
///         q: &SVector<f64, 1>,
///         u: &SVector<f64, 1>,
///         ud: &SVector<f64, 1>,
///     ) -> SVector<f64, 1> {
///         self.mass_matrix(q) * ud + self.coriolis(q, u) + self.gravity(q)
///     }
/// }
///
/// impl InverseDynamicsDerivatives<1> for Pendulum {
///     fn inverse_dynamics_partials(
///         &self,
///         q: &SVector<f64, 1>,
///         _: &SVector<f64, 1>,
///         _: &SVector<f64, 1>,
///     ) -> (SMatrix<f64, 1, 1>, SMatrix<f64, 1, 1>) {
///         let dtau_dq = self.m * self.g * self.l * q[0].cos();
///         (SMatrix::from_element(dtau_dq), SMatrix::zeros())
///     }
/// }
///
/// let p = Pendulum { m: 2.0, l: 0.5, g: 9.81 };
/// let (q, u) = (SVector::from([0.3]), SVector::from([0.0]));
/// let (a, b) = jacobians(&p, &q, &u, &SVector::zeros()).unwrap();
/// // Linearized about q: ü = −(g / l) cos q · δq.
/// assert!((a[0] + 9.81 / 0.5 * 0.3_f64.cos()).abs() < 1e-12);
/// assert_eq!(b[0], 0.0);
/// ```
pub trait InverseDynamicsDerivatives<const N: usize>: RobotDynamics<N> {
    /// `(∂τ/∂q, ∂τ/∂u)` of `τ = M(q) u̇ + c(q, u) + g(q)` at `(q, u, u̇)`: column `j` of each
    /// is the derivative with respect to `q[j]` (resp. `u[j]`); `∂τ/∂u̇` is
    /// [`mass_matrix`](RobotDynamics::mass_matrix). Generated modules split their
    /// `inverse_dynamics_derivatives` (`[∂τ/∂q | ∂τ/∂u]`, N × 2N) into the two blocks.
    fn inverse_dynamics_partials(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
        ud: &SVector<Self::Scalar, N>,
    ) -> (SMatrix<Self::Scalar, N, N>, SMatrix<Self::Scalar, N, N>);

    /// Forward dynamics `u̇ = FD(q, u, τ)` and its derivatives at `(q, u, τ)`: since
    /// `ID(q, u, FD(q, u, τ)) = τ`, `∂u̇/∂q = −M⁻¹ ∂τ/∂q`, `∂u̇/∂u = −M⁻¹ ∂τ/∂u` (the inverse
    /// dynamics partials taken at `u̇ = FD(q, u, τ)`) and `∂u̇/∂τ = M⁻¹`. One inverse-dynamics
    /// pass, one mass matrix and its dense Cholesky factor (nalgebra, on the stack), one
    /// derivative pass and the triangular solves of the `3N` right-hand sides `[−∂τ/∂q | −∂τ/∂u
    /// | I]` in place, eight at a time side by side (compiled for the baseline and, where the
    /// CPU has it, x86-64-v3); no heap. With [`SPEED_PARENTS`](RobotDynamics::SPEED_PARENTS)
    /// `u̇` itself comes from [`mass_matrix_factor`](RobotDynamics::mass_matrix_factor) (a
    /// second mass matrix), so that it is [`forward_dynamics`](RobotDynamics::forward_dynamics)'s
    /// bit for bit.
    ///
    /// `None` when `M(q)` is not positive definite (non-physical parameters), as
    /// [`forward_dynamics`](RobotDynamics::forward_dynamics). `krang-dynamics`'s
    /// `Krang::forward_dynamics_derivatives` is a faster inherent method for that model (its
    /// block Cholesky).
    fn forward_dynamics_derivatives(
        &self,
        q: &SVector<Self::Scalar, N>,
        u: &SVector<Self::Scalar, N>,
        tau: &SVector<Self::Scalar, N>,
    ) -> Option<ForwardDynamicsDerivatives<Self::Scalar, N>> {
        let factor = DenseFactor::new(self.mass_matrix(q))?;
        let bias = self.inverse_dynamics(q, u, &SVector::zeros());
        // `ud` as `forward_dynamics` computes it, bit for bit (along the tree where there is one;
        // the many-column solves below stay with the dense factor's grouped substitutions).
        let ud = if Self::SPEED_PARENTS.is_some() {
            self.mass_matrix_factor(q)?.solve(&(tau - bias))
        } else {
            factor.solve(&(tau - bias))
        };
        let (mut dud_dq, mut dud_du) = self.inverse_dynamics_partials(q, u, &ud);
        // X = M⁻¹ [−∂τ/∂q | −∂τ/∂u | I], solved in place: the partials are negated (exactly)
        // as they are copied into the solve's groups.
        let mut minv = SMatrix::identity();
        let minus_one = -nalgebra::one::<Self::Scalar>();
        factor.solve_columns(
            [&mut dud_dq, &mut dud_du, &mut minv],
            [minus_one, minus_one, nalgebra::one()],
        );
        Some(ForwardDynamicsDerivatives {
            ud,
            dud_dq,
            dud_du,
            minv,
        })
    }
}

/// The dense Cholesky factor `L` of a mass matrix (nalgebra's `cholesky()`, on the stack) with
/// the reciprocals of its diagonal, solved by the runtime's substitutions
/// ([`cholesky_solve_vector`], [`cholesky_solve_columns`]) in their dispatched copies: what the
/// provided `forward_dynamics` and `forward_dynamics_derivatives` share.
pub(crate) struct DenseFactor<T: RealField + Copy, const N: usize> {
    factor: nalgebra::Cholesky<T, nalgebra::Const<N>>,
    inv_diag: [T; N],
}

impl<T: RealField + Copy, const N: usize> DenseFactor<T, N> {
    /// `None` when `m` is not positive definite (or has a NaN entry).
    #[inline(always)]
    pub(crate) fn new(m: SMatrix<T, N, N>) -> Option<Self> {
        let factor = m.cholesky()?;
        let l = factor.l_dirty();
        let inv_diag = core::array::from_fn(|i| T::one() / l[(i, i)]);
        Some(Self { factor, inv_diag })
    }

    /// `M⁻¹ b`.
    #[inline(always)]
    pub(crate) fn solve(&self, b: &SVector<T, N>) -> SVector<T, N> {
        let (l, inv_diag) = (self.factor.l_dirty(), &self.inv_diag);
        crate::isa::dispatch_fused(
            #[inline(always)]
            || cholesky_solve_vector::<_, N, false>(l, inv_diag, b),
            #[inline(always)]
            || cholesky_solve_vector::<_, N, true>(l, inv_diag, b),
        )
    }

    /// `X_m ← s_m M⁻¹ X_m` for each of the matrices `xs` ([`cholesky_solve_columns`]).
    #[inline(always)]
    pub(crate) fn solve_columns<const C: usize, const K: usize>(
        &self,
        xs: [&mut SMatrix<T, N, C>; K],
        s: [T; K],
    ) {
        let (l, inv_diag) = (self.factor.l_dirty(), &self.inv_diag);
        crate::isa::dispatch_fused_with(
            xs,
            #[inline(always)]
            |xs| cholesky_solve_columns::<_, N, C, K, false>(l, inv_diag, xs, s),
            #[inline(always)]
            |xs| cholesky_solve_columns::<_, N, C, K, true>(l, inv_diag, xs, s),
        );
    }
}

/// Right-hand sides per group of [`cholesky_solve_columns`]: two 256-bit vectors of `f64`.
const SOLVE_GROUP: usize = 8;

/// `X_m ← s_m A⁻¹ X_m` for each of the `M` matrices `xs` (`N × C`, every column one
/// right-hand side) and signs or scales `s`, for `A = L Lᵀ`, given the lower triangle of `l`
/// (its strict upper triangle is ignored: nalgebra's `Cholesky::l_dirty`) and the reciprocals
/// of its diagonal `inv_diag`.
///
/// The `M·C` right-hand sides are taken [`SOLVE_GROUP`] at a time, across matrices (the
/// fixed-wheel tree's 3 × 17 in 7 groups): a group is copied (and scaled by `s_m`) into a
/// local `N × SOLVE_GROUP` array whose row `k` holds speed `k` of the group's right-hand sides
/// side by side, solved there ([`solve_group`]: rows in blocks of [`SOLVE_ROWS`], each block
/// accumulated in registers over the rows before it, then stored once), and copied back. The
/// copy in and out is a transposition fused with the solve; a short last group is padded with
/// zeros. The operations and their order are those of the textbook substitutions
/// (`x_i −= l_ik x_k` for `k = 0, 1, …`, then `x_i ← x_i / l_ii` as a product with
/// `inv_diag`; backwards `x_k −= l_ik x_i` for `i = N − 1, …, k + 1`), so each right-hand side
/// gets the bits of solving it alone. With `FUSED` (the x86-64-v3 copy, chosen by
/// `isa::dispatch_fused_with`) each term is one fused multiply-add, as in the generated
/// functions' x86-64-v3 copies: results within rounding of the baseline copy's, not the same
/// bits.
///
/// Measured on the fixed-wheel tree's `forward_dynamics_derivatives` (criterion
/// `fd_derivatives/fixed_wheels_trait`, Nov 2026, Intel Xeon with AVX-512): nalgebra's `Cholesky::solve` and `inverse`, one column at a
/// time through strided loops, took 17.1 µs; solves on transposed copies that
/// passed over all right-hand sides for every `x_i −= l_ik x_k`, storing and reloading `x_i`
/// at each `k`, 7.3–7.7 µs; this form, the figure in docs/derivatives.md.
#[inline(always)]
fn cholesky_solve_columns<
    T: RealField + Copy,
    const N: usize,
    const C: usize,
    const M: usize,
    const FUSED: bool,
>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    xs: [&mut SMatrix<T, N, C>; M],
    s: [T; M],
) {
    let total = M * C;
    let mut first = 0;
    while first < total {
        let width = SOLVE_GROUP.min(total - first);
        let mut group = [[T::zero(); SOLVE_GROUP]; N];
        for j in 0..width {
            let (m, c) = ((first + j) / C, (first + j) % C);
            for (row, x) in group.iter_mut().zip(xs[m].column(c).iter()) {
                row[j] = *x * s[m];
            }
        }
        solve_group::<T, N, SOLVE_GROUP, FUSED>(l, inv_diag, &mut group);
        for j in 0..width {
            let (m, c) = ((first + j) / C, (first + j) % C);
            for (row, x) in group.iter().zip(xs[m].column_mut(c).iter_mut()) {
                *x = row[j];
            }
        }
        first += width;
    }
}

/// Rows per block of [`solve_group`].
const SOLVE_ROWS: usize = 4;

/// `A⁻¹ b` for `A = L Lᵀ` (the lower triangle of `l`, the reciprocals of its diagonal
/// `inv_diag`): [`solve_group`] on one right-hand side, the same bits as that right-hand side
/// solved by [`cholesky_solve_columns`]. What the provided `forward_dynamics` methods solve
/// with: nalgebra's `Cholesky::solve` took 0.33 µs of the fixed-wheel tree's
/// `forward_dynamics_derivatives` (measured with `perf`).
#[inline(always)]
fn cholesky_solve_vector<T: RealField + Copy, const N: usize, const FUSED: bool>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    b: &SVector<T, N>,
) -> SVector<T, N> {
    let mut x = [[T::zero(); 1]; N];
    for (x, b) in x.iter_mut().zip(b.iter()) {
        x[0] = *b;
    }
    solve_group::<T, N, 1, FUSED>(l, inv_diag, &mut x);
    SVector::from_fn(|k, _| x[k][0])
}

/// The two substitutions of [`cholesky_solve_columns`] on one group: `x[k][j]` is speed `k` of
/// right-hand side `j`. The rows are taken [`SOLVE_ROWS`] at a time ([`forward_rows`],
/// [`backward_rows`]): the rows of a block are accumulated in registers together, so that each
/// row already solved is loaded once per block rather than once per row, and the block's rows
/// give the processor independent chains of subtractions. Each row's terms are still
/// subtracted in the textbook order.
#[inline(always)]
fn solve_group<T: RealField + Copy, const N: usize, const W: usize, const FUSED: bool>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    x: &mut [[T; W]; N],
) {
    let full = N - N % SOLVE_ROWS;
    // L y = b: y_i = (b_i − Σ_{k < i} l_ik y_k) / l_ii.
    for first in (0..full).step_by(SOLVE_ROWS) {
        forward_rows::<T, N, W, SOLVE_ROWS, FUSED>(l, inv_diag, x, first);
    }
    for first in full..N {
        forward_rows::<T, N, W, 1, FUSED>(l, inv_diag, x, first);
    }
    // Lᵀ x = y: x_k = (y_k − Σ_{i > k} l_ik x_i) / l_kk, the sum from the last row up.
    for first in (full..N).rev() {
        backward_rows::<T, N, W, 1, FUSED>(l, inv_diag, x, first);
    }
    for first in (0..full).step_by(SOLVE_ROWS).rev() {
        backward_rows::<T, N, W, SOLVE_ROWS, FUSED>(l, inv_diag, x, first);
    }
}

/// Rows `first..first + R` of the forward substitution `L y = b`, the rows before them solved.
#[inline(always)]
fn forward_rows<
    T: RealField + Copy,
    const N: usize,
    const W: usize,
    const R: usize,
    const FUSED: bool,
>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    x: &mut [[T; W]; N],
    first: usize,
) {
    let mut acc = [[T::zero(); W]; R];
    acc.copy_from_slice(&x[first..first + R]);
    for k in 0..first {
        let y = x[k];
        for (r, acc) in acc.iter_mut().enumerate() {
            sub_scaled::<T, W, FUSED>(acc, l[(first + r, k)], &y);
        }
    }
    for r in 0..R {
        for k in 0..r {
            let y = acc[k];
            sub_scaled::<T, W, FUSED>(&mut acc[r], l[(first + r, first + k)], &y);
        }
        store_scaled(&mut x[first + r], &mut acc[r], inv_diag[first + r]);
    }
}

/// Rows `first..first + R` of the back substitution `Lᵀ x = y`, the rows after them solved.
#[inline(always)]
fn backward_rows<
    T: RealField + Copy,
    const N: usize,
    const W: usize,
    const R: usize,
    const FUSED: bool,
>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    x: &mut [[T; W]; N],
    first: usize,
) {
    let mut acc = [[T::zero(); W]; R];
    acc.copy_from_slice(&x[first..first + R]);
    for i in (first + R..N).rev() {
        let xi = x[i];
        for (r, acc) in acc.iter_mut().enumerate() {
            sub_scaled::<T, W, FUSED>(acc, l[(i, first + r)], &xi);
        }
    }
    for r in (0..R).rev() {
        for i in (r + 1..R).rev() {
            let xi = acc[i];
            sub_scaled::<T, W, FUSED>(&mut acc[r], l[(first + i, first + r)], &xi);
        }
        store_scaled(&mut x[first + r], &mut acc[r], inv_diag[first + r]);
    }
}

/// `acc −= a · y`, lane by lane: one term of a row of the substitutions. With `FUSED` one
/// fused multiply-add (`−a · y + acc`, one rounding: the x86-64-v3 copy, see
/// `isa::dispatch_fused`), else a product and a difference (the baseline copy).
#[inline(always)]
fn sub_scaled<T: RealField + Copy, const W: usize, const FUSED: bool>(
    acc: &mut [T; W],
    a: T,
    y: &[T; W],
) {
    for (acc, y) in acc.iter_mut().zip(y) {
        *acc = if FUSED {
            (-a).mul_add(*y, *acc)
        } else {
            *acc - a * *y
        };
    }
}

/// `acc ← acc · d` (a row divided by its pivot, `d` the pivot's reciprocal), stored in `x` too.
#[inline(always)]
fn store_scaled<T: RealField + Copy, const W: usize>(x: &mut [T; W], acc: &mut [T; W], d: T) {
    for (x, acc) in x.iter_mut().zip(acc.iter_mut()) {
        *acc *= d;
        *x = *acc;
    }
}

/// The forward-dynamics derivatives of an `N`-speed robot at one state:
/// `u̇ = FD(q, u, τ)` and its partial derivatives
/// ([`InverseDynamicsDerivatives::forward_dynamics_derivatives`]). For the state `x = [q; u]`
/// with `q̇ = u`, the linearization of `ẋ = f(x, τ)` is `A = [[0, I], [∂u̇/∂q, ∂u̇/∂u]]`,
/// `B = [[0], [M⁻¹]]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForwardDynamicsDerivatives<T, const N: usize> {
    /// `u̇ = M⁻¹ (τ − c − g)`, where the derivatives are taken.
    pub ud: SVector<T, N>,
    /// `∂u̇/∂q` (column j: the derivative with respect to `q[j]`).
    pub dud_dq: SMatrix<T, N, N>,
    /// `∂u̇/∂u`.
    pub dud_du: SMatrix<T, N, N>,
    /// `∂u̇/∂τ = M⁻¹` (symmetric positive definite).
    pub minv: SMatrix<T, N, N>,
}

#[cfg(test)]
mod tests {
    use super::{cholesky_solve_columns, cholesky_solve_vector};
    use nalgebra::{RealField, SMatrix};

    /// A symmetric positive definite `A = B Bᵀ + N I` and right-hand sides from a fixed
    /// sequence of values in `[−1, 1)`.
    fn spd_and_rhs<T: RealField + Copy, const N: usize, const C: usize>()
    -> (SMatrix<T, N, N>, SMatrix<T, N, C>) {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            T::from_f64((state >> 11) as f64 / (1u64 << 52) as f64 - 1.0).unwrap()
        };
        let b = SMatrix::<T, N, N>::from_fn(|_, _| next());
        let a = b * b.transpose() + SMatrix::identity() * T::from_usize(N).unwrap();
        (a, SMatrix::from_fn(|_, _| next()))
    }

    /// Both forms of the substitutions ([`cholesky_solve_columns`]'s `FUSED`: the baseline and
    /// the x86-64-v3 copy's arithmetic).
    fn solves_like_nalgebra<
        T: RealField + Copy,
        const N: usize,
        const C: usize,
        const FUSED: bool,
    >(
        bound: f64,
    ) {
        let (a, b) = spd_and_rhs::<T, N, C>();
        let chol = a.cholesky().unwrap();
        let mut x = b;
        let l = chol.l_dirty();
        let inv_diag = core::array::from_fn(|i| T::one() / l[(i, i)]);
        cholesky_solve_columns::<T, N, C, 1, FUSED>(l, &inv_diag, [&mut x], [T::one()]);
        let expected = chol.solve(&b);
        let err = (x - expected).norm() / expected.norm();
        assert!(err <= T::from_f64(bound).unwrap(), "{N}×{C}: {err}");
        let residual = (a * x - b).norm() / b.norm();
        assert!(
            residual <= T::from_f64(bound).unwrap(),
            "{N}×{C}: {residual}"
        );
    }

    #[test]
    fn many_column_cholesky_solve_matches_nalgebras_solve() {
        solves_like_nalgebra::<f64, 1, 1, false>(1e-15);
        solves_like_nalgebra::<f64, 5, 3, false>(1e-14);
        solves_like_nalgebra::<f64, 17, 17, false>(1e-14);
        solves_like_nalgebra::<f64, 19, 57, false>(1e-14);
        solves_like_nalgebra::<f32, 7, 7, false>(1e-5);
        solves_like_nalgebra::<f64, 1, 1, true>(1e-15);
        solves_like_nalgebra::<f64, 17, 17, true>(1e-14);
        solves_like_nalgebra::<f64, 19, 57, true>(1e-14);
        solves_like_nalgebra::<f32, 7, 7, true>(1e-5);
    }

    /// The groups of right-hand sides cross the matrices' boundaries (3 × 17 columns: six
    /// groups of 8 and one of 3); every column still gets the bits of solving it alone, scaled
    /// (by −1 or 2: exact) before the solve, and so does the one-vector solve of
    /// `forward_dynamics`. Sizes below, at and above the row blocks and groups.
    fn grouped_like_alone<const N: usize, const C: usize, const FUSED: bool>() {
        let (a, b) = spd_and_rhs::<f64, N, C>();
        let chol = a.cholesky().unwrap();
        let l = chol.l_dirty();
        let inv_diag = core::array::from_fn(|i| 1.0 / l[(i, i)]);
        let rhs = [b, b.map(|v| v * v), -b];
        let scales = [1.0, -1.0, 2.0];
        let mut x = rhs;
        let [x0, x1, x2] = &mut x;
        cholesky_solve_columns::<f64, N, C, 3, FUSED>(l, &inv_diag, [x0, x1, x2], scales);
        for m in 0..3 {
            for c in 0..C {
                let mut alone = SMatrix::<f64, N, 1>::from_fn(|r, _| rhs[m][(r, c)] * scales[m]);
                let vector = cholesky_solve_vector::<f64, N, FUSED>(l, &inv_diag, &alone);
                cholesky_solve_columns::<f64, N, 1, 1, FUSED>(l, &inv_diag, [&mut alone], [1.0]);
                assert_eq!(vector.map(f64::to_bits), alone.map(f64::to_bits));
                for r in 0..N {
                    assert_eq!(
                        x[m][(r, c)].to_bits(),
                        alone[r].to_bits(),
                        "{N}×{C}, matrix {m}, entry ({r}, {c})"
                    );
                }
            }
        }
    }

    #[test]
    fn grouped_solves_give_every_right_hand_side_the_bits_of_solving_it_alone() {
        grouped_like_alone::<1, 1, false>();
        grouped_like_alone::<4, 2, false>();
        grouped_like_alone::<5, 3, false>();
        grouped_like_alone::<9, 8, false>();
        grouped_like_alone::<17, 17, false>();
        grouped_like_alone::<19, 19, false>();
        grouped_like_alone::<5, 3, true>();
        grouped_like_alone::<17, 17, true>();
        grouped_like_alone::<19, 19, true>();
    }
}
