//! The building blocks of a generated function's body, shared by every form (straight-line,
//! looped, combined, batched): inputs and what a program reads, the batched sines and cosines,
//! the statements, the result stores, the calls of generic bodies.

use proc_macro2::TokenStream;
use quote::quote;

use super::context::{Context, scalar_type};
use super::print::{Printer, ident, idx, lit, signed_lit};
use super::signature::result_type;
use crate::lower::mirrored_lanes::{LaneLeaves, LanePlan};
use crate::lower::{FunctionProgram, LExpr, Leaf, Program};
use crate::naming;
use crate::registry::{Inputs, Shape};

/// The statement with the highest index that `e` reads, if any.
pub(super) fn last_local(e: &LExpr) -> Option<usize> {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => Some(*i),
        LExpr::Leaf(_) => None,
        LExpr::Sum { terms, .. } => terms.iter().filter_map(|(_, t)| last_local(t)).max(),
        LExpr::Prod(f) => f.iter().filter_map(|(b, _)| last_local(b)).max(),
    }
}

/// Whether any statement or result of `p` reads a leaf satisfying `pred`.
pub(super) fn uses(p: &Program, pred: &dyn Fn(&Leaf) -> bool) -> bool {
    fn walk(e: &LExpr, pred: &dyn Fn(&Leaf) -> bool) -> bool {
        match e {
            LExpr::Leaf(l) => pred(l),
            LExpr::Sum { terms, .. } => terms.iter().any(|(_, t)| walk(t, pred)),
            LExpr::Prod(f) => f.iter().any(|(b, _)| walk(b, pred)),
        }
    }
    p.stmts.iter().any(|s| walk(&s.expr, pred)) || p.outputs.iter().any(|(_, _, e)| walk(e, pred))
}

/// Calls `f` on every leaf of `e`.
pub(super) fn for_each_leaf(e: &LExpr, f: &mut dyn FnMut(&Leaf)) {
    match e {
        LExpr::Leaf(l) => f(l),
        LExpr::Sum { terms, .. } => terms.iter().for_each(|(_, t)| for_each_leaf(t, f)),
        LExpr::Prod(fs) => fs.iter().for_each(|(b, _)| for_each_leaf(b, f)),
    }
}

/// Calls `f` on every leaf of every statement and result entry of `p`.
pub(super) fn for_each_program_leaf(p: &Program, f: &mut dyn FnMut(&Leaf)) {
    for e in p.stmts.iter().map(|s| &s.expr) {
        for_each_leaf(e, f);
    }
    for (_, _, e) in &p.outputs {
        for_each_leaf(e, f);
    }
}

/// How many distinct parameters (`p.…` and `pc.…`) `p` reads.
pub(super) fn params_read(p: &Program) -> usize {
    let mut read = std::collections::BTreeSet::new();
    let mut visit = |l: &Leaf| match *l {
        Leaf::Param(i) => {
            read.insert((0, i));
        }
        Leaf::Pre(i) => {
            read.insert((1, i));
        }
        _ => {}
    };
    for_each_program_leaf(p, &mut visit);
    read.len()
}

/// Which inputs a program reads, per speed, from one walk over it. (Asking [`uses`] once per
/// speed and kind walked the program 5n times: cubic in the length of a chain, since M and C
/// have n² entries.)
pub(super) struct Reads {
    pub(super) coord: Vec<bool>,
    pub(super) speed: Vec<bool>,
    pub(super) accel: Vec<bool>,
    pub(super) sin: Vec<bool>,
    pub(super) cos: Vec<bool>,
    pub(super) param: bool,
    pub(super) pre: bool,
}

impl Reads {
    /// `dof`: the length of the speed vectors (the coordinates of `q` are one more for a
    /// floating base, allowed for).
    pub(super) fn of(p: &Program, dof: usize) -> Self {
        let mut r = Reads {
            coord: vec![false; dof + 1],
            speed: vec![false; dof],
            accel: vec![false; dof],
            sin: vec![false; dof],
            cos: vec![false; dof],
            param: false,
            pre: false,
        };
        let mut visit = |l: &Leaf| match *l {
            Leaf::Coord(s) => r.coord[s] = true,
            Leaf::Speed(s) => r.speed[s] = true,
            Leaf::Accel(s) => r.accel[s] = true,
            Leaf::Sin(s) => r.sin[s] = true,
            Leaf::Cos(s) => r.cos[s] = true,
            Leaf::Param(_) => r.param = true,
            Leaf::Pre(_) => r.pre = true,
            Leaf::Const(_) | Leaf::Local(_) => {}
        };
        for_each_program_leaf(p, &mut visit);
        r
    }
}

/// The state arguments of a function with `inputs`, and their doc line.
pub(super) fn state_args(cx: &Context<'_>, inputs: Inputs) -> (TokenStream, &'static str) {
    let t = scalar_type(cx.precision);
    let nl = idx(cx.low.dof);
    let nq = idx(cx.low.nq);
    match inputs {
        Inputs::Q => (
            quote!(q: &SVector<#t, #nq>),
            " `q`: coordinates in the order of [`COORDINATE_NAMES`].",
        ),
        Inputs::QU => (
            quote!(q: &SVector<#t, #nq>, u: &SVector<#t, #nl>),
            " `q`, `u`: coordinates and speeds in the order of [`COORDINATE_NAMES`], [`SPEED_NAMES`].",
        ),
        Inputs::QUUd => (
            quote!(q: &SVector<#t, #nq>, u: &SVector<#t, #nl>, ud: &SVector<#t, #nl>),
            " `q`, `u`, `ud`: coordinates, speeds and accelerations in the order of [`COORDINATE_NAMES`], [`SPEED_NAMES`].",
        ),
    }
}

/// The names the results of `sin_cos_n` are bound to: `sin_q` and `cos_q`, or `_` for the one
/// the program reads no entry of (a program with a sine and no cosine left `cos_q` unused: a
/// compiler warning in the user's build).
pub(super) fn sin_cos_names(p: &Program, reads: &Reads) -> (TokenStream, TokenStream) {
    let name = |read: &[bool], n: TokenStream| {
        if p.sincos.iter().any(|&s| read[s]) {
            n
        } else {
            quote!(_)
        }
    };
    (
        name(&reads.sin, quote!(sin_q)),
        name(&reads.cos, quote!(cos_q)),
    )
}

/// The bindings of the inputs a function reads: one batched `sin_cos_n` call over the joint
/// angles (vectorized), then per-joint names, coordinates, speeds and accelerations.
pub(super) fn prologue(cx: &Context<'_>, p: &Program, reads: &Reads) -> TokenStream {
    let speeds = &cx.model.speeds;
    let mut ts = TokenStream::new();
    if !p.sincos.is_empty() {
        // `sin_q`/`cos_q` cannot clash with a model name: they are read only by the bindings
        // right below, which come before every other binding, and the sine/cosine names all
        // start with `s_`/`c_`.
        // A dependent (mimic) joint's angle is formed from its master's coordinate.
        let angles = p.sincos.iter().map(|&s| joint_angle(cx, s, &quote!(q)));
        let (sn, cn) = sin_cos_names(p, reads);
        ts.extend(quote!(let (#sn, #cn) = sin_cos_n([#(#angles),*]);));
        for (k, &s) in p.sincos.iter().enumerate() {
            let sn = ident(&naming::sin(&speeds[s].coordinate));
            let cn = ident(&naming::cos(&speeds[s].coordinate));
            let kl = idx(k);
            if reads.sin[s] {
                ts.extend(quote!(let #sn = sin_q[#kl];));
            }
            if reads.cos[s] {
                ts.extend(quote!(let #cn = cos_q[#kl];));
            }
        }
    }
    for (k, name) in cx.model.coordinate_names().into_iter().enumerate() {
        if reads.coord.get(k).copied().unwrap_or(false) {
            let (id, kl) = (ident(name), idx(k));
            ts.extend(quote!(let #id = q[#kl];));
        }
    }
    for (s, speed) in speeds.iter().enumerate() {
        let sl = idx(s);
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

/// The angle whose sine and cosine speed `s`'s joint needs, read from the coordinates `q`
/// (`q[5]`): a dependent (mimic) joint's angle is formed from its master's coordinate
/// (`-q[3]`, `2.0 * q[3] + 0.1`). The single-state prologue indexes `f64`s, the batched one
/// `kanegen_runtime::lanes::Lanes` (whose operators take `f64` on either side).
pub(super) fn joint_angle(cx: &Context<'_>, s: usize, q: &TokenStream) -> TokenStream {
    let coord = |s: usize| if cx.low.floating && s >= 6 { s + 1 } else { s };
    match cx.low.mimic_angles.iter().find(|(d, _)| *d == s) {
        Some((_, m)) => {
            let ml = idx(coord(m.master as usize));
            let aq = match m.multiplier {
                1.0 => quote!(#q[#ml]),
                -1.0 => quote!(-#q[#ml]),
                a => {
                    let a = signed_lit(a, cx.precision);
                    quote!(#a * #q[#ml])
                }
            };
            let b = lit(m.offset.abs(), cx.precision);
            match m.offset {
                0.0 => aq,
                o if o < 0.0 => quote!(#aq - #b),
                _ => quote!(#aq + #b),
            }
        }
        None => {
            let sl = idx(coord(s));
            quote!(#q[#sl])
        }
    }
}

/// The result: its type, its initialisation, the stores placed after the statements they read
/// (`stores[i + 1]` right after statement `i`), and the final expression.
pub(super) struct Result {
    pub(super) ty: TokenStream,
    pub(super) init: TokenStream,
    pub(super) stores: Stores,
    pub(super) value: TokenStream,
    /// Whether the statements and stores run in a block in which the result binding `m` is
    /// the `&mut` to it returned by `core::hint::black_box` (see [`result`]).
    pub(super) in_memory: bool,
}

/// Result stores as text lines (`m[(0, 1)] = d5;`), by position: `stores[i + 1]` right after
/// statement `i` (see [`Printer::statement_block`]).
pub(super) type Stores = Vec<Vec<String>>;

/// `e` as text, with multiply-add chains ([`Printer::expr_text_with`]).
pub(super) fn text(cx: &Context<'_>, printer: &Printer<'_>, e: &LExpr) -> String {
    let mut s = String::new();
    printer.expr_text_with(&cx.leaf_names, e, false, true, &mut s);
    s
}

/// The result entries of `p` that are not the constant zero (the result starts zeroed).
pub(super) fn nonzero_outputs(p: &Program) -> impl Iterator<Item = &(usize, usize, LExpr)> + Clone {
    p.outputs
        .iter()
        .filter(|(_, _, e)| !matches!(e, LExpr::Leaf(Leaf::Const(z)) if *z == 0.0))
}

/// Add the text line `store` to the stores placed right after the last statement `e` reads.
pub(super) fn store_text_after(stores: &mut [Vec<String>], e: &LExpr, store: String) {
    stores[last_local(e).map_or(0, |i| i + 1)].push(store);
}

/// The result of an [`Shape::Isometry`] function: rotation and translation stored like a
/// matrix's entries, then one `Isometry3` (its rotation as a unit quaternion, by
/// `UnitQuaternion::from_rotation_matrix`).
pub(super) fn isometry(
    cx: &Context<'_>,
    printer: &Printer<'_>,
    p: &Program,
    mut stores: Stores,
) -> Result {
    let t = scalar_type(cx.precision);
    let nonzero: Vec<_> = nonzero_outputs(p).collect();
    let rot_mut = binding(nonzero.iter().any(|(_, c, _)| *c < 3));
    let pos_mut = binding(nonzero.iter().any(|(_, c, _)| *c == 3));
    for (r, c, e) in nonzero {
        let v = text(cx, printer, e);
        let store = if *c < 3 {
            format!("rot[({r}, {c})] = {v};")
        } else {
            format!("pos[{r}] = {v};")
        };
        store_text_after(&mut stores, e, store);
    }
    Result {
        ty: result_type(cx, Shape::Isometry),
        init: quote! {
            let #rot_mut rot = nalgebra::Matrix3::<#t>::zeros();
            let #pos_mut pos = nalgebra::Vector3::<#t>::zeros();
        },
        stores,
        in_memory: false,
        value: quote!(nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::from(pos),
            nalgebra::UnitQuaternion::from_rotation_matrix(
                &nalgebra::Rotation3::from_matrix_unchecked(rot),
            ),
        )),
    }
}

/// `mut` for a result binding that is stored to, nothing for one that stays zero.
pub(super) fn binding(stored: bool) -> TokenStream {
    if stored { quote!(mut) } else { quote!() }
}

/// Every result entry is stored right after the last statement it reads, so that values leave
/// registers as soon as they are final (the programs are long; register pressure is what limits
/// their speed).
///
/// An n×n result (M, the Coriolis matrix) is written in memory as it is computed: emitted as
/// an `_into` function ([`into_pair`]), whose `m` is the caller's `&mut` matrix; otherwise
/// (a function without that form) the statements run in a block where `m` is
/// `core::hint::black_box(&mut m)`. Without either LLVM's
/// scalar replacement turns the local matrix into 361 separate values that live (spilled to the
/// stack) until the function's end, where all of them are reloaded and stored into the result —
/// and the lower-triangle copy loop of a symmetric matrix was unrolled into 171 more reloads
/// and stores there (Krang's M, x86-64-v3 copy: 2,867 instructions of which 1,067 addressed the
/// stack). The cost is a `memset` of the zeroed matrix and a `memcpy` into the return slot
/// (2.9 KB each for 19 speeds). A symmetric matrix's lower entry is stored right after its
/// upper one (`m[(3, 5)] = m[(5, 3)];`, which LLVM forwards from the register), so no copy is
/// left at the end (measured on Krang, Nov 2026, Intel Xeon with AVX-512). Vectors stay scalar-replaced (19 values: in memory they
/// measured slower).
pub(super) fn result(cx: &Context<'_>, printer: &Printer<'_>, p: &Program, shape: Shape) -> Result {
    let t = scalar_type(cx.precision);
    let nl = idx(cx.low.dof);
    let mut stores: Stores = vec![Vec::new(); p.stmts.len() + 1];
    let nonzero = nonzero_outputs(p);
    match shape {
        Shape::SymmetricMatrix | Shape::Matrix => {
            let mirror = shape == Shape::SymmetricMatrix;
            for (r, c, e) in nonzero {
                let v = text(cx, printer, e);
                store_text_after(&mut stores, e, format!("m[({r}, {c})] = {v};"));
                if mirror && r != c {
                    store_text_after(&mut stores, e, format!("m[({c}, {r})] = m[({r}, {c})];"));
                }
            }
            Result {
                ty: quote!(SMatrix<#t, #nl, #nl>),
                init: quote!(let mut m = SMatrix::<#t, #nl, #nl>::zeros();),
                stores,
                value: quote!(m),
                in_memory: true,
            }
        }
        Shape::Dense { rows, cols } => {
            let (r, c) = (
                idx(rows.size_in(&cx.low.sizes)),
                idx(cols.size_in(&cx.low.sizes)),
            );
            let mutable = binding(nonzero.clone().next().is_some());
            for (r, c, e) in nonzero {
                let v = text(cx, printer, e);
                store_text_after(&mut stores, e, format!("m[({r}, {c})] = {v};"));
            }
            Result {
                ty: result_type(cx, shape),
                init: quote!(let #mutable m = SMatrix::<#t, #r, #c>::zeros();),
                stores,
                value: quote!(m),
                in_memory: false,
            }
        }
        Shape::Scalar => {
            // The one entry is the function's value, after every statement.
            // With multiply-add chains, as the statements (the text parses: it is what the
            // statements print, which the formatted module parses).
            let value = p.outputs.first().map_or_else(
                || printer.expr(&LExpr::Leaf(Leaf::Const(0.0)), false),
                |(_, _, e)| {
                    text(cx, printer, e)
                        .parse()
                        .unwrap_or_else(|_| printer.expr(e, false))
                },
            );
            Result {
                ty: result_type(cx, shape),
                init: TokenStream::new(),
                stores,
                value,
                in_memory: false,
            }
        }
        Shape::Isometry => isometry(cx, printer, p, stores),
        Shape::Vector => {
            // A structurally zero vector (c, g of a cart on a horizontal rail) is never written.
            let mutable = if nonzero.clone().next().is_some() {
                quote!(mut)
            } else {
                TokenStream::new()
            };
            for (r, _, e) in nonzero {
                let v = text(cx, printer, e);
                // `black_box` keeps LLVM's SLP vectorizer from packing the stores of adjacent
                // entries (and the expression trees behind them) into two-lane vectors: for
                // Krang's inverse dynamics that packing added ~25 % code of shuffles and spills
                // and doubled the time (1.17 µs vs 0.64 µs). (Krang's c got ~5 % slower.)
                store_text_after(
                    &mut stores,
                    e,
                    format!("out[{r}] = core::hint::black_box({v});"),
                );
            }
            Result {
                ty: quote!(SVector<#t, #nl>),
                init: quote!(let #mutable out = SVector::<#t, #nl>::zeros();),
                stores,
                value: quote!(out),
                in_memory: false,
            }
        }
    }
}

/// Whether registry function `f` is emitted as an `_into` function that writes the caller's
/// matrix and a by-value function that calls it: the n×n results (M, the Coriolis matrix).
pub(super) fn has_into(f: &FunctionProgram) -> bool {
    f.frame.is_none() && matches!(f.id.spec().shape, Shape::SymmetricMatrix | Shape::Matrix)
}

/// The lane plan program `p` is emitted with, if any: the lowering paired its statements
/// (`plan`, see [`crate::lower::lanes`]), the module is `f64` and the function is not split
/// into blocks.
pub(super) fn lanes_in<'a>(
    cx: &'a Context<'_>,
    p: &Program,
    plan: Option<&'a LanePlan>,
) -> Option<(&'a LaneLeaves, &'a LanePlan)> {
    let leaves = cx.low.lane_leaves.as_ref()?;
    let plan = plan?;
    (cx.precision == crate::options::Precision::F64 && p.stmts.len() <= cx.split_above)
        .then_some((leaves, plan))
}

/// The statements of `p` with `stores` placed after the statements they read: the lane block
/// where the statements are paired (`lanes`, from [`lanes_in`]), else the plain statement block
/// (which keeps the `stored` and `read_at_end` values visible across its split blocks).
pub(super) fn body_block(
    cx: &Context<'_>,
    printer: &Printer<'_>,
    p: &Program,
    lanes: Option<(&LaneLeaves, &LanePlan)>,
    stores: Vec<Vec<String>>,
    outputs: (&[&LExpr], &[&LExpr]),
) -> super::text::Block {
    match lanes {
        Some((leaves, plan)) => {
            super::mirrored_lanes::lane_block(printer, &cx.leaf_names, leaves, p, plan, stores)
        }
        None => printer.statement_block(&cx.leaf_names, stores, outputs, cx.split_above, true),
    }
}

/// `m[(r, c)] = 0.0;` for every entry of an n×n result that no store of [`result`] writes (the
/// structural zeros), so that the `_into` form writes every entry exactly once.
pub(super) fn zero_stores(p: &Program, n: usize, mirror: bool) -> Vec<String> {
    let mut written = vec![false; n * n];
    for (r, c, _) in nonzero_outputs(p) {
        written[r * n + c] = true;
        if mirror {
            written[c * n + r] = true;
        }
    }
    // Column by column: the matrix's memory order.
    (0..n)
        .flat_map(|c| (0..n).map(move |r| (r, c)))
        .filter(|&(r, c)| !written[r * n + c])
        .map(|(r, c)| format!("m[({r}, {c})] = 0.0;"))
        .collect()
}

/// Which instruction-set copies a dispatched function is compiled in.
#[derive(Clone, Copy)]
pub(super) enum Copies {
    /// The baseline and x86-64-v3 (`isa::dispatch_fused_with`): single-state functions. An
    /// x86-64-v4 copy was measured no faster for them (Krang's M, c, g, τ, C within 5 %) and
    /// cost 43 % more compile time (Nov 2026, Intel Xeon with AVX-512).
    BaselineAndV3,
    /// Also x86-64-v4 (`isa::dispatch_fused_wide_with`): the batched functions, whose loop
    /// over the states LLVM vectorizes 8 lanes wide with AVX-512.
    WithV4,
    /// The baseline and x86-64-v3 for a body with paired statements
    /// (`isa::dispatch_pair_with`): the body's first argument is the copy's two-lane
    /// multiply-add (`lanes`).
    Lanes,
    /// [`Copies::Lanes`] and an x86-64-v4 copy (`isa::dispatch_pair_wide_with`): the looped
    /// derivatives' straight-line part, whose 54 KB of statements (Krang) run 4 % faster with
    /// AVX-512's 32 registers (Nov 2026, Intel Xeon with AVX-512).
    LanesWithV4,
}

/// The call of a generated function's inner `body::<A, …>(…, out)`, generic over the
/// multiply-add (`A: isa::Arith`), that writes into the caller's result `out` (an `_into`
/// form): with dispatch `isa::dispatch_fused_with` (or `dispatch_fused_wide_with`, by
/// `copies`), which hands `out` to the one copy that runs (`Plain` for the baseline, `Fused`
/// for x86-64-v3 and v4; two closures cannot both borrow it), without it `isa::Native`.
/// `generics` follows `A` (`, L` for a batch); `args` are the arguments before `out`, each
/// followed by a comma.
pub(super) fn call_body_into(
    cx: &Context<'_>,
    copies: Copies,
    generics: TokenStream,
    args: TokenStream,
    out: TokenStream,
) -> TokenStream {
    let lanes = matches!(copies, Copies::Lanes | Copies::LanesWithV4);
    if cx.isa_dispatch {
        let dispatch = match copies {
            Copies::BaselineAndV3 => quote!(dispatch_fused_with),
            Copies::WithV4 => quote!(dispatch_fused_wide_with),
            Copies::Lanes => quote!(dispatch_pair_with),
            Copies::LanesWithV4 => quote!(dispatch_pair_wide_with),
        };
        if lanes {
            return quote!(kanegen_runtime::isa::#dispatch(
                #out,
                #[inline(always)]
                |out, lanes| body::<kanegen_runtime::isa::Plain, _ #generics>(lanes, #args out),
                #[inline(always)]
                |out, lanes| body::<kanegen_runtime::isa::Fused, _ #generics>(lanes, #args out),
            ));
        }
        quote!(kanegen_runtime::isa::#dispatch(
            #out,
            #[inline(always)]
            |out| body::<kanegen_runtime::isa::Plain #generics>(#args out),
            #[inline(always)]
            |out| body::<kanegen_runtime::isa::Fused #generics>(#args out),
        ))
    } else if lanes {
        quote!(body::<kanegen_runtime::isa::Native, _ #generics>(
            kanegen_runtime::isa::native_pair(),
            #args #out
        ))
    } else {
        quote!(body::<kanegen_runtime::isa::Native #generics>(#args #out))
    }
}

/// The two functions of an n×n result: `NAME_into(…, out: &mut SMatrix)`, whose body (the
/// statements and stores of [`result`], every entry written once) writes into the caller's
/// matrix, and `NAME(…) -> SMatrix`, which zeroes a matrix and calls it.
///
/// Writing into the caller's matrix is what the by-value form did through
/// `core::hint::black_box(&mut m)` (each entry goes to memory as soon as it is final; see
/// [`result`]), without its two block copies: the `memset` of the zeroed local and the `memcpy`
/// of 2.9 KB (19 speeds) into the return slot. The by-value form keeps one `memset` (safe code
/// initialises the matrix before lending it); the body is compiled once, in `_into`.
pub(super) fn into_pair(
    cx: &Context<'_>,
    f: &FunctionProgram,
    (doc, arg_doc, ops): (&str, &str, &str),
    (param_args, lanes): (TokenStream, bool),
    ty: &TokenStream,
    body: TokenStream,
) -> TokenStream {
    let spec = f.id.spec();
    let fname = ident(spec.name);
    let into = ident(&format!("{}_into", spec.name));
    let (args, _) = state_args(cx, spec.inputs);
    let names = super::signature::arg_names(spec.inputs);
    let (outer_params, pass_params) = outer_params(cx);
    let call = call_body_into(
        cx,
        if lanes {
            Copies::Lanes
        } else {
            Copies::BaselineAndV3
        },
        quote!(),
        quote!(#pass_params #names,),
        quote!(out),
    );
    let (generics, lanes_arg) = body_generics(cx, lanes);
    let into_doc = format!(
        " [`{}`] written into `out` (every entry), without returning the matrix by value: \
         for a caller that keeps its matrix (a controller's workspace), and a little faster.",
        spec.name
    );
    let see_into = format!(
        " [`{}_into`] writes the result into a matrix of the caller's.",
        spec.name
    );
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[doc = #see_into]
        #[inline]
        pub fn #fname(#outer_params #args) -> #ty {
            let mut m = <#ty>::zeros();
            #into(#pass_params #names, &mut m);
            m
        }
        #[doc = #into_doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = #ops]
        #[inline(never)]
        pub fn #into(#outer_params #args, out: &mut #ty) {
            #[inline(always)]
            fn body<#generics>(#lanes_arg #param_args #args, m: &mut #ty) {
                #body
            }
            #call
        }
    }
}

/// The parameter arguments of a function body (`p: &Params, pc: &Precomputed,` with parameters
/// at run time, `_p`/`_pc` where the body does not read them; nothing when they are baked).
pub(super) fn param_args(cx: &Context<'_>, reads: &Reads) -> TokenStream {
    if cx.low.params.is_runtime() {
        let pname = if reads.param { quote!(p) } else { quote!(_p) };
        let pcname = if reads.pre { quote!(pc) } else { quote!(_pc) };
        quote!(#pname: &Params, #pcname: &Precomputed,)
    } else {
        quote!()
    }
}

/// A public function's parameter list (`p: &Params, pc: &Precomputed,` with parameters at run
/// time, else nothing) and the same names passed on to its inner body (`p, pc,`).
pub(super) fn outer_params(cx: &Context<'_>) -> (TokenStream, TokenStream) {
    if cx.low.params.is_runtime() {
        (quote!(p: &Params, pc: &Precomputed,), quote!(p, pc,))
    } else {
        (quote!(), quote!())
    }
}

/// A function's parameters (`p: &Params, pc: &Precomputed,` with parameters at run time) and
/// its body as a generic inner function `body::<A: Arith>` (`A::mul_add` in the statements)
/// followed by its call. With dispatch it is compiled twice, with `Plain` for the baseline and
/// with `Fused` for x86-64-v3, and `kanegen_runtime::isa::dispatch_fused` runs the copy for the
/// CPU (the closures and the body inline into each copy); without, once with `Native` (fused
/// when the crate is compiled with FMA). `param_args` are the inner function's parameters (`_p`
/// when it does not read them); with `lanes` (a body with paired statements, see
/// [`super::lanes`]) the body also takes the copy's two-lane multiply-add `lanes: P` first,
/// passed by `isa::dispatch_pair_with` (`isa::native_pair()` without dispatch).
pub(super) fn generic_body(
    cx: &Context<'_>,
    inputs: Inputs,
    (param_args, lanes): (TokenStream, bool),
    ty: &TokenStream,
    body: TokenStream,
) -> (TokenStream, TokenStream) {
    let (args, _) = state_args(cx, inputs);
    let names = super::signature::arg_names(inputs);
    let (outer_params, pass_params) = outer_params(cx);
    let (generics, lanes_arg) = body_generics(cx, lanes);
    let call = if lanes && cx.isa_dispatch {
        quote!(kanegen_runtime::isa::dispatch_pair_with(
            (),
            #[inline(always)]
            |(), lanes| body::<kanegen_runtime::isa::Plain, _>(lanes, #pass_params #names),
            #[inline(always)]
            |(), lanes| body::<kanegen_runtime::isa::Fused, _>(lanes, #pass_params #names),
        ))
    } else if lanes {
        quote!(body::<kanegen_runtime::isa::Native, _>(
            kanegen_runtime::isa::native_pair(),
            #pass_params #names
        ))
    } else if cx.isa_dispatch {
        quote!(kanegen_runtime::isa::dispatch_fused(
            #[inline(always)]
            || body::<kanegen_runtime::isa::Plain>(#pass_params #names),
            #[inline(always)]
            || body::<kanegen_runtime::isa::Fused>(#pass_params #names),
        ))
    } else {
        quote!(body::<kanegen_runtime::isa::Native>(#pass_params #names))
    };
    let generic = quote! {
        #[inline(always)]
        fn body<#generics>(#lanes_arg #param_args #args) -> #ty {
            #body
        }
        #call
    };
    (outer_params, generic)
}

/// The generic parameters of a function body (`A: Arith<f64>`, and with `lanes` the two-lane
/// multiply-add `P: PairArith`) and, with `lanes`, its first argument `lanes: P,`.
pub(super) fn body_generics(cx: &Context<'_>, lanes: bool) -> (TokenStream, TokenStream) {
    let t = scalar_type(cx.precision);
    if lanes {
        (
            quote!(A: kanegen_runtime::isa::Arith<#t>, P: kanegen_runtime::isa::PairArith),
            quote!(lanes: P,),
        )
    } else {
        (quote!(A: kanegen_runtime::isa::Arith<#t>), quote!())
    }
}

/// Which state inputs `p` reads: `q` (a coordinate, or a joint angle for the sines and
/// cosines), `u`, `ud`.
pub(super) fn state_reads(p: &Program, reads: &Reads) -> [bool; 3] {
    [
        !p.sincos.is_empty() || reads.coord.contains(&true),
        reads.speed.contains(&true),
        reads.accel.contains(&true),
    ]
}

/// `let _ = q;` (and `u`, `ud`) for the inputs a function's program never reads, so that the
/// generated signature stays uniform without unused-variable warnings (single-state and batched
/// forms alike).
pub(super) fn unused_inputs(inputs: Inputs, p: &Program, reads: &Reads) -> TokenStream {
    let [reads_q, reads_u, reads_ud] = state_reads(p, reads);
    let mut unused = TokenStream::new();
    if !reads_q {
        unused.extend(quote!(let _ = q;));
    }
    if inputs.needs_u() && !reads_u {
        unused.extend(quote!(let _ = u;));
    }
    if inputs.needs_ud() && !reads_ud {
        unused.extend(quote!(let _ = ud;));
    }
    unused
}
