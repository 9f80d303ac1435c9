//! The interface every generated robot implements.

use nalgebra::{RealField, SMatrix, SVector};

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
    /// pass at `u̇ = 0`, and `M` is factored by nalgebra's dense Cholesky, on the stack (no
    /// heap, `no_std`).
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
        let factor = self.mass_matrix(q).cholesky()?;
        Some(factor.solve(&(tau - bias)))
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
    /// derivative pass and the triangular solves of `−∂τ/∂q`, `−∂τ/∂u` and `I`, each over all
    /// its columns at once (compiled for the baseline and, where the CPU has it, x86-64-v3);
    /// no heap.
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
        let factor = self.mass_matrix(q).cholesky()?;
        let ud = factor.solve(&(tau - self.inverse_dynamics(q, u, &SVector::zeros())));
        let (dtau_dq, dtau_du) = self.inverse_dynamics_partials(q, u, &ud);
        let l = factor.l_dirty();
        let inv_diag = core::array::from_fn(|i| nalgebra::one::<Self::Scalar>() / l[(i, i)]);
        let solve = |b: SMatrix<Self::Scalar, N, N>| {
            let mut bt = b.transpose();
            crate::isa::dispatch(
                #[inline(always)]
                || cholesky_solve_transposed(l, &inv_diag, &mut bt),
            );
            bt.transpose()
        };
        Some(ForwardDynamicsDerivatives {
            ud,
            dud_dq: solve(-dtau_dq),
            dud_du: solve(-dtau_du),
            minv: solve(SMatrix::identity()),
        })
    }
}

/// `X ← A⁻¹ X` for `A = L Lᵀ`, given the lower triangle of `l` (its strict upper triangle is
/// ignored: nalgebra's `Cholesky::l_dirty`), the reciprocals of its diagonal `inv_diag` (computed
/// once for the three solves of `forward_dynamics_derivatives`) and `xt = Xᵀ`, the right-hand
/// sides as rows.
///
/// On the transpose, row `i` of `X` (speed `i` of every right-hand side) is one contiguous
/// column, so every step of the two triangular substitutions is one `x_i −= l_ik x_k` over all
/// right-hand sides at once, which the compiler vectorizes. nalgebra's `Cholesky::solve` and
/// `inverse` take the right-hand sides one at a time through strided loops: for the fixed-wheel
/// tree's `forward_dynamics_derivatives` (17 speeds, three 17×17 solves) 17.1 µs against 4.3 µs
/// for its block factor (criterion `fd_derivatives/fixed_wheels_trait`, tenth session).
#[inline(always)]
fn cholesky_solve_transposed<T: RealField + Copy, const N: usize, const C: usize>(
    l: &SMatrix<T, N, N>,
    inv_diag: &[T; N],
    xt: &mut SMatrix<T, C, N>,
) {
    // Row k of X is `s[row(k)]`; `sub` is `row dst −= a · row src` (`dst ≠ src`).
    let s = xt.as_mut_slice();
    let row = |k: usize| k * C..(k + 1) * C;
    let sub = |s: &mut [T], dst: usize, src: usize, a: T| {
        let (d, x) = if dst < src {
            let (lo, hi) = s.split_at_mut(src * C);
            (&mut lo[row(dst)], &hi[..C])
        } else {
            let (lo, hi) = s.split_at_mut(dst * C);
            (&mut hi[..C], &lo[row(src)])
        };
        for (d, x) in d.iter_mut().zip(x) {
            *d -= a * *x;
        }
    };
    let scale = |s: &mut [T], k: usize, a: T| {
        for x in &mut s[row(k)] {
            *x *= a;
        }
    };
    // L y = b.
    for i in 0..N {
        for k in 0..i {
            sub(s, i, k, l[(i, k)]);
        }
        scale(s, i, inv_diag[i]);
    }
    // Lᵀ x = y.
    for i in (0..N).rev() {
        scale(s, i, inv_diag[i]);
        for k in 0..i {
            sub(s, k, i, l[(i, k)]);
        }
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
    use super::cholesky_solve_transposed;
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

    fn solves_like_nalgebra<T: RealField + Copy, const N: usize, const C: usize>(bound: f64) {
        let (a, b) = spd_and_rhs::<T, N, C>();
        let chol = a.cholesky().unwrap();
        let mut xt = b.transpose();
        let l = chol.l_dirty();
        cholesky_solve_transposed(l, &core::array::from_fn(|i| T::one() / l[(i, i)]), &mut xt);
        let expected = chol.solve(&b);
        let err = (xt.transpose() - expected).norm() / expected.norm();
        assert!(err <= T::from_f64(bound).unwrap(), "{N}×{C}: {err}");
        let residual = (a * xt.transpose() - b).norm() / b.norm();
        assert!(
            residual <= T::from_f64(bound).unwrap(),
            "{N}×{C}: {residual}"
        );
    }

    #[test]
    fn many_column_cholesky_solve_matches_nalgebras_solve() {
        solves_like_nalgebra::<f64, 1, 1>(1e-15);
        solves_like_nalgebra::<f64, 5, 3>(1e-14);
        solves_like_nalgebra::<f64, 17, 17>(1e-14);
        solves_like_nalgebra::<f64, 19, 57>(1e-14);
        solves_like_nalgebra::<f32, 7, 7>(1e-5);
    }
}
