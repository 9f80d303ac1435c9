//! Batched functions: the statements of one generated function evaluated at `L` states per
//! call (`mass_matrix_batch(p, pc, &[q; L]) -> [SMatrix; L]`), every state-dependent value a
//! `kanegen_runtime::lanes::Lanes<L>`.
//!
//! The statements are printed exactly as for the single-state function: parameters and
//! literals stay `f64` and `Lanes` implements the operators with `f64` on either side, so lane
//! `l` of every value is the single-state value at state `l`, bit for bit. Only the bindings of
//! the inputs (transposed to lane-major order, sines and cosines lane by lane) and the result
//! stores (into a lane-major buffer, transposed at the end) differ. `L` is a const generic: one emitted body for every batch size.

use proc_macro2::TokenStream;
use quote::quote;

use super::Context;
use super::function::{Reads, last_local, nonzero_outputs, unused_inputs};
use super::items::{arg_names, return_type};
use super::print::{ident, idx};
use crate::lower::{FunctionProgram, LExpr, Program};
use crate::naming;
use crate::registry::{FunctionSpec, Inputs, Shape};

/// Whether `f` gets a batched form: the dynamics (M, c, g, τ and C: the functions of the
/// runtime's traits), a vector or matrix result and no frame argument. The opt-in kinematics,
/// derivatives and regressors have none (their single-state code is already long).
fn batched(f: &FunctionProgram) -> bool {
    let spec = f.id.spec();
    f.frame.is_none()
        && spec.runtime_trait.is_some()
        && !spec.per_frame
        && matches!(
            spec.shape,
            Shape::SymmetricMatrix | Shape::Matrix | Shape::Vector | Shape::Dense { .. }
        )
}

/// The name of the batched form of `spec`'s function.
fn batch_name(spec: &FunctionSpec) -> proc_macro2::Ident {
    ident(&format!("{}_batch", spec.name))
}

/// The state arguments: `&[SVector<f64, N>; L]` per input.
fn args(cx: &Context<'_>, inputs: Inputs) -> TokenStream {
    let nl = idx(cx.low.dof);
    let v = quote!(&[SVector<f64, #nl>; L]);
    match inputs {
        Inputs::Q => quote!(q: #v),
        Inputs::QU => quote!(q: #v, u: #v),
        Inputs::QUUd => quote!(q: #v, u: #v, ud: #v),
    }
}

/// The input bindings: per joint angle one lane-wise `sin_cos`, then coordinates, speeds and
/// accelerations gathered from the `L` states.
fn prologue(cx: &Context<'_>, p: &Program, reads: &Reads) -> TokenStream {
    let speeds = &cx.model.speeds;
    let mut ts = TokenStream::new();
    let reads_q = !p.sincos.is_empty() || reads.coord.contains(&true);
    if reads_q {
        ts.extend(quote!(let q = kanegen_runtime::lanes::inputs(q);));
    }
    if reads.speed.contains(&true) {
        ts.extend(quote!(let u = kanegen_runtime::lanes::inputs(u);));
    }
    if reads.accel.contains(&true) {
        ts.extend(quote!(let ud = kanegen_runtime::lanes::inputs(ud);));
    }
    for &s in &p.sincos {
        let sl = idx(s);
        let sn = if reads.sin[s] {
            let id = ident(&naming::sin(&speeds[s].coordinate));
            quote!(#id)
        } else {
            quote!(_)
        };
        let cn = if reads.cos[s] {
            let id = ident(&naming::cos(&speeds[s].coordinate));
            quote!(#id)
        } else {
            quote!(_)
        };
        ts.extend(quote!(let (#sn, #cn) = kanegen_runtime::lanes::sin_cos(q[#sl]);));
    }
    for (s, speed) in speeds.iter().enumerate() {
        let sl = idx(s);
        if reads.coord[s] {
            let id = ident(&speed.coordinate);
            ts.extend(quote!(let #id = q[#sl];));
        }
        if reads.speed[s] {
            let id = ident(&speed.name);
            ts.extend(quote!(let #id = u[#sl];));
        }
        if reads.accel[s] {
            let id = ident(&naming::accel(&speed.name));
            ts.extend(quote!(let #id = ud[#sl];));
        }
    }
    ts
}

/// The batched free function of `f`, or nothing if it has none.
pub(super) fn function(cx: &Context<'_>, f: &FunctionProgram) -> TokenStream {
    if !batched(f) {
        return TokenStream::new();
    }
    let spec = f.id.spec();
    let p = &f.program;
    let printer = cx.printer(&p.stmts);
    let reads = Reads::of(p, cx.low.dof);
    let name = batch_name(spec);
    let single = spec.name;
    let doc = format!(
        " [`{single}`] at `L` states per call: entry `l` of the result is `{single}` at \
         entry `l` of the inputs, bit for bit (the same statements over \
         [`kanegen_runtime::lanes::Lanes`], vectorized across the states)."
    );
    let param_args = super::function::param_args(cx, &reads);
    let state = args(cx, spec.inputs);
    let prologue = prologue(cx, p, &reads);
    let ty = return_type(cx, spec);
    let mut stores: Vec<TokenStream> = vec![TokenStream::new(); p.stmts.len() + 1];
    let store_after = |stores: &mut [TokenStream], e: &LExpr, store: TokenStream| {
        stores[last_local(e).map_or(0, |i| i + 1)].extend(store);
    };
    for (r, c, e) in nonzero_outputs(p) {
        let v = printer.expr(e, false);
        let (r, c) = (idx(*r), idx(*c));
        let store = quote!(buf[#c][#r] = kanegen_runtime::lanes::lanes(#v););
        store_after(&mut stores, e, store);
    }
    let statements = printer.statements(&stores);
    let symmetric = spec.shape == Shape::SymmetricMatrix;
    let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
    let (rows, cols) = (idx(rows), idx(cols));
    let unused = unused_inputs(spec.inputs, p, &reads);
    let body = quote! {
        #unused
        #prologue
        #[allow(unused_mut)]
        let mut buf = kanegen_runtime::lanes::buffer::<L, #rows, #cols>();
        #statements
        kanegen_runtime::lanes::results(&mut buf, #symmetric)
    };
    let body = if cx.isa_dispatch {
        quote!(kanegen_runtime::isa::dispatch(#[inline(always)] || { #body }))
    } else {
        body
    };
    quote! {
        #[doc = #doc]
        #[inline(never)]
        pub fn #name<const L: usize>(#param_args #state) -> [#ty; L] {
            #body
        }
    }
}

/// The wrapper's methods for the batched functions.
pub(super) fn methods(cx: &Context<'_>) -> TokenStream {
    cx.low
        .functions
        .iter()
        .filter(|f| batched(f))
        .map(|f| {
            let spec = f.id.spec();
            let name = batch_name(spec);
            let doc = format!(
                " [`Self::{}`] at `L` states per call (entry `l` of the result at entry `l` of \
                 the inputs, bit for bit; vectorized across the states).",
                spec.name
            );
            let state = args(cx, spec.inputs);
            let ty = return_type(cx, spec);
            let names = arg_names(spec.inputs);
            let call = if cx.low.params.is_runtime() {
                quote!(#name(&self.params, &self.pre, #names))
            } else {
                quote!(#name(#names))
            };
            quote! {
                #[doc = #doc]
                #[inline]
                pub fn #name<const L: usize>(&self, #state) -> [#ty; L] {
                    #call
                }
            }
        })
        .collect()
}
