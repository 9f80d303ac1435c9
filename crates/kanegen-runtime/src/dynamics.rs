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
