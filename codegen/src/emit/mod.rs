//! Emission: lowered programs → Rust source via proc-macro2/quote → syn → prettyplease.
//!
//! A pure function of its inputs ([`emit`]): the model, the lowered programs and
//! [`EmitOptions`] (precision, import notes) give the formatted source; writing files is the
//! caller's business. The generated module holds speed and parameter names, a `Params` struct
//! and a `Precomputed` struct of parameter-only terms (runtime parameters), one free function
//! per lowered registry function, a wrapper type named after the model (`Krang`) with one method
//! per function, and the `kanegen-runtime` traits it satisfies. What every module shares (the
//! batched `sin_cos_n`, `UnknownParameter`, the traits) comes from the `kanegen-runtime` crate.
//! Statements carry the reports' style comments (`let k12 = …; // w2.x`). Output is
//! deterministic byte for byte.
//!
//! Files, each depending only on files listed before it (this file collects them):
//! `print.rs` (expressions, identifiers, literals, comment text), `text.rs` (statement blocks
//! printed as text and spliced into the formatted module), `context.rs` (what every part
//! reads), `mirrored_lanes.rs` (paired statements over two lanes), `signature.rs` (argument
//! names, result types), `body.rs` (the building blocks of a function body),
//! `speed_parents.rs` (the `SPEED_PARENTS` parent array, verified on the mass matrix), the forms
//! `regressor_loop.rs`, `frames.rs` (the `Frame` type and per-frame dispatchers),
//! `function.rs` (straight-line), `derivatives_loop.rs`, `combined.rs`, `batch.rs`,
//! `regressor.rs` (the regressors' items), then `items.rs` (names, `Params`, `Precomputed`, the
//! wrapper collecting every form's methods, trait impls), `annotate.rs` (statement comments)
//! and this file (the module and its header). `wgsl/` prints the same programs as WGSL
//! compute kernels (the module's `gpu` part, on request).

mod annotate;
mod batch;
mod body;
mod combined;
mod context;
mod derivatives_loop;
mod frames;
mod function;
mod items;
mod mirrored_lanes;
mod print;
mod regressor;
mod regressor_loop;
mod signature;
mod speed_parents;
mod text;
pub mod wgsl;

use proc_macro2::TokenStream;
use quote::quote;

use crate::lower::Lowered;
use crate::options::{DerivativesForm, ParamMode, Precision, RegressorForm};
use crate::registry::FunctionId;
use context::{Context, file_name};
use kanegen_model::Model;
pub(crate) use print::comment_text;

/// The generator's version, written into every header.
pub const GENERATOR_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The generated token stream did not parse as a Rust file (a generator bug).
#[derive(Debug, thiserror::Error)]
#[error("generated code for model `{model}` does not parse: {message}")]
pub struct EmitError {
    /// Model name.
    pub model: String,
    /// syn's message.
    pub message: String,
}

/// What the emitter is told besides the model and the programs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EmitOptions {
    /// Run-time instruction-set dispatch (default `true`): every generated function is compiled
    /// for the baseline target and for x86-64-v3 (AVX2 + FMA), the batched ones also for
    /// x86-64-v4 (AVX-512), and
    /// `kanegen_runtime::isa::dispatch` runs the best copy the CPU supports (a plain call in
    /// builds without the runtime's `dispatch` feature, on other architectures and when the
    /// crate is compiled with `-C target-cpu` that has AVX2 and FMA). Off: one copy.
    pub isa_dispatch: bool,
    /// Batched functions (default `false`): `mass_matrix_batch`, `coriolis_batch`, … for `L`
    /// states per call (`f64` modules; every function whose result is a vector or matrix and
    /// that takes no frame), the single-state statements in a loop over the states, vectorized
    /// across them; each in two layouts: an array of states (`NAME_batch[_into]`) and a
    /// structure of arrays over `kanegen_runtime::lanes::Lanes` (`NAME_batch_soa[_into]`).
    pub batch: bool,
    /// With [`EmitOptions::batch`]: the name of a cargo feature of the crate that compiles the
    /// module, behind which every batched item is put (`#[cfg(feature = "NAME")]` on each
    /// batched function and method; default `None`: always compiled). See
    /// [`crate::Builder::batch_feature`].
    pub batch_feature: Option<String>,
    /// Mirrored subtrees in two SIMD lanes (default `false`): see
    /// [`crate::Builder::mirrored_lanes`]. Read by [`crate::generate_combined`], which pairs
    /// the lowered programs ([`crate::lower::mirrored_lanes::apply`]).
    pub mirrored_lanes: bool,
    /// The floating-point type of the module.
    pub precision: Precision,
    /// Lines written as comments after the header (e.g. URDF import notes: snapped angles,
    /// merged and dropped links), under the heading `notes_title`.
    pub notes: Vec<String>,
    /// Heading of the notes block (`URDF import notes`).
    pub notes_title: String,
    /// Functions with more statements than this are split into blocks of 500 (default
    /// [`SPLIT_ABOVE`]: 2,600), so that rustc's debug info does not overflow its stack on them
    /// (see [`SPLIT_ABOVE`]); `usize::MAX` never splits. Lower it if a debug build of a
    /// generated module still crashes rustc.
    pub split_above: usize,
    /// The code shape of `inverse_dynamics_regressor` and `base_regressor` (default
    /// [`RegressorForm::Auto`]). The derivation reads it ([`crate::generate_with`] passes it
    /// on): the loop form's tables are derived with the function.
    pub regressor_form: RegressorForm,
    /// How `inverse_dynamics_derivatives` is emitted (default [`DerivativesForm::Auto`]). Read
    /// by the lowering ([`crate::lower::lower_with`]): the emitter emits the looped form when
    /// [`Lowered::derivative_loop`] is `Some`.
    pub derivatives_form: DerivativesForm,
    /// GPU kernels (default `None`: none): a `pub mod gpu` after the module, with the WGSL
    /// compute kernel of every function of the module that is in the set, and their layout
    /// ([`wgsl`], [`crate::Builder::gpu`]).
    pub gpu: Option<crate::registry::FunctionSet>,
}

pub use text::SPLIT_ABOVE;

impl Default for EmitOptions {
    fn default() -> Self {
        Self {
            isa_dispatch: true,
            batch: false,
            batch_feature: None,
            mirrored_lanes: false,
            precision: Precision::default(),
            notes: Vec::new(),
            notes_title: String::new(),
            split_above: SPLIT_ABOVE,
            regressor_form: RegressorForm::default(),
            derivatives_form: DerivativesForm::default(),
            gpu: None,
        }
    }
}

/// Generate the Rust module for a lowered model. Deterministic: same input, same bytes. The
/// module needs `nalgebra` and `kanegen-runtime` (both build in `no_std` crates).
pub fn emit(model: &Model, low: &Lowered, options: &EmitOptions) -> Result<String, EmitError> {
    let cx = Context {
        model,
        low,
        precision: options.precision,
        isa_dispatch: options.isa_dispatch,
        pre: low
            .pre_slots
            .iter()
            .map(|&i| low.precompute.stmts[i].name.clone())
            .collect(),
        blocks: text::Blocks::default(),
        leaf_names: text::LeafNames::new(model),
        split_above: options.split_above,
        batch_gate: options
            .batch_feature
            .as_deref()
            .map_or_else(TokenStream::new, |name| quote!(#[cfg(feature = #name)])),
    };
    let runtime = low.params.is_runtime();
    let mut items = quote!(
        use nalgebra::{SMatrix, SVector};
    );
    if low.functions.iter().any(|f| !f.program.sincos.is_empty())
        || low.combined.iter().any(|c| !c.program.sincos.is_empty())
    {
        items.extend(match cx.precision {
            Precision::F64 => quote!(
                use kanegen_runtime::trig::sin_cos_n;
            ),
            Precision::F32 => quote!(
                use kanegen_runtime::trig::sin_cos_n_f32 as sin_cos_n;
            ),
        });
    }
    if low.lane_leaves.is_some() {
        items.extend(quote!(
            use kanegen_runtime::pair::F64x2;
        ));
    }
    items.extend(items::names(&cx));
    let mut labels = annotate::Labels::default();
    if runtime {
        items.extend(items::params(&cx));
        items.extend(items::precomputed(&cx));
        labels.add("new", &low.precompute);
    }
    items.extend(regressor::items(&cx));
    if low.functions.iter().any(|f| f.frame.is_some()) {
        items.extend(frames::frame_type(&cx));
    }
    for (i, f) in low.functions.iter().enumerate() {
        // Its statements carry their labels in their block (`text.rs`).
        match &low.derivative_loop {
            Some(looped) if f.id == FunctionId::InverseDynamicsDerivatives => {
                items.extend(derivatives_loop::function(&cx, f, looped));
            }
            _ => items.extend(function::function(&cx, f)),
        }
        items.extend(regressor_loop::straight_into(&cx, f));
        items.extend(derivatives_loop::straight_into(
            &cx,
            f,
            low.derivative_loop.is_some(),
        ));
        // After a per-frame function's last frame, its dispatcher.
        let last = low.functions.get(i + 1).is_none_or(|next| next.id != f.id);
        if f.frame.is_some() && last {
            items.extend(frames::dispatcher(&cx, f.id));
        }
    }
    for c in &low.combined {
        items.extend(combined::items(&cx, c));
        labels.add(&c.spec.name, &c.program);
    }
    let batched = options.batch && cx.precision == Precision::F64;
    if batched {
        for f in &low.functions {
            items.extend(batch::function(&cx, f));
        }
    }
    items.extend(items::wrapper(&cx, batched));
    items.extend(items::trait_impls(&cx));
    items.extend(speed_parents::kernels(&cx));
    // Model names (`MX4l`, `q_1L`) are not snake case, and straight-line code trips clippy's
    // style lints (long functions, many arguments, literal precision): one allowance for the
    // whole generated module instead of one per item.
    let module = quote! {
        pub use self::generated::*;

        #[allow(non_snake_case, clippy::all)]
        mod generated {
            #items
        }
    };
    let file: syn::File = syn::parse2(module).map_err(|e| EmitError {
        model: model.name.clone(),
        message: e.to_string(),
    })?;
    let body = prettyplease::unparse(&file);
    let mut out = header(model, low);
    if !options.notes.is_empty() {
        out.push_str(&format!("// {}:\n", options.notes_title));
        for n in &options.notes {
            out.push_str(&format!("//   - {}\n", comment_text(n)));
        }
        out.push('\n');
    }
    let body = labels.apply(&body);
    let blocks = cx.blocks.take();
    let body = text::splice(&body, &blocks).map_err(|message| EmitError {
        model: model.name.clone(),
        message,
    })?;
    out.push_str(&body);
    if let Some(set) = options.gpu {
        let kernels = wgsl::kernels(model, low, set).map_err(|e| EmitError {
            model: model.name.clone(),
            message: e.to_string(),
        })?;
        out.push_str(&wgsl::rust_module(model, &kernels));
    }
    Ok(out)
}

fn header(model: &Model, low: &Lowered) -> String {
    let mut h = format!(
        "// @generated by kanegen {GENERATOR_VERSION} from model `{}` ({}). Do not edit.\n",
        comment_text(&model.name),
        comment_text(&file_name(&model.source))
    );
    let speeds: Vec<&str> = model.speeds[..low.dof]
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    h.push_str(&format!(
        "// Parameters: {}. Speeds ({}): {}.\n",
        match low.params {
            ParamMode::Runtime => "runtime inputs (Params)",
            ParamMode::Baked => "baked in as constants",
        },
        low.dof,
        comment_text(&speeds.join(", "))
    ));
    h.push_str("// Operation counts per call:\n");
    if low.params.is_runtime() {
        h.push_str(&format!(
            "//   {:<17} {} (once per parameter set)\n",
            "Precomputed::new", low.precompute.ops
        ));
    }
    for f in &low.functions {
        let p = &f.program;
        h.push_str(&format!(
            "//   {:<17} {}; {} K and {} D variables\n",
            p.name, p.ops, p.k_vars, p.d_vars
        ));
    }
    for c in &low.combined {
        let p = &c.program;
        h.push_str(&format!(
            "//   {:<17} {}; {} K and {} D variables (combined: {})\n",
            p.name,
            p.ops,
            p.k_vars,
            p.d_vars,
            c.spec
                .parts
                .iter()
                .map(|p| p.field.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    h.push('\n');
    h
}
