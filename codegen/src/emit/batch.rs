//! Batched functions: the statements of one generated function evaluated at `L` states per
//! call, in two layouts ([`Layout`]): an array of states (`mass_matrix_batch_into(p, pc,
//! &[q; L], &mut [SMatrix; L])`, and the by-value `mass_matrix_batch(p, pc, &[q; L]) ->
//! [SMatrix; L]`) and a structure of arrays (`mass_matrix_batch_soa_into(p, pc,
//! &SVector<Lanes<L>, N>, &mut SMatrix<Lanes<L>, N, N>)` and `mass_matrix_batch_soa`), whose
//! inputs need no transposition and whose result entries are stored as whole vectors.
//!
//! The body is a loop over the states around the single-state function's statements, printed
//! exactly as there (the same multiply-add chains, generic over `A: Arith<f64>` and dispatched
//! like the single-state function, with an x86-64-v4 copy more: `isa::dispatch_fused_wide_with`),
//! so lane `l` is the single-state value at state `l`, bit for bit with the same instruction
//! set (the x86-64-v4 copy gives the x86-64-v3 copy's bits). LLVM's loop vectorizer runs the
//! loop body on vectors across the states. The body is emitted once per function
//! (`NAME_batch_body`, [`shared_body`]) and inlined into both layouts' functions: it reads the
//! inputs as lanes (`&[Lanes<L>; N]`), computes the sines and cosines lane by lane before the
//! loop, and stores each entry through the layout's `kanegen_runtime::lanes::LaneStore`
//! (straight into the caller's `L` results, or into lane `l` of an entry): from a local lane
//! buffer after the loop, or from inside it ([`EntryStores`]). Each layout's function converts
//! its inputs to lanes (transposed, or read in place or copied) and writes the entries no
//! statement stores after the body. A result with more entries than one
//! vectorized loop can store is computed in several loops ([`loop_parts`]). `L` is a const
//! generic: one emitted body for every batch size and both layouts.
//! `docs/batched-and-dispatch.md` has the measured figures.

use std::borrow::Cow;
use std::collections::BTreeMap;

use proc_macro2::TokenStream;
use quote::quote;

use super::body::{
    Reads, Stores, nonzero_outputs, state_reads, store_text_after, text, unused_inputs,
};
use super::context::Context;
use super::print::{Printer, ident, idx};
use super::signature::{arg_names, return_type};
use crate::lower::{self, FunctionProgram, LExpr, Program};
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

/// How a batched function takes its `L` states and gives its `L` results.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Layout {
    /// An array of states: `&[SVector<f64, N>; L]` per input, `&mut [SMatrix<f64, R, C>; L]`
    /// out (`NAME_batch`, `NAME_batch_into`). The inputs are transposed to lane-major order in
    /// the call, and each result entry is scattered into the `L` results.
    States,
    /// A structure of arrays: `&SVector<Lanes<L>, N>` per input, `&mut SMatrix<Lanes<L>, R,
    /// C>` out, every entry holding the `L` states' values (`NAME_batch_soa`,
    /// `NAME_batch_soa_into`): the inputs are read as they are and each result entry is one
    /// vector store.
    Lanes,
}

impl Layout {
    const ALL: [Layout; 2] = [Layout::States, Layout::Lanes];

    /// The by-value function's name (the `_into` form adds `_into`).
    fn name(self, spec: &FunctionSpec) -> String {
        match self {
            Layout::States => format!("{}_batch", spec.name),
            Layout::Lanes => format!("{}_batch_soa", spec.name),
        }
    }

    /// The state arguments: `&[SVector<f64, N>; L]` or `&SVector<Lanes<L>, N>` per input.
    fn args(self, cx: &Context<'_>, inputs: Inputs) -> TokenStream {
        let ty = |n: usize| {
            let n = idx(n);
            match self {
                Layout::States => quote!(&[SVector<f64, #n>; L]),
                Layout::Lanes => quote!(&SVector<kanegen_runtime::lanes::Lanes<L>, #n>),
            }
        };
        // `q` has `NQ` entries (one more than the speeds for a floating base).
        let (v, c) = (ty(cx.low.dof), ty(cx.low.nq));
        match inputs {
            Inputs::Q => quote!(q: #c),
            Inputs::QU => quote!(q: #c, u: #v),
            Inputs::QUUd => quote!(q: #c, u: #v, ud: #v),
        }
    }

    /// The result type: `[SMatrix<f64, R, C>; L]` or `SMatrix<Lanes<L>, R, C>`.
    fn result(self, cx: &Context<'_>, spec: &FunctionSpec) -> TokenStream {
        match self {
            Layout::States => {
                let ty = return_type(cx, spec);
                quote!([#ty; L])
            }
            Layout::Lanes => {
                let (rows, cols) = spec.shape.size_in(&cx.low.sizes);
                let (r, c) = (idx(rows), idx(cols));
                if cols == 1 {
                    quote!(SVector<kanegen_runtime::lanes::Lanes<L>, #r>)
                } else {
                    quote!(SMatrix<kanegen_runtime::lanes::Lanes<L>, #r, #c>)
                }
            }
        }
    }

    /// The initialised result of the by-value form, which the `_into` form then overwrites.
    fn zeros(self, cx: &Context<'_>, spec: &FunctionSpec) -> TokenStream {
        match self {
            Layout::States => {
                let one = return_type(cx, spec);
                quote!([<#one>::zeros(); L])
            }
            Layout::Lanes => quote!(kanegen_runtime::lanes::zeros()),
        }
    }

    /// The state argument `x` as the body reads it, `&[Lanes<L>; N]`: transposed to
    /// lane-major order into a local array (`lanes::inputs`), or, already in lanes, a local
    /// copy (`lanes::inputs_soa`: where the loops read `x` and store straight into the result,
    /// [`EntryStores::Direct`], like the parameters) or the caller's storage itself
    /// (`lanes::as_lanes`: loops that store into local lane buffers, or read only the sines and
    /// cosines computed from `x` before them).
    fn inputs(self, x: &TokenStream, to: EntryStores, read_in_loop: bool) -> TokenStream {
        match (self, to, read_in_loop) {
            (Layout::States, _, _) => quote!(let #x = &kanegen_runtime::lanes::inputs(#x);),
            (Layout::Lanes, EntryStores::Direct, true) => {
                quote!(let #x = &kanegen_runtime::lanes::inputs_soa(#x);)
            }
            (Layout::Lanes, _, _) => quote!(let #x = kanegen_runtime::lanes::as_lanes(#x);),
        }
    }
}

/// A state input the program reads (`q`, `u`, `ud`, as [`state_reads`] says): its name, and
/// whether the loops read it themselves rather than only through the sines and cosines
/// computed before them (those a direct body must copy: [`EntryStores::Direct`]).
struct ReadInput {
    name: TokenStream,
    in_loop: bool,
}

/// The state inputs the program reads, in argument order.
fn read_inputs(p: &Program, reads: &Reads) -> Vec<ReadInput> {
    let in_loop = [&reads.coord, &reads.speed, &reads.accel].map(|r| r.contains(&true));
    state_reads(p, reads)
        .into_iter()
        .zip([quote!(q), quote!(u), quote!(ud)])
        .zip(in_loop)
        .filter_map(|((read, name), in_loop)| read.then_some(ReadInput { name, in_loop }))
        .collect()
}

/// The sines and cosines before the loop: all joint angles of all states in one lane-wise
/// `sin_cos` (a dependent joint's angle from its master's).
fn lane_sin_cos(cx: &Context<'_>, p: &Program, reads: &Reads) -> TokenStream {
    if p.sincos.is_empty() {
        return TokenStream::new();
    }
    // All angles of all states in one call (a dependent joint's from its master's).
    let angles = p.sincos.iter().map(|&s| {
        let a = super::body::joint_angle(cx, s, &quote!(q));
        if cx.low.mimic_angles.iter().any(|(d, _)| *d == s) {
            quote!((#a).0)
        } else {
            quote!(#a.0)
        }
    });
    let (sn, cn) = super::body::sin_cos_names(p, reads);
    quote!(let (#sn, #cn) = kanegen_runtime::lanes::sin_cos_n_inline::<A, _, L>([#(#angles),*]);)
}

/// The scalar bindings at the top of the loop body: lane `l` of every sine, cosine,
/// coordinate, speed and acceleration the program reads.
fn lane_values(cx: &Context<'_>, p: &Program, reads: &Reads) -> TokenStream {
    let mut ts = TokenStream::new();
    for (k, &s) in p.sincos.iter().enumerate() {
        let speed = &cx.model.speeds[s];
        let kl = idx(k);
        if reads.sin[s] {
            let id = ident(&naming::sin(&speed.coordinate));
            ts.extend(quote!(let #id = sin_q[#kl][l];));
        }
        if reads.cos[s] {
            let id = ident(&naming::cos(&speed.coordinate));
            ts.extend(quote!(let #id = cos_q[#kl][l];));
        }
    }
    for (k, name) in cx.model.coordinate_names().into_iter().enumerate() {
        if reads.coord.get(k).copied().unwrap_or(false) {
            let (id, kl) = (ident(name), idx(k));
            ts.extend(quote!(let #id = q[#kl].0[l];));
        }
    }
    for (s, speed) in cx.model.speeds.iter().enumerate() {
        let sl = idx(s);
        if reads.speed[s] {
            let id = ident(&speed.name);
            ts.extend(quote!(let #id = u[#sl].0[l];));
        }
        if reads.accel[s] {
            let id = ident(&naming::accel(&speed.name));
            ts.extend(quote!(let #id = ud[#sl].0[l];));
        }
    }
    ts
}

/// How many lane inputs a loop reads: sines, cosines, coordinates, speeds, accelerations.
fn lane_inputs(reads: &Reads) -> usize {
    [
        &reads.sin,
        &reads.cos,
        &reads.coord,
        &reads.speed,
        &reads.accel,
    ]
    .iter()
    .map(|read| read.iter().filter(|&&r| r).count())
    .sum()
}

/// Where a batched body's loops store the result entries, and so what the loops may read in
/// place.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum EntryStores {
    /// Into a local lane buffer per loop (`entries0[i][l] = value`), each entry copied into
    /// the result after its loop (`out.set_lanes(r, c, &entries0[i])`: one vector store in the
    /// structure-of-arrays layout). The loop's stores then cannot overwrite anything it reads,
    /// so it reads the parameters and the structure-of-arrays inputs where the caller keeps
    /// them: no copies.
    Buffered,
    /// Straight into the result (`out.set(r, c, l, value)`), which the vectorizer must then
    /// know cannot overwrite what the loop reads: the body reads local copies of the parameter
    /// structs (`let p = &{ *p };`) and of the structure-of-arrays inputs the loop reads
    /// (`lanes::inputs_soa`; [`ReadInput::in_loop`]). Without those, LLVM's loop vectorizer
    /// needs run-time checks that the result stores do not overwrite them, and gives up ("loop
    /// not vectorized: runtime pointer checks needed").
    Direct,
}

/// Most memory locations (result entries, lane inputs, parameters read) for which a
/// [`EntryStores::Buffered`] loop is still vectorized. Its parameter loads stay in the loop
/// unless LLVM's LICM hoists them (it gives up after about 100 per loop,
/// `-licm-mssa-optimization-cap`), and with the stores and lane inputs they count against the
/// 250 locations of the alias-set tracker ([`LOOP_LOCATIONS`]). Measured on Krang, LLVM of
/// Rust 1.95: τ (19 entries, 91 lane inputs, 182 parameters: 292) is vectorized buffered, M
/// (141 entries, 34 lane inputs, 160 parameters: 335) is not (1.7 µs per 8 states instead of
/// 0.6).
const BUFFERED_LOCATIONS: usize = 300;

/// [`EntryStores::Buffered`] where it is vectorized ([`BUFFERED_LOCATIONS`]) and cheaper: the
/// buffer costs three vector moves per entry (zeroed, stored, copied out), the copies it
/// saves two moves per parameter read and per lane of the structure-of-arrays inputs the loop
/// reads. Krang: c, g and τ are buffered (10–20 % faster per 8 states than with the copies), M
/// and C direct (M buffered, vectorized or not, is slower: 141 entries against 160 parameters).
fn entry_stores(cx: &Context<'_>, p: &Program, reads: &Reads) -> EntryStores {
    let entries = nonzero_outputs(p).count();
    let params = if cx.low.params.is_runtime() {
        super::body::params_read(p)
    } else {
        0
    };
    let copied_inputs = read_inputs(p, reads).iter().filter(|x| x.in_loop).count();
    let input_lanes = cx.low.dof * copied_inputs;
    let locations = entries + lane_inputs(reads) + params;
    if locations <= BUFFERED_LOCATIONS && 3 * entries < 2 * (params + input_lanes) {
        EntryStores::Buffered
    } else {
        EntryStores::Direct
    }
}

/// Most memory locations one loop over the states may touch: result entries stored plus
/// lane inputs read (sines, cosines, coordinates, speeds, accelerations). LLVM's loop
/// vectorizer needs to know that the loop's stores do not overwrite what it reads; its
/// alias-set tracker gives up beyond 250 distinct locations per loop
/// (`-alias-set-saturation-threshold`), and then the loop stays scalar ("runtime pointer checks
/// needed"). Krang's M (141 entries, 34 sines and cosines read) stays below it; its Coriolis
/// matrix (260 entries, 53 inputs) did not, so it is emitted as two loops ([`loop_parts`]).
const LOOP_LOCATIONS: usize = 240;

/// The programs of the loops over the states: `p` itself, or, when its nonzero result entries
/// and the lane inputs it reads exceed [`LOOP_LOCATIONS`], `p` restricted to the entries whose
/// deeper speed (`max(row, column)`, the order of [`lower::subtree_order`]) is in one of
/// consecutive ranges ([`lower::restrict`]: each part computes the statements its entries
/// read, with the same expressions, so every entry keeps its bits). Each range is as long as
/// the budget allows (the entries it stores plus the inputs the whole program reads): the
/// fewest loops, and for a tree numbered one subtree after the other the last parts are whole
/// subtrees, which read little of the others. Krang's Coriolis matrix: deeper speeds 1–14
/// (trunk, left arm and the right arm's first three joints, 180 entries) and 15–18 (80): 8,619
/// flops per state in all (one loop would be 7,893); by rows, as before, rows 0–11 and 12–18
/// took 9,531 (log, "The Coriolis matrix by the deeper speed"). A speed with more entries than
/// the budget gets a loop of its own (which may stay scalar).
fn loop_parts<'p>(p: &'p Program, reads: &Reads) -> Vec<Cow<'p, Program>> {
    let inputs = lane_inputs(reads);
    // Entry (r, c) belongs to the deeper of its two speeds, `max(r, c)`.
    let key = |r: usize, c: usize| r.max(c);
    let mut per_key: BTreeMap<usize, usize> = BTreeMap::new();
    for (r, c, _) in nonzero_outputs(p) {
        *per_key.entry(key(*r, *c)).or_default() += 1;
    }
    let budget = LOOP_LOCATIONS.saturating_sub(inputs);
    if per_key.values().sum::<usize>() <= budget {
        return vec![Cow::Borrowed(p)];
    }
    // Greedy: each range of keys takes keys while its entries fit the budget.
    let mut ranges: Vec<(usize, usize)> = Vec::new();
    let mut entries = 0;
    for (&k, &n) in &per_key {
        match ranges.last_mut() {
            Some(range) if entries + n <= budget => {
                range.1 = k + 1;
                entries += n;
            }
            _ => {
                ranges.push((k, k + 1));
                entries = n;
            }
        }
    }
    ranges
        .into_iter()
        .map(|(from, to)| Cow::Owned(lower::restrict(p, |r, c| (from..to).contains(&key(r, c)))))
        .collect()
}

/// The result stores inside the loop: the `i`-th nonzero entry `(r, c)` of `p` right after
/// the last statement it reads (with multiply-add chains), as `buffer[i][l] = value` into the
/// loop's local lane buffer or as `out.set(r, c, l, value)` through the layout's
/// `kanegen_runtime::lanes::LaneStore` ([`EntryStores`]; text lines by position, see
/// [`Printer::statement_block`]).
fn loop_stores(
    cx: &Context<'_>,
    printer: &Printer<'_>,
    p: &Program,
    to: EntryStores,
    buffer: &str,
) -> Stores {
    let mut stores: Stores = vec![Vec::new(); p.stmts.len() + 1];
    for (i, (r, c, e)) in nonzero_outputs(p).enumerate() {
        let v = text(cx, printer, e);
        let store = match to {
            EntryStores::Buffered => format!("{buffer}[{i}][l] = {v};"),
            EntryStores::Direct => format!("out.set({r}, {c}, l, {v});"),
        };
        store_text_after(&mut stores, e, store);
    }
    stores
}

/// The stores of a loop of their own after the loops that compute: the lower entries of a
/// symmetric matrix (copied from the upper ones) and `0.0` into every entry no statement
/// writes. With the loops' stores, each entry of the caller's result is written exactly once,
/// so nothing is zeroed first. The mirrored entries and the zeros stay out of the vectorized
/// loop: LLVM merges adjacent zero stores into `memset` calls, and a loop with a call is not
/// vectorized; with the mirrored stores in it (as a copy or as the value again) Krang's M was
/// not vectorized either ("loop not vectorized: runtime pointer checks needed"). In the
/// structure-of-arrays layout they copy (or zero) whole entries of `out`, all lanes at once.
fn after_stores(cx: &Context<'_>, p: &Program, shape: Shape, layout: Layout) -> TokenStream {
    let (rows, cols) = shape.size_in(&cx.low.sizes);
    let vector = cols == 1;
    // State `l`'s result `m` (bound by the loop over `out` around these stores) or `out`
    // itself, whose every entry holds all lanes.
    let m = match layout {
        Layout::States => quote!(m),
        Layout::Lanes => quote!(out),
    };
    let zero = match layout {
        Layout::States => quote!(0.0),
        Layout::Lanes => quote!(kanegen_runtime::lanes::Lanes::splat(0.0)),
    };
    let entry = |r: usize, c: usize| {
        let (ri, ci) = (idx(r), idx(c));
        if vector {
            quote!(#m[#ri])
        } else {
            quote!(#m[(#ri, #ci)])
        }
    };
    let mirror = shape == Shape::SymmetricMatrix;
    let mut written = vec![false; rows * cols];
    let mut after = TokenStream::new();
    for (r, c, _) in nonzero_outputs(p) {
        let (r, c) = (*r, *c);
        written[c * rows + r] = true;
        if mirror && r != c {
            let (to, from) = (entry(c, r), entry(r, c));
            after.extend(quote!(#to = #from;));
            written[r * rows + c] = true;
        }
    }
    for (r, c) in (0..cols).flat_map(|c| (0..rows).map(move |r| (r, c))) {
        if !written[c * rows + r] {
            let to = entry(r, c);
            after.extend(quote!(#to = #zero;));
        }
    }
    after
}

/// The batched free functions of `f` in both layouts (`NAME_batch_into` and `NAME_batch`,
/// `NAME_batch_soa_into` and `NAME_batch_soa`) and the body they share (`NAME_batch_body`), or
/// nothing if it has none.
///
/// The shared body ([`shared_body`]) is one loop over the lanes (several for a result with more
/// entries than one vectorized loop can store: [`loop_parts`]) around the single-state
/// function's statements, printed as they are (multiply-add chains over `A: Arith<f64>`
/// included) and storing each entry through the layout's `LaneStore`: LLVM's loop vectorizer
/// then runs the whole body on vectors across the states (four lanes per AVX2 register, two
/// per SSE2 register, eight per AVX-512 register). Each layout's function converts its inputs
/// to lanes, runs the shared body inlined into its own dispatched copies and then writes the
/// entries no statement stores ([`after_stores`]).
pub(super) fn function(cx: &Context<'_>, f: &FunctionProgram) -> TokenStream {
    if !batched(f) {
        return TokenStream::new();
    }
    // The batched body's own statement order (`lower::batch_program`); the rest of `f` as it
    // is (field by field: `..f.clone()` would copy the whole program only to drop it).
    let reordered;
    let f = match lower::batch_program(f.id, &f.program) {
        Cow::Borrowed(_) => f,
        Cow::Owned(program) => {
            reordered = FunctionProgram {
                id: f.id,
                frame: f.frame,
                program,
                looped: f.looped.clone(),
                lanes: f.lanes.clone(),
            };
            &reordered
        }
    };
    let reads = Reads::of(&f.program, cx.model.speeds.len());
    let to = entry_stores(cx, &f.program, &reads);
    let mut items = shared_body(cx, f, &reads, to);
    items.extend(
        Layout::ALL
            .iter()
            .map(|&layout| function_in(cx, f, &reads, to, layout)),
    );
    items
}

/// The name of the body `f`'s batched functions share.
fn body_name(f: &FunctionProgram) -> proc_macro2::Ident {
    ident(&format!("{}_batch_body", f.id.spec().name))
}

/// `NAME_batch_body::<A, S, L>(params, q, u, ud, out)`, private and `#[inline(always)]`: the
/// statements of `f` for `L` states, from the inputs it reads as lanes (`&[Lanes<L>; N]` each)
/// into any `S: kanegen_runtime::lanes::LaneStore<L>` (both layouts' results). Before the
/// loops: the lane-wise sines and cosines, and, where the loops store straight into the result
/// ([`EntryStores::Direct`]), copies of the parameter structs (`let p = &{ *p };`); a loop
/// storing into a local lane buffer ([`EntryStores::Buffered`]) is followed by the copies of
/// its entries into the result.
fn shared_body(
    cx: &Context<'_>,
    f: &FunctionProgram,
    reads: &Reads,
    to: EntryStores,
) -> TokenStream {
    let spec = f.id.spec();
    let p = &f.program;
    let name = body_name(f);
    let doc = format!(
        " The statements of [`{0}_batch_into`] and [`{0}_batch_soa_into`] for `L` states: \
         lane `l` of every input is state `l`, and each result entry of state `l` goes to \
         lane `l` of its entry in `out`.",
        spec.name
    );
    let param_args = super::body::param_args(cx, reads);
    let (nl, nq) = (idx(cx.low.dof), idx(cx.low.nq));
    let inputs = read_inputs(p, reads).into_iter().map(|x| {
        let name = x.name;
        // `q` has `NQ` entries (one more than the speeds for a floating base).
        let n = if name.to_string() == "q" { &nq } else { &nl };
        quote!(#name: &[kanegen_runtime::lanes::Lanes<L>; #n],)
    });
    let sin_cos = lane_sin_cos(cx, p, reads);
    // One loop per part (one part unless the result has more entries than a vectorized loop
    // can store); none for a structurally zero result (its entries are all written after the
    // body), so no loop leaves `l` unused.
    let mut loops = TokenStream::new();
    for (k, part) in loop_parts(p, reads).iter().enumerate() {
        let entries: Vec<_> = nonzero_outputs(part).collect();
        if entries.is_empty() {
            continue;
        }
        let printer = cx.printer(&part.stmts);
        let part_reads = Reads::of(part, cx.model.speeds.len());
        let lane_values = lane_values(cx, part, &part_reads);
        let buffer = ident(&format!("entries{k}"));
        let stores = loop_stores(cx, &printer, part, to, &buffer.to_string());
        let stored: Vec<&LExpr> = entries.iter().map(|(_, _, e)| e).collect();
        let block =
            printer.statement_block(&cx.leaf_names, stores, (&stored, &[]), cx.split_above, true);
        let statements = cx.blocks.placeholder(block);
        let the_loop = quote!(for l in 0..L { #lane_values #statements });
        loops.extend(match to {
            EntryStores::Buffered => {
                let n = idx(entries.len());
                let copies = entries.iter().enumerate().map(|(i, (r, c, _))| {
                    let (i, r, c) = (idx(i), idx(*r), idx(*c));
                    quote!(out.set_lanes(#r, #c, &#buffer[#i]);)
                });
                quote!(let mut #buffer = [[0.0f64; L]; #n]; #the_loop #(#copies)*)
            }
            EntryStores::Direct => the_loop,
        });
    }
    // Local copies of the parameters ([`EntryStores::Direct`]).
    let mut copies = TokenStream::new();
    if to == EntryStores::Direct && cx.low.params.is_runtime() {
        if reads.param {
            copies.extend(quote!(let p = &{ *p };));
        }
        if reads.pre {
            copies.extend(quote!(let pc = &{ *pc };));
        }
    }
    let out = if loops.is_empty() {
        quote!(_out)
    } else {
        quote!(out)
    };
    let gate = &cx.batch_gate;
    quote! {
        #gate
        #[doc = #doc]
        #[inline(always)]
        fn #name<
            A: kanegen_runtime::isa::Arith<f64>,
            S: kanegen_runtime::lanes::LaneStore<L>,
            const L: usize,
        >(#param_args #(#inputs)* #out: &mut S) {
            #copies
            #sin_cos
            #loops
        }
    }
}

/// The doc comments of the by-value and `_into` batched forms of `single` in `layout`.
fn docs(single: &str, layout: Layout) -> (String, String) {
    match layout {
        Layout::States => (
            format!(
                " [`{single}`] at `L` states per call: entry `l` of the result is `{single}` \
                 at entry `l` of the inputs, bit for bit with the same instruction set (the \
                 same statements in a loop over the states, vectorized across them). Returns \
                 the results by value; [`{single}_batch_into`] writes them into the caller's \
                 array instead (no zeroed array, no copy)."
            ),
            format!(
                " [`{single}`] at `L` states per call, into `out`: entry `l` of `out` becomes \
                 `{single}` at entry `l` of the inputs, bit for bit with the same instruction \
                 set (the same statements in a loop over the states, vectorized across them). \
                 Every entry of `out` is written."
            ),
        ),
        Layout::Lanes => (
            format!(
                " [`{single}`] at `L` states per call, structure of arrays: lane `l` of every \
                 input entry is state `l` (`kanegen_runtime::lanes::soa` builds them from an \
                 array of states), and lane `l` of every result entry is `{single}` at state \
                 `l`, bit for bit with the same instruction set. Returns the result by value; \
                 [`{single}_batch_soa_into`] writes into the caller's instead."
            ),
            format!(
                " [`{single}`] at `L` states per call, structure of arrays, into `out`: lane \
                 `l` of every entry of `out` becomes `{single}` at lane `l` of the inputs, bit \
                 for bit with the same instruction set; every entry is written. The fastest \
                 batched form: the inputs are read as they are and every result entry is one \
                 vector store (the array-of-states form [`{single}_batch_into`] transposes \
                 and scatters)."
            ),
        ),
    }
}

/// [`function`] in one layout: the inputs the program reads converted to lanes, the shared
/// body ([`shared_body`]) inlined into each dispatched copy, then [`after_stores`].
fn function_in(
    cx: &Context<'_>,
    f: &FunctionProgram,
    reads: &Reads,
    to: EntryStores,
    layout: Layout,
) -> TokenStream {
    let spec = f.id.spec();
    let p = &f.program;
    let by_value = layout.name(spec);
    let name = ident(&by_value);
    let name_into = ident(&format!("{by_value}_into"));
    let (doc, doc_into) = docs(spec.name, layout);
    let (outer_params, pass_params) = super::body::outer_params(cx);
    let state = layout.args(cx, spec.inputs);
    let names = arg_names(spec.inputs);
    let ty = layout.result(cx, spec);
    let out = quote!(out: &mut #ty);
    let read = read_inputs(p, reads);
    let converted = read.iter().map(|x| layout.inputs(&x.name, to, x.in_loop));
    let passed = read.iter().map(|x| {
        let name = &x.name;
        quote!(#name,)
    });
    let shared = body_name(f);
    let after = after_stores(cx, p, spec.shape, layout);
    let after_loop = match layout {
        _ if after.is_empty() => TokenStream::new(),
        Layout::States => quote!(for m in out.iter_mut() { #after }),
        Layout::Lanes => after,
    };
    let unused = unused_inputs(spec.inputs, p, reads);
    let call = super::body::call_body_into(
        cx,
        super::body::Copies::WithV4,
        quote!(, L),
        quote!(#pass_params #names,),
        quote!(out),
    );
    let zeros = layout.zeros(cx, spec);
    let gate = &cx.batch_gate;
    quote! {
        #gate
        #[doc = #doc_into]
        #[inline(never)]
        pub fn #name_into<const L: usize>(#outer_params #state, #out) {
            #[inline(always)]
            fn body<A: kanegen_runtime::isa::Arith<f64>, const L: usize>(
                #outer_params #state, #out
            ) {
                #unused
                #(#converted)*
                #shared::<A, _, L>(#pass_params #(#passed)* out);
                #after_loop
            }
            #call
        }

        #gate
        #[doc = #doc]
        #[inline]
        pub fn #name<const L: usize>(#outer_params #state) -> #ty {
            let mut out = #zeros;
            #name_into(#pass_params #names, &mut out);
            out
        }
    }
}

/// The wrapper's methods for the batched functions (by value and `_into`, both layouts).
pub(super) fn methods(cx: &Context<'_>) -> TokenStream {
    let mut methods = TokenStream::new();
    for f in cx.low.functions.iter().filter(|f| batched(f)) {
        for layout in Layout::ALL {
            let spec = f.id.spec();
            let by_value = layout.name(spec);
            let name = ident(&by_value);
            let name_into = ident(&format!("{by_value}_into"));
            let how = match layout {
                Layout::States => "entry `l` of the result at entry `l` of the inputs",
                Layout::Lanes => {
                    "structure of arrays: lane `l` of the result's entries at lane `l` of the \
                     inputs'"
                }
            };
            let doc = format!(
                " [`Self::{}`] at `L` states per call ({how}, bit for bit with the same \
                 instruction set; vectorized across the states). [`Self::{by_value}_into`] \
                 writes into the caller's result instead.",
                spec.name
            );
            let doc_into = format!(
                " [`Self::{}`] at `L` states per call, written into `out` (every entry; {how}, \
                 bit for bit with the same instruction set).",
                spec.name
            );
            let state = layout.args(cx, spec.inputs);
            let ty = layout.result(cx, spec);
            let names = arg_names(spec.inputs);
            let pass = super::signature::wrapper_params(cx);
            let call = quote!(#name(#pass #names));
            let call_into = quote!(#name_into(#pass #names, out));
            let gate = &cx.batch_gate;
            methods.extend(quote! {
                #gate
                #[doc = #doc]
                #[inline]
                pub fn #name<const L: usize>(&self, #state) -> #ty {
                    #call
                }
                #gate
                #[doc = #doc_into]
                #[inline]
                pub fn #name_into<const L: usize>(&self, #state, out: &mut #ty) {
                    #call_into
                }
            });
        }
    }
    methods
}
