//! [`Builder`]: the one way to generate a module, from a build script, the command line or a
//! test.

use std::io::Write as _;
use std::path::PathBuf;

use crate::emit::{self, EmitOptions};
use crate::{
    Combined, DerivativesForm, Error, FunctionId, FunctionSet, Generated, Options, ParamMode,
    Precision, RegressorForm, generate_combined, is_urdf, model, warnings, write_if_changed,
};

/// What a [`Builder`] generates from.
#[derive(Clone, Debug)]
enum Source {
    /// A TOML description file.
    Toml(PathBuf),
    /// A URDF file and its import options.
    Urdf(PathBuf, Box<model::UrdfOptions>),
    /// A model in memory, with the notes of its import (empty if it was not imported).
    Model(Box<model::Model>, Vec<String>),
}

/// Generates a dynamics module: from a build script ([`Builder::run`], [`Builder::build`]) or
/// in memory ([`Builder::generate`]). It starts from a description file ([`Builder::new`],
/// [`Builder::urdf`]) or a model in memory ([`Builder::from_model`], [`Builder::from_import`]);
/// every other setting has a default.
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
    /// The description to generate from.
    source: Source,
    options: Options,
    output: Option<String>,
    out_dir: Option<PathBuf>,
    precision: Precision,
    /// Tool frames added to a TOML or in-memory model ([`Builder::frame`]; a URDF's go to its
    /// [`model::UrdfOptions::frames`]).
    frames: Vec<model::OperationalFrame>,
    /// Combined functions ([`Builder::combined`]).
    combined: Vec<Combined>,
    isa_dispatch: bool,
    batch: bool,
    batch_feature: Option<String>,
    mirrored_lanes: bool,
    split_above: usize,
    regressor_form: RegressorForm,
    derivatives_form: DerivativesForm,
    /// [`Builder::memory_limit`] (`None`: what the process may use).
    memory_limit: Option<u64>,
    /// [`Builder::unoptimised_limit`].
    unoptimised_limit: u64,
    gpu: Option<FunctionSet>,
}

impl Builder {
    /// Generate from the TOML description file `description` (relative to the crate's manifest
    /// directory when run from a build script). A path ending in `.urdf` is imported with the
    /// default [`model::UrdfOptions`] (use [`Builder::urdf`] to set them).
    pub fn new(description: impl Into<PathBuf>) -> Self {
        let path = description.into();
        Self::with_source(if is_urdf(&path) {
            Source::Urdf(path, Box::default())
        } else {
            Source::Toml(path)
        })
    }

    /// Generate from a model built or loaded in memory (no file is read, and
    /// [`Builder::build`] prints no `cargo:rerun-if-changed` line). The default output file is
    /// named after [`model::Model::name`]: lower case, every character other than an ASCII
    /// letter or digit `_`, plus the suffixes of [`Builder::output`].
    ///
    /// ```no_run
    /// let model = kanegen::model::Model::from_toml_file("two-link.toml")?;
    /// let generated = kanegen::Builder::from_model(model).generate()?;
    /// println!("{}", generated.source);
    /// # Ok::<(), kanegen::Error>(())
    /// ```
    pub fn from_model(robot: model::Model) -> Self {
        Self::with_source(Source::Model(Box::new(robot), Vec::new()))
    }

    /// Generate from a URDF imported in memory ([`model::UrdfImport::parse`] of a string, e.g.
    /// the output of `xacro`): like [`Builder::from_model`], and the import's notes are
    /// written into the generated file's header and summarised by [`Builder::build`] as for
    /// [`Builder::urdf`].
    ///
    /// ```no_run
    /// use kanegen::model::{UrdfImport, UrdfOptions};
    /// let text = std::fs::read_to_string("arm.urdf").unwrap();
    /// let import = UrdfImport::parse(&text, "arm.urdf", &UrdfOptions::default())?;
    /// kanegen::Builder::from_import(import).run();
    /// # Ok::<(), kanegen::Error>(())
    /// ```
    pub fn from_import(import: model::UrdfImport) -> Self {
        Self::with_source(Source::Model(Box::new(import.model), import.notes))
    }

    fn with_source(source: Source) -> Self {
        Self {
            source,
            options: Options::default(),
            output: None,
            out_dir: None,
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
            memory_limit: None,
            unoptimised_limit: crate::DEFAULT_UNOPTIMISED_LIMIT,
            gpu: None,
        }
    }

    /// The memory (bytes) the generator may use for this model (default: the process's
    /// address-space limit or the machine's memory, whichever is smaller; [`crate::available_memory`]).
    /// A model whose estimated peak ([`crate::estimate`]) is larger is the typed
    /// [`Error::TooLarge`] before anything is derived, instead of an aborted allocation.
    /// `u64::MAX` turns the check off.
    pub fn memory_limit(mut self, bytes: u64) -> Self {
        self.memory_limit = Some(bytes);
        self
    }

    /// The largest module (estimated bytes of Rust, [`crate::estimate`]) that
    /// [`Builder::build`] generates for an unoptimised build (a build script whose crate has
    /// `OPT_LEVEL=0`, cargo's default `dev` profile); a larger one is the typed
    /// [`Error::TooLarge`] naming the settings that help, before rustc spends minutes and
    /// gigabytes on it (default [`crate::DEFAULT_UNOPTIMISED_LIMIT`]; `u64::MAX` turns the
    /// check off).
    pub fn unoptimised_limit(mut self, bytes: u64) -> Self {
        self.unoptimised_limit = bytes;
        self
    }

    /// Generate from the URDF file `path` (relative to the crate's manifest directory when run
    /// from a build script), imported with `import_options` (see [`model::urdf`]): the module has the
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
    pub fn urdf(path: impl Into<PathBuf>, import_options: model::UrdfOptions) -> Self {
        Self::with_source(Source::Urdf(path.into(), Box::new(import_options)))
    }

    /// How parameters enter and which functions the module gets, both at once (default
    /// [`Options::default`]); [`Builder::baked`] and [`Builder::functions`] set one each.
    ///
    /// ```no_run
    /// use kanegen::{FunctionSet, Options, ParamMode};
    /// let options = Options { params: ParamMode::Baked, functions: FunctionSet::all() };
    /// kanegen::Builder::new("krang.toml").options(options).run();
    /// ```
    pub fn options(mut self, opts: Options) -> Self {
        self.options = opts;
        self
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
    /// line outgrows the instruction cache, e.g. Krang; see docs/regressors.md.
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
    /// with its `batch` feature (docs/runtime.md, "Build time and features"). The crate must declare the
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
    /// mirrored subtrees are unaffected. See docs/batched-and-dispatch.md, "Arms in lanes".
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").mirrored_lanes(true).run();
    /// ```
    pub fn mirrored_lanes(mut self, on: bool) -> Self {
        self.mirrored_lanes = on;
        self
    }

    /// Split generated functions of more than `statements` statements into blocks of 500
    /// (default 2,600): rustc's debug info nests a scope per `let` and
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
    /// [`LOOPED_ABOVE_FLOPS`](crate::LOOPED_ABOVE_FLOPS), such as Krang; straight-line for small models and
    /// models with mimic joints). Both forms give the same matrices to rounding (docs/derivatives.md).
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

    /// GPU kernels (default `false`): the module also gets `pub mod gpu`, every lowered
    /// function of the module ([`Builder::functions`], one kernel per frame of a per-frame
    /// function) as a WGSL compute kernel in `f32` and in `f64` (`gpu::WGSL_F32`,
    /// `gpu::WGSL_F64`), from the same straight-line programs as the Rust functions, and their
    /// layout (`gpu::MODULE`, a `kanegen_runtime::gpu::GpuModule`) for the `kanegen-gpu`
    /// crate. With the mass matrix and `nonlinear_effects`, `coriolis` and `gravity`, or
    /// `inverse_dynamics` in the set, also `forward_dynamics` and `rollout` kernels. The Rust
    /// part of the module is unchanged. See docs/gpu.md.
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").gpu(true).run();
    /// ```
    pub fn gpu(mut self, on: bool) -> Self {
        self.gpu = on.then(FunctionSet::all);
        self
    }

    /// GPU kernels ([`Builder::gpu`]) for the functions of `set` only: a function gets a
    /// kernel when it is both in the module ([`Builder::functions`]) and in `set`. The Rust
    /// functions are as [`Builder::functions`] says; `forward_dynamics` and `rollout` need the
    /// mass matrix and the velocity and gravity terms among the kernels.
    ///
    /// ```no_run
    /// use kanegen::{FunctionId as F, FunctionSet};
    /// let kernels: FunctionSet = [F::MassMatrix, F::NonlinearEffects].into_iter().collect();
    /// kanegen::Builder::new("krang.toml")
    ///     .functions(FunctionSet::default().with(F::NonlinearEffects))
    ///     .gpu_functions(kernels)
    ///     .run();
    /// ```
    pub fn gpu_functions(mut self, set: FunctionSet) -> Self {
        self.gpu = Some(set);
        self
    }

    fn emit_options(&self, notes: Vec<String>) -> EmitOptions {
        let notes_title = if notes.is_empty() {
            String::new()
        } else {
            "URDF import notes".into()
        };
        EmitOptions {
            notes,
            notes_title,
            derivatives_form: self.derivatives_form,
            precision: self.precision,
            isa_dispatch: self.isa_dispatch,
            batch: self.batch,
            batch_feature: self.batch_feature.clone(),
            mirrored_lanes: self.mirrored_lanes,
            split_above: self.split_above,
            regressor_form: self.regressor_form,
            gpu: self.gpu,
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
        match &mut self.source {
            Source::Urdf(_, urdf) => urdf.frames.push(frame),
            Source::Toml(_) | Source::Model(..) => self.frames.push(frame),
        }
        self
    }

    /// Adds a combined function: several registry functions (and frames of the per-frame ones)
    /// as one straight-line program with one result struct, computing every sine, cosine and
    /// substitution variable the parts share once (see [`Combined`]). The separate functions
    /// stay as [`Builder::functions`] says; an unknown frame or a taken name is a typed error of
    /// [`Builder::generate`].
    ///
    /// ```no_run
    /// use kanegen::{Combined, FunctionId as F};
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
    pub fn combined(mut self, function: Combined) -> Self {
        self.combined.push(function);
        self
    }

    /// Run every stage and return the result without writing or printing anything (the
    /// summary lines [`Builder::build`] would print are [`Generated::warnings`]).
    ///
    /// ```no_run
    /// let generated = kanegen::Builder::new("two-link.toml").generate()?;
    /// assert!(generated.source.contains("pub fn mass_matrix"));
    /// # Ok::<(), kanegen::Error>(())
    /// ```
    pub fn generate(&self) -> Result<Generated, Error> {
        let (mut robot, notes) = match &self.source {
            Source::Toml(path) => (model::Model::from_toml_file(path)?, Vec::new()),
            Source::Urdf(path, urdf) => {
                let import = model::UrdfImport::read(path, urdf)?;
                (import.model, import.notes)
            }
            Source::Model(robot, notes) => ((**robot).clone(), notes.clone()),
        };
        for f in &self.frames {
            robot.add_frame(f)?;
        }
        let limit = self.memory_limit.or_else(crate::available_memory);
        crate::size::check_generator_memory(&robot, &self.options, limit)?;
        if self.for_unoptimised_build() {
            crate::size::check_unoptimised_build(&robot, &self.options, self.unoptimised_limit)?;
        }
        generate_combined(
            robot,
            self.options,
            &self.combined,
            &self.emit_options(notes),
        )
    }

    /// Whether this runs in a cargo build script of a crate built without optimisation
    /// (`OPT_LEVEL=0`, with `OUT_DIR` set).
    fn for_unoptimised_build(&self) -> bool {
        std::env::var_os("OUT_DIR").is_some()
            && std::env::var("OPT_LEVEL").is_ok_and(|level| level == "0")
    }

    /// The model file's stem (`-` → `_`), or for a model in memory its name in lower case with
    /// every character other than an ASCII letter or digit `_`: the default file name's stem
    /// and the default name of a bindings crate.
    pub(crate) fn stem(&self) -> String {
        match &self.source {
            Source::Toml(path) | Source::Urdf(path, _) => path
                .file_stem()
                .map(|s| s.to_string_lossy().replace('-', "_"))
                .unwrap_or_else(|| "model".into()),
            Source::Model(robot, _) => robot
                .name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() {
                        c.to_ascii_lowercase()
                    } else {
                        '_'
                    }
                })
                .collect(),
        }
    }

    /// The floating-point type of the module.
    pub(crate) fn precision_of(&self) -> Precision {
        self.precision
    }

    /// The default output file name (see [`Builder::output`]).
    fn file_name(&self) -> String {
        let stem = self.stem();
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

    /// Generate and write the module (only if its bytes changed); returns its path.
    ///
    /// On standard output, for cargo, it prints `cargo:rerun-if-changed=FILE` for the model
    /// file and, once per build, one `cargo:warning=` line per kind of URDF import note that
    /// changes or questions the model's numbers ([`Generated::warnings`]): angles snapped to a
    /// multiple of π/2, links merged through fixed joints, non-physical, zero-mass and
    /// implausible inertias loaded, repaired or dropped, wheel constants averaged. Each line
    /// gives the count, the first three names and the option that decides it:
    ///
    /// ```text
    /// warning: arm@0.1.0: kanegen: arm.urdf: 6 angles snapped to a multiple of π/2 (joint1, joint2, joint4 and 2 more); UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written
    /// ```
    ///
    /// A line already printed by an earlier build of the same process (a build script that
    /// generates several modules from one URDF) is not repeated. Every note, one per angle or
    /// link, is in the generated file's header.
    pub fn build(&self) -> Result<PathBuf, Error> {
        let dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => PathBuf::from(std::env::var_os("OUT_DIR").ok_or(Error::NoOutDir)?),
        };
        if let Source::Toml(path) | Source::Urdf(path, _) = &self.source {
            println!("cargo:rerun-if-changed={}", path.display());
        }
        let g = self.generate()?;
        for line in warnings::not_printed_yet(g.warnings()) {
            println!("cargo:warning={line}");
        }
        let path = dir.join(self.output.clone().unwrap_or_else(|| self.file_name()));
        write_if_changed(&path, &g.source)?;
        Ok(path)
    }

    /// [`Builder::build`] (with its `cargo:warning=` summary of the URDF import), and on error
    /// fail the build with the typed error, printed once.
    ///
    /// In a cargo build script (`CARGO` and `OUT_DIR` set) the error is one
    /// `cargo::error=kanegen: …` line and the script exits with status 0: cargo reports the
    /// error once (`error: arm@0.1.0: kanegen: arm.urdf: …`) and fails the build, without the
    /// dump of the script's output that a failing exit status adds. Elsewhere it is printed to
    /// standard error (`error: kanegen: …`) and the process exits with status 1.
    pub fn run(&self) {
        if let Err(e) = self.build() {
            let message = warnings::one_line(&format!("kanegen: {e}"));
            if std::env::var_os("CARGO").is_some() && std::env::var_os("OUT_DIR").is_some() {
                println!("cargo::error={message}");
                let _ = std::io::stdout().flush();
                std::process::exit(0);
            }
            eprintln!("error: {message}");
            std::process::exit(1);
        }
    }
}
