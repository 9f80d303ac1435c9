//! A regressor in loop form (`kane/regressor_loop.rs`): the straight-line part stores every
//! link's motion and joint transform in a `kin` table (and the wheel columns in the result),
//! then one call of `kanegen_runtime::regressor::inverse_dynamics_regressor` runs the (speed,
//! body) pairs over two constant tables.

use proc_macro2::TokenStream;
use quote::quote;

use super::function::{
    Reads, last_local, param_args, prologue, result_type, state_args, unused_inputs,
};
use super::print::{Printer, idx, signed_lit};
use super::{Context, scalar_type};
use crate::kane::KIN;
use crate::lower::{FunctionProgram, LExpr, Leaf, LoopProgram};
use crate::registry::FunctionId;

/// The free function of regressor `f` in loop form `lp`.
pub(super) fn function(cx: &Context<'_>, f: &FunctionProgram, lp: &LoopProgram) -> TokenStream {
    let spec = f.id.spec();
    let p = &lp.program;
    let t = scalar_type(cx.precision);
    let printer = Printer {
        model: cx.model,
        stmts: &p.stmts,
        pre: &cx.pre,
        precision: cx.precision,
    };
    let reads = Reads::of(p, cx.model.speeds.len());
    let name = super::frames::rust_name(cx, f);
    let fname = super::print::ident(&name);
    let into = super::print::ident(&format!("{name}_into"));
    let doc = format!(" {}", spec.doc);
    let tables = &lp.tables;
    let ops = format!(
        " Generated code in loop form: every link's motion straight-line ({}), then a loop over {} (speed, body) pairs (`kanegen_runtime::regressor`, {} flops); {} flops per call in all (straight-line form: {} flops).",
        p.ops,
        tables.pairs(),
        tables.flops(),
        lp.flops(),
        f.program.ops.flops(),
    );
    let param_args = param_args(cx, &reads);
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let prologue = prologue(cx, p, &reads);
    let ty = result_type(cx, spec.shape);
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (nr, nc) = (idx(rows), idx(cols));
    // Stores right after the last statement each reads; the `kin` values that are the
    // constant zero are not stored (the table starts zeroed).
    let mut stores: Vec<Vec<String>> = vec![Vec::new(); p.stmts.len() + 1];
    let mut stored: Vec<&LExpr> = Vec::new();
    let text = |e: &LExpr| {
        let mut s = String::new();
        printer.expr_text_with(&cx.leaf_names, e, false, false, &mut s);
        s
    };
    for (k, (r, c, e)) in p.outputs.iter().enumerate() {
        if matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0) {
            continue;
        }
        let line = if k < lp.kin_len {
            format!("kin[{}][{}] = {};", r / KIN, r % KIN, text(e))
        } else {
            format!("y[({r}, {c})] = {};", text(e))
        };
        stores[last_local(e).map_or(0, |i| i + 1)].push(line);
        stored.push(e);
    }
    // Plain arithmetic (no multiply-add chains): the straight-line part is small (Krang: 611
    // flops) and the body is not generic over `Arith`.
    let block = printer.statement_block(
        &cx.leaf_names,
        stores,
        (&stored, &[]),
        cx.split_above,
        false,
    );
    let body = cx.blocks.placeholder(block);
    let nl = idx(tables.links.len());
    let (chunks, slots) = tables.chunks();
    let links = tables.links.iter().zip(&chunks).map(|(l, &(n, slot))| {
        let parent = idx(l.parent);
        let columns = l.columns.iter().map(|c| match c {
            Some(c) => {
                let c = idx(*c);
                quote!(#c)
            }
            None => quote!(kanegen_runtime::regressor::NO_COLUMN),
        });
        let (n, slot) = (idx(n), idx(slot));
        quote!(kanegen_runtime::regressor::Link { parent: #parent, columns: [#(#columns),*], chunks: #n, slot: #slot })
    });
    let seeds = tables.seeds();
    let ns = idx(seeds.len());
    let seeds = seeds.iter().map(|&(row, link, x)| {
        let (row, link) = (idx(row), idx(link));
        let x = x.iter().map(|v| signed_lit(*v, cx.precision));
        quote!(kanegen_runtime::regressor::Seed { row: #row, link: #link, phi: [#(#x),*] })
    });
    let slots = idx(slots);
    let unused = unused_inputs(spec, p, &reads);
    let kin_mut = if p.outputs[..lp.kin_len]
        .iter()
        .any(|(_, _, e)| !matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0))
    {
        quote!(mut)
    } else {
        quote!()
    };
    // Columns that are not a body's: zeroed, then their straight-line entries stored.
    let body_columns: std::collections::BTreeSet<usize> = tables
        .links
        .iter()
        .flat_map(|l| l.columns.iter().flatten().copied())
        .collect();
    let others: Vec<_> = (0..cols)
        .filter(|c| !body_columns.contains(c))
        .map(idx)
        .collect();
    let zero_others = if others.is_empty() {
        quote!()
    } else {
        quote!(for c in [#(#others),*] { y.column_mut(c).fill(0.0); })
    };
    // The result is written in place (the closure returns nothing): returned from the dispatch
    // closure and then from the function, its 26 KB (Krang) were copied once more.
    let body = quote! {
        #unused
        #prologue
        let #kin_mut kin = [[0.0; kanegen_runtime::regressor::KIN]; #nl];
        #zero_others
        #body
        kanegen_runtime::regressor::inverse_dynamics_regressor::<_, #nl, #slots>(&kin, &LINKS, &SEEDS, #nr, y.as_mut_slice());
    };
    let body = if cx.isa_dispatch {
        quote!(kanegen_runtime::isa::dispatch(#[inline(always)] || { #body });)
    } else {
        body
    };
    let into_doc = format!(
        " [`{name}`] written into `y` (every entry; nothing to allocate, zero or copy: the fast form for a caller that keeps its result matrix)."
    );
    let forward = if cx.low.params.is_runtime() {
        quote!(p: &Params, pc: &Precomputed,)
    } else {
        quote!()
    };
    let forward_args = if cx.low.params.is_runtime() {
        quote!(p, pc,)
    } else {
        quote!()
    };
    let state = super::items::arg_names(spec.inputs);
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline]
        pub fn #fname(#forward #args) -> #ty {
            let mut y = SMatrix::<#t, #nr, #nc>::zeros();
            #into(#forward_args #state, &mut y);
            y
        }

        #[doc = #into_doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline(never)]
        pub fn #into(#param_args #args, y: &mut SMatrix<#t, #nr, #nc>) {
            /// Per link: its parent, its body's result columns and its row chunks.
            const LINKS: [kanegen_runtime::regressor::Link; #nl] = [#(#links),*];
            /// The joints' own partial velocities, by link.
            const SEEDS: [kanegen_runtime::regressor::Seed<#t>; #ns] = [#(#seeds),*];
            #body
        }
    }
}

/// Whether `f` gets an in-place variant `…_into`: the inverse-dynamics regressor and the base
/// regressor, in either form (the same API whichever form the model gets).
fn has_into(f: &FunctionProgram) -> bool {
    matches!(
        f.id,
        FunctionId::InverseDynamicsRegressor | FunctionId::BaseRegressor
    )
}

/// The in-place variant `…_into` of a straight-line regressor `f` (nothing for other
/// functions or a loop form, which [`function`] emits with its own).
pub(super) fn straight_into(cx: &Context<'_>, f: &FunctionProgram) -> TokenStream {
    if !has_into(f) || f.looped.is_some() {
        return quote!();
    }
    let spec = f.id.spec();
    let name = super::frames::rust_name(cx, f);
    let fname = super::print::ident(&name);
    let into = super::print::ident(&format!("{name}_into"));
    let t = scalar_type(cx.precision);
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (nr, nc) = (idx(rows), idx(cols));
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let state = super::items::arg_names(spec.inputs);
    let (params, forward) = if cx.low.params.is_runtime() {
        (quote!(p: &Params, pc: &Precomputed,), quote!(p, pc,))
    } else {
        (quote!(), quote!())
    };
    let doc = format!(
        " [`{name}`] written into `y` (the same API as a loop-form regressor's; here it stores the by-value result)."
    );
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[inline]
        pub fn #into(#params #args, y: &mut SMatrix<#t, #nr, #nc>) {
            *y = #fname(#forward #state);
        }
    }
}

/// The wrapper's methods `…_into(&self, …, y)` of the module's inverse-dynamics and base
/// regressors.
pub(super) fn methods(cx: &Context<'_>) -> TokenStream {
    cx.low
        .functions
        .iter()
        .filter(|f| has_into(f))
        .map(|f| {
            let spec = f.id.spec();
            let name = format!("{}_into", spec.name);
            let into = super::print::ident(&name);
            let doc = if f.looped.is_some() {
                format!(
                    " [`Self::{}`] written into `y` (every entry; nothing to allocate, zero or copy).",
                    spec.name
                )
            } else {
                format!(" [`Self::{}`] written into `y`.", spec.name)
            };
            let (args, _) = state_args(cx, spec.inputs);
            let t = scalar_type(cx.precision);
            let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
            let (nr, nc) = (idx(rows), idx(cols));
            let state = super::items::arg_names(spec.inputs);
            let call = if cx.low.params.is_runtime() {
                quote!(#into(&self.params, &self.pre, #state, y))
            } else {
                quote!(#into(#state, y))
            };
            quote! {
                #[doc = #doc]
                #[inline]
                pub fn #into(&self, #args, y: &mut SMatrix<#t, #nr, #nc>) {
                    #call
                }
            }
        })
        .collect()
}
