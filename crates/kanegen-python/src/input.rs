//! State arguments: NumPy arrays of dtype `float64` and the expected shape.

use nalgebra::SVector;
use numpy::{PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray};
use numpy::{PyUntypedArrayMethods, dtype};
use pyo3::prelude::*;

use crate::exceptions::{DtypeError, ShapeError, shape_error};

/// `obj` as a `float64` array, or a `DtypeError` naming the argument `name`.
pub fn float64<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    name: &str,
) -> PyResult<&'a Bound<'py, PyArrayDyn<f64>>> {
    let Ok(untyped) = obj.cast::<PyUntypedArray>() else {
        let ty = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default();
        return Err(DtypeError::new_err(format!(
            "`{name}` must be a NumPy array of dtype float64, got `{ty}` (convert it with np.asarray(x, dtype=np.float64))"
        )));
    };
    let found = untyped.dtype();
    if !found.is_equiv_to(&dtype::<f64>(obj.py())) {
        return Err(DtypeError::new_err(format!(
            "`{name}` must have dtype float64, got {found}"
        )));
    }
    obj.cast::<PyArrayDyn<f64>>()
        .map_err(|_| DtypeError::new_err(format!("`{name}` must have dtype float64")))
}

/// A read-only borrow of `array`, or a `ShapeError` if a writer holds it (an `out=` array of
/// the same call).
pub fn borrow<'py>(
    array: &Bound<'py, PyArrayDyn<f64>>,
    name: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    array.try_readonly().map_err(|e| {
        ShapeError::new_err(format!("`{name}` cannot be read while it is written: {e}"))
    })
}

/// The vector argument `name` of length `N` (a 1-D `float64` array of any strides), copied.
pub fn vector<const N: usize>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<SVector<f64, N>> {
    let array = float64(obj, name)?;
    if array.shape() != [N] {
        return Err(shape_error(name, &[N], array.shape()));
    }
    let view = borrow(array, name)?;
    Ok(match view.as_slice() {
        Ok(s) => SVector::from_column_slice(s),
        Err(_) => SVector::from_iterator(view.as_array().iter().copied()),
    })
}

/// The rows of a batch argument: a C-contiguous `float64` array of shape `(n, cols)`,
/// borrowed read-only.
pub struct Rows<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
    /// The number of rows (states) n.
    pub n: usize,
}

impl<'py> Rows<'py> {
    /// The batch argument `name` with rows of `cols` values; `n`, if given, the number of rows
    /// it must have (the first batch argument's).
    pub fn new(
        obj: &Bound<'py, PyAny>,
        name: &str,
        cols: usize,
        n: Option<usize>,
    ) -> PyResult<Self> {
        let array = float64(obj, name)?;
        let shape = array.shape();
        let rows = match (shape, n) {
            ([rows, c], None) if *c == cols => *rows,
            ([rows, c], Some(n)) if *c == cols && *rows == n => n,
            _ => {
                let expected = n.map_or("n".to_string(), |n| n.to_string());
                return Err(ShapeError::new_err(format!(
                    "`{name}` must have shape ({expected}, {cols}), got {}",
                    crate::exceptions::tuple(shape)
                )));
            }
        };
        // `as_slice` also accepts Fortran order, whose rows are not consecutive.
        if !array.is_c_contiguous() {
            return Err(ShapeError::new_err(format!(
                "`{name}` must be C-contiguous (np.ascontiguousarray(x))"
            )));
        }
        let array = borrow(array, name)?;
        Ok(Self { array, n: rows })
    }

    /// The values, row after row (`n × cols`).
    pub fn values(&self) -> &[f64] {
        // Checked C-contiguous in `new`.
        self.array.as_slice().unwrap_or(&[])
    }
}
