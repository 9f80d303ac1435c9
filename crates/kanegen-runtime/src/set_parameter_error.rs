//! The error of a generated `Params::set`: an unknown name, or a value the parameter cannot take.

use crate::{InvalidParameter, UnknownParameter};

/// Why a generated `Params::set(name, value)` refused: the model has no parameter `name`, or
/// `value` is not one the parameter can take on its own (not finite; a mass, wheel radius,
/// track width or wheel mass that is not positive; a wheel inertia that is negative).
///
/// Checks that involve several parameters at once (a body's inertia about its centre of mass)
/// cannot be made one value at a time; `Params::validate` makes them. Allocation-free.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SetParameterError {
    /// The model has no parameter of this name (see `Params::NAMES`).
    Unknown(UnknownParameter),
    /// The parameter exists, but the value is not physical or not finite.
    Invalid(InvalidParameter),
}

impl SetParameterError {
    /// The name that was passed to `set`.
    pub fn name(&self) -> &str {
        match self {
            Self::Unknown(e) => e.name(),
            Self::Invalid(e) => e.name(),
        }
    }
}

impl From<UnknownParameter> for SetParameterError {
    fn from(e: UnknownParameter) -> Self {
        Self::Unknown(e)
    }
}

impl From<InvalidParameter> for SetParameterError {
    fn from(e: InvalidParameter) -> Self {
        Self::Invalid(e)
    }
}

impl core::fmt::Display for SetParameterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unknown(e) => e.fmt(f),
            Self::Invalid(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for SetParameterError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Unknown(e) => Some(e),
            Self::Invalid(e) => Some(e),
        }
    }
}
