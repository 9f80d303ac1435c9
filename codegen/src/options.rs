//! What a generated module looks like: how parameters enter, which functions it has, and its
//! floating-point precision. Decided once (by [`Builder`](crate::Builder) or the CLI) and read by
//! every stage.

use crate::registry::{FunctionId, FunctionSet};

/// How model parameters enter the generated code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ParamMode {
    /// Parameters are runtime inputs (a `Params` value); parameter-only subexpressions are
    /// computed once per parameter set, outside the hot path.
    #[default]
    Runtime,
    /// The model file's values are folded in as constants; terms of zero parameters vanish.
    Baked,
}

impl ParamMode {
    /// Whether parameters are runtime inputs.
    pub fn is_runtime(self) -> bool {
        self == ParamMode::Runtime
    }
}

/// The floating-point type of a generated module: every matrix, vector, parameter and literal
/// is of this type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// `f64` (the default).
    #[default]
    F64,
    /// `f32`, sines and cosines included (`kanegen_runtime::trig::sin_cos_n_f32`).
    F32,
}

/// The code shape of `inverse_dynamics_regressor` and `base_regressor` (see docs/regressors.md); chosen
/// with
/// [`Builder::regressor_form`](crate::Builder::regressor_form).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RegressorForm {
    /// The loop form for models without mimic joints with at least 40 (speed, body) pairs
    /// (where the straight line outgrows the instruction cache), the straight line otherwise.
    #[default]
    Auto,
    /// One straight-line program per function (every entry its own derivative chain).
    StraightLine,
    /// Per-link motion straight-line, the (speed, body) pairs as a loop over a constant table
    /// (`kanegen_runtime::regressor`). Models with mimic joints keep the straight line.
    Loop,
}

/// How `inverse_dynamics_derivatives` is emitted
/// ([`Builder::derivatives_form`](crate::Builder::derivatives_form)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DerivativesForm {
    /// [`DerivativesForm::Looped`] when the model allows it and the straight-line form has more
    /// than [`LOOPED_ABOVE_FLOPS`] flops (its code would not fit a 32 KB instruction cache),
    /// else [`DerivativesForm::StraightLine`] (the default).
    #[default]
    Auto,
    /// One straight-line program (every (column, ancestor) step unrolled).
    StraightLine,
    /// Per-link and per-column quantities straight-line into a workspace, then the
    /// O(columns × ancestors) steps as a loop over generated tables
    /// (`kanegen_runtime::derivatives_loop`). Models with mimic joints keep the straight-line
    /// form (the tables do not express the constraint's sums).
    Looped,
}

/// [`DerivativesForm::Auto`] loops above this many flops of the straight-line form: about
/// 32 KB of x86-64 code, the size of a level-1 instruction cache (straight-line derivative
/// code takes about 16 bytes per flop: Krang's 14,728 flops are 233 KB).
pub const LOOPED_ABOVE_FLOPS: usize = 2_000;

/// Generator options: what the derivation, the lowering and the emitter produce.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// How parameters enter.
    pub params: ParamMode,
    /// Which registry functions the module gets (default: [`FunctionSet::default`]). The
    /// Coriolis matrix costs about four times the operations of `coriolis` (Krang: ≈ 7,900
    /// flops) and roughly doubles the compile time of a large model's module; leave it out when
    /// only M, c, g and τ are needed.
    pub functions: FunctionSet,
}

impl Options {
    /// Whether the module gets function `f`.
    pub fn has(&self, f: FunctionId) -> bool {
        self.functions.contains(f)
    }
}
