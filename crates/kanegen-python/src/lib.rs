//! What every Python extension that `kanegen python` generates shares.
//!
//! A generated extension crate holds one generated dynamics module and a PyO3 class wrapping its
//! robot type; the checks of its NumPy arguments, the writing of results into NumPy arrays and
//! the typed exceptions are here, once:
//!
//! - [`exceptions`]: `ParameterError`, `ShapeError`, `DtypeError`, `FrameError`, each a
//!   subclass of a built-in Python exception, and [`exceptions::add_to`], which exports them
//!   from the extension module.
//! - [`input`]: state arguments: a `float64` NumPy array of the expected shape, copied into a
//!   `nalgebra` vector ([`input::vector`]) or borrowed as rows of a batch ([`input::Rows`]).
//! - [`output`]: results: a new array, or the caller's `out=` array checked for shape, dtype,
//!   layout and writability and filled in place ([`output::single`], [`output::batch`], which
//!   releases the GIL while it fills).
//! - [`write`](mod@write): nalgebra results into row-major (C-order) slices.
//! - [`params`]: parameters by name and from a dict, with errors as `ParameterError`.
//!
//! Everything is safe Rust: NumPy buffers are reached only through the `numpy` crate's borrow
//! checking, so an `out=` array that shares memory with an input is refused with an exception
//! instead of being read and written at once.
#![forbid(unsafe_code)]

pub mod exceptions;
pub mod input;
pub mod output;
pub mod params;
pub mod write;

pub use nalgebra;
pub use numpy;
pub use pyo3;
