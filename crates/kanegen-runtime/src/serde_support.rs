//! `serde` for the generated `Params`, switched on by this crate's `serde` feature.
//!
//! A generated module wraps its `Params` definition in [`params_struct!`](crate::params_struct).
//! With the feature the macro adds `#[derive(Serialize, Deserialize)]` through the `serde`
//! this crate re-exports (`kanegen_runtime::serde`), with `#[serde(default,
//! deny_unknown_fields)]`: a file lists the parameters it changes (the others keep the values of
//! the model file the module was generated from), and a misspelt name is an error. Without the
//! feature the macro emits the struct unchanged. So the switch is the feature of
//! `kanegen-runtime`, not of the crate that includes the generated code: that crate neither
//! declares a feature nor depends on `serde` for it.

/// Defines a generated `Params` struct; with the `serde` feature of `kanegen-runtime` it also
/// derives `serde::Serialize` and `serde::Deserialize` (with `#[serde(default,
/// deny_unknown_fields)]`, so the struct must implement `Default`). See the
/// [module docs](crate#parameters-as-data).
#[cfg(feature = "serde")]
#[macro_export]
macro_rules! params_struct {
    ($(#[$meta:meta])* $vis:vis struct $name:ident { $($body:tt)* }) => {
        $(#[$meta])*
        #[derive($crate::serde::Serialize, $crate::serde::Deserialize)]
        #[serde(crate = "kanegen_runtime::serde", default, deny_unknown_fields)]
        $vis struct $name { $($body)* }
    };
}

/// Defines a generated `Params` struct; with the `serde` feature of `kanegen-runtime` it also
/// derives `serde::Serialize` and `serde::Deserialize` (with `#[serde(default,
/// deny_unknown_fields)]`, so the struct must implement `Default`). See the
/// [module docs](crate#parameters-as-data).
#[cfg(not(feature = "serde"))]
#[macro_export]
macro_rules! params_struct {
    ($(#[$meta:meta])* $vis:vis struct $name:ident { $($body:tt)* }) => {
        $(#[$meta])*
        $vis struct $name { $($body)* }
    };
}

/// The error of [`params_from_model_toml`]: the text is not TOML, has no `[parameters]` table,
/// or that table does not fit the `Params` (an unknown name, a value that is not a number).
#[cfg(feature = "toml")]
#[derive(Debug)]
pub struct ModelFileError(toml::de::Error);

#[cfg(feature = "toml")]
impl core::fmt::Display for ModelFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "model file parameters: {}", self.0)
    }
}

#[cfg(feature = "toml")]
impl core::error::Error for ModelFileError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        Some(&self.0)
    }
}

/// The parameter values of a model description file (its `[parameters]` table) as a generated
/// `Params`, read at run time: e.g. identified values kept in a copy of the model file. The
/// other sections of the file are not read (no derivation happens at run time; the frames and
/// joints are those the module was generated from). Parameters the table leaves out keep their
/// defaults; a name the module does not have is an error.
///
/// ```
/// # #[derive(serde::Deserialize, Default, Debug, PartialEq)]
/// # #[serde(default, deny_unknown_fields)]
/// # struct Params { g: f64, m1: f64 }
/// let text = "name = \"pendulum\"\n[parameters]\ng = 9.81\nm1 = 2\n[[frames]]\nname = \"1\"\n";
/// let p: Params = kanegen_runtime::params_from_model_toml(text)?;
/// assert_eq!(p, Params { g: 9.81, m1: 2.0 });
/// assert!(kanegen_runtime::params_from_model_toml::<Params>("[parameters]\nm7 = 1.0").is_err());
/// # Ok::<(), kanegen_runtime::ModelFileError>(())
/// ```
///
/// # Errors
/// [`ModelFileError`] if the text is not TOML, has no `[parameters]` table, or the table does
/// not deserialize into `P`.
#[cfg(feature = "toml")]
pub fn params_from_model_toml<P: serde::de::DeserializeOwned>(
    text: &str,
) -> Result<P, ModelFileError> {
    #[derive(serde::Deserialize)]
    struct ModelFile<P> {
        parameters: P,
    }
    toml::from_str::<ModelFile<P>>(text)
        .map(|f| f.parameters)
        .map_err(ModelFileError)
}
