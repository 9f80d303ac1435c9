//! kanegen: a build-time symbolic Kane's-method code generator for robot dynamics.
//!
//! A build script turns a robot description (TOML or URDF) into a Rust module of flat,
//! straight-line functions (mass matrix, Coriolis and gravity terms, inverse dynamics, and on
//! request kinematics, derivatives and regressors), which the crate compiles like its own code.
//!
//! # Using it in a crate
//!
//! The crates are not on crates.io: take them from the repository (or a local checkout with
//! `path = "…"`). `kanegen` is only a build dependency; the generated code needs
//! `kanegen-runtime` (batched sines and cosines, `UnknownParameter`, the `RobotDynamics`
//! trait) and `nalgebra`:
//!
//! ```toml
//! [dependencies]
//! kanegen-runtime = { git = "https://github.com/kanegen/kanegen" }
//! nalgebra = "0.35"
//!
//! [build-dependencies]
//! kanegen = { git = "https://github.com/kanegen/kanegen" }
//! ```
//!
//! The build script is one call to [`Builder`] (paths relative to the crate's manifest
//! directory):
//!
//! ```no_run
//! // build.rs
//! fn main() {
//!     kanegen::Builder::new("two-link.toml").run(); // writes $OUT_DIR/two_link.rs
//! }
//! ```
//!
//! A URDF works the same way ([`Builder::urdf`], import options in [`model::UrdfOptions`]);
//! `Builder::new("arm.urdf")` imports with the default options.
//!
//! The crate includes the generated file, named after the model file (its stem, `-` → `_`,
//! see [`Builder::output`]):
//!
//! ```ignore
//! // src/lib.rs
//! pub mod two_link {
//!     include!(concat!(env!("OUT_DIR"), "/two_link.rs"));
//! }
//! ```
//!
//! (In a private module, or a binary, rustc warns of every generated item the crate does not
//! use: add `#[allow(dead_code)]` to the module there.)
//!
//! The module holds `DOF`, `SPEED_NAMES` and `COORDINATE_NAMES`, a `Params` struct of the
//! model's parameters (`Params::default()`: the description's values), a free function per
//! generated function (`mass_matrix(&p, &pc, &q)`, …) and a wrapper type that keeps the
//! parameters and their precomputed terms. The wrapper is named after the model (the TOML
//! `name`, the URDF `<robot name>` or [`model::UrdfOptions::name`]) in upper camel case: every
//! run of characters other than ASCII letters and digits is dropped and the next letter
//! capitalised (`two-link` → `TwoLink`, `krang` → `Krang`, `ur5_robot` → `Ur5Robot`; `Model…`
//! before a name that does not start with a letter). Its methods, with `q`, `u`, `ud` of type
//! `SVector<f64, DOF>`:
//!
//! | method | result |
//! |---|---|
//! | `new(params)`, `default()`, `params()`, `set_params(params)` | construction |
//! | `mass_matrix(&q)` | `M(q)`, `SMatrix<f64, DOF, DOF>` |
//! | `coriolis(&q, &u)` | `c(q, u)`, the velocity terms |
//! | `gravity(&q)` | `g(q)` |
//! | `inverse_dynamics(&q, &u, &ud)` | `τ = M ud + c + g` |
//! | `coriolis_matrix(&q, &u)` | `C(q, u)` with `c = C u` ([`Builder::coriolis_matrix`]) |
//! | `forward_dynamics(&q, &u, &tau)` | `ud`, from the `kanegen_runtime::RobotDynamics` trait |
//!
//! and `…_into` forms of the matrix-valued ones (`mass_matrix_into(&q, &mut m)`) that write into
//! the caller's matrix. [`Builder::functions`] adds kinematics (`frame_pose`, `frame_jacobian`,
//! `center_of_mass`, …), derivatives and regressors.
//!
//! ```ignore
//! use kanegen_runtime::RobotDynamics as _; // forward_dynamics
//! use nalgebra::SVector;
//! use two_link::{DOF, Params, TwoLink};
//!
//! let robot = TwoLink::new(Params::default());
//! let q = SVector::<f64, DOF>::from_element(0.3);
//! let u = SVector::<f64, DOF>::zeros();
//! let m = robot.mass_matrix(&q);
//! let tau = robot.inverse_dynamics(&q, &u, &u); // holding torque: g(q)
//! let ud = robot.forward_dynamics(&q, &u, &tau).expect("M is positive definite");
//! ```
//!
//! # Generating without a build script
//!
//! [`Builder::generate`] returns the [`Generated`] module (its source, the validated model)
//! without writing anything; [`Builder::from_model`] and [`Builder::from_import`] start from a
//! model in memory. [`stats`] and [`listing`] print what the `kanegen` command line prints.
//!
//! # Build output
//!
//! [`Builder::build`] prints, besides `cargo:rerun-if-changed`, one `cargo:warning=` line per
//! kind of URDF import decision that changes or questions the model's numbers (angles snapped
//! to π/2, links merged, inertias repaired or dropped; [`Generated::warnings`]), and
//! [`Builder::run`] fails the build with the typed [`Error`], reported once.
#![forbid(unsafe_code)]
// The build-script examples above show their `fn main`.
#![allow(clippy::needless_doctest_main)]

pub mod bindings;
mod builder;
// Internal stages, public only for the workspace's own tests and tools; not part of the API
// (their documentation may link to the crate's private items).
#[doc(hidden)]
pub mod combined;
#[doc(hidden)]
#[allow(rustdoc::private_intra_doc_links)]
pub mod emit;
#[doc(hidden)]
#[allow(rustdoc::private_intra_doc_links)]
pub mod expr;
pub mod floating;
#[doc(hidden)]
#[allow(rustdoc::private_intra_doc_links)]
pub mod kane;
#[doc(hidden)]
#[allow(rustdoc::private_intra_doc_links)]
pub mod lower;
#[doc(hidden)]
pub mod naming;
mod options;
#[doc(hidden)]
pub mod pinocchio;
#[doc(hidden)]
pub mod registry;
mod report;
mod size;
mod warnings;
/// The robot description IR and its loaders (re-exported from `kanegen-model`).
pub mod model {
    pub use kanegen_model::*;
}

use std::path::{Path, PathBuf};

pub use builder::Builder;
pub use combined::{Combined, CombinedError};
pub use emit::EmitError;
use emit::EmitOptions;
pub use options::{
    DerivativesForm, LOOPED_ABOVE_FLOPS, Options, ParamMode, Precision, RegressorForm,
};
pub use registry::{FunctionId, FunctionSet};
pub use report::{listing, stats};
pub use size::{DEFAULT_UNOPTIMISED_LIMIT, SizeEstimate, available_memory, estimate};

/// Anything that can go wrong while generating.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The description file is malformed or not physical.
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// A combined function names an unknown frame, a taken name, … ([`Builder::combined`]).
    #[error(transparent)]
    Combined(#[from] CombinedError),
    /// The generated code did not parse (a generator bug).
    #[error(transparent)]
    Emit(#[from] EmitError),
    /// A generated function would contain a constant that is not a finite number of the
    /// module's precision: a parameter-free part of the model divides by zero or overflows
    /// (a model built in memory without speeds or mass, baked values beyond `f32`'s range).
    #[error(
        "model `{model}`: function `{function}` would contain the constant {value:e}, which is not a finite {precision} number; {fix}"
    )]
    NonFiniteConstant {
        /// The model's name.
        model: String,
        /// The generated function (or `precompute`).
        function: String,
        /// The constant, as folded at generation time.
        value: f64,
        /// `f64` or `f32`.
        precision: &'static str,
        /// How to avoid it.
        fix: &'static str,
    },
    /// A bindings crate cannot be written for this module ([`Builder::python_crate`],
    /// [`Builder::c_crate`]).
    #[error(transparent)]
    Bindings(#[from] bindings::BindingsError),
    /// Writing the generated file failed.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The model is too large for this generation: its estimated memory exceeds what the
    /// process may use, or its module is too large for an unoptimised build
    /// ([`estimate`], docs/big-models.md). Found before anything is derived.
    #[error("model `{model}` is too large: {what}; {fix}")]
    TooLarge {
        /// The model's name.
        model: String,
        /// The estimate and the limit it exceeds.
        what: String,
        /// What to do.
        fix: String,
    },
    /// The build script environment lacks `OUT_DIR`.
    #[error(
        "OUT_DIR is not set: Builder::build must run inside a cargo build script (or call Builder::out_dir)"
    )]
    NoOutDir,
    /// A floating-base model asked for something the generator does not emit for a floating
    /// base yet (see [`floating::SUPPORTED`]).
    #[error("model `{model}` ({file}): {what} is not generated for a floating base yet; {fix}")]
    FloatingBase {
        /// The model's name.
        model: String,
        /// The description file.
        file: String,
        /// The function or option.
        what: String,
        /// How to avoid it.
        fix: &'static str,
    },
}

/// Everything the generator produced for one model.
#[derive(Clone, Debug)]
pub struct Generated {
    /// The validated model.
    pub model: model::Model,
    /// The symbolic derivation (internal: for the workspace's own tests and reports).
    #[doc(hidden)]
    pub derivation: kane::Derivation,
    /// The straight-line programs (internal: for the workspace's own tests and reports).
    #[doc(hidden)]
    pub lowered: lower::Lowered,
    /// The notes of the URDF import (snapped angles, merged and dropped links, inertias, wheel
    /// constants; one line each), also written after the generated file's header; empty for
    /// TOML and in-memory models.
    pub notes: Vec<String>,
    /// The formatted Rust source.
    pub source: String,
}

impl Generated {
    /// The import notes that change or question the model's numbers, one line per kind (count,
    /// first names, the option that decides it): what [`Builder::build`] prints after
    /// `cargo:warning=`, and the command line on standard error. Empty for TOML models and for
    /// URDF imports that kept every number as written.
    ///
    /// ```text
    /// kanegen: arm.urdf: 2 angles snapped to a multiple of π/2 (joint1, joint3); UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written
    /// ```
    pub fn warnings(&self) -> Vec<String> {
        warnings::summary(&self.model.source, &self.notes)
    }
}

/// Run every stage on a loaded model, emitting with `emit_options` (precision, notes).
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn generate_with(
    robot: model::Model,
    opts: Options,
    emit_options: &EmitOptions,
) -> Result<Generated, Error> {
    generate_combined(robot, opts, &[], emit_options)
}

/// Run every stage on a loaded model with the combined functions `combined_functions` (see
/// [`Builder::combined`]), emitting with `emit_options`.
pub(crate) fn generate_combined(
    robot: model::Model,
    opts: Options,
    combined_functions: &[Combined],
    emit_options: &EmitOptions,
) -> Result<Generated, Error> {
    // The loaders check names; a model built in memory is checked here.
    robot.check_names()?;
    floating::check(
        &robot,
        &opts,
        combined_functions,
        emit_options.gpu.is_some(),
    )?;
    let resolved = combined::resolve(&robot, combined_functions)?;
    let mut progress = Progress::new(&robot);
    let derivation = kane::derive_shaped(&robot, opts, &resolved, emit_options.regressor_form);
    progress.stage(&format!(
        "derived ({} expression nodes, {} substitution variables)",
        derivation.arena.len(),
        derivation.arena.vars().len()
    ));
    let mut lowered = lower::lower_with(&derivation, emit_options.derivatives_form);
    if emit_options.mirrored_lanes && emit_options.precision == Precision::F64 {
        lower::lanes::apply(&mut lowered, &derivation);
    }
    progress.stage("lowered to straight-line programs");
    check_constants(&robot, &lowered, emit_options.precision)?;
    let source = emit::emit(&robot, &lowered, emit_options)?;
    progress.stage(&format!("emitted ({} bytes of Rust)", source.len()));
    Ok(Generated {
        model: robot,
        derivation,
        lowered,
        notes: emit_options.notes.clone(),
        source,
    })
}

/// [`Error::NonFiniteConstant`] if a program of `lowered` has a constant that the emitter could
/// not print as a literal of `precision` (it would panic in `proc_macro2`).
fn check_constants(
    robot: &model::Model,
    lowered: &lower::Lowered,
    precision: Precision,
) -> Result<(), Error> {
    let (name, fix): (_, &'static str) = match precision {
        Precision::F64 => (
            "f64",
            "a parameter-free part of the model divides by zero or overflows: a model needs a speed and a body with mass (the loaders check that), and baked parameter values must keep its constants finite",
        ),
        Precision::F32 => (
            "f32",
            "an f32 module holds no constant beyond ±3.4e38: generate it with runtime parameters, or in f64",
        ),
    };
    let fits = |v: f64| match precision {
        Precision::F64 => v.is_finite(),
        Precision::F32 => (v as f32).is_finite(),
    };
    match lowered.constant_where(fits) {
        Some((function, value)) => Err(Error::NonFiniteConstant {
            model: robot.name.clone(),
            function: function.to_owned(),
            value,
            precision: name,
            fix,
        }),
        None => Ok(()),
    }
}

/// Progress lines on stderr for long generations: a model with at least
/// [`Progress::LARGE_DOF`] speeds announces itself, and every stage that ends more than a second
/// after the start prints one line (`kanegen: chain200: lowered … after 41.3 s`). Small models
/// print nothing.
struct Progress {
    start: std::time::Instant,
    name: String,
}

impl Progress {
    /// Models with at least this many speeds announce their generation.
    const LARGE_DOF: usize = 50;

    fn new(robot: &model::Model) -> Self {
        let name = robot.name.escape_default().to_string();
        if robot.dof() >= Self::LARGE_DOF {
            eprintln!(
                "kanegen: {name}: generating the dynamics of {} speeds and {} frames (large models take a while)",
                robot.independent_dof(),
                robot.links.len()
            );
        }
        Self {
            start: std::time::Instant::now(),
            name,
        }
    }

    fn stage(&mut self, what: &str) {
        let t = self.start.elapsed().as_secs_f64();
        if t > 1.0 {
            eprintln!("kanegen: {}: {what} after {t:.1} s", self.name);
        }
    }
}

/// Write `contents` to `path` only if the file does not already hold exactly these bytes (so
/// that cargo does not recompile an unchanged module). Returns whether the file was written.
pub fn write_if_changed(path: &Path, contents: &str) -> Result<bool, Error> {
    if std::fs::read(path).is_ok_and(|old| old == contents.as_bytes()) {
        return Ok(false);
    }
    let write_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| Error::Write { path, source }
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    }
    std::fs::write(path, contents).map_err(write_error(path))?;
    Ok(true)
}

/// Whether `path` names a URDF file (by its extension, case-insensitive).
pub fn is_urdf(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
}
