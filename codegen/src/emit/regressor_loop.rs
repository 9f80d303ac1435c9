//! A regressor in loop form (`kane/regressor_loop.rs`): the straight-line part stores every
//! link's motion, joint transform and entry coefficients in a `kin` table (and the wheel columns
//! in the result), then one call of `kanegen_runtime::regressor::inverse_dynamics_regressor`
//! runs the (speed, body) pairs over the constant tables of its plan (columns, steps, seeds,
//! zero chunks). The body is generic over `Arith` and dispatched like the straight-line
//! functions' (`Plain` baseline, `Fused` x86-64-v3), the kernel included.

use proc_macro2::TokenStream;
use quote::quote;

use super::body::{Reads, last_local, param_args, prologue, state_args, unused_inputs};
use super::context::{Context, scalar_type};
use super::print::{idx, signed_lit};
use super::signature::result_type;
use crate::kane::{CarryFrom, KIN};
use crate::lower::{FunctionProgram, LExpr, Leaf, LoopProgram};
use crate::registry::FunctionId;

/// The free function of regressor `f` in loop form `lp`.
pub(super) fn function(cx: &Context<'_>, f: &FunctionProgram, lp: &LoopProgram) -> TokenStream {
    let spec = f.id.spec();
    let p = &lp.program;
    let t = scalar_type(cx.precision);
    let printer = cx.printer(&p.stmts);
    let reads = Reads::of(p, cx.model.speeds.len());
    let name = super::frames::rust_name(cx, f);
    let fname = super::print::ident(&name);
    let into = super::print::ident(&format!("{name}_into"));
    let doc = format!(" {}", spec.doc);
    let tables = &lp.tables;
    let ops = format!(
        " Generated code in loop form: every link's motion straight-line ({}), then a loop over {} (speed, body) pairs (`kanegen_runtime::regressor`, {} lane flops); {} flops per call in all (straight-line form: {} flops).",
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
    // Multiply-add chains: the body is generic over `Arith` (fused in the x86-64-v3 copy).
    let block =
        printer.statement_block(&cx.leaf_names, stores, (&stored, &[]), cx.split_above, true);
    let body = cx.blocks.placeholder(block);
    let nl = idx(tables.links.len());
    let plan = tables.plan(rows);
    let columns = tables.links.iter().map(|l| {
        let columns = l.columns.iter().map(|c| match c {
            Some(c) => {
                let c = idx(*c);
                quote!(#c)
            }
            None => quote!(kanegen_runtime::regressor::NO_COLUMN),
        });
        quote!([#(#columns),*])
    });
    let steps = plan.steps.iter().map(|s| {
        let (link, chunk) = (idx(s.link), idx(s.chunk));
        let slot = match s.slot {
            Some(d) => {
                let d = idx(d);
                quote!(#d)
            }
            None => quote!(kanegen_runtime::regressor::NO_SLOT),
        };
        let from = match s.from {
            Some(CarryFrom::Slot(f)) => {
                let f = idx(f);
                quote!(#f)
            }
            Some(CarryFrom::Previous) => quote!(kanegen_runtime::regressor::PREVIOUS),
            None => quote!(kanegen_runtime::regressor::NO_SLOT),
        };
        let seed = match s.seed {
            Some(f) => {
                let f = idx(f);
                quote!(#f)
            }
            None => quote!(kanegen_runtime::regressor::NO_SEED),
        };
        let j = tables.joints[s.link];
        let rotation = match j.axis {
            Some((r, c)) => {
                let code = proc_macro2::Literal::u8_unsuffixed((3 * r + c) as u8);
                quote!(#code)
            }
            None => quote!(kanegen_runtime::regressor::DENSE_ROTATION),
        };
        let (offset, body) = (j.offset, s.body);
        let first = first_column(&tables.links[s.link].columns);
        quote!(kanegen_runtime::regressor::Step { link: #link, chunk: #chunk, slot: #slot, from: #from, seed: #seed, rotation: #rotation, offset: #offset, body: #body, first: #first })
    });
    let ns = idx(plan.steps.len());
    let nseeds = idx(plan.seeds.len());
    let seeds = plan.seeds.iter().map(|c| {
        let comps = c.iter().map(|lanes| {
            let x = lanes.iter().map(|v| signed_lit(*v, cx.precision));
            quote!([#(#x),*])
        });
        quote!([#(#comps),*])
    });
    let nz = idx(plan.zeros.len());
    let zeros = plan.zeros.iter().map(|&(l, c)| {
        let first = first_column(&tables.links[l].columns);
        let (l, c) = (idx(l), idx(c));
        quote!(kanegen_runtime::regressor::ZeroChunk { link: #l, chunk: #c, first: #first })
    });
    let slots = idx(plan.slots);
    let unused = unused_inputs(spec.inputs, p, &reads);
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
        quote!(for c in [#(#others),*] { y.column_mut(c).as_mut_slice().fill(0.0); })
    };
    let body = quote! {
        #unused
        #prologue
        let #kin_mut kin = [[0.0; kanegen_runtime::regressor::KIN]; #nl];
        #zero_others
        #body
        let plan = kanegen_runtime::regressor::Plan { columns: &COLUMNS, steps: &STEPS, seeds: &SEEDS, zeros: &ZEROS };
        kanegen_runtime::regressor::inverse_dynamics_regressor::<A, _, #nl, #slots>(&kin, &plan, #nr, y.as_mut_slice());
    };
    let (outer_params, pass_params) = super::body::outer_params(cx);
    let state = super::signature::arg_names(spec.inputs);
    // The body generic over the multiply-add, compiled twice with dispatch (`Plain` for the
    // baseline, `Fused` for x86-64-v3), writing into `y`.
    let call = super::body::call_body_into(
        cx,
        super::body::Copies::BaselineAndV3,
        quote!(),
        quote!(#pass_params #state,),
        quote!(y),
    );
    let call = quote!(#call;);
    let into_doc = format!(
        " [`{name}`] written into `y` (every entry; nothing to allocate, zero or copy: the fast form for a caller that keeps its result matrix)."
    );
    let plan_doc = format!(
        " The loop's plan: {} steps ((link, four-row chunk) pairs some ancestor speed moves), {} chunks of zeros, {} seed chunks, {} scratch slots; {} lane flops.",
        plan.steps.len(),
        plan.zeros.len(),
        plan.seeds.len(),
        plan.slots,
        plan.flops,
    );
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline]
        pub fn #fname(#outer_params #args) -> #ty {
            let mut y = SMatrix::<#t, #nr, #nc>::zeros();
            #into(#pass_params #state, &mut y);
            y
        }

        #[doc = #into_doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #plan_doc]
        #[inline(never)]
        pub fn #into(#outer_params #args, y: &mut SMatrix<#t, #nr, #nc>) {
            /// Per link: the result columns of its body's parameters.
            const COLUMNS: [[u16; 10]; #nl] = [#(#columns),*];
            /// The (link, row chunk) steps, chunk by chunk, depth-first.
            const STEPS: [kanegen_runtime::regressor::Step; #ns] = [#(#steps),*];
            /// The joints' own partial velocities, one chunk each.
            const SEEDS: [kanegen_runtime::regressor::Chunk<#t>; #nseeds] = [#(#seeds),*];
            /// The (link, row chunk) pairs whose entries are zero.
            const ZEROS: [kanegen_runtime::regressor::ZeroChunk; #nz] = [#(#zeros),*];
            #[inline(always)]
            fn body<A: kanegen_runtime::isa::Arith<#t>>(#param_args #args, y: &mut SMatrix<#t, #nr, #nc>) {
                #body
            }
            #call
        }
    }
}

/// The first of a body's ten result columns when they are consecutive (the kernel's fast
/// store), else `NO_COLUMN`.
fn first_column(columns: &[Option<usize>; 10]) -> TokenStream {
    match columns[0] {
        Some(c0) if (0..10).all(|t| columns[t] == Some(c0 + t)) => {
            let c0 = idx(c0);
            quote!(#c0)
        }
        _ => quote!(kanegen_runtime::regressor::NO_COLUMN),
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
    let state = super::signature::arg_names(spec.inputs);
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
            let state = super::signature::arg_names(spec.inputs);
            let pass = super::signature::wrapper_params(cx);
            let call = quote!(#into(#pass #state, y));
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
