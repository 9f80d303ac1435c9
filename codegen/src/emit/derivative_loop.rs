//! The looped form of `inverse_dynamics_derivatives` (`kane/rnea_derivatives_loop.rs`): the
//! straight-line statements fill a workspace array, then
//! `kanegen_runtime::derivative_steps::run` walks the generated tables (a `const` next to the
//! function) and writes the result.

use proc_macro2::TokenStream;
use quote::quote;

use super::function::{
    Reads, Stores, generic_body, nonzero_outputs, param_args, prologue, result_type, state_args,
    store_text_after, text, unused_inputs,
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
    let block =
        printer.statement_block(&cx.leaf_names, stores, (&stored, &[]), cx.split_above, true);
    let body = cx.blocks.placeholder(block);
    let unused = unused_inputs(spec.inputs, p, &reads);
    let t = scalar_type(cx.precision);
    let zero = lit(0.0, cx.precision);
    let len = idx(looped.plan.workspace);
    let ty = result_type(cx, spec.shape);
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
        let mut m = SMatrix::<#t, #rows, #cols>::zeros();
        #run(&#tables_name, &w, m.as_mut_slice());
        m
    };
    // Multiply-add chains in the straight-line part: fused in the x86-64-v3 copy, like every
    // single-state function (`generic_body`).
    let (outer_params, generic) = generic_body(cx, spec.inputs, param_args, &ty, body);
    let tables = tables(&looped.plan);
    quote! {
        #tables

        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline(never)]
        pub fn #fname(#outer_params #args) -> #ty {
            #generic
        }
    }
}
