//! One straight-line generated function: signature, inputs, the batched sines and cosines, the
//! statements and the result stores (the building blocks in `body.rs`).

use proc_macro2::TokenStream;
use quote::quote;

use super::body::*;
use super::context::Context;
use super::print::ident;
use crate::lower::{FunctionProgram, LExpr};
use crate::registry::Shape;

/// The free function of registry function `f`.
pub(super) fn function(cx: &Context<'_>, f: &FunctionProgram) -> TokenStream {
    if let Some(lp) = &f.looped {
        return super::regressor_loop::function(cx, f, lp);
    }
    let spec = f.id.spec();
    let p = &f.program;
    let printer = cx.printer(&p.stmts);
    let reads = Reads::of(p, cx.model.speeds.len());
    let fname = ident(&super::frames::rust_name(cx, f));
    let doc = match f.frame {
        Some(l) => format!(
            " {} Frame `{}` (see [`Frame`]).",
            spec.doc, cx.model.links[l].name
        ),
        None => format!(" {}", spec.doc),
    };
    let ops = format!(" Generated straight-line code: {}.", p.ops);
    let param_args = param_args(cx, &reads);
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let prologue = prologue(cx, p, &reads);
    let Result {
        ty,
        init,
        mut stores,
        value,
        in_memory,
    } = result(cx, &printer, p, spec.shape);
    let into = has_into(f);
    if into {
        // The `_into` form writes every entry of the caller's matrix: the entries no statement
        // stores are zeroed first.
        stores[0].extend(zero_stores(
            p,
            cx.low.dof,
            spec.shape == Shape::SymmetricMatrix,
        ));
    }
    // The statements are printed as text and spliced in after formatting (`text.rs`).
    // A scalar result is the final expression; every other entry is stored in the block.
    let outputs: Vec<&LExpr> = nonzero_outputs(p).map(|(_, _, e)| e).collect();
    let (stored, read_at_end) = if spec.shape == Shape::Scalar {
        (Vec::new(), outputs)
    } else {
        (outputs, Vec::new())
    };
    let lanes = lanes_in(cx, p, f.lanes.as_ref());
    let block = body_block(cx, &printer, p, lanes, stores, (&stored, &read_at_end));
    let body = cx.blocks.placeholder(block);
    let unused = unused_inputs(spec.inputs, p, &reads);
    let lanes = lanes.is_some();
    if into {
        return into_pair(
            cx,
            f,
            (&doc, arg_doc, &ops),
            (param_args, lanes),
            &ty,
            quote! {
                #unused
                #prologue
                #body
            },
        );
    }
    let body = if in_memory {
        quote!({
            let m = core::hint::black_box(&mut m);
            #body
        })
    } else {
        body
    };
    let body = quote! {
        #unused
        #prologue
        #init
        #body
        #value
    };
    let (outer_params, generic) = generic_body(cx, spec.inputs, (param_args, lanes), &ty, body);
    quote! {
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
