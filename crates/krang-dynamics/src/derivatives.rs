//! Derivatives of the dynamics for LQR and MPC (feature `derivatives`).
//!
//! The generated `inverse_dynamics_derivatives(q, u, u̇)` gives the exact `∂τ/∂q` and `∂τ/∂u`
//! of `τ = M(q) u̇ + c(q, u) + g(q)` (∂τ/∂u̇ = M). Forward dynamics `u̇ = FD(q, u, τ)` is the
//! solution of `ID(q, u, u̇) = τ`, so by the implicit function theorem, at `u̇ = FD(q, u, τ)`,
//!
//! ```text
//! ∂u̇/∂q = −M⁻¹ ∂τ/∂q,   ∂u̇/∂u = −M⁻¹ ∂τ/∂u,   ∂u̇/∂τ = M⁻¹
//! ```
//!
//! with the products formed by triangular solves with the block Cholesky factor of M
//! ([`MassMatrixCholesky`]), never by a dense inverse: `[∂τ/∂q | ∂τ/∂u | I]` (57 columns; M⁻¹
//! itself is one of the results) is solved in one pass over all its columns
//! ([`MassMatrixCholesky::solve_columns_mut`]). Everything is fixed-size on the stack.
//!
//! Along an MPC horizon or in an iLQR/DDP backward pass, where the derivatives are needed at
//! many states, [`Krang::forward_dynamics_derivatives_with`] writes them into a
//! [`ForwardDynamicsDerivativesWorkspace`] the caller keeps: the same bits without zeroing
//! and copying some 30 KB of matrices per call (5–12 % faster on Krang).
//!
//! [`Krang::linearize`] turns them into the `(A, B)` of `ẋ = f(x, a)` for the state
//! `x = [q; u]` (38) and the 18 actuator torques `a` of the actuator map (`τ = B_act a`),
//! with `q̇ = u` (the wheeled base's x and ψ are integrated from ẋ and ψ̇ like every other
//! coordinate).

use kanegen_runtime::{InverseDynamicsDerivatives, RobotDynamics};
use nalgebra::{SMatrix, SVector};

use crate::Krang;
use crate::actuators::ACTUATOR_COUNT;
use crate::forward::{BlockCholesky, MassMatrixCholesky, NotPositiveDefinite};

/// The forward-dynamics derivatives of an `N`-speed model at one state (`u̇`, `∂u̇/∂q`,
/// `∂u̇/∂u`, `M⁻¹`): `kanegen_runtime`'s struct in `f64`, which every generated robot with
/// derivatives also returns from
/// [`InverseDynamicsDerivatives::forward_dynamics_derivatives`].
pub type ForwardDynamicsDerivatives<const N: usize> =
    kanegen_runtime::ForwardDynamicsDerivatives<f64, N>;

/// Square block `k` of a matrix of `N×N` blocks side by side: column-major, the block is the
/// `k`-th run of `N²` entries of the storage, copied as a slice (one `memcpy`). A view's
/// `into_owned` copies through nalgebra's strided iterator, a scalar loop of ≈ 3 cycles per
/// entry, and `from_column_slice` was not much faster (criterion: `id_partials/generated` 3.07
/// µs with `into_owned`, 2.89 with `from_column_slice`, 2.34 with slice copies).
fn square_block<const N: usize, const C: usize>(
    m: &SMatrix<f64, N, C>,
    k: usize,
) -> SMatrix<f64, N, N> {
    let mut b = SMatrix::<f64, N, N>::zeros();
    b.as_mut_slice()
        .copy_from_slice(&m.as_slice()[N * N * k..N * N * (k + 1)]);
    b
}

/// `(A, B)` of `ẋ = f(x, input)` for `x = [q; u]` and `q̇ = u`, from the forward-dynamics
/// derivatives and `∂u̇/∂input`.
fn state_space<const N: usize, const X: usize, const I: usize>(
    fd: &ForwardDynamicsDerivatives<N>,
    dud_dinput: &SMatrix<f64, N, I>,
) -> (SMatrix<f64, X, X>, SMatrix<f64, X, I>) {
    assert_eq!(X, 2 * N, "the state is [q; u]");
    let mut a = SMatrix::<f64, X, X>::zeros();
    write_a_upper::<N, X>(&mut a);
    write_a_lower(&mut a, fd);
    let mut b = SMatrix::<f64, X, I>::zeros();
    b.fixed_view_mut::<N, I>(N, 0).copy_from(dud_dinput);
    (a, b)
}

/// `[0, I]` (`q̇ = u`) into the upper half of `A`'s columns.
fn write_a_upper<const N: usize, const X: usize>(a: &mut SMatrix<f64, X, X>) {
    for (j, column) in a.as_mut_slice().chunks_exact_mut(X).enumerate() {
        column[..N].fill(0.0);
        if j >= N {
            column[j - N] = 1.0;
        }
    }
}

/// `[∂u̇/∂q, ∂u̇/∂u]` into the lower half of `A`'s columns (column slices: nalgebra's strided
/// views copy with scalar loops).
fn write_a_lower<const N: usize, const X: usize>(
    a: &mut SMatrix<f64, X, X>,
    fd: &ForwardDynamicsDerivatives<N>,
) {
    let blocks = fd
        .dud_dq
        .as_slice()
        .chunks_exact(N)
        .chain(fd.dud_du.as_slice().chunks_exact(N));
    for (column, block) in a.as_mut_slice().chunks_exact_mut(X).zip(blocks) {
        column[N..].copy_from_slice(block);
    }
}

/// Forward dynamics and its derivatives at `(q, u, τ)` with the block Cholesky factor of
/// `M(q)` already computed (Krang's and the fixed-wheel tree's, whose `linearize` reuses it):
/// `derivatives` is the model's generated `inverse_dynamics_derivatives` (`N×D`, `D = 2N`),
/// and `[−∂τ/∂q | −∂τ/∂u | I]` (`N×C`, `C = 3N`: column-major, the blocks are consecutive
/// slices) is solved in one pass, `M⁻¹` itself being its last block.
fn forward_dynamics_derivatives_by_value<
    R,
    const T: usize,
    const N: usize,
    const D: usize,
    const C: usize,
>(
    robot: &R,
    chol: &BlockCholesky<T, N>,
    (q, u, tau): (&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>),
    derivatives: impl FnOnce(&SVector<f64, N>) -> SMatrix<f64, N, D>,
) -> ForwardDynamicsDerivatives<N>
where
    R: RobotDynamics<N, Scalar = f64>,
{
    const {
        assert!(
            D == 2 * N && C == 3 * N,
            "[∂τ/∂q | ∂τ/∂u] and [∂τ/∂q | ∂τ/∂u | I]"
        )
    };
    let bias = robot.inverse_dynamics(q, u, &SVector::zeros());
    let ud = chol.solve(&(tau - bias));
    let d = derivatives(&ud);
    let mut x = SMatrix::<f64, N, C>::zeros();
    let (dx, ix) = x.as_mut_slice().split_at_mut(N * D);
    for (x, d) in dx.iter_mut().zip(d.as_slice()) {
        *x = -d;
    }
    for i in 0..N {
        ix[(N + 1) * i] = 1.0;
    }
    chol.solve_columns_mut(&mut x);
    ForwardDynamicsDerivatives {
        ud,
        dud_dq: square_block(&x, 0),
        dud_du: square_block(&x, 1),
        minv: square_block(&x, 2),
    }
}

/// What [`Krang::forward_dynamics_derivatives_with`] keeps across calls: the inverse-dynamics
/// derivatives' workspace, `M(q)` and the result (about 26 KB), made once by
/// [`new`](ForwardDynamicsDerivativesWorkspaceOf::new). Each call overwrites every entry it
/// returns, so nothing is zeroed per call; the result stays readable through
/// [`result`](ForwardDynamicsDerivativesWorkspaceOf::result) until the next call.
pub type ForwardDynamicsDerivativesWorkspace =
    ForwardDynamicsDerivativesWorkspaceOf<crate::DerivativesWorkspace, 19>;

/// The kept workspace of `forward_dynamics_derivatives_with` for a model of `N` speeds whose
/// generated module's derivatives workspace is `W`: Krang's
/// [`ForwardDynamicsDerivativesWorkspace`] and the fixed-wheel tree's
/// `fixed_wheels::ForwardDynamicsDerivativesWorkspace` (feature `fixed-wheels`).
#[derive(Clone, Debug)]
pub struct ForwardDynamicsDerivativesWorkspaceOf<W, const N: usize> {
    derivatives: W,
    mass_matrix: SMatrix<f64, N, N>,
    result: ForwardDynamicsDerivatives<N>,
}

impl<W: Default, const N: usize> ForwardDynamicsDerivativesWorkspaceOf<W, N> {
    /// A workspace whose result is NaN until the first evaluation.
    pub fn new() -> Self {
        Self {
            derivatives: W::default(),
            mass_matrix: SMatrix::zeros(),
            result: nan_derivatives(),
        }
    }

    /// The derivatives of the last `forward_dynamics_derivatives_with` (Krang's
    /// [`Krang::forward_dynamics_derivatives_with`] or the fixed-wheel tree's) into this
    /// workspace: NaN before the first, and after one with non-physical parameters.
    pub fn result(&self) -> &ForwardDynamicsDerivatives<N> {
        &self.result
    }
}

impl<W: Default, const N: usize> Default for ForwardDynamicsDerivativesWorkspaceOf<W, N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Fills `ws` with forward dynamics and its derivatives at `(q, u, τ)` (Krang's and the
/// fixed-wheel tree's `forward_dynamics_derivatives_with`): `M(q)` into the kept matrix by
/// `mass_matrix_into`, its block Cholesky factor (`T` trunk speeds), then
/// [`forward_dynamics_derivatives_onto`] through the kept derivatives workspace
/// (`derivatives_with`: the model's generated `inverse_dynamics_derivatives_with`). `false`,
/// and the result NaN, where `M(q)` is not positive definite.
fn forward_dynamics_derivatives_kept<R, W, const T: usize, const N: usize, const D: usize>(
    robot: &R,
    (q, u, tau): (&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>),
    ws: &mut ForwardDynamicsDerivativesWorkspaceOf<W, N>,
    mass_matrix_into: impl FnOnce(&mut SMatrix<f64, N, N>),
    derivatives_with: impl for<'w> FnOnce(&SVector<f64, N>, &'w mut W) -> &'w SMatrix<f64, N, D>,
) -> bool
where
    R: RobotDynamics<N, Scalar = f64>,
{
    mass_matrix_into(&mut ws.mass_matrix);
    let Ok(chol) = BlockCholesky::<T, N>::new(&ws.mass_matrix) else {
        ws.result = nan_derivatives();
        return false;
    };
    let (derivatives, result) = (&mut ws.derivatives, &mut ws.result);
    forward_dynamics_derivatives_onto(
        robot,
        &chol,
        (q, u, tau),
        |ud| derivatives_with(ud, derivatives),
        result,
    );
    true
}

/// [`forward_dynamics_derivatives_by_value`] into a result the caller keeps: `−∂τ/∂q` and
/// `−∂τ/∂u` are written into `out.dud_dq` and `out.dud_du`, `I` into `out.minv`, and each is
/// solved in place (three solves of `N` columns take as many groups of lanes as one of `3N`,
/// Krang: 15 of four, and each column gets the bits it gets alone). No matrix is zeroed or
/// copied: besides their own time, a few KB stored just before the generated code slow that
/// code (about 40 ns per 3 KB stored; Intel Xeon, Nov 2026).
fn forward_dynamics_derivatives_onto<'d, R, const T: usize, const N: usize, const D: usize>(
    robot: &R,
    chol: &BlockCholesky<T, N>,
    (q, u, tau): (&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>),
    derivatives: impl FnOnce(&SVector<f64, N>) -> &'d SMatrix<f64, N, D>,
    out: &mut ForwardDynamicsDerivatives<N>,
) where
    R: RobotDynamics<N, Scalar = f64>,
{
    const { assert!(D == 2 * N, "[∂τ/∂q | ∂τ/∂u]") };
    let bias = robot.inverse_dynamics(q, u, &SVector::zeros());
    out.ud = chol.solve(&(tau - bias));
    let (dq, du) = derivatives(&out.ud).as_slice().split_at(N * N);
    for (o, x) in out.dud_dq.as_mut_slice().iter_mut().zip(dq) {
        *o = -x;
    }
    for (o, x) in out.dud_du.as_mut_slice().iter_mut().zip(du) {
        *o = -x;
    }
    // The identity, column by column (a one, then the N zeros down to the next diagonal).
    for column in out.minv.as_mut_slice().chunks_mut(N + 1) {
        column[0] = 1.0;
        column[1..].fill(0.0);
    }
    chol.solve_columns_mut(&mut out.dud_dq);
    chol.solve_columns_mut(&mut out.dud_du);
    chol.solve_columns_mut(&mut out.minv);
}

impl Krang {
    /// `(∂τ/∂q, ∂τ/∂u)` of inverse dynamics at `(q, u, u̇)`: the generated
    /// [`inverse_dynamics_derivatives`](Self::inverse_dynamics_derivatives) as two 19×19
    /// matrices. Columns `index::X` and `index::PSI` of ∂τ/∂q are exactly zero (the position
    /// and heading do not enter the dynamics); ∂τ/∂u̇ is [`mass_matrix`](Self::mass_matrix).
    pub fn inverse_dynamics_partials(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        ud: &SVector<f64, 19>,
    ) -> (SMatrix<f64, 19, 19>, SMatrix<f64, 19, 19>) {
        InverseDynamicsDerivatives::inverse_dynamics_partials(self, q, u, ud)
    }

    /// Forward dynamics and its derivatives at `(q, u, τ)`: `u̇ = FD(q, u, τ)`, `∂u̇/∂q`,
    /// `∂u̇/∂u` and `M⁻¹ = ∂u̇/∂τ` (see the [module docs](self)). One inverse-dynamics pass,
    /// one mass matrix and its block Cholesky factor, one derivative pass, one block triangular
    /// solve pair over 57 right-hand sides. Allocation-free.
    ///
    /// # Errors
    /// [`NotPositiveDefinite`] for non-physical parameters.
    pub fn try_forward_dynamics_derivatives(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        tau: &SVector<f64, 19>,
    ) -> Result<ForwardDynamicsDerivatives<19>, NotPositiveDefinite> {
        Ok(self.forward_dynamics_derivatives_factored(&self.mass_matrix_cholesky(q)?, q, u, tau))
    }

    /// [`try_forward_dynamics_derivatives`](Self::try_forward_dynamics_derivatives) with the
    /// factor of `M(q)` already computed (`linearize` reuses it for `M⁻¹ B_act`).
    fn forward_dynamics_derivatives_factored(
        &self,
        chol: &MassMatrixCholesky,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        tau: &SVector<f64, 19>,
    ) -> ForwardDynamicsDerivatives<19> {
        forward_dynamics_derivatives_by_value::<_, 5, 19, 38, 57>(self, chol, (q, u, tau), |ud| {
            self.inverse_dynamics_derivatives(q, u, ud)
        })
    }

    /// As [`try_forward_dynamics_derivatives`](Self::try_forward_dynamics_derivatives), but
    /// infallible: for non-physical parameters every entry is NaN.
    pub fn forward_dynamics_derivatives(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        tau: &SVector<f64, 19>,
    ) -> ForwardDynamicsDerivatives<19> {
        self.try_forward_dynamics_derivatives(q, u, tau)
            .unwrap_or_else(|_| nan_derivatives())
    }

    /// [`forward_dynamics_derivatives`](Self::forward_dynamics_derivatives) written into a
    /// workspace the caller keeps across calls, whose result it returns: the same bits, without
    /// zeroing and copying the matrices of every call (5–12 % faster). For MPC
    /// and iLQR/DDP, which need the derivatives at every state of a horizon. NaN-filled for
    /// non-physical parameters, like the by-value form. Allocation-free.
    ///
    /// ```
    /// use krang_dynamics::Krang;
    /// use krang_dynamics::ForwardDynamicsDerivativesWorkspace;
    /// use nalgebra::SVector;
    ///
    /// let k = Krang::default();
    /// let mut ws = ForwardDynamicsDerivativesWorkspace::new();
    /// let (q, u, tau) = (SVector::zeros(), SVector::zeros(), SVector::zeros());
    /// for _knot in 0..3 {
    ///     let fd = k.forward_dynamics_derivatives_with(&q, &u, &tau, &mut ws);
    ///     assert!(fd.minv[(7, 7)] > 0.0);
    /// }
    /// ```
    pub fn forward_dynamics_derivatives_with<'w>(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        tau: &SVector<f64, 19>,
        ws: &'w mut ForwardDynamicsDerivativesWorkspace,
    ) -> &'w ForwardDynamicsDerivatives<19> {
        self.forward_dynamics_derivatives_kept(q, u, tau, ws);
        &ws.result
    }

    /// [`forward_dynamics_derivatives_with`](Self::forward_dynamics_derivatives_with) into
    /// `ws`; `false` (and NaN) where `M(q)` is not positive definite.
    fn forward_dynamics_derivatives_kept(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        tau: &SVector<f64, 19>,
        ws: &mut ForwardDynamicsDerivativesWorkspace,
    ) -> bool {
        forward_dynamics_derivatives_kept::<_, _, 5, 19, 38>(
            self,
            (q, u, tau),
            ws,
            |m| self.mass_matrix_into(q, m),
            |ud, w| self.inverse_dynamics_derivatives_with(q, u, ud, w),
        )
    }

    /// The linearization `(A, B)` of `ẋ = f(x, a)` at `(q, u, a)`, with the state
    /// `x = [q; u]` (38: `q̇ = u`, `u̇ = FD(q, u, B_act a)`) and the 18 actuator torques `a`
    /// of [`generalized_forces`](Self::generalized_forces) (`[τL, τR, τ_waist, τ_torso,
    /// τ_1l … τ_7r]`, N·m): `A = [[0, I], [∂u̇/∂q, ∂u̇/∂u]]`, `B = [[0], [M⁻¹ B_act]]`.
    /// Not at an equilibrium, `f(x, a)` itself is `[u; FD(q, u, B_act a)]`. NaN-filled for
    /// non-physical parameters.
    ///
    /// ```
    /// use krang_dynamics::{Krang, index};
    /// use nalgebra::SVector;
    ///
    /// let k = Krang::default();
    /// let mut q = SVector::<f64, 19>::zeros();
    /// q[index::Q_IMU] = k.upright_pitch(&q);
    /// // Hold the pose: the actuator torques that cancel gravity at the joints.
    /// let g = k.gravity(&q);
    /// let mut a = SVector::<f64, 18>::zeros();
    /// for j in 2..18 {
    ///     a[j] = g[j + 1];
    /// }
    /// let (a_mat, b_mat) = k.linearize(&q, &SVector::zeros(), &a);
    /// assert_eq!(a_mat[(index::Q_IMU, 19 + index::QD_IMU)], 1.0);
    /// assert!(b_mat.fixed_rows::<19>(0).iter().all(|&x| x == 0.0));
    /// ```
    pub fn linearize(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        a: &SVector<f64, ACTUATOR_COUNT>,
    ) -> (SMatrix<f64, 38, 38>, SMatrix<f64, 38, ACTUATOR_COUNT>) {
        let Ok(chol) = self.mass_matrix_cholesky(q) else {
            return (
                SMatrix::from_element(f64::NAN),
                SMatrix::from_element(f64::NAN),
            );
        };
        let fd =
            self.forward_dynamics_derivatives_factored(&chol, q, u, &self.generalized_forces(a));
        let mut dud_da = SMatrix::<f64, 19, ACTUATOR_COUNT>::zeros();
        self.minv_times_actuators(&fd.minv, dud_da.as_mut_slice().chunks_exact_mut(19));
        state_space(&fd, &dud_da)
    }
}

impl Krang {
    /// `M⁻¹ B_act` from the `M⁻¹` just computed, into `columns` (19 entries each, zero on
    /// entry): a column of `B_act` has one non-zero (a joint's actuator) or three (a wheel's: ẋ,
    /// ψ̇, q_imu), so each column of the product is one column of `M⁻¹` or a sum of three,
    /// instead of 18 more triangular solves. (Column slices: nalgebra's strided column
    /// iterators compile to scalar loops.)
    fn minv_times_actuators<'c>(
        &self,
        minv: &SMatrix<f64, 19, 19>,
        columns: impl Iterator<Item = &'c mut [f64]>,
    ) {
        let b_act = self.actuator_matrix();
        let minv = minv.as_slice();
        for (out, b) in columns.zip(b_act.as_slice().chunks_exact(19)) {
            for (r, &x) in b.iter().enumerate().filter(|(_, x)| **x != 0.0) {
                for (o, m) in out.iter_mut().zip(&minv[19 * r..19 * (r + 1)]) {
                    *o += x * m;
                }
            }
        }
    }

    /// [`linearize`](Self::linearize) written into a workspace the caller keeps across calls,
    /// whose `(A, B)` it returns: the same bits, through
    /// [`forward_dynamics_derivatives_with`](Self::forward_dynamics_derivatives_with), with
    /// the constant blocks of `A` and `B` (`0`, `I`) written once instead of every call. For
    /// an iLQR/DDP or MPC horizon, which linearizes at every knot. NaN-filled for non-physical
    /// parameters, like `linearize`. Allocation-free.
    ///
    /// ```
    /// use krang_dynamics::{Krang, LinearizationWorkspace};
    /// use nalgebra::SVector;
    ///
    /// let k = Krang::default();
    /// let mut ws = LinearizationWorkspace::new();
    /// let (q, u) = (SVector::zeros(), SVector::zeros());
    /// let (a_mat, b_mat) = k.linearize_with(&q, &u, &SVector::zeros(), &mut ws);
    /// assert_eq!(a_mat[(0, 19)], 1.0);
    /// assert_eq!(b_mat[(0, 0)], 0.0);
    /// ```
    pub fn linearize_with<'w>(
        &self,
        q: &SVector<f64, 19>,
        u: &SVector<f64, 19>,
        a: &SVector<f64, ACTUATOR_COUNT>,
        ws: &'w mut LinearizationWorkspace,
    ) -> (
        &'w SMatrix<f64, 38, 38>,
        &'w SMatrix<f64, 38, ACTUATOR_COUNT>,
    ) {
        let ok =
            self.forward_dynamics_derivatives_kept(q, u, &self.generalized_forces(a), &mut ws.fd);
        // B's lower half: M⁻¹ B_act.
        ws.fill(ok, |minv, b| {
            let lower = b.as_mut_slice().chunks_exact_mut(38).map(|c| {
                let lower = &mut c[19..];
                lower.fill(0.0);
                lower
            });
            self.minv_times_actuators(minv, lower);
        })
    }
}

/// What [`Krang::linearize_with`] keeps across calls: a [`ForwardDynamicsDerivativesWorkspace`]
/// and `A` (38 × 38) and `B` (38 × 18), whose constant blocks are written once (about 43 KB),
/// made once by [`new`](LinearizationWorkspaceOf::new). `A` and `B` are NaN before the first
/// linearization.
pub type LinearizationWorkspace =
    LinearizationWorkspaceOf<crate::DerivativesWorkspace, 19, 38, ACTUATOR_COUNT>;

/// The kept workspace of `linearize_with` for a model of `N` speeds (the state `X = 2N`, `I`
/// inputs) whose generated module's derivatives workspace is `W`: Krang's
/// [`LinearizationWorkspace`] and the fixed-wheel tree's `fixed_wheels::LinearizationWorkspace`
/// (feature `fixed-wheels`: 17 speeds, 17 inputs).
#[derive(Clone, Debug)]
pub struct LinearizationWorkspaceOf<W, const N: usize, const X: usize, const I: usize> {
    fd: ForwardDynamicsDerivativesWorkspaceOf<W, N>,
    a: SMatrix<f64, X, X>,
    b: SMatrix<f64, X, I>,
    /// Whether the upper halves of `A` (`[0, I]`) and `B` (`0`) hold their constants (not
    /// after a linearization with non-physical parameters, which NaN-fills both).
    constant_blocks: bool,
}

impl<W: Default, const N: usize, const X: usize, const I: usize>
    LinearizationWorkspaceOf<W, N, X, I>
{
    /// A workspace whose `A` and `B` are NaN until the first linearization.
    pub fn new() -> Self {
        const { assert!(X == 2 * N, "the state is [q; u]") };
        Self {
            fd: ForwardDynamicsDerivativesWorkspaceOf::new(),
            a: SMatrix::from_element(f64::NAN),
            b: SMatrix::from_element(f64::NAN),
            constant_blocks: false,
        }
    }
}

impl<W, const N: usize, const X: usize, const I: usize> LinearizationWorkspaceOf<W, N, X, I> {
    /// `A` and `B` from the forward-dynamics derivatives just written into `self.fd` (`ok`:
    /// `M(q)` was positive definite, else both NaN, as by value): the constant upper halves
    /// once, `[∂u̇/∂q, ∂u̇/∂u]` into `A`'s lower half, and `B`'s lower half (`∂u̇/∂input`, its
    /// `N` rows of each column) by `input` from `M⁻¹` (the upper rows it must leave).
    fn fill(
        &mut self,
        ok: bool,
        input: impl FnOnce(&SMatrix<f64, N, N>, &mut SMatrix<f64, X, I>),
    ) -> (&SMatrix<f64, X, X>, &SMatrix<f64, X, I>) {
        if !ok {
            self.a.as_mut_slice().fill(f64::NAN);
            self.b.as_mut_slice().fill(f64::NAN);
            self.constant_blocks = false;
            return (&self.a, &self.b);
        }
        if !self.constant_blocks {
            write_a_upper::<N, X>(&mut self.a);
            for column in self.b.as_mut_slice().chunks_exact_mut(X) {
                column[..N].fill(0.0);
            }
            self.constant_blocks = true;
        }
        write_a_lower(&mut self.a, &self.fd.result);
        input(&self.fd.result.minv, &mut self.b);
        (&self.a, &self.b)
    }
}

impl<W: Default, const N: usize, const X: usize, const I: usize> Default
    for LinearizationWorkspaceOf<W, N, X, I>
{
    fn default() -> Self {
        Self::new()
    }
}

fn nan_derivatives<const N: usize>() -> ForwardDynamicsDerivatives<N> {
    ForwardDynamicsDerivatives {
        ud: SVector::from_element(f64::NAN),
        dud_dq: SMatrix::from_element(f64::NAN),
        dud_du: SMatrix::from_element(f64::NAN),
        minv: SMatrix::from_element(f64::NAN),
    }
}

#[cfg(feature = "fixed-wheels")]
impl crate::fixed_wheels::KrangFixedWheels {
    /// `(∂τ/∂q, ∂τ/∂u)` of the fixed-wheel model's inverse dynamics (17×17 each).
    pub fn inverse_dynamics_partials(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        ud: &SVector<f64, 17>,
    ) -> (SMatrix<f64, 17, 17>, SMatrix<f64, 17, 17>) {
        InverseDynamicsDerivatives::inverse_dynamics_partials(self, q, u, ud)
    }

    /// Forward dynamics and its derivatives at `(q, u, τ)`, as
    /// [`Krang::try_forward_dynamics_derivatives`]: the block Cholesky factor of `M(q)`
    /// ([`mass_matrix_cholesky`](Self::mass_matrix_cholesky)), one derivative pass, one solve
    /// over the 51 right-hand sides `[−∂τ/∂q | −∂τ/∂u | I]`. Allocation-free. (The runtime
    /// trait's [`forward_dynamics_derivatives`](kanegen_runtime::InverseDynamicsDerivatives::forward_dynamics_derivatives)
    /// gives the same values through nalgebra's dense Cholesky.)
    ///
    /// # Errors
    /// [`NotPositiveDefinite`] for non-physical parameters.
    pub fn try_forward_dynamics_derivatives(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        tau: &SVector<f64, 17>,
    ) -> Result<ForwardDynamicsDerivatives<17>, NotPositiveDefinite> {
        let chol = self.mass_matrix_cholesky(q)?;
        Ok(forward_dynamics_derivatives_by_value::<_, 3, 17, 34, 51>(
            self,
            &chol,
            (q, u, tau),
            |ud| self.inverse_dynamics_derivatives(q, u, ud),
        ))
    }

    /// The linearization `(A, B)` of the fixed-wheel model's `ẋ = f(x, τ)` for `x = [q; u]`
    /// (34) and the 17 joint torques `τ` (every speed is actuated): `A = [[0, I], [∂u̇/∂q,
    /// ∂u̇/∂u]]`, `B = [[0], [M⁻¹]]`. NaN-filled for non-physical parameters.
    pub fn linearize(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        tau: &SVector<f64, 17>,
    ) -> (SMatrix<f64, 34, 34>, SMatrix<f64, 34, 17>) {
        match self.try_forward_dynamics_derivatives(q, u, tau) {
            Ok(fd) => state_space(&fd, &fd.minv),
            // All NaN, as Krang's (not only the blocks that depend on the parameters).
            Err(_) => (
                SMatrix::from_element(f64::NAN),
                SMatrix::from_element(f64::NAN),
            ),
        }
    }

    /// [`try_forward_dynamics_derivatives`](Self::try_forward_dynamics_derivatives) written into
    /// a workspace the caller keeps across calls, whose result it returns, as
    /// [`Krang::forward_dynamics_derivatives_with`]: the same bits, without zeroing and copying
    /// the matrices of every call; NaN-filled for non-physical parameters. Allocation-free.
    ///
    /// ```
    /// use krang_dynamics::fixed_wheels::{ForwardDynamicsDerivativesWorkspace, KrangFixedWheels};
    /// use nalgebra::SVector;
    ///
    /// let k = KrangFixedWheels::default();
    /// let mut ws = ForwardDynamicsDerivativesWorkspace::new();
    /// let (q, u, tau) = (SVector::zeros(), SVector::zeros(), SVector::zeros());
    /// let fd = k.forward_dynamics_derivatives_with(&q, &u, &tau, &mut ws);
    /// assert!(fd.minv[(5, 5)] > 0.0);
    /// ```
    pub fn forward_dynamics_derivatives_with<'w>(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        tau: &SVector<f64, 17>,
        ws: &'w mut crate::fixed_wheels::ForwardDynamicsDerivativesWorkspace,
    ) -> &'w ForwardDynamicsDerivatives<17> {
        self.forward_dynamics_derivatives_kept(q, u, tau, ws);
        &ws.result
    }

    /// [`forward_dynamics_derivatives_with`](Self::forward_dynamics_derivatives_with) into
    /// `ws`; `false` (and NaN) where `M(q)` is not positive definite.
    fn forward_dynamics_derivatives_kept(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        tau: &SVector<f64, 17>,
        ws: &mut crate::fixed_wheels::ForwardDynamicsDerivativesWorkspace,
    ) -> bool {
        forward_dynamics_derivatives_kept::<_, _, 3, 17, 34>(
            self,
            (q, u, tau),
            ws,
            |m| self.mass_matrix_into(q, m),
            |ud, w| self.inverse_dynamics_derivatives_with(q, u, ud, w),
        )
    }

    /// [`linearize`](Self::linearize) written into a workspace the caller keeps across calls,
    /// whose `(A, B)` it returns, as [`Krang::linearize_with`]: the same bits, the constant
    /// blocks written once; NaN-filled for non-physical parameters. Allocation-free.
    ///
    /// ```
    /// use krang_dynamics::fixed_wheels::{KrangFixedWheels, LinearizationWorkspace};
    /// use nalgebra::SVector;
    ///
    /// let k = KrangFixedWheels::default();
    /// let mut ws = LinearizationWorkspace::new();
    /// let (q, u) = (SVector::zeros(), SVector::zeros());
    /// let (a_mat, b_mat) = k.linearize_with(&q, &u, &SVector::zeros(), &mut ws);
    /// assert_eq!(a_mat[(0, 17)], 1.0);
    /// assert!(b_mat[(17, 0)] > 0.0);
    /// ```
    pub fn linearize_with<'w>(
        &self,
        q: &SVector<f64, 17>,
        u: &SVector<f64, 17>,
        tau: &SVector<f64, 17>,
        ws: &'w mut crate::fixed_wheels::LinearizationWorkspace,
    ) -> (&'w SMatrix<f64, 34, 34>, &'w SMatrix<f64, 34, 17>) {
        let ok = self.forward_dynamics_derivatives_kept(q, u, tau, &mut ws.fd);
        // B's lower half: M⁻¹ (every speed is actuated).
        ws.fill(ok, |minv, b| {
            let lower = b.as_mut_slice().chunks_exact_mut(34).map(|c| &mut c[17..]);
            for (lower, column) in lower.zip(minv.as_slice().chunks_exact(17)) {
                lower.copy_from_slice(column);
            }
        })
    }
}
