//! `serde` for the generated `Params`, switched on by this crate's `serde` feature.
//!
//! A generated module invokes [`params_serde!`](crate::params_serde) after its `Params`. With
//! the feature the macro implements `Serialize` (a map from parameter name to value, in the
//! order of `Params::NAMES`) and `Deserialize` (from such a map: names left out keep their
//! defaults, an unknown name or a value `set` refuses is an error) through the `serde` this crate re-exports, using only
//! `NAMES`, `to_array`, `set` and `Default` of the generated `Params`. Without the feature the
//! macro expands to nothing. So the switch is the feature of `kanegen-runtime`, not of the crate
//! that includes the generated code: that crate neither declares a feature nor depends on
//! `serde` for it.

/// Implements `serde::Serialize` and `serde::Deserialize` for a generated `Params` (with
/// scalar `f64` or `f32`) when `kanegen-runtime`'s `serde` feature is on; nothing otherwise.
/// See the [crate docs](crate#parameters-as-data).
#[cfg(feature = "serde")]
#[macro_export]
macro_rules! params_serde {
    ($params:ident, $scalar:ty) => {
        impl $crate::serde::Serialize for $params {
            fn serialize<S: $crate::serde::Serializer>(
                &self,
                serializer: S,
            ) -> ::core::result::Result<S::Ok, S::Error> {
                $crate::serde_support::serialize(&Self::NAMES, &self.to_array(), serializer)
            }
        }

        impl<'de> $crate::serde::Deserialize<'de> for $params {
            fn deserialize<D: $crate::serde::Deserializer<'de>>(
                deserializer: D,
            ) -> ::core::result::Result<Self, D::Error> {
                let mut params = <Self as ::core::default::Default>::default();
                $crate::serde_support::deserialize::<$scalar, D>(
                    &Self::NAMES,
                    deserializer,
                    |name, value| params.set(name, value),
                )?;
                ::core::result::Result::Ok(params)
            }
        }
    };
}

/// Implements `serde::Serialize` and `serde::Deserialize` for a generated `Params` (with
/// scalar `f64` or `f32`) when `kanegen-runtime`'s `serde` feature is on; nothing otherwise.
/// See the [crate docs](crate#parameters-as-data).
#[cfg(not(feature = "serde"))]
#[macro_export]
macro_rules! params_serde {
    ($params:ident, $scalar:ty) => {};
}

/// `values` as a map from `names` (the body of a generated `Params`' `Serialize`).
#[cfg(feature = "serde")]
pub fn serialize<T: serde::Serialize, S: serde::Serializer>(
    names: &[&str],
    values: &[T],
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = serializer.serialize_map(Some(names.len()))?;
    for (name, value) in names.iter().zip(values) {
        map.serialize_entry(name, value)?;
    }
    map.end()
}

/// Reads a map from parameter names (each one of `names`, or an `unknown field` error) to
/// values and hands each pair to `set` (the body of a generated `Params`' `Deserialize`); a value
/// `set` refuses (not finite, not physical) is a custom error that names the parameter.
/// Allocation-free: keys are matched as they are read.
#[cfg(feature = "serde")]
pub fn deserialize<'de, T, D>(
    names: &'static [&'static str],
    deserializer: D,
    set: impl FnMut(&'static str, T) -> Result<(), crate::SetParameterError>,
) -> Result<(), D::Error>
where
    T: serde::Deserialize<'de>,
    D: serde::Deserializer<'de>,
{
    use core::marker::PhantomData;
    use serde::de::{DeserializeSeed, Error, MapAccess, Visitor};

    /// A key: the index of its name in `names`.
    struct Key(&'static [&'static str]);
    impl<'de> DeserializeSeed<'de> for Key {
        type Value = usize;
        fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
            d.deserialize_str(self)
        }
    }
    impl Visitor<'_> for Key {
        type Value = usize;
        fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            f.write_str("a parameter name")
        }
        fn visit_str<E: Error>(self, name: &str) -> Result<usize, E> {
            self.0
                .iter()
                .position(|n| *n == name)
                .ok_or_else(|| E::unknown_field(name, self.0))
        }
    }

    struct Table<T, F>(&'static [&'static str], F, PhantomData<T>);
    impl<'de, T, F> Visitor<'de> for Table<T, F>
    where
        T: serde::Deserialize<'de>,
        F: FnMut(&'static str, T) -> Result<(), crate::SetParameterError>,
    {
        type Value = ();
        fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            f.write_str("a table of parameter values by name")
        }
        fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<(), A::Error> {
            while let Some(i) = map.next_key_seed(Key(self.0))? {
                let value = map.next_value::<T>()?;
                (self.1)(self.0[i], value).map_err(A::Error::custom)?;
            }
            Ok(())
        }
    }

    deserializer.deserialize_map(Table(names, set, PhantomData))
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
