//! Parameters by name and from a dict: the generated class's parameter methods call these with
//! closures over its `Params`.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyDictMethods};

use crate::exceptions::ParameterError;

/// A `ParameterError` with the message of `e` (a `SetParameterError` or `InvalidParameter`).
pub fn error(e: impl std::fmt::Display) -> PyErr {
    ParameterError::new_err(e.to_string())
}

/// The `(name, value)` pairs of `dict`: string keys and float values, else a `ParameterError`.
pub fn pairs(dict: &Bound<'_, PyDict>) -> PyResult<Vec<(String, f64)>> {
    dict.iter()
        .map(|(k, v)| {
            let name: String = k.extract().map_err(|_| {
                ParameterError::new_err(format!("parameter names are strings, got {k}"))
            })?;
            let value: f64 = v.extract().map_err(|_| {
                ParameterError::new_err(format!("parameter `{name}` needs a number, got {v}"))
            })?;
            Ok((name, value))
        })
        .collect()
}

/// A dict of `names` and `values`, in order.
pub fn dict<'py>(py: Python<'py>, names: &[&str], values: &[f64]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (n, v) in names.iter().zip(values) {
        d.set_item(n, v)?;
    }
    Ok(d)
}

/// The index of the frame `frame` (a name of `names` or an index into it), else a `FrameError`.
pub fn frame(frame: &Bound<'_, PyAny>, names: &[&str]) -> PyResult<usize> {
    if let Ok(i) = frame.extract::<usize>() {
        if i < names.len() {
            return Ok(i);
        }
    } else if let Ok(name) = frame.extract::<String>()
        && let Some(i) = names.iter().position(|n| *n == name)
    {
        return Ok(i);
    }
    Err(crate::exceptions::FrameError::new_err(format!(
        "no frame {frame} (the frames: FRAME_NAMES, or an index below {})",
        names.len()
    )))
}
