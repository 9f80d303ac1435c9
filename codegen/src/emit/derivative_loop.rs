//! The looped form of `inverse_dynamics_derivatives` (`kane/rnea_derivatives_loop.rs`): the
//! straight-line statements fill a workspace array, then
//! `kanegen_runtime::derivative_steps::run` walks the generated tables (a `const` next to the
//! function) and writes the result.

use proc_macro2::TokenStream;
use quote::quote;

use super::function::{
    Reads, Stores, nonzero_outputs, param_args, prologue, state_args, store_text_after, text,
    unused_inputs,
};
use super::print::{ident, idx, lit};
use super::{Context, scalar_type};
use crate::kane::DerivativeLoop;
use crate::lower::{FunctionProgram, LExpr, LoopedProgram};

/// The name of the tables' `const`.
const TABLES: &str = "INVERSE_DYNAMICS_DERIVATIVES_STEPS";

/// The tables as a `kanegen_runtime::derivative_steps::Plan` constant.
fn tables(plan: &DerivativeLoop) -> TokenStream {
    let u16_of = |x: usize| {
        let v = u16::try_from(x).expect("`lower_with` checked that the tables fit u16");
        proc_macro2::Literal::u16_unsuffixed(v)
    };
    let links = plan.links.iter().map(|l| {
        let parent = match l.parent {
            Some(p) => {
                let p = u16_of(p);
                quote!(#p)
            }
            None => quote!(kanegen_runtime::derivative_steps::NO_PARENT),
        };
        let (t, a, b) = (
            u16_of(l.transform),
            u16_of(l.speeds.start),
            u16_of(l.speeds.end),
        );
        quote!(kanegen_runtime::derivative_steps::Link { parent: #parent, transform: #t, first: #a, end: #b })
    });
    let speeds = plan.speeds.iter().map(|s| {
        let (i, m, j) = (u16_of(s.index), u16_of(s.motion), s.joint);
        let axis = match s.axis {
            Some(k) => {
                let k = proc_macro2::Literal::u8_unsuffixed(k);
                quote!(#k)
            }
            None => quote!(kanegen_runtime::derivative_steps::DENSE),
        };
        quote!(kanegen_runtime::derivative_steps::Speed { index: #i, motion: #m, joint: #j, axis: #axis })
    });
    let columns = plan.columns.iter().map(|c| {
        let (l, s, f) = (u16_of(c.link), u16_of(c.speed), u16_of(c.forces));
        quote!(kanegen_runtime::derivative_steps::Column { link: #l, speed: #s, forces: #f })
    });
    let name = ident(TABLES);
    let dof = idx(plan.dof);
    let doc = format!(
        " The tables of `inverse_dynamics_derivatives`'s loop: {} links, {} speeds, {} columns, {} steps up; a workspace of {} values.",
        plan.links.len(),
        plan.speeds.len(),
        plan.columns.len(),
        plan.steps(),
        plan.workspace
    );
    quote! {
        #[doc = #doc]
        const #name: kanegen_runtime::derivative_steps::Plan<'static> =
            kanegen_runtime::derivative_steps::Plan {
                dof: #dof,
                links: &[#(#links),*],
                speeds: &[#(#speeds),*],
                columns: &[#(#columns),*],
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
        " Generated code: {} straight-line (per link and per column, into a workspace of {} values), then a loop of {} steps over `{TABLES}` (`kanegen_runtime::derivative_steps::run`, {} flops).",
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
    let lanes = super::function::lanes_in(cx, p, looped.lanes.as_ref());
    let block = match lanes {
        Some((leaves, plan)) => {
            super::lanes::lane_block(&printer, &cx.leaf_names, leaves, p, plan, stores)
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
        crate::options::Precision::F64 => quote!(kanegen_runtime::derivative_steps::run),
        crate::options::Precision::F32 => quote!(kanegen_runtime::derivative_steps::run_generic),
    };
    let body = quote! {
        #unused
        #prologue
        let mut w: [#t; #len] = [#zero; #len];
        #body
        #run(&#tables_name, &w, m.as_mut_slice());
    };
    let mat = quote!(SMatrix<#t, #rows, #cols>);
    // The body generic over the multiply-add (fused in the x86-64-v3 copy, like every
    // single-state function's), writing into `m`.
    let (outer_params, pass_params) = super::function::outer_params(cx);
    let state = super::items::arg_names(spec.inputs);
    let call = super::function::call_body_into(
        cx,
        if lanes {
            super::function::Copies::Lanes
        } else {
            super::function::Copies::BaselineAndV3
        },
        quote!(),
        quote!(#pass_params #state,),
        quote!(m),
    );
    let call = quote!(#call;);
    let tables = tables(&looped.plan);
    let (generics, lanes_arg) = super::function::body_generics(cx, lanes);
    let into = ident(&format!("{}_into", spec.name));
    let onto = ident(&format!("{}_onto", spec.name));
    let into_doc = format!(
        " [`{}`] written into `m` (every entry; no copy of the result: the form for a caller that keeps its matrix).",
        spec.name
    );
    let onto_doc = format!(
        " The entries of [`{}`] written into `m`, whose other entries are zero (the structural zeros are not written): the by-value function passes a new zero matrix, so that the result is built where the caller keeps it rather than copied out.",
        spec.name
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
            #onto(#pass_params #state, &mut m);
            m
        }

        #[doc = #into_doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline]
        pub fn #into(#outer_params #args, m: &mut #mat) {
            *m = <#mat>::zeros();
            #onto(#pass_params #state, m);
        }

        #[doc = #onto_doc]
        #[inline(never)]
        fn #onto(#outer_params #args, m: &mut #mat) {
            #[inline(always)]
            fn body<#generics>(#lanes_arg #param_args #args, m: &mut #mat) {
                #body
            }
            #call
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
    let state = super::items::arg_names(spec.inputs);
    let (outer_params, pass_params) = super::function::outer_params(cx);
    let doc = format!(" [`{}`] written into `m`.", spec.name);
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline]
        pub fn #into(#outer_params #args, m: &mut SMatrix<#t, #rows, #cols>) {
            *m = #fname(#pass_params #state);
        }
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
    let state = super::items::arg_names(spec.inputs);
    let call = if cx.low.params.is_runtime() {
        quote!(#into(&self.params, &self.pre, #state, m))
    } else {
        quote!(#into(#state, m))
    };
    quote! {
        #[doc = #doc]
        #[inline]
        pub fn #into(&self, #args, m: &mut SMatrix<#t, #rows, #cols>) {
            #call
        }
    }
}
