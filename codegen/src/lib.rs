//! kanegen: a build-time symbolic Kane's-method code generator for robot dynamics.
//!
//! Stages, one module each, dependencies one way only:
//! [`model`] (description files → validated IR) → [`expr`] (hash-consed expression arena) →
//! [`kane`] (recursive Kane's derivation with K/D substitution) → [`lower`] (straight-line
//! programs, dead-code elimination, op counts) → [`emit`] (quote/syn/prettyplease → Rust source).
#![forbid(unsafe_code)]

pub mod expr;
pub mod kane;
/// The robot description IR and its loaders (re-exported from `kanegen-model`).
pub mod model {
    pub use kanegen_model::*;
}
