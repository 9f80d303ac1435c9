//! Golem Krang's dynamics, generated at build time by [kanegen] from `krang.toml`.
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
//! p.set("MX4l", 0.12)?;                     // reports' symbols; Err if unknown
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
//! # Ok::<(), krang_dynamics::UnknownParameter>(())
//! ```
//!
//! Every module also has the generated Coriolis matrix (`Krang::coriolis_matrix(&q, &u)`, the
//! free function `coriolis_matrix` in `baked`): the full `C(q, u)` with `c = C u` and `Ṁ − 2C`
//! skew-symmetric, for passivity-based controllers (e.g. Slotine–Li `τ = M a_r + C v_r + g − K s`).
//!
//! [kanegen]: https://docs.rs/kanegen
//!
//! # `f32` and `no_std`
//!
//! [`f32`](mod@f32) is the same model in single precision (`krang_dynamics::f32::{Krang,
//! Params}`), for controllers on FPUs without double precision. Without the default feature
//! `std` the crate is `#![no_std]`: the generated code needs only `core` and `nalgebra`, and the
//! hand-written parts take square roots and `atan2` from `libm` through nalgebra.
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]

include!(concat!(env!("OUT_DIR"), "/krang.rs"));

/// Krang with the parameter values of `krang.toml` folded in as constants (faster; no `Params`).
pub mod baked {
    include!(concat!(env!("OUT_DIR"), "/krang_baked.rs"));
}

/// Krang in single precision: the module of the crate root with `f32` matrices, vectors and
/// parameters (`krang_dynamics::f32::{Krang, Params}`).
pub mod f32 {
    include!(concat!(env!("OUT_DIR"), "/krang_f32.rs"));
}

/// Krang on fixed wheels: the 17-DOF tree of seed 002 (frame 0 fixed).
pub mod fixed_wheels {
    include!(concat!(env!("OUT_DIR"), "/krang_fixed_wheels.rs"));
}

/// Seed 002 Appendix B: the two-link model (bodies 1 and 2, frame 0 fixed).
pub mod two_link {
    include!(concat!(env!("OUT_DIR"), "/two_link.rs"));
}

pub mod forward;
pub use forward::{Block, MassMatrixCholesky, NotPositiveDefinite, solve_spd};

pub mod actuators;
pub use actuators::{ACTUATOR_COUNT, ACTUATOR_NAMES, actuator, hardware, saturate, saturate_to};
