//! kanegen: a build-time symbolic Kane's-method code generator for robot dynamics.
//!
//! Stages, one module each, dependencies one way only:
//! [`model`] (description files → validated IR) → [`expr`] (hash-consed expression arena) →
//! [`kane`] (recursive Kane's derivation with K/D substitution) → [`lower`] (straight-line
//! programs, dead-code elimination, op counts) → [`emit`] (quote/syn/prettyplease → Rust source).
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
//!
//! Any robot described in URDF works the same way ([`Builder::urdf`], options in
//! [`model::UrdfOptions`]):
//!
//! ```no_run
//! // build.rs
//! kanegen::Builder::urdf("robot.urdf", kanegen::model::UrdfOptions::default()).run();
//! ```
#![forbid(unsafe_code)]

pub mod emit;
pub mod expr;
pub mod kane;
pub mod lower;
pub mod trig;
/// The robot description IR and its loaders (re-exported from `kanegen-model`).
pub mod model {
    pub use kanegen_model::*;
}

use std::path::{Path, PathBuf};

pub use emit::Scalar;
pub use kane::{Options, ParamMode};

/// Anything that can go wrong while generating.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The description file is malformed or not physical.
    #[error(transparent)]
    Model(#[from] model::ModelError),
    /// Code emission or writing failed.
    #[error(transparent)]
    Emit(#[from] emit::EmitError),
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

/// Run every stage on a loaded model.
pub fn generate_model(model: model::Model, options: Options) -> Result<Generated, Error> {
    let derivation = kane::derive(&model, options);
    let lowered = lower::lower(&derivation);
    let source = emit::emit(&model, &lowered)?;
    Ok(Generated {
        model,
        derivation,
        lowered,
        source,
    })
}

/// Import a URDF file and run every stage. The import notes (snapped angles, merged and dropped
/// links, wheel constants) are written as comments after the generated file's header.
pub fn generate_urdf(
    path: impl AsRef<Path>,
    urdf: &model::UrdfOptions,
    options: Options,
) -> Result<Generated, Error> {
    let import = model::UrdfImport::read(path, urdf)?;
    let mut g = generate_model(import.model, options)?;
    if !import.notes.is_empty() {
        let mut notes = String::from("// URDF import notes:\n");
        for n in &import.notes {
            notes.push_str(&format!("//   - {n}\n"));
        }
        notes.push('\n');
        // After the header (which ends at the first blank line).
        let at = g.source.find("\n\n").map_or(0, |i| i + 2);
        g.source.insert_str(at, &notes);
    }
    Ok(g)
}

/// Load a description file and run every stage.
pub fn generate(path: impl AsRef<Path>, options: Options) -> Result<Generated, Error> {
    let model = model::Model::from_toml_file(path)?;
    generate_model(model, options)
}

/// Generates a dynamics module from a build script.
///
/// ```no_run
/// kanegen::Builder::new("models/krang.toml")
///     .baked(false)
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
    scalar: Scalar,
}

impl Builder {
    /// Generate from the description file `model` (relative to the crate's manifest directory
    /// when run from a build script).
    pub fn new(model: impl Into<PathBuf>) -> Self {
        Self {
            model: model.into(),
            options: Options::default(),
            output: None,
            out_dir: None,
            urdf: None,
            scalar: Scalar::F64,
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

    /// Whether the module has `coriolis_matrix`, the Coriolis matrix C(q, u) with
    /// `c = C u` and `Ṁ − 2C` skew-symmetric (default `true`, so that every generated module
    /// has the same API). It is about four times the operations of `coriolis` and roughly
    /// doubles the compile time of a large model's module (Krang: ≈ 9,500 flops, +3 s of
    /// release compilation per module); build scripts that need only M, c, g and τ can leave it
    /// out:
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").coriolis_matrix(false).run();
    /// ```
    pub fn coriolis_matrix(mut self, on: bool) -> Self {
        self.options.coriolis_matrix = on;
        self
    }

    /// The scalar type of the generated module (default [`Scalar::F64`]). With
    /// [`Scalar::F32`] every matrix, vector, `Params` field and literal is `f32`, and the
    /// default file name gets the suffix `_f32.rs`:
    ///
    /// ```no_run
    /// kanegen::Builder::new("krang.toml").scalar(kanegen::Scalar::F32).run(); // krang_f32.rs
    /// ```
    pub fn scalar(mut self, scalar: Scalar) -> Self {
        self.scalar = scalar;
        self
    }

    /// Name of the generated file in the output directory (default: the model file's stem
    /// plus `.rs`, or `_baked.rs` in baked mode; `_f32.rs`, `_baked_f32.rs` for
    /// [`Scalar::F32`]).
    pub fn output(mut self, file_name: impl Into<String>) -> Self {
        self.output = Some(file_name.into());
        self
    }

    /// Write into `dir` instead of `$OUT_DIR`.
    pub fn out_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Generate and write the module (only if its bytes changed); returns its path. Prints the
    /// `cargo:rerun-if-changed` line for the model file.
    pub fn build(&self) -> Result<PathBuf, Error> {
        let dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => PathBuf::from(std::env::var_os("OUT_DIR").ok_or(Error::NoOutDir)?),
        };
        println!("cargo:rerun-if-changed={}", self.model.display());
        let mut g = match &self.urdf {
            Some(urdf) => generate_urdf(&self.model, urdf, self.options)?,
            None => generate(&self.model, self.options)?,
        };
        if self.scalar != Scalar::F64 {
            // Re-emit, keeping any URDF import notes (the block after the header).
            let at = g.source.find("\n\n").map_or(0, |i| i + 2);
            let notes = if g.source[at..].starts_with("// URDF import notes:\n") {
                let end = g.source[at..]
                    .find("\n\n")
                    .map_or(g.source.len(), |i| at + i + 2);
                g.source[at..end].to_owned()
            } else {
                String::new()
            };
            let mut source = emit::emit_scalar(&g.model, &g.lowered, self.scalar)?;
            let at = source.find("\n\n").map_or(0, |i| i + 2);
            source.insert_str(at, &notes);
            g.source = source;
        }
        let name = self.output.clone().unwrap_or_else(|| {
            let stem = self
                .model
                .file_stem()
                .map(|s| s.to_string_lossy().replace('-', "_"))
                .unwrap_or_else(|| "model".into());
            let suffix = match self.scalar {
                Scalar::F64 => "",
                Scalar::F32 => "_f32",
            };
            match self.options.params {
                ParamMode::Runtime => format!("{stem}{suffix}.rs"),
                ParamMode::Baked => format!("{stem}_baked{suffix}.rs"),
            }
        });
        let path = dir.join(name);
        emit::write_if_changed(&path, &g.source)?;
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

/// A per-function summary: K/D counts and op counts, as printed by `kanegen stats`.
pub fn stats(g: &Generated) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let d = &g.derivation;
    let k = d
        .arena
        .vars()
        .iter()
        .filter(|v| v.kind == expr::VarKind::K)
        .count();
    let dv = d.arena.vars().len() - k;
    let _ = writeln!(
        s,
        "model {} ({}): {} speeds, {} bodies, {} parameters; parameters {}",
        g.model.name,
        g.model.source,
        g.model.dof(),
        g.model.body_count(),
        g.model.params.len(),
        match d.options.params {
            ParamMode::Runtime => "at run time",
            ParamMode::Baked => "baked",
        }
    );
    let _ = writeln!(
        s,
        "derivation: {} expression nodes, {} substitution variables ({} K, {} D)",
        d.arena.len(),
        d.arena.vars().len(),
        k,
        dv
    );
    let _ = writeln!(
        s,
        "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6}",
        "function", "K", "D", "temps", "adds", "muls", "divs", "sin/cos", "flops", "live"
    );
    let low = &g.lowered;
    let mut row = |name: &str, p: &lower::Program| {
        let temps = p.stmts.len() - p.k_vars - p.d_vars;
        let _ = writeln!(
            s,
            "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6}",
            name,
            p.k_vars,
            p.d_vars,
            temps,
            p.ops.adds,
            p.ops.muls,
            p.ops.divs,
            p.ops.sincos,
            p.ops.flops(),
            p.max_live()
        );
    };
    if d.options.params == ParamMode::Runtime {
        row("precompute (once)", &low.precompute);
    }
    for p in &low.functions {
        row(&p.name, p);
    }
    s
}

/// The substitution listing of a model in the reports' style, function by function.
pub fn listing(g: &Generated) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "% Substitution listing of `{}` (kanegen {}). K: kinematic, D: inertial/gravity.",
        g.model.name,
        emit::GENERATOR_VERSION
    );
    let d = &g.derivation;
    let mut shown = vec![false; d.arena.vars().len()];
    for f in &d.functions {
        let roots: Vec<expr::ExprId> = f.entries.iter().map(|e| e.2).collect();
        let needed = d.arena.reachable_vars(&roots);
        let _ = writeln!(s, "\n% ---- {} ----", f.name);
        for (i, info) in d.arena.vars().iter().enumerate() {
            if needed[i] && !shown[i] {
                shown[i] = true;
                let _ = writeln!(
                    s,
                    "{} = {};  % {}",
                    d.arena.atom_name(expr::Atom::Var(i as u32)),
                    d.arena.display(info.def),
                    info.label
                );
            }
        }
        for &(r, c, e) in &f.entries {
            let lhs = match f.shape {
                kane::Shape::SymmetricMatrix => format!("M({},{})", r + 1, c + 1),
                kane::Shape::Matrix => format!("C({},{})", r + 1, c + 1),
                kane::Shape::Vector => format!("{}({})", f.name, r + 1),
            };
            let _ = writeln!(s, "{lhs} = {};", d.arena.display(e));
        }
    }
    s
}
