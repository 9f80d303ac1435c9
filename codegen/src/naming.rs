//! How generated code names what comes from the model: identifiers, accelerations, sines and
//! cosines of coordinates, index constants, the wrapper type. Shared by the expression printer
//! of [`expr`](crate::expr) (listings) and by [`emit`](crate::emit) (Rust source), so that a
//! listing and the generated code use the same names.
//!
//! The names are defined once, in [`kanegen_model::names`], next to the validation
//! ([`Model::check_names`](kanegen_model::Model::check_names)) that keeps every model name out of
//! the names generated code binds itself (`k1`, `d1`, `t1`, `pc1`, `q`, `m`, …).

pub use kanegen_model::names::{accel, cos, index_constant, sin, type_name};

/// A model name as a Rust identifier, by the one sanitiser
/// [`sanitize_identifier`](kanegen_model::sanitize_identifier): NFC; letters of every script,
/// digits and `_` are kept, ASCII punctuation becomes `_` and other characters their code point
/// (`_u2192_`), a name that is empty or starts with a digit gets
/// a leading `_`, and a keyword gets a trailing `_`. Names of a validated model are returned
/// unchanged.
pub fn identifier(name: &str) -> String {
    kanegen_model::sanitize_identifier(name)
}
