//! kanegen: a build-time symbolic Kane's-method code generator for robot dynamics.
//!
//! Stages, one module each, dependencies one way only:
//! [`model`] (description files → validated IR) → [`expr`] (hash-consed expression arena) →
//! [`kane`] (recursive Kane's derivation with K/D substitution) → [`lower`] (straight-line
//! programs, dead-code elimination, op counts) → [`emit`] (quote/syn/prettyplease → Rust source).
//! Every stage reads the [`registry`] (which functions exist, their inputs and result shapes)
//! and the [`options`] (which functions a module gets, how parameters enter, its precision).
//!
//! A build script generates a dynamics module in one call:
//!
//! ```no_run
//! // build.rs
//! kanegen::Builder::new("krang.toml").run();
//! ```
//!
//! and the crate includes it with
//! `include!(concat!(env!("OUT_DIR"), "/krang.rs"));` (the file is named after the model file).
//! Generated code uses the `kanegen-runtime` crate (batched `sin_cos_n`, `UnknownParameter`,
//! the `RobotDynamics` trait) and `nalgebra`: add both as dependencies.
//!
//! Any robot described in URDF works the same way ([`Builder::urdf`], options in
//! [`model::UrdfOptions`]):
//!
//! ```no_run
//! // build.rs
//! kanegen::Builder::urdf("robot.urdf", kanegen::model::UrdfOptions::default()).run();
//! ```
#![forbid(unsafe_code)]

pub mod combined;
pub mod emit;
pub mod expr;
pub mod kane;
pub mod lower;
pub mod naming;
pub mod options;
pub mod pinocchio;
pub mod registry;
pub mod report;
/// The robot description IR and its loaders (re-exported from `kanegen-model`).
pub mod model {
    pub use kanegen_model::*;
}

use std::path::{Path, PathBuf};

pub use emit::EmitOptions;
pub use options::{DerivativesForm, Options, ParamMode, Precision, RegressorForm};
pub use registry::{FunctionId, FunctionSet};
pub use report::{listing, stats};

/// Anything that can go wrong while generating.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The description file is malformed or not physical.
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// A combined function names an unknown frame, a taken name, … ([`Builder::combined`]).
    #[error(transparent)]
    Combined(#[from] combined::CombinedError),
    /// The generated code did not parse (a generator bug).
    #[error(transparent)]
    Emit(#[from] emit::EmitError),
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
    /// Writing the generated file failed.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The build script environment lacks `OUT_DIR`.
    #[error(
        "OUT_DIR is not set: Builder::build must run inside a cargo build script (or call Builder::out_dir)"
    )]
    NoOutDir,
}

/// Everything the generator produced for one model.
#[derive(Clone, Debug)]
pub struct Generated {
    /// The validated model.
    pub model: model::Model,
    /// The symbolic derivation.
    pub derivation: kane::Derivation,
    /// The straight-line programs.
    pub lowered: lower::Lowered,
    /// The formatted Rust source.
    pub source: String,
}

/// Run every stage on a loaded model (an `f64` module without notes; see [`generate_with`]).
pub fn generate_model(model: model::Model, options: Options) -> Result<Generated, Error> {
    generate_with(model, options, &EmitOptions::default())
}

/// Run every stage on a loaded model, emitting with `emit` (precision, notes).
pub fn generate_with(
    model: model::Model,
    options: Options,
    emit: &EmitOptions,
) -> Result<Generated, Error> {
    generate_combined(model, options, &[], emit)
}

/// [`generate_with`], with the combined functions `combined` (see [`combined`] and
/// [`Builder::combined`]).
pub fn generate_combined(
    model: model::Model,
    options: Options,
    combined: &[combined::Combined],
    emit: &EmitOptions,
) -> Result<Generated, Error> {
    // The loaders check names; a model built in memory is checked here.
    model.check_names()?;
    let combined = combined::resolve(&model, combined)?;
    let mut progress = Progress::new(&model);
    let derivation = kane::derive_shaped(&model, options, &combined, emit.regressor_form);
    progress.stage(&format!(
        "derived ({} expression nodes, {} substitution variables)",
        derivation.arena.len(),
        derivation.arena.vars().len()
    ));
    let mut lowered = lower::lower_with(&derivation, emit.derivatives_form);
    if emit.mirrored_lanes && emit.precision == Precision::F64 {
        lower::lanes::apply(&mut lowered, &derivation);
    }
    progress.stage("lowered to straight-line programs");
    check_constants(&model, &lowered, emit.precision)?;
    let source = emit::emit(&model, &lowered, emit)?;
    progress.stage(&format!("emitted ({} bytes of Rust)", source.len()));
    Ok(Generated {
        model,
        derivation,
        lowered,
        source,
    })
}

/// [`Error::NonFiniteConstant`] if a program of `lowered` has a constant that the emitter could
/// not print as a literal of `precision` (it would panic in `proc_macro2`).
fn check_constants(
    model: &model::Model,
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
            model: model.name.clone(),
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

    fn new(model: &model::Model) -> Self {
        let name = model.name.escape_default().to_string();
        if model.dof() >= Self::LARGE_DOF {
            eprintln!(
                "kanegen: {name}: generating the dynamics of {} speeds and {} frames (large models take a while)",
                model.independent_dof(),
                model.links.len()
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

/// Import a URDF file and run every stage. The import notes (snapped angles, merged and dropped
/// links, wheel constants) are written as comments after the generated file's header.
pub fn generate_urdf(
    path: impl AsRef<Path>,
    urdf: &model::UrdfOptions,
    options: Options,
) -> Result<Generated, Error> {
    urdf_with(path.as_ref(), urdf, options, &[], EmitOptions::default())
}

fn urdf_with(
    path: &Path,
    urdf: &model::UrdfOptions,
    options: Options,
    combined: &[combined::Combined],
    emit: EmitOptions,
) -> Result<Generated, Error> {
    let import = model::UrdfImport::read(path, urdf)?;
    let emit = EmitOptions {
        notes: import.notes,
        notes_title: "URDF import notes".into(),
        ..emit
    };
    generate_combined(import.model, options, combined, &emit)
}

/// Load a TOML description file and run every stage (f64 module).
pub fn generate(path: impl AsRef<Path>, options: Options) -> Result<Generated, Error> {
    let model = model::Model::from_toml_file(path)?;
    generate_model(model, options)
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

/// Generates a dynamics module from a build script.
///
/// ```no_run
/// use kanegen::{FunctionId, FunctionSet};
/// kanegen::Builder::new("models/krang.toml")
///     .baked(false)
///     .functions(FunctionSet::default().without(FunctionId::CoriolisMatrix))
///     .output("krang.rs")
///     .run();
/// ```
#[derive(Clone, Debug)]
pub struct Builder {
    model: PathBuf,
    options: Options,
    output: Option<String>,
    out_dir: Option<PathBuf>,
    /// `Some` when the model file is a URDF to import with these options.
    urdf: Option<model::UrdfOptions>,
    precision: Precision,
    /// Tool frames added to the loaded model ([`Builder::frame`]).
    frames: Vec<model::OperationalFrame>,
    /// Combined functions ([`Builder::combined`]).
    combined: Vec<combined::Combined>,
    isa_dispatch: bool,
    batch: bool,
    batch_feature: Option<String>,
    mirrored_lanes: bool,
    split_above: usize,
    regressor_form: RegressorForm,
    derivatives_form: DerivativesForm,
}

impl Builder {
    /// Generate from the TOML description file `model` (relative to the crate's manifest
    /// directory when run from a build script). A path ending in `.urdf` is imported with the
    /// default [`model::UrdfOptions`] (use [`Builder::urdf`] to set them).
    pub fn new(model: impl Into<PathBuf>) -> Self {
        let model = model.into();
        let urdf = is_urdf(&model).then(model::UrdfOptions::default);
        Self {
            model,
            options: Options::default(),
            output: None,
            out_dir: None,
            urdf,
            precision: Precision::F64,
            frames: Vec::new(),
            combined: Vec::new(),
            isa_dispatch: true,
            batch: false,
            batch_feature: None,
            mirrored_lanes: false,
            split_above: emit::SPLIT_ABOVE,
            regressor_form: RegressorForm::Auto,
            derivatives_form: DerivativesForm::Auto,
        }
    }

    /// Generate from the URDF file `path` (relative to the crate's manifest directory when run
    /// from a build script), imported with `options` (see [`model::urdf`]): the module has the
    /// same shape as for a TOML model, with URDF-derived names (`Params` fields `m_<link>`,
    /// `MX_<link>`…, speeds `qd_<joint>`) and a wrapper struct named after the `<robot name>`
    /// (or [`model::UrdfOptions::name`]).
    ///
    /// ```no_run
    /// use kanegen::model::{UrdfOptions, WheeledBaseSpec};
    /// kanegen::Builder::urdf("arm.urdf", UrdfOptions::default()).run();
    /// let base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    /// kanegen::Builder::urdf("Krang.urdf", UrdfOptions::wheeled(base).drop_links(["lgPlate1"])).run();
    /// ```
    pub fn urdf(path: impl Into<PathBuf>, options: model::UrdfOptions) -> Self {
        Self {
            urdf: Some(options),
            ..Self::new(path)
        }
    }

    /// Fold the model file's parameter values in as constants (default: runtime parameters).
    pub fn baked(mut self, baked: bool) -> Self {
        self.options.params = if baked {
            ParamMode::Baked
        } else {
            ParamMode::Runtime
        };
        self
    }

    /// Which registry functions the module gets (default [`FunctionSet::default`]: M, c, g, τ
    /// and the Coriolis matrix). Heavy functions can be left out of modules that do not need
    /// them; the wrapper type implements a `kanegen-runtime` trait only if the module has all of
    /// its functions.
    ///
    /// ```no_run
    /// use kanegen::{FunctionId, FunctionSet};
    /// let set: FunctionSet = [FunctionId::MassMatrix, FunctionId::Gravity].into_iter().collect();
    /// kanegen::Builder::new("krang.toml").functions(set).run();
    /// ```
    pub fn functions(mut self, functions: FunctionSet) -> Self {
        self.options.functions = functions;
        self
    }

    /// Whether the module has `coriolis_matrix`, the Coriolis matrix C(q, u) with `c = C u`
    /// and `Ṁ − 2C` skew-symmetric (default `true`): shorthand for adding or removing
    /// [`FunctionId::CoriolisMatrix`] with [`Builder::functions`]. It is about four times the
    /// operations of `coriolis` and roughly doubles the compile time of a large model's module
    /// (Krang: ≈ 7,900 flops, +3 s of release compilation per module).
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").coriolis_matrix(false).run();
    /// ```
    pub fn coriolis_matrix(mut self, on: bool) -> Self {
        let f = FunctionId::CoriolisMatrix;
        let set = self.options.functions;
        self.options.functions = if on { set.with(f) } else { set.without(f) };
        self
    }

    /// Whether the module has `inverse_dynamics_derivatives`, the exact `[∂τ/∂q | ∂τ/∂u]` of
    /// inverse dynamics (default `false`): shorthand for adding or removing
    /// [`FunctionId::InverseDynamicsDerivatives`] with [`Builder::functions`]. It is the
    /// largest generated function (Krang: see README, section "Derivatives").
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").derivatives(true).run();
    /// ```
    pub fn derivatives(mut self, on: bool) -> Self {
        let f = FunctionId::InverseDynamicsDerivatives;
        let set = self.options.functions;
        self.options.functions = if on { set.with(f) } else { set.without(f) };
        self
    }

    /// The code shape of `inverse_dynamics_regressor` and `base_regressor` (default
    /// [`RegressorForm::Auto`]: a loop over (speed, body) pairs for models where the straight
    /// line outgrows the instruction cache, e.g. Krang; see README, "Regressors: the loop
    /// form").
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").regressor_form(kanegen::RegressorForm::StraightLine).run();
    /// ```
    pub fn regressor_form(mut self, form: RegressorForm) -> Self {
        self.regressor_form = form;
        self
    }

    /// The floating-point type of the generated module (default [`Precision::F64`]). With
    /// [`Precision::F32`] every matrix, vector, `Params` field and literal is `f32`, and the
    /// default file name gets the suffix `_f32.rs`:
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").precision(kanegen::Precision::F32).run(); // krang_f32.rs
    /// ```
    pub fn precision(mut self, precision: Precision) -> Self {
        self.precision = precision;
        self
    }

    /// Run-time instruction-set dispatch (default `true`): every generated function is
    /// compiled for the baseline target and for x86-64-v3 (AVX2 + FMA), and the copy the CPU
    /// supports runs (`kanegen_runtime::isa`, detected once). Turn it off to get one copy per
    /// function (half the code) when the crate is built with `-C target-cpu=…` anyway; the
    /// runtime's `dispatch` feature turns it off for every module of a build. The x86-64-v3 copy
    /// fuses multiply-adds (`kanegen_runtime::isa::Arith`), so its results differ from the
    /// baseline copy's in the last bits; without dispatch the one copy fuses them when the crate
    /// is compiled with FMA (`isa::Native`).
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").isa_dispatch(false).run();
    /// ```
    pub fn isa_dispatch(mut self, on: bool) -> Self {
        self.isa_dispatch = on;
        self
    }

    /// Batched functions (default `false`; `f64` modules): `mass_matrix_batch(p, pc, &[q; L])
    /// -> [SMatrix; L]` and likewise for every function with a vector or matrix result and no
    /// frame argument (free functions and wrapper methods), the single-state statements
    /// evaluated at `L` states per call in SIMD lanes, bit for bit the single-state results;
    /// and the structure-of-arrays forms `mass_matrix_batch_soa(p, pc, &SVector<Lanes<L>, N>)
    /// -> SMatrix<Lanes<L>, N, N>` (each entry the `L` states' values side by side: no
    /// transposition, one vector store per entry; the faster form). `_into` forms of both
    /// write into the caller's results.
    /// Generic in `L`: nothing is compiled for a batch size nobody calls. Unoptimised builds
    /// keep every statement's lanes on the stack (Krang at `L = 8`: more than a thread's
    /// default 2 MB); optimised builds need a few KB.
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").batch(true).run();
    /// ```
    pub fn batch(mut self, on: bool) -> Self {
        self.batch = on;
        self
    }

    /// Batched functions ([`Builder::batch`]), each behind the cargo feature `name` of the crate
    /// that includes the module: every batched function and method gets
    /// `#[cfg(feature = "name")]`. A crate can then ship one module (pre-generated, or
    /// generated the same way with every feature set) whose batched half — 40 % of Krang's
    /// source — is not even type-checked unless a user asks for it. `krang-dynamics` does this
    /// with its `batch` feature (README, "Build time and features"). The crate must declare the
    /// feature (`[features] batch = []`), or rustc warns of an unexpected `cfg`.
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").batch_feature("batch").run();
    /// ```
    pub fn batch_feature(mut self, name: impl Into<String>) -> Self {
        self.batch = true;
        self.batch_feature = Some(name.into());
        self
    }

    /// Mirrored subtrees in two SIMD lanes ("arms in lanes", default `false`; `f64` modules):
    /// where the model has two sibling subtrees of the same shape (Krang's arms: the same
    /// joints, axes and geometry below their first joint, each with its own inertial
    /// parameters), the single-state M, c, g, τ, C, nonlinear effects and centre-of-mass
    /// functions, the combined functions and the looped derivatives' straight-line part compute
    /// each pair of mirrored statements once, the first subtree in the low lane of a
    /// `kanegen_runtime::pair::F64x2` and the second in the high lane. Every result entry is
    /// computed with the same operations as the scalar statements, in the same order (tested
    /// bit for bit); the right subtree's sums are printed in the left's order. Models without
    /// mirrored subtrees are unaffected. See README, "Arms in lanes".
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").mirrored_lanes(true).run();
    /// ```
    pub fn mirrored_lanes(mut self, on: bool) -> Self {
        self.mirrored_lanes = on;
        self
    }

    /// Split generated functions of more than `statements` statements into blocks of 500
    /// (default [`emit::SPLIT_ABOVE`], 2,600): rustc's debug info nests a scope per `let` and
    /// overflowed its stack on longer functions (`rustc unexpectedly overflowed its stack` in a
    /// debug build). Lower it if a debug build of the module still crashes; optimised code is
    /// the same either way (the blocks pass their values on as tuples).
    ///
    /// ```no_run
    /// kanegen::Builder::new("big.urdf").split_functions_above(1000).run();
    /// ```
    pub fn split_functions_above(mut self, statements: usize) -> Self {
        self.split_above = statements;
        self
    }

    /// How `inverse_dynamics_derivatives` is emitted (default [`DerivativesForm::Auto`]: looped
    /// for models whose straight-line derivatives exceed
    /// [`options::LOOPED_ABOVE_FLOPS`], such as Krang; straight-line for small models and
    /// models with mimic joints). Both forms give the same matrices to rounding (README,
    /// "Derivatives: the looped form").
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml")
    ///     .derivatives(true)
    ///     .derivatives_form(kanegen::DerivativesForm::StraightLine)
    ///     .run();
    /// ```
    pub fn derivatives_form(mut self, form: DerivativesForm) -> Self {
        self.derivatives_form = form;
        self
    }

    fn emit_options(&self) -> EmitOptions {
        EmitOptions {
            derivatives_form: self.derivatives_form,
            precision: self.precision,
            isa_dispatch: self.isa_dispatch,
            batch: self.batch,
            batch_feature: self.batch_feature.clone(),
            mirrored_lanes: self.mirrored_lanes,
            split_above: self.split_above,
            regressor_form: self.regressor_form,
            ..EmitOptions::default()
        }
    }

    /// Name of the generated file in the output directory (default: the model file's stem
    /// plus `.rs`, or `_baked.rs` in baked mode; `_f32.rs`, `_baked_f32.rs` for
    /// [`Precision::F32`]).
    pub fn output(mut self, file_name: impl Into<String>) -> Self {
        self.output = Some(file_name.into());
        self
    }

    /// Write into `dir` instead of `$OUT_DIR`.
    pub fn out_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Adds an operational (tool) frame to the model, after the description's own frames: a
    /// frame fixed to `frame.parent` at a constant offset (see [`model::OperationalFrame`]). It
    /// joins the generated `Frame` type and the per-frame functions (`frame_pose`,
    /// `frame_jacobian`, `frame_bias_acceleration`); a bad name, parent or rotation is a typed
    /// error of [`Builder::generate`].
    ///
    /// ```no_run
    /// use kanegen::model::OperationalFrame;
    /// kanegen::Builder::new("arm.urdf")
    ///     .frame(OperationalFrame::new("tool", "link7", [0.0, 0.0, 0.107]))
    ///     .run();
    /// ```
    pub fn frame(mut self, frame: model::OperationalFrame) -> Self {
        match &mut self.urdf {
            Some(urdf) => urdf.frames.push(frame),
            None => self.frames.push(frame),
        }
        self
    }

    /// Adds a combined function: several registry functions (and frames of the per-frame ones)
    /// as one straight-line program with one result struct, computing every sine, cosine and
    /// substitution variable the parts share once (see [`combined`]). The separate functions
    /// stay as [`Builder::functions`] says; an unknown frame or a taken name is a typed error of
    /// [`Builder::generate`].
    ///
    /// ```no_run
    /// use kanegen::{FunctionId as F, combined::Combined};
    /// kanegen::Builder::new("krang.toml")
    ///     .combined(
    ///         Combined::new("balance_terms")
    ///             .with(F::MassMatrix)
    ///             .with(F::NonlinearEffects)
    ///             .with(F::ComJacobian)
    ///             .with(F::ComBiasAcceleration),
    ///     )
    ///     .run();
    /// ```
    pub fn combined(mut self, combined: combined::Combined) -> Self {
        self.combined.push(combined);
        self
    }

    /// Run every stage and return the result without writing anything.
    pub fn generate(&self) -> Result<Generated, Error> {
        match &self.urdf {
            Some(urdf) => urdf_with(
                &self.model,
                urdf,
                self.options,
                &self.combined,
                self.emit_options(),
            ),
            None => {
                let mut model = model::Model::from_toml_file(&self.model)?;
                for f in &self.frames {
                    model.add_frame(f)?;
                }
                generate_combined(model, self.options, &self.combined, &self.emit_options())
            }
        }
    }

    /// The default output file name (see [`Builder::output`]).
    fn file_name(&self) -> String {
        let stem = self
            .model
            .file_stem()
            .map(|s| s.to_string_lossy().replace('-', "_"))
            .unwrap_or_else(|| "model".into());
        let baked = match self.options.params {
            ParamMode::Runtime => "",
            ParamMode::Baked => "_baked",
        };
        let precision = match self.precision {
            Precision::F64 => "",
            Precision::F32 => "_f32",
        };
        format!("{stem}{baked}{precision}.rs")
    }

    /// Generate and write the module (only if its bytes changed); returns its path. Prints the
    /// `cargo:rerun-if-changed` line for the model file.
    pub fn build(&self) -> Result<PathBuf, Error> {
        let dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => PathBuf::from(std::env::var_os("OUT_DIR").ok_or(Error::NoOutDir)?),
        };
        println!("cargo:rerun-if-changed={}", self.model.display());
        let g = self.generate()?;
        let path = dir.join(self.output.clone().unwrap_or_else(|| self.file_name()));
        write_if_changed(&path, &g.source)?;
        Ok(path)
    }

    /// [`Builder::build`], and on error print the typed error and fail the build.
    pub fn run(&self) {
        if let Err(e) = self.build() {
            eprintln!("error: kanegen: {e}");
            println!("cargo::error=kanegen: {e}");
            std::process::exit(1);
        }
    }
}

/// Whether `path` names a URDF file (by its extension, case-insensitive).
pub fn is_urdf(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
}
