//! The looped form of `inverse_dynamics_derivatives` (`kane/derivatives_loop.rs`): the
//! straight-line statements fill a workspace array, then
//! `kanegen_runtime::derivatives_loop::run` walks the generated tables (a `const` next to the
//! function) and writes the result.

use proc_macro2::TokenStream;
use quote::quote;

use super::body::{
    Reads, Stores, nonzero_outputs, param_args, prologue, state_args, store_text_after, text,
    unused_inputs,
};
use super::context::{Context, scalar_type};
use super::print::{ident, idx, lit};
use crate::kane::DerivativeLoop;
use crate::lower::{FunctionProgram, LExpr, LoopedProgram};

/// The name of the tables' `const`.
const TABLES: &str = "INVERSE_DYNAMICS_DERIVATIVES_STEPS";

/// The workspace type kept across calls of the derivatives (every module with them has one).
const WORKSPACE: &str = "DerivativesWorkspace";

/// The tables as a `kanegen_runtime::derivatives_loop::Plan` constant.
fn tables(plan: &DerivativeLoop) -> TokenStream {
    let u16_of = |x: usize| {
        let v = u16::try_from(x).expect("`lower_with` checked that the tables fit u16");
        proc_macro2::Literal::u16_unsuffixed(v)
    };
    let u32_of = |x: usize| {
        let v = u32::try_from(x).expect("`lower_with` checked that the tables fit u32");
        proc_macro2::Literal::u32_unsuffixed(v)
    };
    let (flat_columns, flat_steps) = plan.flatten();
    let steps = flat_steps.iter().map(|s| {
        let speed = plan.speeds[s.speed];
        let transform = match s.transform {
            Some(t) => {
                let t = u16_of(t);
                quote!(#t)
            }
            None => quote!(kanegen_runtime::derivatives_loop::NO_TRANSFORM),
        };
        let (m, j) = match (s.root, plan.floating_root) {
            (true, Some(root)) => (u16_of(root), false),
            _ => (u16_of(speed.motion), speed.joint),
        };
        let axis = match speed.axis {
            _ if s.root => quote!(kanegen_runtime::derivatives_loop::FLOATING_ROOT),
            Some(k) => {
                let k = proc_macro2::Literal::u8_unsuffixed(k);
                quote!(#k)
            }
            None => quote!(kanegen_runtime::derivatives_loop::DENSE),
        };
        let entries = s.entries.map(|e| match e {
            Some(e) => {
                let e = u32_of(e);
                quote!(#e)
            }
            None => quote!(kanegen_runtime::derivatives_loop::NO_ENTRY),
        });
        quote!(kanegen_runtime::derivatives_loop::Step {
            transform: #transform, motion: #m, axis: #axis, joint: #j, entries: [#(#entries),*]
        })
    });
    let columns = flat_columns.iter().map(|c| {
        let (f, a, o, e) = (
            u16_of(c.forces),
            u32_of(c.first),
            u32_of(c.own),
            u32_of(c.end),
        );
        quote!(kanegen_runtime::derivatives_loop::Column { forces: #f, first: #a, own: #o, end: #e })
    });
    let name = ident(TABLES);
    let dof = idx(plan.dof);
    let doc = format!(
        " The tables of `inverse_dynamics_derivatives`'s loop: {} links, {} speeds, {} columns, {} steps up, {} reads; a workspace of {} values.",
        plan.links.len(),
        plan.speeds.len(),
        plan.columns.len(),
        plan.steps(),
        flat_steps.len(),
        plan.workspace
    );
    quote! {
        #[doc = #doc]
        const #name: kanegen_runtime::derivatives_loop::Plan<'static> =
            kanegen_runtime::derivatives_loop::Plan {
                dof: #dof,
                columns: &[#(#columns),*],
                steps: &[#(#steps),*],
            };
    }
}

/// The free function `inverse_dynamics_derivatives` in its looped form, and its tables.
pub(super) fn function(
    cx: &Context<'_>,
    f: &FunctionProgram,
    looped: &LoopedProgram,
) -> TokenStream {
    let spec = f.id.spec();
    let p = &looped.program;
    let printer = cx.printer(&p.stmts);
    let reads = Reads::of(p, cx.model.speeds.len());
    let fname = ident(spec.name);
    let doc = format!(" {}", spec.doc);
    let ops = format!(
        " Generated code: {} straight-line (per link and per column, into a workspace of {} values), then a loop of {} steps over `{TABLES}` (`kanegen_runtime::derivatives_loop::run`, {} flops).",
        p.ops,
        looped.plan.workspace,
        looped.plan.steps(),
        looped.plan.flops()
    );
    let param_args = param_args(cx, &reads);
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let prologue = prologue(cx, p, &reads);
    let mut stores: Stores = vec![Vec::new(); p.stmts.len() + 1];
    for (k, _, e) in nonzero_outputs(p) {
        let v = text(cx, &printer, e);
        store_text_after(&mut stores, e, format!("w[{k}] = {v};"));
    }
    let stored: Vec<&LExpr> = nonzero_outputs(p).map(|(_, _, e)| e).collect();
    let lanes = super::body::lanes_in(cx, p, looped.lanes.as_ref());
    let block = match lanes {
        Some((leaves, plan)) => {
            super::mirrored_lanes::lane_block(&printer, &cx.leaf_names, leaves, p, plan, stores)
        }
        None => {
            printer.statement_block(&cx.leaf_names, stores, (&stored, &[]), cx.split_above, true)
        }
    };
    let lanes = lanes.is_some();
    let body = cx.blocks.placeholder(block);
    let unused = unused_inputs(spec.inputs, p, &reads);
    let t = scalar_type(cx.precision);
    let zero = lit(0.0, cx.precision);
    let len = idx(looped.plan.workspace);
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (rows, cols) = (idx(rows), idx(cols));
    let tables_name = ident(TABLES);
    // f64: the dispatched kernel (AVX2 copy); other precisions: the portable one.
    let run = match cx.precision {
        crate::options::Precision::F64 => quote!(kanegen_runtime::derivatives_loop::run),
        crate::options::Precision::F32 => quote!(kanegen_runtime::derivatives_loop::run_generic),
    };
    let body = quote! {
        #unused
        #prologue
        #body
        #run(&#tables_name, &w[..], m.as_mut_slice());
    };
    let mat = quote!(SMatrix<#t, #rows, #cols>);
    // The body generic over the multiply-add (fused in the x86-64-v3 copy), writing into `m`.
    // With the arms in lanes (Krang) an x86-64-v4 copy too, unlike the other single-state
    // functions: its long straight-line part gains from the 32 registers (4 % on Krang,
    // Nov 2026, Intel Xeon with AVX-512); models without lanes were not measured.
    let (outer_params, pass_params) = super::body::outer_params(cx);
    let state = super::signature::arg_names(spec.inputs);
    let call = super::body::call_body_into(
        cx,
        if lanes {
            super::body::Copies::LanesWithV4
        } else {
            super::body::Copies::BaselineAndV3
        },
        quote!(),
        quote!(#pass_params #state,),
        quote!((w, m)),
    );
    let call = quote!(#call;);
    let tables = tables(&looped.plan);
    let (generics, lanes_arg) = super::body::body_generics(cx, lanes);
    let into = ident(&format!("{}_into", spec.name));
    let onto = ident(&format!("{}_onto", spec.name));
    let into_doc = format!(
        " [`{}`] written into `m` (every entry; no copy of the result: the form for a caller that keeps its matrix).",
        spec.name
    );
    let onto_doc = format!(
        " The entries of [`{}`] written into `m`, whose other entries are zero (the structural zeros are not written), through the workspace `w`, whose slots the statements write before the loop reads them (those never written stay zero): the by-value function passes a new zero matrix and workspace, so that the result is built where the caller keeps it rather than copied out; [`{WORKSPACE}`] keeps both across calls.",
        spec.name
    );
    let workspace = workspace(
        cx,
        f,
        (&mat, Some(&len), &zero),
        quote!(#onto(#pass_params #state, &mut self.w, &mut self.m)),
    );
    quote! {
        #tables

        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline]
        pub fn #fname(#outer_params #args) -> #mat {
            let mut m = <#mat>::zeros();
            #onto(#pass_params #state, &mut [#zero; #len], &mut m);
            m
        }

        #[doc = #into_doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline]
        pub fn #into(#outer_params #args, m: &mut #mat) {
            *m = <#mat>::zeros();
            #onto(#pass_params #state, &mut [#zero; #len], m);
        }

        #workspace

        #[doc = #onto_doc]
        #[inline(never)]
        fn #onto(#outer_params #args, w: &mut [#t; #len], m: &mut #mat) {
            #[inline(always)]
            fn body<#generics>(#lanes_arg #param_args #args, (w, m): (&mut [#t; #len], &mut #mat)) {
                #body
            }
            #call
        }
    }
}

/// `DerivativesWorkspace`: the derivatives' result matrix (and, in the looped form, the loop's
/// workspace array) kept by the caller across calls, zeroed once when it is made. Each
/// evaluation writes the same entries and slots (the statements are straight-line, the loop's
/// steps fixed by the model): those it never writes are the structural zeros, which stay
/// zero, so nothing is zeroed per call. The third argument is `(result type, workspace length,
/// zero literal)` (a length of `None`: the straight-line form, no workspace array), `fill` the
/// statement that fills `self.m` (and `self.w`) from the free function's arguments.
fn workspace(
    cx: &Context<'_>,
    f: &FunctionProgram,
    (mat, len, zero): (
        &TokenStream,
        Option<&proc_macro2::Literal>,
        &proc_macro2::Literal,
    ),
    fill: TokenStream,
) -> TokenStream {
    let spec = f.id.spec();
    let name = ident(WORKSPACE);
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let (outer_params, _) = super::body::outer_params(cx);
    let t = scalar_type(cx.precision);
    let (field, init) = match len {
        Some(len) => (quote!(w: [#t; #len],), quote!(w: [#zero; #len],)),
        None => (quote!(), quote!()),
    };
    let doc = format!(
        " What [`{0}`] needs kept across calls for [`{WORKSPACE}::evaluate`]: its result matrix (and its loop's workspace, the per-link values the statements compute for the loop's steps), zeroed once by [`{WORKSPACE}::new`]. Each evaluation writes the same entries, so the ones it never writes (the structural zeros) stay zero and nothing is zeroed per call: for a caller that evaluates the derivatives at many states (MPC along a horizon, iLQR/DDP backward passes), the same bits as [`{0}`] without zeroing the workspace and the matrix every call.",
        spec.name
    );
    let eval_doc = format!(
        " [`{}`] at the given state, written into the kept matrix, which it returns (`[∂τ/∂q | ∂τ/∂u]`, N × 2N).",
        spec.name
    );
    quote! {
        #[doc = #doc]
        #[derive(Clone, Debug)]
        pub struct #name {
            #field
            m: #mat,
        }

        impl #name {
            /// A workspace with every value zero (no evaluation yet: [`Self::result`] is zero).
            pub fn new() -> Self {
                Self { #init m: <#mat>::zeros() }
            }

            /// The matrix of the last [`Self::evaluate`] (zero before the first).
            pub fn result(&self) -> &#mat {
                &self.m
            }

            #[doc = #eval_doc]
            #[doc = ""]
            #[doc = #arg_doc]
            #[inline]
            pub fn evaluate(&mut self, #outer_params #args) -> &#mat {
                #fill;
                &self.m
            }
        }

        impl Default for #name {
            fn default() -> Self {
                Self::new()
            }
        }
    }
}

/// The in-place `inverse_dynamics_derivatives_into` of the straight-line form (the looped form's
/// [`function`] emits its own): the same API whichever form a model gets.
pub(super) fn straight_into(cx: &Context<'_>, f: &FunctionProgram, looped: bool) -> TokenStream {
    if f.id != crate::registry::FunctionId::InverseDynamicsDerivatives || looped {
        return quote!();
    }
    let spec = f.id.spec();
    let fname = ident(spec.name);
    let into = ident(&format!("{}_into", spec.name));
    let t = scalar_type(cx.precision);
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (rows, cols) = (idx(rows), idx(cols));
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let state = super::signature::arg_names(spec.inputs);
    let (outer_params, pass_params) = super::body::outer_params(cx);
    let doc = format!(" [`{}`] written into `m`.", spec.name);
    let mat = quote!(SMatrix<#t, #rows, #cols>);
    let zero = lit(0.0, cx.precision);
    let workspace = workspace(
        cx,
        f,
        (&mat, None, &zero),
        quote!(self.m = #fname(#pass_params #state)),
    );
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline]
        pub fn #into(#outer_params #args, m: &mut #mat) {
            *m = #fname(#pass_params #state);
        }

        #workspace
    }
}

/// The wrapper's method `inverse_dynamics_derivatives_into(&self, …, m)` when the module has
/// the derivatives.
pub(super) fn methods(cx: &Context<'_>) -> TokenStream {
    let Some(f) = cx
        .low
        .functions
        .iter()
        .find(|f| f.id == crate::registry::FunctionId::InverseDynamicsDerivatives)
    else {
        return quote!();
    };
    let spec = f.id.spec();
    let into = ident(&format!("{}_into", spec.name));
    let doc = format!(
        " [`Self::{}`] written into `m` (no result copy; for a caller that keeps its matrix, e.g. along an MPC horizon).",
        spec.name
    );
    let (args, _) = state_args(cx, spec.inputs);
    let t = scalar_type(cx.precision);
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (rows, cols) = (idx(rows), idx(cols));
    let state = super::signature::arg_names(spec.inputs);
    let pass = super::signature::wrapper_params(cx);
    let call = quote!(#into(#pass #state, m));
    let with = ident(&format!("{}_with", spec.name));
    let name = ident(WORKSPACE);
    let with_doc = format!(
        " [`Self::{}`] written into the matrix of a [`{WORKSPACE}`] the caller keeps across calls (made once by `{WORKSPACE}::new()`), which it returns: the same bits, without zeroing a workspace and a matrix every call.",
        spec.name
    );
    let eval = quote!(ws.evaluate(#pass #state));
    quote! {
        #[doc = #doc]
        #[inline]
        pub fn #into(&self, #args, m: &mut SMatrix<#t, #rows, #cols>) {
            #call
        }

        #[doc = #with_doc]
        #[inline]
        pub fn #with<'w>(&self, #args, ws: &'w mut #name) -> &'w SMatrix<#t, #rows, #cols> {
            #eval
        }
    }
}
