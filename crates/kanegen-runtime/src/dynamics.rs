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
