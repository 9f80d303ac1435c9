//! Bindings for other languages, after emission: a generated module wrapped as a ready crate.
//!
//! - [`Builder::python_crate`]: a PyO3 extension crate (built by maturin as an abi3 wheel):
//!   `Cargo.toml`, `pyproject.toml`, `src/<name>_model.rs` (the generated Rust module) and
//!   `src/lib.rs` (one class named after the wrapper type; `python.rs`).
//! - [`Builder::c_crate`]: a C library crate (static and shared): `Cargo.toml`, `build.rs`
//!   (cbindgen writes `include/<name>.h`), `src/<name>_model.rs` and `src/lib.rs` (`extern "C"`
//!   functions over plain arrays; `c_abi.rs`).
//!
//! The crates include the generated source: building them runs no generator. Both need a
//! module with run-time parameters in `f64` (the default). What every Python extension shares
//! is the crate `kanegen-python`; the C crates need only `kanegen-runtime`.

mod c_abi;
mod functions;
mod manifest;
mod python;

use std::path::{Path, PathBuf};

pub use manifest::KanegenSource;

use crate::options::{ParamMode, Precision};
use crate::{Builder, Error, Generated};

/// The options of a bindings crate ([`Builder::python_crate`], [`Builder::c_crate`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BindingsOptions {
    /// The Python module (and crate) name, or the C library name and prefix of its functions
    /// (default: the model file's stem, `-` → `_`, as for [`Builder::output`]; for a model in
    /// memory its name in lower case).
    pub name: Option<String>,
    /// Where the crate takes the kanegen runtime crates from (default: the git repository).
    pub kanegen: KanegenSource,
}

/// Why a bindings crate cannot be written for a module.
#[derive(Debug, thiserror::Error)]
pub enum BindingsError {
    /// The module is not `f64` with run-time parameters.
    #[error(
        "model `{model}`: bindings wrap a module with run-time parameters in f64; remove `--baked`/`.baked(true)` and `--f32`/`.precision(Precision::F32)`"
    )]
    Unsupported {
        /// The model's name.
        model: String,
    },
    /// The model has a floating base: the bindings' arrays hold DOF coordinates per state, not
    /// NQ.
    #[error(
        "model `{model}`: bindings wrap fixed and wheeled bases only (their `q` arrays have DOF entries; a floating base has NQ = DOF + 1); generate the floating model as a Rust module (`Builder::output`) or import it with a fixed base (`UrdfBase::Fixed`, `[base] type = \"fixed\"`)"
    )]
    FloatingBase {
        /// The model's name.
        model: String,
    },
    /// The name is not a valid Python module or C identifier.
    #[error(
        "`{name}` cannot name a bindings crate: use ASCII letters, digits and `_`, not starting with a digit (e.g. `--name my_robot`)"
    )]
    BadName {
        /// The name given.
        name: String,
    },
}

/// The kinds of bindings crate.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Python,
    C,
}

impl Builder {
    /// Generates the module and writes a Python extension crate for it into `dir`: a PyO3
    /// module named `options.name` (default: the model file's stem) with one class named after
    /// the wrapper type, built with maturin (`pip install DIR`). Files are written only if
    /// their bytes changed; returns their paths. See docs/python.md.
    ///
    /// ```no_run
    /// use kanegen::bindings::{BindingsOptions, KanegenSource};
    /// let options = BindingsOptions {
    ///     name: Some("arm_dynamics".into()),
    ///     kanegen: KanegenSource::Path("../kanegen".into()),
    /// };
    /// kanegen::Builder::new("arm.urdf").python_crate("arm-python", &options)?;
    /// # Ok::<(), kanegen::Error>(())
    /// ```
    pub fn python_crate(
        &self,
        dir: impl AsRef<Path>,
        options: &BindingsOptions,
    ) -> Result<Vec<PathBuf>, Error> {
        self.bindings(dir.as_ref(), options, Kind::Python)
    }

    /// Generates the module and writes a C library crate for it into `dir`: `extern "C"`
    /// functions over plain `double` arrays, a parameter struct, the sizes as constants, a
    /// header written by cbindgen when it builds (`include/<name>.h`) and a static library
    /// (`cargo build --release` → `target/release/lib<name>.a`). Returns the written paths.
    /// See docs/c-and-cpp.md.
    ///
    /// ```no_run
    /// use kanegen::bindings::BindingsOptions;
    /// kanegen::Builder::new("arm.urdf").c_crate("arm-c", &BindingsOptions::default())?;
    /// # Ok::<(), kanegen::Error>(())
    /// ```
    pub fn c_crate(
        &self,
        dir: impl AsRef<Path>,
        options: &BindingsOptions,
    ) -> Result<Vec<PathBuf>, Error> {
        self.bindings(dir.as_ref(), options, Kind::C)
    }

    fn bindings(
        &self,
        dir: &Path,
        options: &BindingsOptions,
        kind: Kind,
    ) -> Result<Vec<PathBuf>, Error> {
        let name = options.name.clone().unwrap_or_else(|| self.stem());
        if !is_identifier(&name) {
            return Err(BindingsError::BadName { name }.into());
        }
        let g = self.generate()?;
        if g.lowered.params != ParamMode::Runtime || self.precision_of() != Precision::F64 {
            return Err(BindingsError::Unsupported {
                model: g.model.name.clone(),
            }
            .into());
        }
        if g.model.is_floating() {
            return Err(BindingsError::FloatingBase {
                model: g.model.name.clone(),
            }
            .into());
        }
        let files = match kind {
            Kind::Python => python_files(&g, &name, options, dir)?,
            Kind::C => c_files(&g, &name, options, dir)?,
        };
        let mut written = Vec::new();
        for (path, text) in files {
            let path = dir.join(path);
            crate::write_if_changed(&path, &text)?;
            written.push(path);
        }
        Ok(written)
    }
}

/// Whether `name` is an ASCII identifier (a Python module name and a C prefix).
fn is_identifier(name: &str) -> bool {
    name.chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `(path in the crate, contents)` of every file of a Python crate.
fn python_files(
    g: &Generated,
    name: &str,
    options: &BindingsOptions,
    dir: &Path,
) -> Result<Vec<(PathBuf, String)>, Error> {
    let class = crate::naming::type_name(&g.model.name);
    let rust_file = format!("{name}_model.rs");
    let frames: Vec<String> = g.model.links.iter().map(|l| l.name.clone()).collect();
    let functions = functions::wrapped(&g.lowered);
    let lib = python::lib_rs(&python::PythonModule {
        module: name,
        class: &class,
        model: &g.model.name,
        rust_file: &rust_file,
        frames: &frames,
        functions: &functions,
    });
    Ok(vec![
        (
            "Cargo.toml".into(),
            manifest::python_cargo(name, &g.model.name, &options.kanegen, dir),
        ),
        (
            "pyproject.toml".into(),
            manifest::pyproject(name, &g.model.name),
        ),
        (Path::new("src").join(&rust_file), g.source.clone()),
        ("src/lib.rs".into(), format_rust(&g.model.name, &lib)?),
    ])
}

/// `(path in the crate, contents)` of every file of a C crate.
fn c_files(
    g: &Generated,
    name: &str,
    options: &BindingsOptions,
    dir: &Path,
) -> Result<Vec<(PathBuf, String)>, Error> {
    let class = crate::naming::type_name(&g.model.name);
    let rust_file = format!("{name}_model.rs");
    let frames: Vec<String> = g.model.links.iter().map(|l| l.name.clone()).collect();
    let functions = functions::wrapped(&g.lowered);
    let module = c_abi::CModule {
        name,
        class: &class,
        model: &g.model.name,
        rust_file: &rust_file,
        frames: &frames,
        params: g.model.params.iter().map(|p| p.name.as_str()).collect(),
        dof: g.lowered.dof,
        functions: &functions,
    };
    Ok(vec![
        (
            "Cargo.toml".into(),
            manifest::c_cargo(name, &g.model.name, &options.kanegen, dir),
        ),
        ("build.rs".into(), c_abi::build_rs(name)),
        (Path::new("src").join(&rust_file), g.source.clone()),
        (
            "src/lib.rs".into(),
            format_rust(&g.model.name, &c_abi::lib_rs(&module))?,
        ),
    ])
}

/// `source` formatted by prettyplease (an [`crate::EmitError`] if it does not parse: a
/// generator bug).
fn format_rust(model: &str, source: &str) -> Result<String, Error> {
    let file = syn::parse_file(source).map_err(|e| crate::EmitError {
        model: model.to_owned(),
        message: format!("bindings: {e}"),
    })?;
    Ok(format!(
        "// @generated by kanegen {}. Do not edit.\n{}",
        crate::emit::GENERATOR_VERSION,
        prettyplease::unparse(&file)
    ))
}
