//! Emission: lowered programs → Rust source via proc-macro2/quote → syn → prettyplease.
//!
//! The generated module is self-contained (it needs only `nalgebra`): speed and parameter names,
//! a `Params` struct (runtime mode), a `Precomputed` struct of parameter-only terms, the free
//! functions `mass_matrix`, `coriolis`, `gravity`, `inverse_dynamics`, `coriolis_matrix`, and
//! a wrapper struct named after the model (`Krang`) holding a parameter set. Statements carry the reports'
//! style comments (`let k12 = …; // w2.x`). Output is deterministic byte for byte.

use std::collections::HashMap;
use std::path::Path;

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

use crate::expr::accel_name;
use crate::kane::{ParamMode, Shape, Signature};
use crate::lower::{LExpr, Leaf, Lowered, Program};
use crate::model::{Model, ParamKind};

/// The generator's version, written into every header.
pub const GENERATOR_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Errors of emission.
#[derive(Debug, thiserror::Error)]
pub enum EmitError {
    /// The token stream did not parse as a Rust file (a generator bug).
    #[error("generated code for model `{model}` does not parse: {message}")]
    Parse {
        /// Model name.
        model: String,
        /// syn's message.
        message: String,
    },
    /// Writing the output failed.
    #[error("cannot write {path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        message: String,
    },
}

/// The floating-point type of a generated module: every matrix, vector, parameter and
/// literal is of this type.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Scalar {
    /// `f64` (the default).
    #[default]
    F64,
    /// `f32`; `sin_cos_n` computes in `f64` and rounds.
    F32,
}

impl Scalar {
    fn ty(self) -> TokenStream {
        match self {
            Scalar::F64 => quote!(f64),
            Scalar::F32 => quote!(f32),
        }
    }
}

/// `krang-fixed-wheels` → `KrangFixedWheels`.
pub fn type_name(model: &str) -> String {
    let mut out = String::new();
    let mut up = true;
    for ch in model.chars() {
        if ch.is_ascii_alphanumeric() {
            if up {
                out.extend(ch.to_uppercase());
            } else {
                out.push(ch);
            }
            up = false;
        } else {
            up = true;
        }
    }
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert_str(0, "Model");
    }
    out
}

fn ident(name: &str) -> Ident {
    // Model-derived names are sanitised to identifiers.
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    if syn::parse_str::<Ident>(&s).is_err() {
        return Ident::new_raw(&s, Span::call_site());
    }
    Ident::new(&s, Span::call_site())
}

fn lit(v: f64, scalar: Scalar) -> Literal {
    let mut l = match scalar {
        Scalar::F64 => Literal::f64_unsuffixed(v.abs()),
        // The shortest literal that rounds to the same f32.
        Scalar::F32 => Literal::f32_unsuffixed(v.abs() as f32),
    };
    l.set_span(Span::call_site());
    l
}

fn idx(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

fn signed_lit(v: f64, scalar: Scalar) -> TokenStream {
    let l = lit(v, scalar);
    if v < 0.0 { quote!(-#l) } else { quote!(#l) }
}

struct Names<'a> {
    model: &'a Model,
    stmt: &'a [crate::lower::Stmt],
    pre: &'a [String],
    scalar: Scalar,
}

impl Names<'_> {
    fn leaf(&self, l: &Leaf) -> TokenStream {
        let m = self.model;
        match *l {
            Leaf::Const(c) => signed_lit(c, self.scalar),
            Leaf::Param(p) => {
                let id = ident(&m.params[p].name);
                quote!(p.#id)
            }
            Leaf::Pre(s) => {
                let id = ident(&self.pre[s]);
                quote!(pc.#id)
            }
            Leaf::Speed(s) => {
                let id = ident(&m.speeds[s].name);
                quote!(#id)
            }
            Leaf::Accel(s) => {
                let id = ident(&accel_name(&m.speeds[s].name));
                quote!(#id)
            }
            Leaf::Sin(s) => {
                let id = ident(&format!("s_{}", m.speeds[s].coordinate));
                quote!(#id)
            }
            Leaf::Cos(s) => {
                let id = ident(&format!("c_{}", m.speeds[s].coordinate));
                quote!(#id)
            }
            Leaf::Coord(s) => {
                let id = ident(&m.speeds[s].coordinate);
                quote!(#id)
            }
            Leaf::Local(i) => {
                let id = ident(&self.stmt[i].name);
                quote!(#id)
            }
        }
    }

    /// An expression; `atomic` asks for parentheses around anything that is not a primary.
    fn expr(&self, e: &LExpr, atomic: bool) -> TokenStream {
        match e {
            LExpr::Leaf(Leaf::Const(c)) if *c < 0.0 && atomic => {
                let l = lit(*c, self.scalar);
                quote!((-#l))
            }
            LExpr::Leaf(l) => self.leaf(l),
            LExpr::Sum { constant, terms } => {
                let mut ts = TokenStream::new();
                // Start with a positive term when there is one (`b - a`, not `-a + b`): saves a
                // negation per statement.
                let mut terms: Vec<&(f64, LExpr)> = terms.iter().collect();
                if let Some(first_pos) = terms.iter().position(|(k, _)| *k > 0.0) {
                    let t = terms.remove(first_pos);
                    terms.insert(0, t);
                }
                for (i, (k, t)) in terms.into_iter().enumerate() {
                    let body = if k.abs() == 1.0 {
                        self.expr(t, false)
                    } else {
                        let kl = lit(*k, self.scalar);
                        let inner = self.expr(t, true);
                        quote!(#kl * #inner)
                    };
                    ts.extend(match (i, *k < 0.0) {
                        (0, false) => body,
                        (0, true) => quote!(-#body),
                        (_, false) => quote!(+ #body),
                        (_, true) => quote!(- #body),
                    });
                }
                if *constant != 0.0 {
                    let cl = lit(*constant, self.scalar);
                    ts.extend(if *constant < 0.0 {
                        quote!(- #cl)
                    } else {
                        quote!(+ #cl)
                    });
                }
                if atomic { quote!((#ts)) } else { ts }
            }
            LExpr::Prod(f) => {
                let mut num: Vec<TokenStream> = Vec::new();
                let mut den: Vec<TokenStream> = Vec::new();
                for (b, p) in f {
                    let t = self.expr(b, true);
                    for _ in 0..p.unsigned_abs() {
                        if *p > 0 {
                            num.push(t.clone());
                        } else {
                            den.push(t.clone());
                        }
                    }
                }
                let numt = if num.is_empty() {
                    quote!(1.0)
                } else {
                    let first = &num[0];
                    let rest = &num[1..];
                    quote!(#first #(* #rest)*)
                };
                let out = if den.is_empty() {
                    numt
                } else {
                    let first = &den[0];
                    let rest = &den[1..];
                    if den.len() == 1 {
                        quote!(#numt / #first)
                    } else {
                        quote!(#numt / (#first #(* #rest)*))
                    }
                };
                if atomic { quote!((#out)) } else { out }
            }
        }
    }
}

/// Statement comments of one program, keyed by local name.
fn comment_map(p: &Program) -> HashMap<String, String> {
    p.stmts
        .iter()
        .map(|s| (s.name.clone(), s.comment.clone()))
        .collect()
}

/// The `let` statements of `p`, with `after[0]` before the first and `after[i + 1]` right after
/// statement `i` (missing entries: nothing).
fn statements(names: &Names<'_>, p: &Program, after: &[TokenStream]) -> TokenStream {
    let mut ts = after.first().cloned().unwrap_or_default();
    for (i, s) in p.stmts.iter().enumerate() {
        let id = ident(&s.name);
        let e = names.expr(&s.expr, false);
        ts.extend(quote!(let #id = #e;));
        if let Some(a) = after.get(i + 1) {
            ts.extend(a.clone());
        }
    }
    ts
}

/// The statement with the highest index that `e` reads, if any.
fn last_local(e: &LExpr) -> Option<usize> {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => Some(*i),
        LExpr::Leaf(_) => None,
        LExpr::Sum { terms, .. } => terms.iter().filter_map(|(_, t)| last_local(t)).max(),
        LExpr::Prod(f) => f.iter().filter_map(|(b, _)| last_local(b)).max(),
    }
}

fn uses(p: &Program, pred: &dyn Fn(&Leaf) -> bool) -> bool {
    fn walk(e: &LExpr, pred: &dyn Fn(&Leaf) -> bool) -> bool {
        match e {
            LExpr::Leaf(l) => pred(l),
            LExpr::Sum { terms, .. } => terms.iter().any(|(_, t)| walk(t, pred)),
            LExpr::Prod(f) => f.iter().any(|(b, _)| walk(b, pred)),
        }
    }
    p.stmts.iter().any(|s| walk(&s.expr, pred)) || p.outputs.iter().any(|(_, _, e)| walk(e, pred))
}

fn function(
    model: &Model,
    low: &Lowered,
    pre: &[String],
    p: &Program,
    scalar: Scalar,
) -> TokenStream {
    let n = low.dof;
    let nl = idx(n);
    let t = scalar.ty();
    let names = Names {
        model,
        stmt: &p.stmts,
        pre,
        scalar,
    };
    let fname = ident(&p.name);
    let doc = format!(" {}", p.doc);
    let ops = format!(" Generated straight-line code: {}.", p.ops);
    let runtime = low.params == ParamMode::Runtime;
    let uses_p = uses(p, &|l| matches!(l, Leaf::Param(_)));
    let uses_pc = uses(p, &|l| matches!(l, Leaf::Pre(_)));
    let pname = if uses_p { quote!(p) } else { quote!(_p) };
    let pcname = if uses_pc { quote!(pc) } else { quote!(_pc) };
    let param_args = if runtime {
        quote!(#pname: &Params, #pcname: &Precomputed,)
    } else {
        quote!()
    };
    let (args, arg_doc) = match p.signature {
        Signature::Q => (
            quote!(q: &SVector<#t, #nl>),
            " `q`: coordinates in the order of [`COORDINATE_NAMES`].",
        ),
        Signature::QU => (
            quote!(q: &SVector<#t, #nl>, u: &SVector<#t, #nl>),
            " `q`, `u`: coordinates and speeds in the order of [`COORDINATE_NAMES`], [`SPEED_NAMES`].",
        ),
        Signature::QUUd => (
            quote!(q: &SVector<#t, #nl>, u: &SVector<#t, #nl>, ud: &SVector<#t, #nl>),
            " `q`, `u`, `ud`: coordinates, speeds and accelerations in the order of [`COORDINATE_NAMES`], [`SPEED_NAMES`].",
        ),
    };
    let mut prologue = TokenStream::new();
    if !p.sincos.is_empty() {
        // One batched call over the joint angles the function needs (vectorized), then the
        // per-joint names the statements use. `sin_q`/`cos_q` cannot clash with a model name:
        // they are read only by the bindings right below, which come before every other
        // binding, and the sine/cosine names all start with `s_`/`c_`.
        let angles = p.sincos.iter().map(|&s| {
            let sl = idx(s);
            quote!(q[#sl])
        });
        prologue.extend(quote!(let (sin_q, cos_q) = sin_cos_n([#(#angles),*]);));
        for (k, &s) in p.sincos.iter().enumerate() {
            let sn = ident(&format!("s_{}", model.speeds[s].coordinate));
            let cn = ident(&format!("c_{}", model.speeds[s].coordinate));
            let kl = idx(k);
            prologue.extend(quote!(let #sn = sin_q[#kl]; let #cn = cos_q[#kl];));
        }
    }
    for s in 0..n {
        if uses(p, &|l| *l == Leaf::Coord(s)) {
            let id = ident(&model.speeds[s].coordinate);
            let sl = idx(s);
            prologue.extend(quote!(let #id = q[#sl];));
        }
        if uses(p, &|l| *l == Leaf::Speed(s)) {
            let id = ident(&model.speeds[s].name);
            let sl = idx(s);
            prologue.extend(quote!(let #id = u[#sl];));
        }
        if uses(p, &|l| *l == Leaf::Accel(s)) {
            let id = ident(&accel_name(&model.speeds[s].name));
            let sl = idx(s);
            prologue.extend(quote!(let #id = ud[#sl];));
        }
    }
    // Every result entry is stored right after the last statement it reads, so that values
    // leave registers as soon as they are final (the programs are long; register pressure is
    // what limits their speed).
    let mut stores: Vec<TokenStream> = vec![TokenStream::new(); p.stmts.len() + 1];
    let (ret, init, result) = match p.shape {
        Shape::SymmetricMatrix | Shape::Matrix => {
            for (r, c, e) in &p.outputs {
                if matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0) {
                    continue;
                }
                let v = names.expr(e, false);
                let (r, c) = (idx(*r), idx(*c));
                stores[last_local(e).map_or(0, |i| i + 1)].extend(quote!(m[(#r, #c)] = #v;));
            }
            // Symmetric: the lower triangle is copied at the end by a loop over the column-major
            // storage. Mirrored stores next to the computation, or unrolled copies at the end
            // (which the compiler turns back into long-lived registers), cost much more
            // (measured for Krang: 1.2 µs vs 0.8 µs), and nalgebra's generic
            // `fill_lower_triangle_with_upper_triangle` runs 2800 instructions for Krang's 171
            // copies (this loop: about 0.25 µs less).
            let result = if p.shape == Shape::SymmetricMatrix {
                quote!({
                    let s = m.as_mut_slice();
                    for c in 1..#nl {
                        for r in 0..c {
                            s[r * #nl + c] = s[c * #nl + r];
                        }
                    }
                    m
                })
            } else {
                quote!(m)
            };
            (
                quote!(SMatrix<#t, #nl, #nl>),
                quote!(let mut m = SMatrix::<#t, #nl, #nl>::zeros();),
                result,
            )
        }
        Shape::Vector => {
            for (r, _, e) in &p.outputs {
                if matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0) {
                    continue;
                }
                let v = names.expr(e, false);
                let r = idx(*r);
                // `black_box` keeps LLVM's SLP vectorizer from packing the stores of adjacent
                // entries (and the expression trees behind them) into two-lane vectors: for
                // Krang's inverse dynamics that packing added ~25 % code of shuffles and spills
                // and doubled the time (1.17 µs vs 0.64 µs). (Krang's c got ~5 % slower.)
                stores[last_local(e).map_or(0, |i| i + 1)]
                    .extend(quote!(out[#r] = core::hint::black_box(#v);));
            }
            (
                quote!(SVector<#t, #nl>),
                quote!(let mut out = SVector::<#t, #nl>::zeros();),
                quote!(out),
            )
        }
    };
    let body = statements(&names, p, &stores);
    let unused_q = if p.sincos.is_empty() && !(0..n).any(|s| uses(p, &|l| *l == Leaf::Coord(s))) {
        quote!(let _ = q;)
    } else {
        quote!()
    };
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[allow(non_snake_case, unused_variables, clippy::all)]
        #[inline(never)]
        pub fn #fname(#param_args #args) -> #ret {
            #unused_q
            #prologue
            #init
            #body
            #result
        }
    }
}

fn params_items(model: &Model, scalar: Scalar) -> TokenStream {
    let np = idx(model.params.len());
    let t = scalar.ty();
    let fields: Vec<TokenStream> = model
        .params
        .iter()
        .map(|p| {
            let id = ident(&p.name);
            let what = match p.kind {
                ParamKind::Length => "length (m)",
                ParamKind::Gravity => "gravity acceleration (m/s²)",
                ParamKind::Inertial => match p.name.chars().next() {
                    Some('m') => "mass (kg)",
                    Some('M') => "first moment m·S (kg·m)",
                    _ => "inertia about the frame origin (kg·m²)",
                },
                ParamKind::Wheel => "wheel constant",
            };
            let doc = format!(" `{}`: {} (default {:?}).", p.name, what, p.value);
            quote!(#[doc = #doc] pub #id: #t,)
        })
        .collect();
    let defaults: Vec<TokenStream> = model
        .params
        .iter()
        .map(|p| {
            let id = ident(&p.name);
            let v = signed_lit(p.value, scalar);
            quote!(#id: #v,)
        })
        .collect();
    let names: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
    let ids: Vec<Ident> = model.params.iter().map(|p| ident(&p.name)).collect();
    let source = format!(
        " Model parameters of `{}`, named with the reports' symbols; `Default` holds the values of `{}`.",
        model.name,
        file_name(&model.source)
    );
    quote! {
        /// Number of model parameters.
        pub const PARAM_COUNT: usize = #np;

        #[doc = #source]
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[allow(non_snake_case)]
        pub struct Params {
            #(#fields)*
        }

        impl Default for Params {
            fn default() -> Self {
                Self { #(#defaults)* }
            }
        }

        /// A parameter name that the model does not have. Allocation-free (`no_std`): the name
        /// is kept inline, truncated to [`UnknownParameter::CAPACITY`] bytes.
        #[derive(Clone, Copy, PartialEq, Eq, Hash)]
        pub struct UnknownParameter {
            name: [u8; UnknownParameter::CAPACITY],
            len: u8,
        }

        impl UnknownParameter {
            /// The longest name kept, in bytes (longer names are cut at a character boundary).
            pub const CAPACITY: usize = 48;

            /// The error for `name` (truncated to [`UnknownParameter::CAPACITY`] bytes).
            pub fn new(name: &str) -> Self {
                let mut len = name.len().min(Self::CAPACITY);
                while !name.is_char_boundary(len) {
                    len -= 1;
                }
                let mut buf = [0u8; Self::CAPACITY];
                buf[..len].copy_from_slice(&name.as_bytes()[..len]);
                Self { name: buf, len: len as u8 }
            }

            /// The name that was asked for (truncated to [`UnknownParameter::CAPACITY`] bytes).
            pub fn name(&self) -> &str {
                core::str::from_utf8(&self.name[..usize::from(self.len)]).unwrap_or("")
            }
        }

        impl core::fmt::Debug for UnknownParameter {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.debug_struct("UnknownParameter").field("name", &self.name()).finish()
            }
        }

        impl core::fmt::Display for UnknownParameter {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                write!(f, "unknown parameter `{}`; the valid names are listed in Params::NAMES", self.name())
            }
        }

        impl core::error::Error for UnknownParameter {}

        #[allow(non_snake_case)]
        impl Params {
            /// Parameter names in declaration order (the order of [`Params::to_array`]).
            pub const NAMES: [&'static str; #np] = [#(#names),*];

            /// The value of parameter `name`, or `None` if the model has no such parameter.
            pub fn get(&self, name: &str) -> Option<#t> {
                match name {
                    #(#names => Some(self.#ids),)*
                    _ => None,
                }
            }

            /// Set parameter `name`; an error if the model has no such parameter.
            pub fn set(&mut self, name: &str, value: #t) -> Result<(), UnknownParameter> {
                match name {
                    #(#names => self.#ids = value,)*
                    _ => return Err(UnknownParameter::new(name)),
                }
                Ok(())
            }

            /// All values in the order of [`Params::NAMES`].
            pub fn to_array(&self) -> [#t; #np] {
                [#(self.#ids),*]
            }

            /// Parameters from values in the order of [`Params::NAMES`].
            pub fn from_array(v: [#t; #np]) -> Self {
                let [#(#ids),*] = v;
                Self { #(#ids),* }
            }
        }
    }
}

fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.to_owned())
}

fn precompute_items(model: &Model, low: &Lowered, pre: &[String], scalar: Scalar) -> TokenStream {
    let p = &low.precompute;
    let t = scalar.ty();
    let names = Names {
        model,
        stmt: &p.stmts,
        pre,
        scalar,
    };
    let body = statements(&names, p, &[]);
    let fields: Vec<Ident> = pre.iter().map(|s| ident(s)).collect();
    let uses_p = uses(p, &|l| matches!(l, Leaf::Param(_)));
    let pname = if uses_p { quote!(p) } else { quote!(_p) };
    let ops = format!(" Generated straight-line code: {}.", p.ops);
    quote! {
        /// Parameter-only subexpressions of the dynamics, computed once per parameter set.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Precomputed {
            #(#fields: #t,)*
        }

        impl Precomputed {
            /// Compute the parameter-only terms for `p`.
            #[doc = ""]
            #[doc = #ops]
            #[allow(non_snake_case, unused_variables, clippy::all)]
            pub fn new(#pname: &Params) -> Self {
                #body
                Self { #(#fields),* }
            }
        }
    }
}

fn wrapper_items(model: &Model, low: &Lowered, scalar: Scalar) -> TokenStream {
    let nl = idx(low.dof);
    let t = scalar.ty();
    let ty = ident(&type_name(&model.name));
    let doc = format!(
        " The dynamics of `{}` with one parameter set: `τ = M(q) u̇ + c(q, u) + g(q)`.",
        model.name
    );
    let coriolis_matrix = if low.function("coriolis_matrix").is_some() {
        quote! {
            /// Coriolis matrix C(q, u): `c(q, u) = C(q, u) u`, and `Ṁ − 2C` is
            /// skew-symmetric (Ṁ along q̇; for a wheeled base x and ψ do not enter M).
            #[inline]
            pub fn coriolis_matrix(
                &self,
                q: &SVector<#t, #nl>,
                u: &SVector<#t, #nl>,
            ) -> SMatrix<#t, #nl, #nl> {
                coriolis_matrix(&self.params, &self.pre, q, u)
            }
        }
    } else {
        quote!()
    };
    quote! {
        #[doc = #doc]
        ///
        /// Construction precomputes the parameter-only terms; the evaluation methods are
        /// allocation-free and cannot fail.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct #ty {
            params: Params,
            pre: Precomputed,
        }

        impl Default for #ty {
            fn default() -> Self {
                Self::new(Params::default())
            }
        }

        impl #ty {
            /// The model with parameter set `params`.
            pub fn new(params: Params) -> Self {
                Self { pre: Precomputed::new(&params), params }
            }

            /// The parameter set.
            pub fn params(&self) -> &Params {
                &self.params
            }

            /// Replace the parameter set (recomputes the parameter-only terms).
            pub fn set_params(&mut self, params: Params) {
                *self = Self::new(params);
            }

            /// Mass matrix M(q), symmetric positive definite.
            #[inline]
            pub fn mass_matrix(&self, q: &SVector<#t, #nl>) -> SMatrix<#t, #nl, #nl> {
                mass_matrix(&self.params, &self.pre, q)
            }

            /// Coriolis and centrifugal vector c(q, u).
            #[inline]
            pub fn coriolis(&self, q: &SVector<#t, #nl>, u: &SVector<#t, #nl>) -> SVector<#t, #nl> {
                coriolis(&self.params, &self.pre, q, u)
            }

            /// Gravity vector g(q).
            #[inline]
            pub fn gravity(&self, q: &SVector<#t, #nl>) -> SVector<#t, #nl> {
                gravity(&self.params, &self.pre, q)
            }

            /// Inverse dynamics τ = M(q) u̇ + c(q, u) + g(q), in one generated pass.
            #[inline]
            pub fn inverse_dynamics(
                &self,
                q: &SVector<#t, #nl>,
                u: &SVector<#t, #nl>,
                ud: &SVector<#t, #nl>,
            ) -> SVector<#t, #nl> {
                inverse_dynamics(&self.params, &self.pre, q, u, ud)
            }

            #coriolis_matrix
        }
    }
}

/// Generate the Rust module for a lowered model. Deterministic: same input, same bytes.
pub fn emit(model: &Model, low: &Lowered) -> Result<String, EmitError> {
    emit_scalar(model, low, Scalar::F64)
}

/// [`emit`] with the scalar type `scalar`. The module needs only `core` and `nalgebra` (it
/// builds in `no_std` crates).
pub fn emit_scalar(model: &Model, low: &Lowered, scalar: Scalar) -> Result<String, EmitError> {
    let nl = idx(low.dof);
    let runtime = low.params == ParamMode::Runtime;
    let pre: Vec<String> = low
        .pre_slots
        .iter()
        .map(|&i| low.precompute.stmts[i].name.clone())
        .collect();
    let speed_names: Vec<&str> = model.speeds.iter().map(|s| s.name.as_str()).collect();
    let coord_names: Vec<&str> = model.speeds.iter().map(|s| s.coordinate.as_str()).collect();
    let index_consts: Vec<TokenStream> = model
        .speeds
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let id = ident(&s.coordinate.to_uppercase());
            let doc = format!(
                " Index of `{}` in q (and of `{}` in u).",
                s.coordinate, s.name
            );
            let i = idx(i);
            quote!(#[doc = #doc] pub const #id: usize = #i;)
        })
        .collect();
    let trig: TokenStream = match scalar {
        Scalar::F64 => crate::trig::SIN_COS_SOURCE
            .parse()
            .expect("the sin_cos routine is valid Rust"),
        Scalar::F32 => {
            // The f64 routines stay (the batched one renamed); the functions call an `f32`
            // `sin_cos_n` that widens, calls the f64 batch and rounds.
            let f64_routine: TokenStream = crate::trig::SIN_COS_SOURCE
                .replacen("fn sin_cos_n<", "fn sin_cos_n_f64<", 1)
                .parse()
                .expect("the sin_cos routine is valid Rust");
            quote! {
                #f64_routine

                /// `(sin x[k], cos x[k])` in `f32` for every lane: computed in `f64` (batched)
                /// and rounded (correctly rounded but for double rounding).
                #[inline(always)]
                #[allow(clippy::needless_range_loop)]
                fn sin_cos_n<const N: usize>(x: [f32; N]) -> ([f32; N], [f32; N]) {
                    let mut wide = [0.0; N];
                    for k in 0..N {
                        wide[k] = f64::from(x[k]);
                    }
                    let (s, c) = sin_cos_n_f64(wide);
                    let mut out = ([0.0; N], [0.0; N]);
                    for k in 0..N {
                        out.0[k] = s[k] as f32;
                        out.1[k] = c[k] as f32;
                    }
                    out
                }
            }
        }
    };
    let mut items = quote! {
        use nalgebra::{SMatrix, SVector};

        #trig

        /// Number of generalized speeds (and coordinates).
        pub const DOF: usize = #nl;
        /// Generalized speed names, in the order of `u`.
        pub const SPEED_NAMES: [&str; #nl] = [#(#speed_names),*];
        /// Coordinate names, in the order of `q`.
        pub const COORDINATE_NAMES: [&str; #nl] = [#(#coord_names),*];

        /// Index constants of the coordinates (and of their speeds).
        pub mod index {
            #(#index_consts)*
        }
    };
    if runtime {
        items.extend(params_items(model, scalar));
        items.extend(precompute_items(model, low, &pre, scalar));
    }
    // Comments per generated function (local names are numbered per function).
    let mut comments: HashMap<String, HashMap<String, String>> = HashMap::new();
    comments.insert("new".into(), comment_map(&low.precompute));
    for p in &low.functions {
        items.extend(function(model, low, &pre, p, scalar));
        comments.insert(p.name.clone(), comment_map(p));
    }
    if runtime {
        items.extend(wrapper_items(model, low, scalar));
    }
    let file: syn::File = syn::parse2(items).map_err(|e| EmitError::Parse {
        model: model.name.clone(),
        message: e.to_string(),
    })?;
    let body = prettyplease::unparse(&file);
    let mut out = header(model, low);
    out.push_str(&annotate(&body, &comments));
    Ok(out)
}

fn header(model: &Model, low: &Lowered) -> String {
    let mut h = format!(
        "// @generated by kanegen {GENERATOR_VERSION} from model `{}` ({}). Do not edit.\n",
        model.name,
        file_name(&model.source)
    );
    h.push_str(&format!(
        "// Parameters: {}. Speeds ({}): {}.\n",
        match low.params {
            ParamMode::Runtime => "runtime inputs (Params)",
            ParamMode::Baked => "baked in as constants",
        },
        low.dof,
        model
            .speeds
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    h.push_str("// Operation counts per call:\n");
    if low.params == ParamMode::Runtime {
        h.push_str(&format!(
            "//   {:<17} {} (once per parameter set)\n",
            "Precomputed::new", low.precompute.ops
        ));
    }
    for p in &low.functions {
        h.push_str(&format!(
            "//   {:<17} {}; {} K and {} D variables\n",
            p.name, p.ops, p.k_vars, p.d_vars
        ));
    }
    h.push('\n');
    h
}

/// Append `// comment` to every `let NAME = …;` statement of the formatted source, using the
/// comments of the function the statement is in.
fn annotate(src: &str, comments: &HashMap<String, HashMap<String, String>>) -> String {
    let mut out = String::with_capacity(src.len() * 5 / 4);
    let mut pending: Option<&str> = None;
    let empty = HashMap::new();
    let mut current = &empty;
    for line in src.lines() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("pub fn ") {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            current = comments.get(&name).unwrap_or(&empty);
        }
        if pending.is_none()
            && let Some(rest) = t.strip_prefix("let ")
        {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if let Some(c) = current.get(&name)
                && !c.is_empty()
            {
                pending = Some(c.as_str());
            }
        }
        out.push_str(line);
        if let Some(c) = pending
            && t.ends_with(';')
        {
            out.push_str(" // ");
            out.push_str(c);
            pending = None;
        }
        out.push('\n');
    }
    out
}

/// Write `contents` to `path` only if the file does not already hold exactly these bytes.
/// Returns whether the file was written.
pub fn write_if_changed(path: &Path, contents: &str) -> Result<bool, EmitError> {
    if std::fs::read(path).is_ok_and(|old| old == contents.as_bytes()) {
        return Ok(false);
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| EmitError::Io {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?;
    }
    std::fs::write(path, contents).map_err(|e| EmitError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(true)
}
