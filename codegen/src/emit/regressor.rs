//! The regressors' items: the parameter orders (`INERTIAL_NAMES`, `BETA_NAMES`), `Params`
//! conversions to and from those vectors, and the base parameters (`BASE_PARAMETER_NAMES`,
//! `base_parameters`, and the same for the gravity regressor).

use proc_macro2::{Ident, TokenStream};
use quote::quote;

use super::context::{Context, scalar_type};
use super::print::{ident, idx, signed_lit};
use crate::kane::{BaseParameters, Coefficient};
use crate::registry::FunctionId;

/// Whether the module has function `id`.
fn has(cx: &Context<'_>, id: FunctionId) -> bool {
    cx.low.functions.iter().any(|f| f.id == id)
}

/// Every regressor item the module's functions call for (nothing without regressors).
pub(super) fn items(cx: &Context<'_>) -> TokenStream {
    let mut out = TokenStream::new();
    let reg = &cx.low.regressors;
    let full = has(cx, FunctionId::InverseDynamicsRegressor) || has(cx, FunctionId::BaseRegressor);
    let gravity =
        has(cx, FunctionId::GravityRegressor) || has(cx, FunctionId::BaseGravityRegressor);
    if full {
        out.extend(vector_items(
            cx,
            &reg.inertial,
            &ident("INERTIAL_NAMES"),
            &ident("inertial_vector"),
            &ident("set_inertial_vector"),
            "inertial parameters π of the inverse-dynamics regressor (τ = Y π): per body in link order m, MX, MY, MZ, XX, XY, XZ, YY, YZ, ZZ (Khalil's standard parameters about the body frame's origin), then a wheeled base's mw, YYw, ZZw",
        ));
    }
    if gravity {
        out.extend(vector_items(
            cx,
            &reg.beta,
            &ident("BETA_NAMES"),
            &ident("beta_vector"),
            &ident("set_beta_vector"),
            "gravity parameters β of the gravity regressor (g = Y_g β): per body in link order m, MX, MY, MZ (mass and first moments in the body frame)",
        ));
    }
    if let (true, Some(b)) = (has(cx, FunctionId::BaseRegressor), &reg.base) {
        out.extend(base_items(
            cx,
            b,
            reg.inertial.len(),
            &ident("BASE_PARAMETER_NAMES"),
            &ident("base_parameters"),
            &ident("base_parameters_of"),
            &ident("inertial_vector"),
            "INERTIAL_NAMES",
            "base parameters π_b of `base_regressor` (τ = Y_b π_b)",
        ));
    }
    if let (true, Some(b)) = (has(cx, FunctionId::BaseGravityRegressor), &reg.base_beta) {
        out.extend(base_items(
            cx,
            b,
            reg.beta.len(),
            &ident("BASE_BETA_NAMES"),
            &ident("base_beta"),
            &ident("base_beta_of"),
            &ident("beta_vector"),
            "BETA_NAMES",
            "base gravity parameters β_b of `base_gravity_regressor` (g = Y_gb β_b)",
        ));
    }
    out
}

/// `NAMES` and, with runtime parameters, `Params::{get, set}` of the vector.
fn vector_items(
    cx: &Context<'_>,
    params: &[usize],
    names_id: &Ident,
    get: &Ident,
    set: &Ident,
    what: &str,
) -> TokenStream {
    let t = scalar_type(cx.precision);
    let n = idx(params.len());
    let names: Vec<&str> = params
        .iter()
        .map(|&p| cx.model.params[p].name.as_str())
        .collect();
    let fields: Vec<Ident> = names.iter().map(|n| ident(n)).collect();
    let ks: Vec<_> = (0..params.len()).map(idx).collect();
    let doc = format!(" Names of the {what}.");
    let mut out = quote! {
        #[doc = #doc]
        pub const #names_id: [&str; #n] = [#(#names),*];
    };
    if cx.low.params.is_runtime() {
        let get_doc = format!(" The {what}, in the order of [`{names_id}`].");
        let set_doc = format!(" Set the {what} from a vector in the order of [`{names_id}`].");
        out.extend(quote! {
            impl Params {
                #[doc = #get_doc]
                pub fn #get(&self) -> SVector<#t, #n> {
                    SVector::<#t, #n>::from([#(self.#fields),*])
                }

                #[doc = #set_doc]
                pub fn #set(&mut self, v: &SVector<#t, #n>) {
                    #(self.#fields = v[#ks];)*
                }
            }
        });
    }
    out
}

/// `NAMES`, `…_of(full vector)` and, with runtime parameters, `…(&Params)`.
#[allow(clippy::too_many_arguments)]
fn base_items(
    cx: &Context<'_>,
    b: &BaseParameters,
    full_len: usize,
    names_id: &Ident,
    from_params: &Ident,
    from_vector: &Ident,
    getter: &Ident,
    full_names: &str,
    what: &str,
) -> TokenStream {
    let t = scalar_type(cx.precision);
    let nb = idx(b.names.len());
    let np = idx(full_len);
    let names = &b.names;
    let values = b.groups.iter().map(|g| {
        let terms = g.iter().map(|&(i, c)| {
            let i = idx(i);
            if c == 1.0 {
                quote!(v[#i])
            } else {
                let c = signed_lit(c, cx.precision);
                quote!(#c * v[#i])
            }
        });
        quote!(#(#terms)+*)
    });
    let doc = format!(
        " Names of the {what}: Khalil's style, `R` after the kind prefix when other parameters are grouped into one (`XXR4l`)."
    );
    let of_doc = format!(
        " The {what} from the full vector (in the order of [`{full_names}`]); the grouping coefficients hold for the model file's lengths."
    );
    // No base parameter (a gravity regressor of a model gravity does not act on, such as a
    // cart on a horizontal rail): the vector is not read.
    let v = if b.names.is_empty() {
        quote!(_v)
    } else {
        quote!(v)
    };
    let mut out = quote! {
        #[doc = #doc]
        pub const #names_id: [&str; #nb] = [#(#names),*];

        #[doc = #of_doc]
        pub fn #from_vector(#v: &SVector<#t, #np>) -> SVector<#t, #nb> {
            SVector::<#t, #nb>::from([#(#values),*])
        }
    };
    if cx.low.params.is_runtime() {
        let exact = b.exactness.skipped.is_none() && b.exactness.numeric_only.is_empty();
        let doc = if exact {
            format!(
                " The {what} of a parameter set, with the grouping coefficients of its own geometry (lengths, wheel radius and track): exact expressions, verified at generation time."
            )
        } else {
            format!(
                " The {what} of a parameter set (grouping coefficients as in [`{from_vector}`] where they are numbers for the model file's geometry only)."
            )
        };
        let values = b.symbolic.iter().map(|g| {
            let terms = g.iter().map(|(i, c)| {
                let i = idx(*i);
                if c.is_one() {
                    quote!(v[#i])
                } else {
                    let c = coefficient_tokens(cx, c);
                    quote!((#c) * v[#i])
                }
            });
            quote!(#(#terms)+*)
        });
        let body = if b.names.is_empty() {
            quote!(let _ = p;)
        } else {
            quote!(let v = p.#getter();)
        };
        out.extend(quote! {
            #[doc = #doc]
            pub fn #from_params(p: &Params) -> SVector<#t, #nb> {
                #body
                SVector::<#t, #nb>::from([#(#values),*])
            }
        });
    }
    out
}

/// A grouping coefficient as an expression of the `Params` fields `p.L1`, `p.R`, ….
fn coefficient_tokens(cx: &Context<'_>, c: &Coefficient) -> TokenStream {
    let terms = c.terms.iter().map(|(v, m)| {
        let field = |p: usize| ident(&cx.model.params[p].name);
        let num: Vec<TokenStream> = m
            .iter()
            .filter(|(_, e)| *e > 0)
            .flat_map(|&(p, e)| {
                let f = field(p);
                (0..e).map(move |_| quote!(p.#f))
            })
            .collect();
        let den: Vec<TokenStream> = m
            .iter()
            .filter(|(_, e)| *e < 0)
            .flat_map(|&(p, e)| {
                let f = field(p);
                (0..-e).map(move |_| quote!(p.#f))
            })
            .collect();
        let lit = signed_lit(*v, cx.precision);
        let product = |f: Vec<TokenStream>| {
            f.into_iter()
                .reduce(|a, b| quote!(#a * #b))
                .unwrap_or_default()
        };
        let mut t = if num.is_empty() {
            quote!(#lit)
        } else if *v == 1.0 {
            product(num)
        } else {
            let n = product(num);
            quote!(#lit * #n)
        };
        if !den.is_empty() {
            let d = product(den);
            t = quote!(#t / (#d));
        }
        t
    });
    quote!(#(#terms)+*)
}
