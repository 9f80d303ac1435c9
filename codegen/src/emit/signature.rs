//! What the wrapper's methods and the free functions agree on: argument names, return types and
//! the parameters a method passes first.

use proc_macro2::TokenStream;
use quote::quote;

use super::context::{Context, scalar_type};
use super::print::idx;
use crate::registry::{FunctionSpec, Inputs, Shape};

/// The argument names of a function with `inputs`, as passed on by a wrapper.
pub(super) fn arg_names(inputs: Inputs) -> TokenStream {
    match inputs {
        Inputs::Q => quote!(q),
        Inputs::QU => quote!(q, u),
        Inputs::QUUd => quote!(q, u, ud),
    }
}

/// The return type of a registry function.
pub(super) fn return_type(cx: &Context<'_>, spec: &FunctionSpec) -> TokenStream {
    result_type(cx, spec.shape)
}

/// What a method of the wrapper passes first to a free function: the wrapper's parameters and
/// their precomputed values (`&self.params, &self.pre,`) in a runtime-parameter module, nothing
/// in a baked one (the free function's own first arguments: [`super::body::outer_params`]).
pub(super) fn wrapper_params(cx: &Context<'_>) -> TokenStream {
    if cx.low.params.is_runtime() {
        quote!(&self.params, &self.pre,)
    } else {
        quote!()
    }
}

/// The Rust type of a result of `shape` (`SMatrix<f64, 19, 19>`, `SVector<f64, 3>`, `f64`,
/// `nalgebra::Isometry3<f64>`).
pub(super) fn result_type(cx: &Context<'_>, shape: Shape) -> TokenStream {
    let t = scalar_type(cx.precision);
    let (rows, cols) = shape.size_in(&cx.low.sizes);
    let (r, c) = (idx(rows), idx(cols));
    match shape {
        Shape::Scalar => quote!(#t),
        Shape::Isometry => quote!(nalgebra::Isometry3<#t>),
        _ if cols == 1 => quote!(SVector<#t, #r>),
        _ => quote!(SMatrix<#t, #r, #c>),
    }
}
