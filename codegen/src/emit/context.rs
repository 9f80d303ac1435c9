//! What every part of the emitter reads ([`Context`]: the model, the lowered programs, the
//! precision, the text blocks) and the small helpers all forms share.

use std::path::Path;

use proc_macro2::TokenStream;
use quote::quote;

use super::print::Printer;
use super::text::{Blocks, LeafNames};
use crate::lower::Lowered;
use crate::options::Precision;
use kanegen_model::Model;

/// What every part of the emitter reads.
pub(crate) struct Context<'a> {
    pub(super) model: &'a Model,
    pub(super) low: &'a Lowered,
    pub(super) precision: Precision,
    /// See [`EmitOptions::isa_dispatch`].
    pub(super) isa_dispatch: bool,
    /// Field names of the precomputed values, by slot.
    pub(super) pre: Vec<String>,
    /// The statement blocks of the functions, spliced in after formatting (`text.rs`).
    pub(super) blocks: Blocks,
    /// The model's leaves as printed in statement blocks.
    pub(super) leaf_names: LeafNames,
    /// See [`EmitOptions::split_above`].
    pub(super) split_above: usize,
    /// `#[cfg(feature = "…")]` before every batched item ([`EmitOptions::batch_feature`]), or
    /// nothing.
    pub(super) batch_gate: TokenStream,
}

impl Context<'_> {
    /// The expression printer for a program's statements `stmts`.
    pub(super) fn printer<'p>(&'p self, stmts: &'p [crate::lower::Stmt]) -> Printer<'p> {
        Printer {
            model: self.model,
            stmts,
            pre: &self.pre,
            precision: self.precision,
            lane: None,
        }
    }
}

pub(super) fn scalar_type(precision: Precision) -> TokenStream {
    match precision {
        Precision::F64 => quote!(f64),
        Precision::F32 => quote!(f32),
    }
}

pub(super) fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_owned())
}
