//! The runtime shared by all code that [kanegen](https://github.com/kanegen/kanegen) generates:
//! what every generated module would otherwise carry its own copy of, as generated protobuf code
//! uses `prost`.
//!
//! - [`trig`]: the batched `sin`/`cos` of the joint angles, [`trig::sin_cos_n`] (`f64`) and
//!   [`trig::sin_cos_n_f32`] (`f32`), that each generated function calls once; a `core`-only,
//!   branch-free fdlibm kernel that the compiler vectorizes.
//! - [`SetParameterError`]: the allocation-free error of a generated `Params::set`, either
//!   [`UnknownParameter`] (a name the model does not have) or [`InvalidParameter`] (a value
//!   that is not finite or not physical); [`InvalidParameter`] is also the error of
//!   `Params::validate`, with the checks it runs ([`validate`]).
//! - [`params_serde!`]: the macro a generated module invokes after its `Params`, which
//!   implements `serde`'s traits with the `serde` feature; `params_from_model_toml` (feature
//!   `toml`) reads the parameter values of a model file at run time.
//! - [`RobotDynamics`] (and [`CoriolisMatrix`], for modules generated with the Coriolis
//!   matrix): the trait every generated robot type implements, so that a controller can be
//!   written once for any generated robot; its provided `forward_dynamics` gives every
//!   generated robot forward dynamics (dense Cholesky, [`RobotDynamics::forward_dynamics`]).
//!   [`InverseDynamicsDerivatives`], for modules generated with `inverse_dynamics_derivatives`:
//!   the partials of inverse dynamics and, provided, those of forward dynamics
//!   ([`ForwardDynamicsDerivatives`]), for LQR and MPC on any generated robot.
//! - [`Multibody`]: the same dynamics with the configuration as an associated type and the
//!   configuration space's `integrate`, `difference`, `neutral` and `normalize`, implemented by
//!   every generated robot, floating bases included (whose `q` has one entry more than `u`);
//!   [`free_flyer`]: a floating base's configuration space (Pinocchio's free-flyer layout).
//!
//! - [`contact`]: contact-constrained forward dynamics and contact impulses (point and frame
//!   contacts, the Schur complement of the mass matrix's Cholesky factor), allocation-free.
//! - [`tree_factor`]: the mass matrix factored along the kinematic tree without fill-in
//!   (`M = Lᵀ D L` over the speeds' parent array, a generated module's `SPEED_PARENTS`), what the
//!   traits' `forward_dynamics` and `mass_matrix_factor` of generated robots use.
//!
//! - [`isa`]: run-time instruction-set dispatch (baseline or x86-64-v3, AVX2 + FMA; the
//!   batched functions also x86-64-v4, AVX-512), the
//!   crate's `unsafe` calls (see below), and [`isa::Arith`], the multiply-add the copies
//!   differ in; [`lanes`]: the lane type of the batched functions; [`pair`]: two lanes (arms
//!   in lanes); [`quad`]: four fused lanes of the x86-64-v3 copy (solves with many columns).
//! - [`regressor`]: the loop of a loop-form inverse-dynamics regressor (per link and four rows
//!   at a time, over a generated plan; generic over [`isa::Arith`]).
//! - [`gpu`]: the layout of a generated module's GPU kernels (`gpu::MODULE`, generated with
//!   `Builder::gpu`), which the `kanegen-gpu` crate runs.
//! - [`derivatives_loop`]: the loop of the looped `inverse_dynamics_derivatives` (the
//!   (column, ancestor) steps of the analytic recursion over generated tables); its AVX2 copy
//!   is called only after the same feature check.
//!
//! `#![no_std]`; `unsafe` only to call code compiled for x86-64-v3 or v4 after the CPU was
//! checked ([`isa::dispatch`], [`isa::dispatch_fused_with`], [`isa::dispatch_fused_wide_with`],
//! [`derivatives_loop::run`]) and for the SSE2/FMA intrinsics of [`pair::F64x2`] and the
//! AVX/FMA intrinsics of [`quad::F64x4`] (made only where FMA is present); no dependency
//! but [`nalgebra`] (re-exported: its vector and matrix types are the trait's argument types)
//! and, behind features, `serde` and `toml`.
//!
//! # How generated code uses it
//!
//! A generated module (for a robot called `TwoLink`, say) imports the routines instead of
//! defining them, and implements the traits on its robot type by forwarding to its inherent
//! methods:
//!
//! ```text
//! use kanegen_runtime::trig::sin_cos_n;            // f32 modules: sin_cos_n_f32 as sin_cos_n
//! pub use kanegen_runtime::{SetParameterError, UnknownParameter}; // errors of Params::set
//!
//! impl kanegen_runtime::RobotDynamics<2> for TwoLink {
//!     type Scalar = f64;
//!     const SPEED_NAMES: [&'static str; 2] = SPEED_NAMES;
//!     const COORDINATE_NAMES: [&'static str; 2] = COORDINATE_NAMES;
//!     fn mass_matrix(&self, q: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> { self.mass_matrix(q) }
//!     // … coriolis, gravity, inverse_dynamics; CoriolisMatrix if generated
//! }
//! ```
//!
//! The crate that includes the generated code depends on `kanegen-runtime` (and on the same
//! `nalgebra`). A generic controller then works for every generated robot. Here it is run on a
//! hand-written pendulum that implements the trait as generated code does:
//!
//! ```
//! use kanegen_runtime::RobotDynamics;
//! use nalgebra::{SMatrix, SVector};
//!
//! /// A point mass `m` on a massless rod of length `l`; `q` is the angle from straight down.
//! struct Pendulum {
//!     m: f64,
//!     l: f64,
//!     g: f64,
//! }
//!
//! impl RobotDynamics<1> for Pendulum {
//!     type Scalar = f64;
//!     const SPEED_NAMES: [&'static str; 1] = ["qd"];
//!     const COORDINATE_NAMES: [&'static str; 1] = ["q"];
//!
//!     fn mass_matrix(&self, _q: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
//!         SMatrix::from_element(self.m * self.l * self.l)
//!     }
//!     fn coriolis(&self, _q: &SVector<f64, 1>, _u: &SVector<f64, 1>) -> SVector<f64, 1> {
//!         SVector::zeros()
//!     }
//!     fn gravity(&self, q: &SVector<f64, 1>) -> SVector<f64, 1> {
//!         SVector::from_element(self.m * self.g * self.l * q[0].sin())
//!     }
//!     fn inverse_dynamics(
//!         &self,
//!         q: &SVector<f64, 1>,
//!         u: &SVector<f64, 1>,
//!         ud: &SVector<f64, 1>,
//!     ) -> SVector<f64, 1> {
//!         self.mass_matrix(q) * ud + self.coriolis(q, u) + self.gravity(q)
//!     }
//! }
//!
//! /// Computed-torque control, written once for any robot: the torque that gives the
//! /// acceleration `u̇ = kp (q_ref − q) − kd u`.
//! fn computed_torque<R: RobotDynamics<N>, const N: usize>(
//!     robot: &R,
//!     q: &SVector<R::Scalar, N>,
//!     u: &SVector<R::Scalar, N>,
//!     q_ref: &SVector<R::Scalar, N>,
//!     (kp, kd): (R::Scalar, R::Scalar),
//! ) -> SVector<R::Scalar, N> {
//!     let ud = (q_ref - q) * kp - u * kd;
//!     robot.inverse_dynamics(q, u, &ud)
//! }
//!
//! let pendulum = Pendulum { m: 2.0, l: 0.5, g: 9.81 };
//! let (q, u) = (SVector::from([0.3]), SVector::from([0.0]));
//! // At the reference and at rest: exactly the torque that holds it against gravity.
//! let tau = computed_torque(&pendulum, &q, &u, &q, (25.0, 10.0));
//! assert_eq!(tau, pendulum.gravity(&q));
//! // Below the reference: gravity plus M·kp·(q_ref − q).
//! let tau = computed_torque(&pendulum, &q, &u, &SVector::from([0.5]), (25.0, 10.0));
//! assert!((tau[0] - (9.81 * 0.3_f64.sin() + 0.5 * 25.0 * 0.2)).abs() < 1e-12);
//! assert_eq!(Pendulum::SPEED_NAMES, ["qd"]);
//! ```
//!
//! # Parameters as data
//!
//! Every generated `Params` (one field per model parameter, named with the model's symbols)
//! has `validate()`, which checks what a parameter set needs to be physical and returns the
//! first violation as an [`InvalidParameter`]: every value finite, every body's mass positive
//! and its inertia about the centre of mass within the triangle inequalities
//! ([`validate::check_body`]), a wheeled base's radius, track and wheel mass positive and its
//! wheel inertias non-negative.
//!
//! With the `serde` feature of this crate, every generated `Params` implements
//! `serde::Serialize` and `serde::Deserialize` (missing fields keep their defaults, unknown
//! ones are errors), so identified parameters load from TOML, JSON or any serde format. The
//! feature belongs to `kanegen-runtime`, not to the crate that includes the generated code:
//! generated code invokes [`params_serde!`], whose expansion depends on it.
//! A crate such as `krang-dynamics` forwards it as its own `serde` feature.
//!
//! # Features
//!
//! - `std` (default): forwards `nalgebra/std`. Without it the crate needs only `core`
//!   (nalgebra's math goes through `libm`); the crate itself is `#![no_std]` either way.
//! - `serde`: `Serialize`/`Deserialize` for every generated `Params` (`no_std`-compatible);
//!   re-exports `serde`.
//! - `dispatch` (default; needs `std` for feature detection): every generated function is
//!   compiled for the baseline and for x86-64-v3 (the batched ones also for x86-64-v4) and
//!   the best copy runs ([`isa`]).
//! - `toml` (implies `serde` and `std`): `params_from_model_toml`, the `[parameters]` table
//!   of a model description file as a generated `Params`, at run time.

#![no_std]
// `unsafe` only to call a copy compiled for x86-64-v3 or v4 after feature detection (`isa`,
// `derivatives_loop::run`) and for the SSE2/FMA intrinsics of `pair::F64x2` and the AVX/FMA
// ones of `quad::F64x4`; each use is
// allowed where it is.
#![deny(unsafe_code)]

#[cfg(feature = "std")]
extern crate std;

mod arith;
pub mod contact;
pub mod derivatives_loop;
mod dynamics;
pub mod free_flyer;
pub mod gpu;
mod invalid_parameter;
pub mod isa;
pub mod lanes;
mod multibody;
pub mod pair;
pub mod quad;
pub mod regressor;
#[doc(hidden)]
pub mod serde_support;
mod set_parameter_error;
pub mod tree_factor;
pub mod trig;
mod unknown_parameter;

pub use dynamics::{
    CoriolisMatrix, ForwardDynamicsDerivatives, InverseDynamicsDerivatives, RobotDynamics,
};
pub use invalid_parameter::{InvalidParameter, Problem};
pub use multibody::Multibody;
pub use nalgebra;
#[cfg(feature = "serde")]
pub use serde;
#[cfg(feature = "toml")]
pub use serde_support::{ModelFileError, params_from_model_toml};
pub use set_parameter_error::SetParameterError;
pub use unknown_parameter::UnknownParameter;

/// The checks of a generated `Params::validate` (see the [crate docs](crate#parameters-as-data)).
pub mod validate {
    pub use crate::invalid_parameter::{
        check_body, check_finite, check_non_negative, check_positive,
    };
}
