//! What the Python and C bindings know of each generated function: its name, its state inputs,
//! whether it takes a frame, the shape of its result as a flat row-major array, and how a
//! result of that shape is written from the Rust wrapper's return value.

use crate::lower::Lowered;
use crate::registry::{FunctionSpec, Inputs, Shape};

/// One wrapped function of a generated module.
#[derive(Clone, Debug)]
pub(crate) struct Wrapped {
    /// The registry entry (name, documentation, inputs).
    pub spec: &'static FunctionSpec,
    /// The result's dimensions in the bindings: `[]` for a scalar, `[n]` for a vector, `[r, c]`
    /// for a matrix (a pose is its 4 × 4 homogeneous matrix).
    pub dims: Vec<usize>,
    /// How the Rust result is written into a row-major slice.
    pub write: Write,
}

/// How a Rust result reaches a row-major slice of `f64`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Write {
    /// A scalar: one value.
    Scalar,
    /// A symmetric matrix: its column-major storage, as is.
    Symmetric,
    /// A vector: its storage, as is.
    Vector,
    /// A general matrix, transposed from column-major to row-major.
    Matrix,
    /// An `Isometry3`, as its 4 × 4 homogeneous matrix.
    Isometry,
}

impl Wrapped {
    /// The number of values of one result.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// The state argument names, in order (`q`, `u`, `ud`).
    pub fn state_args(&self) -> &'static [&'static str] {
        match self.spec.inputs {
            Inputs::Q => &["q"],
            Inputs::QU => &["q", "u"],
            Inputs::QUUd => &["q", "u", "ud"],
        }
    }
}

/// The registry functions of `low`, once each (a per-frame function has one program per
/// frame), in the module's order.
pub(crate) fn wrapped(low: &Lowered) -> Vec<Wrapped> {
    let mut out: Vec<Wrapped> = Vec::new();
    for f in &low.functions {
        let spec = f.id.spec();
        if out.iter().any(|w| w.spec.id == f.id) {
            continue;
        }
        let (rows, cols) = spec.shape.size_in(&low.sizes);
        let (dims, write) = match spec.shape {
            Shape::Scalar => (vec![], Write::Scalar),
            Shape::Isometry => (vec![4, 4], Write::Isometry),
            Shape::SymmetricMatrix => (vec![rows, cols], Write::Symmetric),
            _ if cols == 1 => (vec![rows], Write::Vector),
            _ => (vec![rows, cols], Write::Matrix),
        };
        out.push(Wrapped { spec, dims, write });
    }
    out
}

/// A shape as Python prints it: `(19,)`, `(19, 19)`, `()`.
pub(crate) fn shape_text(dims: &[usize]) -> String {
    match dims {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            dims.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}
