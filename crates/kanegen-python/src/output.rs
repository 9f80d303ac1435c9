//! Results: a new NumPy array, or the caller's `out=` array filled in place.
//!
//! An `out=` array must have dtype `float64`, exactly the result's shape, be C-contiguous and
//! writable; it is filled entry by entry without any allocation, and returned.

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::exceptions::{ShapeError, shape_error};
use crate::input::float64;

/// Calls `fill` with the row-major values of the result of shape `shape`: the caller's `out`
/// array (checked) or a new one, which it returns.
pub fn single<'py>(
    py: Python<'py>,
    out: Option<&Bound<'py, PyAny>>,
    shape: &[usize],
    fill: impl FnOnce(&mut [f64]),
) -> PyResult<Bound<'py, PyAny>> {
    let array = target(py, out, shape)?;
    {
        let mut rw = writable(&array)?;
        let values = rw
            .as_slice_mut()
            .map_err(|_| ShapeError::new_err("`out` must be C-contiguous"))?;
        fill(values);
    }
    Ok(array.into_any())
}

/// [`single`] for a batch: `fill` runs with the GIL released (other Python threads run
/// meanwhile), so it must not touch Python objects.
pub fn batch<'py>(
    py: Python<'py>,
    out: Option<&Bound<'py, PyAny>>,
    shape: &[usize],
    fill: impl FnOnce(&mut [f64]) + Send,
) -> PyResult<Bound<'py, PyAny>> {
    let array = target(py, out, shape)?;
    {
        let mut rw = writable(&array)?;
        let values = rw
            .as_slice_mut()
            .map_err(|_| ShapeError::new_err("`out` must be C-contiguous"))?;
        py.detach(|| fill(values));
    }
    Ok(array.into_any())
}

/// The array to write: `out` after its checks, or a new zeroed array of `shape`.
fn target<'py>(
    py: Python<'py>,
    out: Option<&Bound<'py, PyAny>>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    match out {
        None => Ok(PyArrayDyn::<f64>::zeros(py, shape, false)),
        Some(obj) => {
            let array = float64(obj, "out")?;
            if array.shape() != shape {
                return Err(shape_error("out", shape, array.shape()));
            }
            if !array.is_c_contiguous() {
                return Err(ShapeError::new_err(
                    "`out` must be C-contiguous (np.empty(shape) is)",
                ));
            }
            Ok(array.clone())
        }
    }
}

/// A writable borrow of `array`: a `ShapeError` if it is read-only or an input of the same call.
fn writable<'py>(
    array: &Bound<'py, PyArrayDyn<f64>>,
) -> PyResult<numpy::PyReadwriteArrayDyn<'py, f64>> {
    array.try_readwrite().map_err(|e| {
        ShapeError::new_err(format!(
            "`out` cannot be written (read-only, or it shares memory with an input): {e}"
        ))
    })
}
