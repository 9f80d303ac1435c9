//! Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))`, allocation-free.
//!
//! Krang's mass matrix has a fixed sparsity pattern: the five trunk speeds
//! `[ẋ, ψ̇, q̇_imu, q̇_w, q̇_torso]` (indices `0..5`) couple to everything, but the left arm
//! (`5..12`) and the right arm (`12..19`) do not couple to each other: `M[left, right] = 0`
//! exactly (no body's motion depends on both arms; the generated code never writes those
//! 98 entries). [`MassMatrixCholesky`] orders the factorisation arms first, so that
//!
//! ```text
//!          ⎡ A_l   0     B_lᵀ  ⎤               ⎡ L_l   0     0     ⎤
//! P M Pᵀ = ⎢ 0     A_r   B_rᵀ  ⎥ = L Lᵀ,   L = ⎢ 0     L_r   0     ⎥,
//!          ⎣ B_l   B_r   T     ⎦               ⎣ W_lᵀ  W_rᵀ  L_s   ⎦
//! ```
//!
//! with `A = L Lᵀ` per arm (7×7), `W = L⁻¹ Bᵀ` (7×5) and `L_s` the Cholesky factor of the
//! 5×5 Schur complement `S = T − W_lᵀ W_l − W_rᵀ W_r`. There is no fill-in: the zero block
//! stays zero, and the work is two 7×7 and one 5×5 factorisation plus two 7×7 triangular
//! solves with five right-hand sides: about a third of the flops of a dense 19×19 Cholesky
//! and solve.
//! Everything is fixed-size nalgebra on the stack; nothing allocates and nothing panics.
//!
//! The fixed-wheel model (17 speeds, feature `fixed-wheels`) has the same structure with a
//! trunk of three speeds: [`BlockCholesky`] is generic over the trunk size
//! ([`MassMatrixCholesky`] = `BlockCholesky<5, 19>`, the fixed-wheel tree's
//! `BlockCholesky<3, 17>`), and both models get the same three methods from one definition:
//! `mass_matrix_cholesky`, `try_forward_dynamics` (typed errors) and `forward_dynamics`
//! (NaN-filled on failure). [`solve_spd`] is the dense fallback for any other size.
//!
//! ```
//! use krang_dynamics::{Krang, index};
//! use nalgebra::SVector;
//!
//! let k = Krang::default();
//! let mut q = SVector::<f64, 19>::zeros();
//! q[index::Q_IMU] = 0.3;
//! let u = SVector::<f64, 19>::from_element(0.1);
//! let tau = SVector::<f64, 19>::zeros();
//! let ud = k.forward_dynamics(&q, &u, &tau);
//! let back = k.inverse_dynamics(&q, &u, &ud);
//! assert!((back - tau).norm() < 1e-9);
//! ```

use core::fmt;

use nalgebra::{SMatrix, SVector};

pub use crate::cholesky::{
    Block, BlockCholesky, MassMatrixCholesky, NotPositiveDefinite, solve_spd,
};

use crate::Krang;
#[cfg(feature = "fixed-wheels")]
use crate::fixed_wheels::KrangFixedWheels;

/// Indices of the trunk speeds `[ẋ, ψ̇, q̇_imu, q̇_w, q̇_torso]` in `u`.
pub const TRUNK: core::ops::Range<usize> = 0..5;
/// Indices of the left-arm speeds `q̇_1l … q̇_7l` in `u`.
pub const LEFT_ARM: core::ops::Range<usize> = 5..12;
/// Indices of the right-arm speeds `q̇_1r … q̇_7r` in `u`.
pub const RIGHT_ARM: core::ops::Range<usize> = 12..19;

/// Why [`Krang::try_forward_dynamics`] has no result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ForwardDynamicsError {
    /// The mass matrix is not positive definite (non-physical parameters, or non-finite `q`).
    NotPositiveDefinite(NotPositiveDefinite),
    /// An input or the result is not finite: an infinite or NaN entry of `q`, `u` or `τ`
    /// (named), or a result that overflowed (`"u̇"`: e.g. infinite parameters). The result is
    /// never returned with an infinity or a NaN in it.
    NotFinite(&'static str),
}

impl fmt::Display for ForwardDynamicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotPositiveDefinite(e) => e.fmt(f),
            Self::NotFinite(what) => write!(
                f,
                "forward dynamics: `{what}` is not finite (an infinity or NaN); check the state, the forces and Params::validate()"
            ),
        }
    }
}

impl core::error::Error for ForwardDynamicsError {}

impl From<NotPositiveDefinite> for ForwardDynamicsError {
    fn from(e: NotPositiveDefinite) -> Self {
        Self::NotPositiveDefinite(e)
    }
}

/// `Err(NotFinite(what))` unless every entry of `v` is finite.
fn finite<const N: usize>(
    v: &SVector<f64, N>,
    what: &'static str,
) -> Result<(), ForwardDynamicsError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ForwardDynamicsError::NotFinite(what))
    }
}

/// Forward dynamics through the block Cholesky factor, for Krang and the fixed-wheel tree: the
/// inputs checked, `c + g` from `bias(q, u)` (inverse dynamics at `u̇ = 0`), `M` written by
/// `mass_matrix_into`, then [`BlockCholesky::solve_once`], and the result checked.
fn block_forward_dynamics<const T: usize, const N: usize>(
    (q, u, tau): (&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>),
    bias: impl FnOnce(&SVector<f64, N>, &SVector<f64, N>) -> SVector<f64, N>,
    mass_matrix_into: impl FnOnce(&SVector<f64, N>, &mut SMatrix<f64, N, N>),
) -> Result<SVector<f64, N>, ForwardDynamicsError> {
    finite(q, "q")?;
    finite(u, "u")?;
    finite(tau, "tau")?;
    let rhs = tau - bias(q, u);
    // Into a local matrix rather than by value: a 19 × 19 copy less (about 5 % of
    // `forward_dynamics`).
    let mut m = SMatrix::zeros();
    mass_matrix_into(q, &mut m);
    let ud = BlockCholesky::<T, N>::solve_once(&m, &rhs)?;
    finite(&ud, "u̇")?;
    Ok(ud)
}

/// The forward-dynamics methods of a generated model whose mass matrix has the block structure
/// of the [module docs](self) (`$trunk` trunk speeds, then two 7-speed arms; `$n` speeds in
/// all), written once for both models: inherent methods, so that `k.forward_dynamics(…)` needs
/// no trait in scope and takes precedence over the dense `RobotDynamics::forward_dynamics`.
macro_rules! block_forward_dynamics {
    ($model:ident, $trunk:literal, $n:literal) => {
        impl $model {
            #[doc = concat!(
                "The block Cholesky factorisation of `M(q)`: `BlockCholesky<", $trunk, ", ", $n,
                ">` (a trunk of ", $trunk, " speeds, two arms that do not couple; ",
                "[`MassMatrixCholesky`] for Krang).",
            )]
            ///
            /// # Errors
            /// [`NotPositiveDefinite`] for non-physical parameters.
            #[inline]
            pub fn mass_matrix_cholesky(
                &self,
                q: &SVector<f64, $n>,
            ) -> Result<BlockCholesky<$trunk, $n>, NotPositiveDefinite> {
                // Into a local matrix rather than by value: a copy less (as in
                // `block_forward_dynamics`).
                let mut m = SMatrix::zeros();
                self.mass_matrix_into(q, &mut m);
                BlockCholesky::new(&m)
            }

            /// Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))`.
            ///
            /// `tau` are the generalized active forces other than gravity (for Krang,
            /// [`Krang::generalized_forces`] maps wheel and joint torques to them). `c + g`
            /// comes from one generated inverse-dynamics pass with `u̇ = 0`; `M` is factorised
            /// by the block Cholesky ([`BlockCholesky::solve_once`]). Allocation-free.
            ///
            /// # Errors
            /// [`ForwardDynamicsError::NotPositiveDefinite`] for non-physical parameters;
            /// [`ForwardDynamicsError::NotFinite`] for an infinite or NaN entry of `q`, `u` or
            /// `tau`, or a result that is not finite (infinite parameters).
            pub fn try_forward_dynamics(
                &self,
                q: &SVector<f64, $n>,
                u: &SVector<f64, $n>,
                tau: &SVector<f64, $n>,
            ) -> Result<SVector<f64, $n>, ForwardDynamicsError> {
                block_forward_dynamics::<$trunk, $n>(
                    (q, u, tau),
                    |q, u| self.inverse_dynamics(q, u, &SVector::zeros()),
                    |q, m| self.mass_matrix_into(q, m),
                )
            }

            /// Forward dynamics `u̇ = M(q)⁻¹ (τ − c(q, u) − g(q))`, as
            /// [`try_forward_dynamics`](Self::try_forward_dynamics) but infallible: if `M(q)` is
            /// not positive definite (non-physical parameters) or an input or the result is not
            /// finite, every entry of the result is NaN.
            ///
            /// The model also implements the runtime trait
            /// [`RobotDynamics`](crate::RobotDynamics), whose provided `forward_dynamics`
            /// returns an `Option` through a dense Cholesky (what generic code over any robot
            /// calls: `RobotDynamics::forward_dynamics(&k, &q, &u, &tau)`). In method syntax,
            /// `k.forward_dynamics(…)` is this inherent method: Rust picks an inherent method
            /// before a trait's.
            #[inline]
            pub fn forward_dynamics(
                &self,
                q: &SVector<f64, $n>,
                u: &SVector<f64, $n>,
                tau: &SVector<f64, $n>,
            ) -> SVector<f64, $n> {
                self.try_forward_dynamics(q, u, tau)
                    .unwrap_or_else(|_| SVector::from_element(f64::NAN))
            }
        }
    };
}

block_forward_dynamics!(Krang, 5, 19);
#[cfg(feature = "fixed-wheels")]
block_forward_dynamics!(KrangFixedWheels, 3, 17);

impl Krang {
    /// The base pitch `q_imu` that puts the centre of mass above the axle, for the waist,
    /// torso and arm angles of `q` (the balancing equilibrium; `q[Q_IMU]` is ignored).
    ///
    /// All bodies rotate rigidly with `q_imu` about the axle, so the potential energy is
    /// `V = A cos q_imu + B sin q_imu + C` and `g_imu = ∂V/∂q_imu = −A sin q_imu + B cos q_imu`.
    /// Two gravity evaluations give `B = g_imu(0)` and `A = −g_imu(π/2)`; the maximum of `V`
    /// (centre of mass above, not below, the axle) is at `atan2(B, A)`. Exact, no iteration.
    pub fn upright_pitch(&self, q: &SVector<f64, 19>) -> f64 {
        let mut q = *q;
        q[crate::index::Q_IMU] = 0.0;
        let b = self.gravity(&q)[crate::index::Q_IMU];
        q[crate::index::Q_IMU] = core::f64::consts::FRAC_PI_2;
        let a = -self.gravity(&q)[crate::index::Q_IMU];
        nalgebra::RealField::atan2(b, a)
    }
}
