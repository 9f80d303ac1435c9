//! Combined functions (see [`crate::combined`]): the result struct (one field per part), the free
//! function (one straight-line program: one batched `sin_cos_n`, every shared statement once,
//! each part's entries stored into its field right after the last statement they read), and the
//! wrapper method.

use proc_macro2::TokenStream;
use quote::quote;

use super::body::{
    Reads, Stores, generic_body, prologue, state_args, store_text_after, text, unused_inputs,
};
use super::context::Context;
use super::context::scalar_type;
use super::print::{ident, idx};
use super::signature::arg_names;
use super::signature::result_type;
use crate::lower::{CombinedProgram, LExpr, Leaf};
use crate::registry::Shape;

/// The documentation of part `i`'s field.
fn field_doc(cx: &Context<'_>, c: &CombinedProgram, i: usize) -> String {
    let part = &c.spec.parts[i];
    let spec = part.function.spec();
    match part.frame {
        Some(l) => format!(
            " `{}` of frame `{}`: {}",
            spec.name, cx.model.links[l].name, spec.doc
        ),
        None => format!(" `{}`: {}", spec.name, spec.doc),
    }
}

/// The result struct and the free function of combined function `c`.
pub(super) fn items(cx: &Context<'_>, c: &CombinedProgram) -> TokenStream {
    let t = scalar_type(cx.precision);
    let p = &c.program;
    let printer = cx.printer(&p.stmts);
    let reads = Reads::of(p, cx.model.speeds.len());
    let ty = ident(&c.spec.type_name);
    let fname = ident(&c.spec.name);
    let shapes: Vec<Shape> = c
        .spec
        .parts
        .iter()
        .map(|part| part.function.spec().shape)
        .collect();

    // The struct.
    let fields: Vec<_> = c.spec.parts.iter().map(|part| ident(&part.field)).collect();
    let docs = (0..fields.len()).map(|i| field_doc(cx, c, i));
    let types = shapes.iter().map(|s| result_type(cx, *s));
    let struct_doc = format!(
        " The results of [`{}`]: {}, computed by one straight-line program that shares every sine, cosine and intermediate value between them.",
        c.spec.name,
        c.spec
            .parts
            .iter()
            .map(|p| format!("`{}`", p.field))
            .collect::<Vec<_>>()
            .join(", ")
    );

    // The body: `out` is a tuple with one element per part (an isometry's is `(rotation,
    // translation)`), filled by stores after the statements they read.
    let lanes = super::body::lanes_in(cx, p, c.lanes.as_ref());
    // Text lines by position (see `Printer::statement_block`), for either block form.
    let mut stores: Stores = vec![Vec::new(); p.stmts.len() + 1];
    let mut stored_exprs: Vec<&LExpr> = Vec::new();
    let mut inits = Vec::new();
    let mut finals = Vec::new();
    for (i, (shape, range)) in shapes.iter().zip(&c.parts).enumerate() {
        let k = syn::Index::from(i);
        let (rows, cols) = shape.size_in(&cx.low.sizes);
        let (rl, cl) = (idx(rows), idx(cols));
        let entries = p.outputs[range.clone()]
            .iter()
            .filter(|(_, _, e)| !matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0));
        for (r, col, e) in entries {
            let v = text(cx, &printer, e);
            let line = match shape {
                Shape::Vector => format!("out.{i}[{r}] = core::hint::black_box({v});"),
                Shape::Scalar => format!("out.{i} = {v};"),
                Shape::Isometry if *col == 3 => format!("out.{i}.1[{r}] = {v};"),
                Shape::Isometry => format!("out.{i}.0[({r}, {col})] = {v};"),
                _ => format!("out.{i}[({r}, {col})] = {v};"),
            };
            store_text_after(&mut stores, e, line);
            // The lower entry right after its upper twin, as the separate `mass_matrix`.
            if *shape == Shape::SymmetricMatrix && r != col {
                let copy = format!("out.{i}[({col}, {r})] = out.{i}[({r}, {col})];");
                store_text_after(&mut stores, e, copy);
            }
            stored_exprs.push(e);
        }
        let f = &fields[i];
        match shape {
            Shape::Scalar => {
                inits.push(quote!(0.0 as #t));
                finals.push(quote!(#f: out.#k));
            }
            Shape::Isometry => {
                inits.push(quote!((
                    nalgebra::Matrix3::<#t>::zeros(),
                    nalgebra::Vector3::<#t>::zeros()
                )));
                finals.push(quote!(#f: nalgebra::Isometry3::from_parts(
                    nalgebra::Translation3::from(out.#k.1),
                    nalgebra::UnitQuaternion::from_rotation_matrix(
                        &nalgebra::Rotation3::from_matrix_unchecked(out.#k.0),
                    ),
                )));
            }
            _ => {
                inits.push(quote!(SMatrix::<#t, #rl, #cl>::zeros()));
                finals.push(quote!(#f: out.#k));
            }
        }
    }
    let stored = !stored_exprs.is_empty();
    let block = super::body::body_block(cx, &printer, p, lanes, stores, (&stored_exprs, &[]));
    let body = cx.blocks.placeholder(block);
    let prologue = prologue(cx, p, &reads);
    let unused = unused_inputs(c.spec.inputs, p, &reads);
    let mutable = if stored { quote!(mut) } else { quote!() };
    let body = quote! {
        #unused
        #prologue
        let #mutable out = (#(#inits,)*);
        #body
        #ty { #(#finals,)* }
    };
    let param_args = super::body::param_args(cx, &reads);
    // Generic over the multiply-add, as the separate functions (whose bits it gives).
    let (param_args, body) = generic_body(
        cx,
        c.spec.inputs,
        (param_args, lanes.is_some()),
        &quote!(#ty),
        body,
    );
    let (args, arg_doc) = state_args(cx, c.spec.inputs);
    let doc = format!(
        " Combined function: {} in one straight-line program (every sine, cosine and shared intermediate value computed once); each field equals the separate function's value (bit for bit in the baseline copy; in the x86-64-v3 copy, which fuses multiply-adds, to rounding where a product is shared here and inline there; with mirrored lanes, to rounding also for a per-frame part of the second subtree, which this program adds in the first subtree's order).",
        c.spec
            .parts
            .iter()
            .map(|p| format!("`{}`", p.field))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let ops = format!(" Generated straight-line code: {}.", p.ops);
    quote! {
        #[doc = #struct_doc]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct #ty {
            #(#[doc = #docs] pub #fields: #types,)*
        }

        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline(never)]
        pub fn #fname(#param_args #args) -> #ty {
            #body
        }
    }
}

/// The wrapper's method of every combined function.
pub(super) fn methods(cx: &Context<'_>) -> TokenStream {
    cx.low
        .combined
        .iter()
        .map(|c| {
            let name = ident(&c.spec.name);
            let ty = ident(&c.spec.type_name);
            let (args, _) = state_args(cx, c.spec.inputs);
            let names = arg_names(c.spec.inputs);
            let pass = super::signature::wrapper_params(cx);
            let call = quote!(#name(#pass #names));
            let doc = format!(" Combined function [`{}`] (free function).", c.spec.name);
            quote! {
                #[doc = #doc]
                #[inline]
                pub fn #name(&self, #args) -> #ty {
                    #call
                }
            }
        })
        .collect()
}
