//! The typed exceptions of a generated extension.
//!
//! Each extension module exports them under the same names (`krang_dynamics.ShapeError`), so
//! that callers can catch them specifically or as the built-in exception they derive from.

use pyo3::create_exception;
use pyo3::exceptions::{PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    kanegen,
    ParameterError,
    PyValueError,
    "A parameter name the model does not have, a value that is not finite, or a parameter set that is not physical (a non-positive mass, an inertia outside the triangle inequalities)."
);
create_exception!(
    kanegen,
    ShapeError,
    PyValueError,
    "An array argument (or `out=`) of the wrong shape, batches of different lengths, or an `out=` array that is not C-contiguous, not writable or shares memory with an input."
);
create_exception!(
    kanegen,
    DtypeError,
    PyTypeError,
    "An argument that is not a NumPy array of dtype float64."
);
create_exception!(
    kanegen,
    FrameError,
    PyKeyError,
    "A frame name (or index) the model does not have."
);

/// Adds the exception classes to the extension module `m`.
pub fn add_to(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ParameterError", py.get_type::<ParameterError>())?;
    m.add("ShapeError", py.get_type::<ShapeError>())?;
    m.add("DtypeError", py.get_type::<DtypeError>())?;
    m.add("FrameError", py.get_type::<FrameError>())?;
    Ok(())
}

/// A `ShapeError` for argument `name`: expected `expected`, got `got`.
pub fn shape_error(name: &str, expected: &[usize], got: &[usize]) -> PyErr {
    ShapeError::new_err(format!(
        "`{name}` must have shape {}, got {}",
        tuple(expected),
        tuple(got)
    ))
}

/// A shape as Python prints it: `(19,)`, `(1000, 19)`.
pub fn tuple(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}
