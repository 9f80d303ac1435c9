//! [`Multibody`]: the interface of every generated robot, fixed, wheeled or floating, whose
//! configuration `q` may have more entries than the speeds `u` (a floating base's quaternion).

use core::fmt::Debug;

use nalgebra::{RealField, SMatrix, SVector};

use crate::RobotDynamics;
use crate::dynamics::DenseFactor;
use crate::tree_factor::TreeFactor;

/// The dynamics `τ = M(q) u̇ + c(q, u) + g(q)` of a robot with `N` speeds `u` and a
/// configuration `q` of type [`Configuration`](Self::Configuration), with the operations of its
/// configuration space: a controller, estimator or simulator written against this trait runs on
/// every generated robot.
///
/// * Fixed and wheeled bases: `Configuration = SVector<Scalar, N>` (the coordinates are a vector
///   space: [`integrate`](Self::integrate) is `q + u dt`). Every [`RobotDynamics`] robot has this
///   trait through a blanket implementation.
/// * A floating base (`Base::Floating`): `Configuration = SVector<Scalar, NQ>` with
///   `NQ = N + 1` (position and unit quaternion of the base first); the configuration-space
///   operations are [`crate::free_flyer`]'s. Generated floating-base robots implement this trait
///   directly (they cannot implement [`RobotDynamics`], whose `q` has `N` entries).
///
/// Vectors of speeds (`u`, `u̇`, `τ`) are ordered as [`SPEED_NAMES`](Self::SPEED_NAMES), `q` as
/// [`COORDINATE_NAMES`](Self::COORDINATE_NAMES). Bring either this trait or [`RobotDynamics`]
/// into scope in a generic function, not both: their methods have the same names.
pub trait Multibody<const N: usize> {
    /// The scalar (`f64` or `f32`).
    type Scalar: RealField + Copy;
    /// The configuration `q`: `SVector<Scalar, N>`, or `SVector<Scalar, N + 1>` for a floating
    /// base.
    type Configuration: Clone + Copy + Debug + PartialEq;

    /// Generalized speed names, in the order of `u`.
    const SPEED_NAMES: [&'static str; N];

    /// Coordinate names, in the order of `q` (`N` of them, `N + 1` for a floating base).
    const COORDINATE_NAMES: &'static [&'static str];

    /// The speeds' parent array `λ` when `M` has the tree's pattern (generated modules:
    /// `Some(SPEED_PARENTS)`, see [`RobotDynamics::SPEED_PARENTS`]); `None` (the default): `M`
    /// is taken as dense.
    const SPEED_PARENTS: Option<[Option<usize>; N]> = None;

    /// The neutral configuration: zero coordinates (a floating base at the origin with the
    /// identity quaternion).
    fn neutral(&self) -> Self::Configuration;

    /// `q ⊕ u dt`: `q + u dt` for a vector space; a floating base moves by the SE(3)
    /// exponential of its twist (`pinocchio::integrate`).
    fn integrate(
        &self,
        q: &Self::Configuration,
        u: &SVector<Self::Scalar, N>,
        dt: Self::Scalar,
    ) -> Self::Configuration;

    /// The speeds `δ` with `integrate(q0, δ, 1) = q1` (`q1 − q0` for a vector space;
    /// `pinocchio::difference` for a floating base).
    fn difference(
        &self,
        q0: &Self::Configuration,
        q1: &Self::Configuration,
    ) -> SVector<Self::Scalar, N>;

    /// `q` with a floating base's quaternion scaled to unit norm (`q` itself otherwise).
    fn normalize(&self, q: &Self::Configuration) -> Self::Configuration;

    /// The mass matrix `M(q)` (symmetric positive definite).
    fn mass_matrix(&self, q: &Self::Configuration) -> SMatrix<Self::Scalar, N, N>;

    /// The Coriolis and centrifugal vector `c(q, u)`.
    fn coriolis(
        &self,
        q: &Self::Configuration,
        u: &SVector<Self::Scalar, N>,
    ) -> SVector<Self::Scalar, N>;

    /// The gravity vector `g(q)`.
    fn gravity(&self, q: &Self::Configuration) -> SVector<Self::Scalar, N>;

    /// Inverse dynamics `τ = M(q) u̇ + c(q, u) + g(q)`.
    fn inverse_dynamics(
        &self,
        q: &Self::Configuration,
        u: &SVector<Self::Scalar, N>,
        ud: &SVector<Self::Scalar, N>,
    ) -> SVector<Self::Scalar, N>;

    /// Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))`, `M` factored along the tree with
    /// [`SPEED_PARENTS`](Self::SPEED_PARENTS), else by a dense Cholesky factorisation (as
    /// [`RobotDynamics::forward_dynamics`]); `None` when `M(q)` is not positive definite.
    /// For a floating base the first six entries of `tau` are the generalized forces on the
    /// base (zero for a robot in free flight).
    fn forward_dynamics(
        &self,
        q: &Self::Configuration,
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
    fn mass_matrix_factor(&self, q: &Self::Configuration) -> Option<TreeFactor<Self::Scalar, N>> {
        let parents = Self::SPEED_PARENTS.unwrap_or(crate::tree_factor::chain_parents());
        TreeFactor::new(&self.mass_matrix(q), &parents)
    }
}

impl<R: RobotDynamics<N>, const N: usize> Multibody<N> for R {
    type Scalar = R::Scalar;
    type Configuration = SVector<R::Scalar, N>;
    const SPEED_NAMES: [&'static str; N] = R::SPEED_NAMES;
    const COORDINATE_NAMES: &'static [&'static str] = &R::COORDINATE_NAMES;
    const SPEED_PARENTS: Option<[Option<usize>; N]> = R::SPEED_PARENTS;

    fn neutral(&self) -> Self::Configuration {
        SVector::zeros()
    }

    fn integrate(
        &self,
        q: &Self::Configuration,
        u: &SVector<R::Scalar, N>,
        dt: R::Scalar,
    ) -> Self::Configuration {
        q + u * dt
    }

    fn difference(
        &self,
        q0: &Self::Configuration,
        q1: &Self::Configuration,
    ) -> SVector<R::Scalar, N> {
        q1 - q0
    }

    fn normalize(&self, q: &Self::Configuration) -> Self::Configuration {
        *q
    }

    fn mass_matrix(&self, q: &Self::Configuration) -> SMatrix<R::Scalar, N, N> {
        RobotDynamics::mass_matrix(self, q)
    }

    fn coriolis(
        &self,
        q: &Self::Configuration,
        u: &SVector<R::Scalar, N>,
    ) -> SVector<R::Scalar, N> {
        RobotDynamics::coriolis(self, q, u)
    }

    fn gravity(&self, q: &Self::Configuration) -> SVector<R::Scalar, N> {
        RobotDynamics::gravity(self, q)
    }

    fn inverse_dynamics(
        &self,
        q: &Self::Configuration,
        u: &SVector<R::Scalar, N>,
        ud: &SVector<R::Scalar, N>,
    ) -> SVector<R::Scalar, N> {
        RobotDynamics::inverse_dynamics(self, q, u, ud)
    }

    fn forward_dynamics(
        &self,
        q: &Self::Configuration,
        u: &SVector<R::Scalar, N>,
        tau: &SVector<R::Scalar, N>,
    ) -> Option<SVector<R::Scalar, N>> {
        RobotDynamics::forward_dynamics(self, q, u, tau)
    }

    fn mass_matrix_factor(&self, q: &Self::Configuration) -> Option<TreeFactor<R::Scalar, N>> {
        RobotDynamics::mass_matrix_factor(self, q)
    }
}
