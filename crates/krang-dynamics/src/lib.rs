//! Golem Krang's dynamics, generated at build time by kanegen (the generator crate, `codegen/` in
//! this crate's repository) from `krang.toml`.
//!
//! `τ = M(q) u̇ + c(q, u) + g(q)` for the 19 generalized speeds
//! `u = [ẋ, ψ̇, q̇_imu, q̇_w, q̇_torso, q̇_1l … q̇_7l, q̇_1r … q̇_7r]` (coordinates
//! `q = [x, ψ, q_imu, q_w, q_torso, q_1l … q_7l, q_1r … q_7r]`; x and ψ do not enter).
//! The generated code is flat straight-line Rust: no loops, no allocation, no panics.
//!
//! ```
//! use krang_dynamics::{Krang, Params, index};
//! use nalgebra::{SMatrix, SVector};
//!
//! let mut p = Params::default();            // the values of models/krang.toml
//! p.set("MX4l", 0.12)?;                     // reports' symbols; Err if unknown or not finite
//! assert!(p.set("MX4k", 0.12).is_err());
//! let k = Krang::new(p);
//! let mut q = SVector::<f64, 19>::zeros();
//! q[index::Q_IMU] = 0.1;                    // base pitch
//! let u = SVector::<f64, 19>::from_element(0.2);
//! let ud = SVector::<f64, 19>::zeros();
//! let m: SMatrix<f64, 19, 19> = k.mass_matrix(&q);
//! let c: SVector<f64, 19> = k.coriolis(&q, &u);
//! let g: SVector<f64, 19> = k.gravity(&q);
//! let tau: SVector<f64, 19> = k.inverse_dynamics(&q, &u, &ud); // M ud + c + g, one pass
//! assert!((tau - (m * ud + c + g)).norm() < 1e-9);
//! # Ok::<(), krang_dynamics::SetParameterError>(())
//! ```
//!
//! `index` names every coordinate (`index::Q_IMU`, in `q`) and every speed (`index::QD_IMU`, in
//! `u`, `u̇` and `τ`; the same number). A group of joints has one name wherever it appears, a
//! range of indices into the vector at hand: [`forward::LEFT_ARM`] (`5..12` in `u`),
//! [`actuator::LEFT_ARM`] (`4..11` in the actuator vector).
//!
//! # Features: optional modules and compile time
//!
//! Each generated module is one generator call in `build.rs` and about 100–300 KB of Rust to
//! compile, so the optional ones are features (the guide's docs/runtime.md, "Build time and features", has the
//! measured build times). Default: `std`, `isa-dispatch` and the f64 Krang model above (M, c, g,
//! inverse dynamics, pre-generated), with forward dynamics and the actuator map. Every feature
//! but `std`, `isa-dispatch`, `batch`, `serde` and `toml` makes the generator a build
//! dependency.
//!
//! | feature | adds |
//! |---|---|
//! | `std` (default) | `std` for nalgebra and the runtime; without it the crate is `#![no_std]` (nalgebra's math through `libm`) |
//! | `isa-dispatch` (default) | run-time instruction-set dispatch: every generated function compiled for the baseline and for x86-64-v3 (AVX2 + FMA; fused multiply-adds, so results differ from the baseline copy's in the last bits), the CPU's best copy runs (`isa::active()`); turn it off when compiling with `-C target-cpu=native`, or to halve the generated code's size |
//! | `coriolis-matrix` | `coriolis_matrix(&q, &u)`, the Coriolis matrix `C(q, u)` with `c = C u` and `Ṁ − 2C` skew-symmetric (Slotine–Li `τ = M a_r + C v_r + g − K s`), and the `CoriolisMatrix` trait, in every module built; about doubles each module's compile time |
//! | `kinematics` | on `Krang`: centre of mass, its Jacobian and bias acceleration, frame poses, Jacobians and bias accelerations (`Frame`), kinetic and potential energy, `nonlinear_effects` (c + g), and the combined functions `whole_body_terms` (M, c + g, the centre-of-mass terms and both hands' pose, Jacobian and bias in one program) and `hands_jacobians` |
//! | `derivatives` | `inverse_dynamics_derivatives` (∂τ/∂q, ∂τ/∂u) in the Krang, fixed-wheel and two-link modules built, `forward_dynamics_derivatives` and `linearize` (with workspaces kept across calls) on `Krang` and `KrangFixedWheels` |
//! | `regressors` | on `Krang` and (with `fixed-wheels`) `KrangFixedWheels`: `τ = Y π`, `g = Y_g β`, the base regressors and base parameters (`inertial_vector`, `base_parameters`), for identification and adaptive control |
//! | `batch` | the batched functions (`Krang::mass_matrix_batch`, `_batch_into`, `_batch_soa`, … for every function with a vector or matrix result) and the batched forward dynamics (`forward_batch`): L states per call in SIMD lanes; without it they are not compiled (about 40 % of the crate's compile time) |
//! | `baked` | `baked`: the parameter values of `krang.toml` folded in as constants |
//! | `f32` | `f32::{Krang, Params}`: single precision, sin/cos computed in `f32` too |
//! | `fixed-wheels` | `fixed_wheels::KrangFixedWheels` (17 speeds) and its forward dynamics |
//! | `two-link` | `two_link::TwoLink`, the two-link model of the reports (a check against printed matrices) |
//! | `gpu` | `gpu::MODULE` and `gpu::WGSL_F32`/`WGSL_F64`: WGSL compute kernels of M, c, g, τ, `nonlinear_effects` (c + g, added to `Krang`), forward dynamics and rollouts, run by the `kanegen-gpu` crate (re-exported as `kanegen_gpu`) on any Vulkan, Metal or DX12 device; docs/gpu.md |
//! | `full` | every optional module and function: `batch`, `coriolis-matrix`, `kinematics`, `derivatives`, `regressors`, `baked`, `f32`, `fixed-wheels`, `two-link` (not `serde`, `toml`) |
//! | `serde` | `Serialize`/`Deserialize` for every `Params` (`no_std`-compatible) |
//! | `toml` | `params_from_model_toml`: `Params` from a model file's `[parameters]` at run time (needs `std`) |
//!
//! # Parameters as data
//!
//! `Params::validate` checks that a parameter set is physical (finite values, positive masses,
//! inertias within the triangle inequalities about the centre of mass, positive wheel radius and
//! track). With the `serde` feature, identified parameters load from any serde format; fields
//! left out keep the values of `krang.toml`; unknown names and values `Params::set` refuses
//! (not finite, a negative mass) are errors:
//!
//! ```
//! # #[cfg(feature = "serde")] {
//! let p: krang_dynamics::Params = serde_json::from_str(r#"{ "m4l": 4.5, "MX4l": 0.12 }"#)?;
//! assert_eq!((p.m4l, p.MX4l, p.g), (4.5, 0.12, 9.81));
//! p.validate()?;
//! let bad = serde_json::from_str::<krang_dynamics::Params>(r#"{ "m4l": -1.0 }"#);
//! assert!(bad.unwrap_err().to_string().contains("`m4l` must be positive"));
//! assert!(serde_json::from_str::<krang_dynamics::Params>(r#"{ "m4k": 1.0 }"#).is_err());
//! let bad: krang_dynamics::Params = serde_json::from_str(r#"{ "XX4l": 100.0 }"#)?;
//! assert_eq!(bad.validate().unwrap_err().name(), "4l"); // the inertia: validate's check
//! # }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # `f32` and `no_std`
//!
//! The `f32` module (feature `f32`) is the same model in single precision
//! (`krang_dynamics::f32::{Krang, Params}`) for controllers on FPUs without double precision:
//! its sines and cosines are computed in `f32` too (`kanegen_runtime::trig::sin_cos_n_f32`,
//! within an ulp of the correctly rounded value), so it needs no `f64` arithmetic. Without the
//! default feature `std` the crate is `#![no_std]`: the generated code needs only `core` and
//! `nalgebra`, and the hand-written parts take square roots and `atan2` from `libm` through
//! nalgebra.
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

// The default module is pre-generated (no generator in a default build); with the Coriolis
// matrix, the kinematics, the derivatives, the regressors or the GPU kernels it is generated
// by build.rs.
#[cfg(not(any(
    feature = "coriolis-matrix",
    feature = "kinematics",
    feature = "derivatives",
    feature = "regressors",
    feature = "gpu"
)))]
include!("generated/krang.rs");
#[cfg(any(
    feature = "coriolis-matrix",
    feature = "kinematics",
    feature = "derivatives",
    feature = "regressors",
    feature = "gpu"
))]
include!(concat!(env!("OUT_DIR"), "/krang.rs"));

/// The GPU runtime the kernels of `gpu::MODULE` run on (feature `gpu`; docs/gpu.md).
#[cfg(feature = "gpu")]
pub use kanegen_gpu;

/// Krang with the parameter values of `krang.toml` folded in as constants (faster; no `Params`).
#[cfg(feature = "baked")]
pub mod baked {
    include!(concat!(env!("OUT_DIR"), "/krang_baked.rs"));
}

/// Krang in single precision: the module of the crate root with `f32` matrices, vectors and
/// parameters (`krang_dynamics::f32::{Krang, Params}`).
#[cfg(feature = "f32")]
pub mod f32 {
    include!(concat!(env!("OUT_DIR"), "/krang_f32.rs"));
}

/// Krang on fixed wheels: the 17-DOF tree of the fixed-wheels report (Zafar 2014) (frame 0 fixed).
#[cfg(feature = "fixed-wheels")]
pub mod fixed_wheels {
    include!(concat!(env!("OUT_DIR"), "/krang_fixed_wheels.rs"));

    /// What [`KrangFixedWheels::forward_dynamics_derivatives_with`] keeps across calls (17
    /// speeds; see [`crate::ForwardDynamicsDerivativesWorkspace`], Krang's).
    #[cfg(feature = "derivatives")]
    pub type ForwardDynamicsDerivativesWorkspace =
        crate::derivatives::ForwardDynamicsDerivativesWorkspaceOf<DerivativesWorkspace, 17>;

    /// What [`KrangFixedWheels::linearize_with`] keeps across calls (`A` 34 × 34, `B` 34 × 17;
    /// see [`crate::LinearizationWorkspace`], Krang's).
    #[cfg(feature = "derivatives")]
    pub type LinearizationWorkspace =
        crate::derivatives::LinearizationWorkspaceOf<DerivativesWorkspace, 17, 34, 17>;
}

/// Appendix B of the fixed-wheels report (Zafar 2014): the two-link model (bodies 1 and 2, frame 0 fixed).
#[cfg(feature = "two-link")]
pub mod two_link {
    include!(concat!(env!("OUT_DIR"), "/two_link.rs"));
}

/// `each!(i < n; { … })` runs the block for `i` = 0, 1, … while `i < n`, written out with
/// literal indices up to 8 (every `n` of the block factor is at most 8: `BlockCholesky` asserts
/// `T ≤ 8`), so that the block indexes its arrays with constants: the block factor's
/// substitutions (`forward`) keep their values in registers, and the batched solver's loop body
/// (`forward_batch`) is straight-line code that the compiler vectorizes across the states.
/// Defined before both modules, which use it.
macro_rules! each {
    ($i:ident < $n:expr; $body:block) => {
        each!(@ $i < $n; $body; 0 1 2 3 4 5 6 7)
    };
    (@ $i:ident < $n:expr; $body:block; $($k:literal)*) => {$(
        if $k < $n {
            let $i: usize = $k;
            $body
        }
    )*};
}

mod cholesky;
pub mod forward;
pub use forward::{
    Block, BlockCholesky, ForwardDynamicsError, MassMatrixCholesky, NotPositiveDefinite, solve_spd,
};
#[cfg(feature = "batch")]
pub mod forward_batch;

pub mod actuators;

#[cfg(feature = "derivatives")]
pub mod derivatives;
pub use actuators::{ACTUATOR_COUNT, ACTUATOR_NAMES, actuator, hardware, saturate, saturate_to};
#[cfg(feature = "derivatives")]
pub use derivatives::{
    ForwardDynamicsDerivatives, ForwardDynamicsDerivativesWorkspace, LinearizationWorkspace,
};
/// The trait of the generated derivatives (`inverse_dynamics_partials`, and the provided,
/// dense `forward_dynamics_derivatives` that generic code gets; `Krang`'s inherent one uses
/// the block Cholesky).
#[cfg(feature = "derivatives")]
pub use kanegen_runtime::InverseDynamicsDerivatives;

/// What a controller uses besides the model: the traits every generated robot implements (so
/// that `Krang` works with generic controller code), the errors of `Params`, and nalgebra.
#[cfg(feature = "coriolis-matrix")]
pub use kanegen_runtime::CoriolisMatrix;
pub use kanegen_runtime::{InvalidParameter, Problem, RobotDynamics, nalgebra};
#[cfg(feature = "toml")]
pub use kanegen_runtime::{ModelFileError, params_from_model_toml};
/// Run-time instruction-set dispatch of the generated functions (which copy runs:
/// `isa::active()`; `isa::select` for benchmarks) and the lane type of the batched functions
/// (`Krang::mass_matrix_batch`, …).
pub use kanegen_runtime::{isa, lanes};
