//! Lowering: from the derivation's expression DAG to straight-line programs.
//!
//! For every generated function only the statements its outputs need are kept (dead-code
//! elimination through the substitution variables), in topological order. Substitution
//! variables become `let` statements named `k1, k2, …` (kinematic) and `d1, d2, …` (inertial and
//! gravity terms), numbered per function; other subexpressions used more than once become `t1, …`
//! statements (common subexpressions). With runtime parameters, every parameter-only
//! subexpression moves to a separate *precompute* program that runs once per parameter set
//! (its results are `pc1, pc2, …`). Each joint's sin/cos is computed once. Op counts are kept
//! per program. No model name can have these shapes
//! ([`kanegen_model::names::is_generated_local`], checked by
//! [`Model::check_names`](kanegen_model::Model::check_names)), so a local never shadows a speed,
//! coordinate or parameter.

use std::collections::BTreeSet;
use std::fmt;

use rustc_hash::{FxHashMap, FxHashSet};

use crate::expr::{Arena, Atom, ExprId, MimicLeaf, Node, VarKind};
use crate::kane::{Derivation, Function};
use crate::options::{DerivativesForm, LOOPED_ABOVE_FLOPS, ParamMode};
use crate::registry::FunctionId;

pub mod lanes;

/// A leaf of a lowered expression.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Leaf {
    /// A number.
    Const(f64),
    /// A model parameter (runtime input).
    Param(usize),
    /// A precomputed parameter-only value (slot in the precompute program).
    Pre(usize),
    /// `u[i]`.
    Speed(usize),
    /// `u̇[i]`.
    Accel(usize),
    /// `sin(q[i])`.
    Sin(usize),
    /// `cos(q[i])`.
    Cos(usize),
    /// `q[i]`.
    Coord(usize),
    /// An earlier statement of the same program.
    Local(usize),
}

/// A lowered expression: a small tree over leaves.
#[derive(Clone, Debug, PartialEq)]
pub enum LExpr {
    /// A leaf.
    Leaf(Leaf),
    /// `constant + Σ coef·term`.
    Sum {
        /// Constant part.
        constant: f64,
        /// `(coefficient, term)`.
        terms: Vec<(f64, LExpr)>,
    },
    /// `Π base^power`.
    Prod(Vec<(LExpr, i32)>),
}

impl LExpr {
    /// The first constant or coefficient of this expression that `fits` refuses.
    fn constant_where(&self, fits: &impl Fn(f64) -> bool) -> Option<f64> {
        match self {
            LExpr::Leaf(Leaf::Const(v)) => (!fits(*v)).then_some(*v),
            LExpr::Leaf(_) => None,
            LExpr::Sum { constant, terms } => {
                (!fits(*constant)).then_some(*constant).or_else(|| {
                    terms.iter().find_map(|(c, t)| {
                        (!fits(*c)).then_some(*c).or_else(|| t.constant_where(fits))
                    })
                })
            }
            LExpr::Prod(factors) => factors.iter().find_map(|(b, _)| b.constant_where(fits)),
        }
    }
}

/// One `let` statement.
#[derive(Clone, Debug)]
pub struct Stmt {
    /// Local name (`k12`, `d3`, `t4`, `pc7`).
    pub name: String,
    /// Right-hand side.
    pub expr: LExpr,
    /// What it is (`w2.x`), from the derivation.
    pub comment: String,
}

/// Operation counts of a program.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCount {
    /// Additions and subtractions.
    pub adds: usize,
    /// Multiplications.
    pub muls: usize,
    /// Divisions.
    pub divs: usize,
    /// `sin_cos` evaluations (one per joint used).
    pub sincos: usize,
    /// Multiply-adds the x86-64-v3 copy fuses (`A::mul_add` in the generated source, see
    /// [`fusable`]): each is one of the multiplications and one of the additions above,
    /// executed as one FMA instruction there (the baseline copy still runs both).
    pub fmas: usize,
}

impl OpCount {
    /// Total floating-point operations (adds + muls + divs).
    pub fn flops(&self) -> usize {
        self.adds + self.muls + self.divs
    }

    /// Floating-point instructions of the x86-64-v3 copy: [`OpCount::flops`] less one per
    /// fused multiply-add.
    pub fn fused_instructions(&self) -> usize {
        self.flops() - self.fmas
    }
}

impl fmt::Display for OpCount {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} adds, {} muls, {} divs, {} sin/cos",
            self.adds, self.muls, self.divs, self.sincos
        )?;
        if self.fmas > 0 {
            write!(f, " ({} multiply-adds fused with FMA)", self.fmas)?;
        }
        Ok(())
    }
}

/// A straight-line program.
#[derive(Clone, Debug)]
pub struct Program {
    /// Its name in listings and statistics (`mass_matrix`, `precompute`).
    pub name: String,
    /// Speed indices whose sin/cos the program needs.
    pub sincos: Vec<usize>,
    /// Statements in execution order.
    pub stmts: Vec<Stmt>,
    /// `(row, col, value)`; for symmetric matrices the upper triangle.
    pub outputs: Vec<(usize, usize, LExpr)>,
    /// Operation counts.
    pub ops: OpCount,
    /// Number of K and D variables kept.
    pub k_vars: usize,
    /// Number of D variables kept.
    pub d_vars: usize,
}

impl Program {
    /// The largest number of statement values that are live at once (computed and still to be
    /// read by a later statement or result entry), with every result entry stored right after
    /// the last statement it reads, as emitted. A measure of register pressure: the statement
    /// order is chosen to keep it low.
    pub fn max_live(&self) -> usize {
        let n = self.stmts.len();
        // last_read[i]: the position after which statement i is dead.
        let mut last_read: Vec<usize> = (0..n).collect();
        let mut reads = Vec::new();
        for (j, s) in self.stmts.iter().enumerate() {
            reads.clear();
            locals(&s.expr, &mut reads);
            for &i in &reads {
                last_read[i] = last_read[i].max(j);
            }
        }
        for (_, _, e) in &self.outputs {
            reads.clear();
            locals(e, &mut reads);
            if let Some(&at) = reads.iter().max() {
                for &i in &reads {
                    last_read[i] = last_read[i].max(at);
                }
            }
        }
        // +1 when a value is defined, −1 after its last read.
        let mut delta = vec![0i64; n + 1];
        for (i, &l) in last_read.iter().enumerate() {
            if l > i {
                delta[i] += 1;
                delta[l] -= 1;
            }
        }
        let (mut live, mut max) = (0i64, 0i64);
        for d in delta {
            live += d;
            max = max.max(live);
        }
        max as usize
    }
}

/// The statements an expression reads.
fn locals(e: &LExpr, out: &mut Vec<usize>) {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => out.push(*i),
        LExpr::Leaf(_) => {}
        LExpr::Sum { terms, .. } => terms.iter().for_each(|(_, t)| locals(t, out)),
        LExpr::Prod(f) => f.iter().for_each(|(b, _)| locals(b, out)),
    }
}

/// The program `p` restricted to the result entries `keep(row, col)` selects: those entries
/// and the statements they read, directly or not, in `p`'s order and with `p`'s names, so
/// every value is the same expression as in `p` (the same bits). Its operation counts are its
/// own; its `sincos` is `p`'s (the angles a caller computed for `p`, in `p`'s order), and so
/// are its K and D variable counts (the derivation's, for reports). What the batched functions
/// use to split a program with more result entries than one vectorized loop can store into
/// several loops (`emit::batch`).
pub fn restrict(p: &Program, keep: impl Fn(usize, usize) -> bool) -> Program {
    let outputs: Vec<(usize, usize, LExpr)> = p
        .outputs
        .iter()
        .filter(|(r, c, _)| keep(*r, *c))
        .cloned()
        .collect();
    let mut needed = vec![false; p.stmts.len()];
    let mut stack = Vec::new();
    for (_, _, e) in &outputs {
        locals(e, &mut stack);
    }
    while let Some(i) = stack.pop() {
        if !needed[i] {
            needed[i] = true;
            locals(&p.stmts[i].expr, &mut stack);
        }
    }
    let mut index = vec![usize::MAX; p.stmts.len()];
    let mut stmts = Vec::new();
    for (i, s) in p.stmts.iter().enumerate() {
        if needed[i] {
            index[i] = stmts.len();
            stmts.push(s.clone());
        }
    }
    let mut q = Program {
        name: p.name.clone(),
        sincos: Vec::new(),
        stmts,
        outputs,
        ops: OpCount::default(),
        k_vars: p.k_vars,
        d_vars: p.d_vars,
    };
    q.stmts
        .iter_mut()
        .for_each(|s| renumber(&mut s.expr, &index));
    q.outputs
        .iter_mut()
        .for_each(|(_, _, e)| renumber(e, &index));
    finish(&mut q);
    q.sincos = p.sincos.clone();
    q
}

/// Reorders the statements of a program whose result entries are indexed by speed (their row:
/// c, τ, the Coriolis matrix) per subtree: one arm's forward and backward passes before the
/// other arm's, instead of the forward pass of all frames before the backward pass of all
/// (which keeps every frame's velocities and accelerations live until the backward pass reads
/// them).
///
/// Found on the dependency graph alone. The result entries are taken from the last speed to
/// the first, each entry `(r, c)` at the deeper of its two speeds, `max(r, c)` (a vector's
/// entries at their row): C's entry `[t, j]` of a trunk speed t and an arm speed j goes with
/// the arm, so the arm's column forces carried up to the trunk are read as soon as they are
/// made instead of staying live until the trunk's rows (Krang's C: 144 values live instead of
/// 236 by rows; log, "The Coriolis matrix by the deeper speed"); consecutive entries form one
/// *group* (a chain of joints) while each shares at least half of the statements it reads,
/// directly or not, with the previous one (joint j's torque reads most of what its child's
/// does; the first joint of the other arm, or the trunk joint where both arms meet, does not).
/// Each group in turn places the statements its entries read that no earlier group placed, in
/// their derivation order, and then every statement that is ready (all it reads placed) and
/// reads a value of this group that no later group's entries read, except the last group (the
/// root's): e.g. an arm's first link force, which only the trunk's torques read but which frees
/// that link's velocities and accelerations. For a tree
/// whose speeds are numbered parent before child, one subtree after the other (Krang: trunk,
/// left arm, right arm), that is the right arm, the left arm, then the trunk. Values are
/// unchanged: every statement still follows the statements it reads; only the order, and so
/// the values live at once ([`Program::max_live`]), changes. Statement names are kept.
pub fn subtree_order(p: &mut Program) {
    let n = p.stmts.len();
    let words = n.div_ceil(64);
    let bit = |set: &[u64], i: usize| set[i / 64] & (1 << (i % 64)) != 0;
    let mut reads = Vec::new();
    let deps: Vec<Vec<usize>> = p
        .stmts
        .iter()
        .map(|s| {
            reads.clear();
            locals(&s.expr, &mut reads);
            reads.clone()
        })
        .collect();
    // The statements each result entry reads, directly or not, as a bit set.
    let closure = |e: &LExpr| {
        let mut set = vec![0u64; words];
        let mut stack = Vec::new();
        locals(e, &mut stack);
        while let Some(i) = stack.pop() {
            if !bit(&set, i) {
                set[i / 64] |= 1 << (i % 64);
                stack.extend_from_slice(&deps[i]);
            }
        }
        set
    };
    let count = |a: &[u64]| a.iter().map(|w| w.count_ones() as usize).sum::<usize>();
    let union = |into: &mut [u64], b: &[u64]| into.iter_mut().zip(b).for_each(|(x, y)| *x |= y);
    let mut outs: Vec<usize> = (0..p.outputs.len()).collect();
    // Last speed first; a stable sort keeps the columns of a row in order.
    outs.sort_by_key(|&o| std::cmp::Reverse(p.outputs[o].0.max(p.outputs[o].1)));
    // The groups' closures (the union of their entries').
    let mut groups: Vec<Vec<u64>> = Vec::new();
    let mut prev: Option<Vec<u64>> = None;
    for o in outs {
        let c = closure(&p.outputs[o].2);
        let chained = prev.as_ref().is_some_and(|pr| {
            let common: usize = pr
                .iter()
                .zip(&c)
                .map(|(x, y)| (x & y).count_ones() as usize)
                .sum();
            2 * common >= count(pr) && 2 * common >= count(&c)
        });
        match groups.last_mut() {
            Some(g) if chained => union(g, &c),
            _ => groups.push(c.clone()),
        }
        prev = Some(c);
    }
    let mut placed = vec![0u64; words];
    let mut order: Vec<usize> = Vec::with_capacity(n);
    for (gi, g) in groups.iter().enumerate() {
        // What the later groups, the last one excepted, read.
        let mut later = vec![0u64; words];
        if gi + 1 < groups.len() {
            for h in &groups[gi + 1..groups.len() - 1] {
                union(&mut later, h);
            }
        }
        // This group's statements: those its entries read that no earlier group placed, and
        // (but in the last group) every statement that is ready with them and reads a value of
        // the group that no later group but the last reads, in derivation order (which is
        // topological, so one pass also takes what reads the statements it takes).
        let mut mine = vec![0u64; words];
        let mut own = vec![0u64; words];
        for i in 0..n {
            let take = if bit(g, i) {
                true
            } else {
                gi + 1 < groups.len()
                    && !bit(&later, i)
                    && !bit(&placed, i)
                    && deps[i].iter().all(|&d| bit(&placed, d) || bit(&mine, d))
                    && deps[i].iter().any(|&d| bit(&own, d))
            };
            if take && !bit(&placed, i) {
                mine[i / 64] |= 1 << (i % 64);
                if !bit(&later, i) {
                    own[i / 64] |= 1 << (i % 64);
                }
            }
        }
        for i in 0..n {
            if bit(&mine, i) {
                order.push(i);
                placed[i / 64] |= 1 << (i % 64);
            }
        }
    }
    // Statements no entry reads (none after dead-code elimination) keep their place at the end.
    order.extend((0..n).filter(|&i| !bit(&placed, i)));
    apply_order(p, &order);
}

/// Rewrites the statement references of `e` through `new_index`.
fn renumber(e: &mut LExpr, new_index: &[usize]) {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => *i = new_index[*i],
        LExpr::Leaf(_) => {}
        LExpr::Sum { terms, .. } => terms.iter_mut().for_each(|(_, t)| renumber(t, new_index)),
        LExpr::Prod(f) => f.iter_mut().for_each(|(b, _)| renumber(b, new_index)),
    }
}

/// The program of one registry function.
#[derive(Clone, Debug)]
pub struct FunctionProgram {
    /// Which function (its name, inputs and result shape are in the registry).
    pub id: FunctionId,
    /// The body frame (link index) of a per-frame function, else `None`.
    pub frame: Option<usize>,
    /// Its straight-line program; `outputs` are the entries of the result's shape.
    pub program: Program,
    /// The loop form of a regressor, when the derivation chose it: what the emitted function
    /// runs instead of `program` (which stays the reference for evaluation and counts).
    pub looped: Option<LoopProgram>,
    /// The two-lane form of `program` (arms in lanes, see [`lanes`]), when
    /// [`lanes::apply`] paired its statements: `program` is then the rewritten program.
    pub lanes: Option<lanes::LanePlan>,
}

/// A regressor's loop form, lowered: the straight-line part and the loop's tables.
#[derive(Clone, Debug)]
pub struct LoopProgram {
    /// The straight-line part: `outputs[..kin_len]` are the `kin` table's values (row = slot,
    /// column 0), the rest result entries stored directly (`(row, column)`).
    pub program: Program,
    /// Number of `kin` values ([`crate::kane::KIN`] per link).
    pub kin_len: usize,
    /// The loop's tables.
    pub tables: crate::kane::RegressorLoop,
}

impl LoopProgram {
    /// Flops per call: the straight-line part's and the loop's.
    pub fn flops(&self) -> usize {
        self.program.ops.flops() + self.tables.flops()
    }
}

/// All programs of a model: the precompute program and one per function.
#[derive(Clone, Debug)]
pub struct Lowered {
    /// Parameter-only values (empty in baked mode); statement `i` of it computes slot `pc{i+1}`
    /// when listed in [`Lowered::pre_slots`].
    pub precompute: Program,
    /// Statement index in `precompute` of every slot, in slot order.
    pub pre_slots: Vec<usize>,
    /// The hot-path functions, in registry order.
    pub functions: Vec<FunctionProgram>,
    /// Number of speeds.
    pub dof: usize,
    /// Parameter mode.
    pub params: ParamMode,
    /// The dependent (mimic) speeds whose `sin`/`cos` leaves the programs may read: speed index
    /// and its angle `a·q[master] + b` (see [`Arena::set_mimic`](crate::expr::Arena::set_mimic)).
    pub mimic_angles: Vec<(usize, MimicLeaf)>,
    /// Result sizes (speeds, regressor columns).
    pub sizes: crate::registry::Sizes,
    /// The regressors' parameters and base parameters (see [`Derivation::regressors`]).
    pub regressors: crate::kane::Regressors,
    /// The combined functions (see [`crate::combined`]).
    pub combined: Vec<CombinedProgram>,
    /// The looped form of `inverse_dynamics_derivatives` (see
    /// [`Derivation::derivative_loop`]): the program filling its workspace and the tables;
    /// `Some` when that form is chosen (see [`lower_with`]) and emitted instead of the
    /// straight-line program of [`Lowered::functions`] (which the batched form, `listing` and
    /// the interpreter keep using).
    pub derivative_loop: Option<LoopedProgram>,
    /// The mirrors of the leaves, when [`lanes::apply`] paired a function's statements (what
    /// the emitter prints for a leaf in two lanes).
    pub lane_leaves: Option<lanes::LaneLeaves>,
}

/// The program of the looped `inverse_dynamics_derivatives`: its outputs `(offset, 0, value)`
/// are the workspace entries that `kanegen_runtime::derivative_steps::run` reads with `plan`.
#[derive(Clone, Debug)]
pub struct LoopedProgram {
    /// The straight-line part.
    pub program: Program,
    /// The tables of the loop.
    pub plan: crate::kane::DerivativeLoop,
    /// The two-lane form of `program` (see [`lanes`]), when [`lanes::apply`] paired it.
    pub lanes: Option<lanes::LanePlan>,
}

/// The program of one combined function: one straight-line program whose outputs are the
/// parts' entries, one after the other.
#[derive(Clone, Debug)]
pub struct CombinedProgram {
    /// What was asked for, resolved against the model.
    pub spec: crate::combined::ResolvedCombined,
    /// The program; `outputs[parts[i].clone()]` are part `i`'s entries.
    pub program: Program,
    /// Per part, its range in `program.outputs`.
    pub parts: Vec<std::ops::Range<usize>>,
    /// The two-lane form of `program` (see [`lanes`]), when [`lanes::apply`] paired it.
    pub lanes: Option<lanes::LanePlan>,
}

impl Lowered {
    /// The first constant of any program (precompute, functions, their loop forms, combined
    /// functions) that `fits` refuses, as `(program name, value)`: the emitter prints constants
    /// as literals, and a literal must be a finite number of the module's precision.
    pub fn constant_where(&self, fits: impl Fn(f64) -> bool) -> Option<(&str, f64)> {
        let programs = std::iter::once(&self.precompute)
            .chain(self.functions.iter().flat_map(|f| {
                std::iter::once(&f.program).chain(f.looped.as_ref().map(|l| &l.program))
            }))
            .chain(self.combined.iter().map(|c| &c.program))
            .chain(self.derivative_loop.as_ref().map(|l| &l.program));
        for p in programs {
            let exprs = p
                .stmts
                .iter()
                .map(|s| &s.expr)
                .chain(p.outputs.iter().map(|(_, _, e)| e));
            for e in exprs {
                if let Some(v) = e.constant_where(&fits) {
                    return Some((&p.name, v));
                }
            }
        }
        None
    }

    /// The program of function `id`, if the module has it (frame 0's of a per-frame function).
    pub fn function(&self, id: FunctionId) -> Option<&Program> {
        self.function_at(id, None)
    }

    /// The program of function `id` for body frame `frame` (a link index; `None` for a function
    /// without frames), if the module has it.
    pub fn function_at(&self, id: FunctionId, frame: Option<usize>) -> Option<&Program> {
        self.functions
            .iter()
            .find(|f| f.id == id && (frame.is_none() || f.frame == frame))
            .map(|f| &f.program)
    }
}

/// The functions whose statements are put in [`subtree_order`] after lowering (where that
/// lowers the values live at once). Only the Coriolis matrix: measured on Krang
/// (`docs/measurement-log.md`, "Instruction sets at run time and batched evaluation", "Single
/// state toward 10× Pinocchio"), it
/// cut C's values live from 455 to 236 (144 since entries go by their deeper speed), its
/// instructions per call by 2.5 % and its time by 1–2 %; for c and τ (111 → 83 and 87 live)
/// the instructions moved by −1.8 % and +1.6 % and the time not at all or up, so they keep the
/// derivation's order.
pub const SUBTREE_ORDER: [FunctionId; 1] = [FunctionId::CoriolisMatrix];

/// The functions whose batched bodies (`emit::batch`: the statements in a loop over the states,
/// vectorized across them, 32 vector registers in the x86-64-v4 copy) run their statements in
/// [`subtree_order`] where that lowers the values live at once ([`batch_program`]), although
/// their single-state form keeps its own order. Measured on Krang with mirrored lanes (whose
/// pairing reorders the single-state program; `docs/measurement-log.md`, "Batched bodies in
/// subtree order"): 8 states of τ 403 → 352 ns (121 → 87 values live), g 152 → 148 ns (34 →
/// 24), C 1,970 → 1,905 ns (193 → 144); c (121 → 83) got slower, 351 → 373 ns, and stays out.
pub const BATCH_SUBTREE_ORDER: [FunctionId; 3] = [
    FunctionId::InverseDynamics,
    FunctionId::Gravity,
    FunctionId::CoriolisMatrix,
];

/// The statements of function `id`'s batched body: `p` in [`subtree_order`] when `id` is in
/// [`BATCH_SUBTREE_ORDER`] and that order keeps fewer values live, else `p` itself. The same
/// statements in another order: every entry keeps its bits.
pub fn batch_program(id: FunctionId, p: &Program) -> std::borrow::Cow<'_, Program> {
    if BATCH_SUBTREE_ORDER.contains(&id)
        && let Some(reordered) = in_subtree_order_if_fewer_live(p)
    {
        return std::borrow::Cow::Owned(reordered);
    }
    std::borrow::Cow::Borrowed(p)
}

/// `p` in [`subtree_order`] if that keeps fewer values live at once ([`Program::max_live`]),
/// else `None` (the derivation's order can keep fewer). What [`SUBTREE_ORDER`] and
/// [`BATCH_SUBTREE_ORDER`] apply.
fn in_subtree_order_if_fewer_live(p: &Program) -> Option<Program> {
    let mut reordered = p.clone();
    subtree_order(&mut reordered);
    (reordered.max_live() < p.max_live()).then_some(reordered)
}

/// Lower every function of a derivation (`inverse_dynamics_derivatives` in the form
/// [`DerivativesForm::Auto`] chooses).
pub fn lower(d: &Derivation) -> Lowered {
    lower_with(d, DerivativesForm::Auto)
}

/// [`lower`], with `inverse_dynamics_derivatives` in form `form` where the model allows it
/// (see [`DerivativesForm`]): [`Lowered::derivative_loop`] is `Some` when the looped form is
/// chosen.
pub fn lower_with(d: &Derivation, form: DerivativesForm) -> Lowered {
    let hoist = d.options.params.is_runtime();
    let mut pre = PreSet::default();
    let functions: Vec<FunctionProgram> = d
        .functions
        .iter()
        .map(|f| {
            let mut program = lower_function(&d.arena, f, hoist, &mut pre);
            if SUBTREE_ORDER.contains(&f.id)
                && let Some(reordered) = in_subtree_order_if_fewer_live(&program)
            {
                program = reordered;
            }
            if let Some(l) = f.frame {
                program.name = format!("{}[{}]", f.id.name(), d.frame_names[l]);
            }
            let looped = f.looped.as_ref().map(|l| {
                let mut entries: Vec<(usize, usize, ExprId)> =
                    l.kin.iter().enumerate().map(|(i, &e)| (i, 0, e)).collect();
                entries.extend_from_slice(&l.extra);
                let name = format!("{} (loop form)", f.id.name());
                LoopProgram {
                    program: lower_entries(&d.arena, &name, &entries, &f.order, hoist, &mut pre),
                    kin_len: l.kin.len(),
                    tables: l.clone(),
                }
            });
            FunctionProgram {
                id: f.id,
                frame: f.frame,
                program,
                looped,
                lanes: None,
            }
        })
        .collect();
    let combined: Vec<CombinedProgram> = d
        .combined
        .iter()
        .map(|c| {
            let mut parts = Vec::with_capacity(c.parts.len());
            let mut entries = Vec::new();
            for p in &c.parts {
                parts.push(entries.len()..entries.len() + p.len());
                entries.extend_from_slice(p);
            }
            let program =
                lower_entries(&d.arena, &c.spec.name, &entries, &c.order, hoist, &mut pre);
            CombinedProgram {
                spec: c.spec.clone(),
                program,
                parts,
                lanes: None,
            }
        })
        .collect();
    // After every other program: the precomputed slots of the others keep their numbers.
    let straight_flops = functions
        .iter()
        .find(|f| f.id == FunctionId::InverseDynamicsDerivatives)
        .map_or(0, |f| f.program.ops.flops());
    let looped = match form {
        DerivativesForm::StraightLine => false,
        DerivativesForm::Looped => true,
        DerivativesForm::Auto => straight_flops > LOOPED_ABOVE_FLOPS,
    };
    // The runtime's tables hold u16 workspace and u32 result offsets: larger models keep the
    // straight-line form.
    let derivative_loop = d
        .derivative_loop
        .as_ref()
        .filter(|l| looped && l.plan.fits_tables())
        .map(|l| LoopedProgram {
            program: lower_entries(
                &d.arena,
                "inverse_dynamics_derivatives (looped)",
                &l.entries,
                &l.order,
                hoist,
                &mut pre,
            ),
            plan: l.plan.clone(),
            lanes: None,
        });
    let (precompute, pre_slots) = lower_precompute(&d.arena, &pre);
    Lowered {
        precompute,
        pre_slots,
        functions,
        dof: d.dof,
        params: d.options.params,
        mimic_angles: (0..d.arena.names.speeds.len())
            .filter_map(|s| d.arena.mimic(s as u32).map(|m| (s, m)))
            .collect(),
        sizes: d.sizes,
        regressors: d.regressors.clone(),
        combined,
        derivative_loop,
        lane_leaves: None,
    }
}

/// Parameter-only nodes needed by the hot programs, in slot order of first request.
#[derive(Default)]
struct PreSet {
    slot: FxHashMap<ExprId, usize>,
    nodes: Vec<ExprId>,
}

impl PreSet {
    fn get(&mut self, e: ExprId) -> usize {
        if let Some(&s) = self.slot.get(&e) {
            return s;
        }
        let s = self.nodes.len();
        self.nodes.push(e);
        self.slot.insert(e, s);
        s
    }
}

fn is_compound(n: &Node) -> bool {
    matches!(n, Node::Sum { .. } | Node::Prod(_))
}

/// Shared machinery: which nodes become statements and how to expand expressions.
struct ProgramBuilder<'a> {
    ar: &'a Arena,
    /// Nodes that are leaves of this program because they are precomputed (runtime mode).
    hoist: bool,
    /// node → statement index.
    local: FxHashMap<ExprId, usize>,
}

impl ProgramBuilder<'_> {
    fn is_pre(&self, e: ExprId) -> bool {
        self.hoist
            && self.ar.is_param_only(e)
            && match self.ar.node(e) {
                Node::Atom(Atom::Var(_)) => true,
                n => is_compound(n),
            }
    }

    fn expand(&self, e: ExprId, top: bool, pre: &mut PreSet) -> LExpr {
        if !top && let Some(&i) = self.local.get(&e) {
            return LExpr::Leaf(Leaf::Local(i));
        }
        if !top && self.is_pre(e) {
            return LExpr::Leaf(Leaf::Pre(pre.get(e)));
        }
        match self.ar.node(e) {
            Node::Const(c) => LExpr::Leaf(Leaf::Const(c.get())),
            Node::Atom(a) => LExpr::Leaf(match *a {
                Atom::Param(p) => Leaf::Param(p as usize),
                Atom::Speed(s) => Leaf::Speed(s as usize),
                Atom::Accel(s) => Leaf::Accel(s as usize),
                Atom::Sin(s) => Leaf::Sin(s as usize),
                Atom::Cos(s) => Leaf::Cos(s as usize),
                Atom::Coord(s) => Leaf::Coord(s as usize),
                Atom::Var(v) => {
                    let def = self.ar.vars()[v as usize].def;
                    match self.local.get(&def) {
                        Some(&i) => Leaf::Local(i),
                        None => return self.expand(def, false, pre),
                    }
                }
            }),
            Node::Sum { constant, terms } => LExpr::Sum {
                constant: constant.get(),
                terms: terms
                    .iter()
                    .map(|(t, k)| (k.get(), self.expand(*t, false, pre)))
                    .collect(),
            },
            Node::Prod(f) => LExpr::Prod(
                f.iter()
                    .map(|(b, p)| (self.expand(*b, false, pre), *p))
                    .collect(),
            ),
        }
    }
}

/// Collect the statements of a program computing `roots`.
///
/// Returns the statement nodes in topological order: variable definitions (each labelled by its
/// variable) and common subexpressions. With `order` (per node, when the function's derivation
/// first asked for it), statements follow the derivation's own order and a statement it never
/// asked for (a definition reached through a cached variable) is placed just before its first
/// user; without, they follow arena order.
fn schedule(
    ar: &Arena,
    roots: &[ExprId],
    is_leaf: &dyn Fn(ExprId) -> bool,
    order: Option<&[ExprId]>,
) -> Vec<(ExprId, Option<u32>)> {
    // Reachability with parent counting; a variable is a leaf whose definition is a new root.
    // (Hash tables keyed by node, not arrays over the arena: a module can have hundreds of
    // small programs, one per frame of a per-frame function, over one large arena.)
    let mut uses: FxHashMap<ExprId, usize> = FxHashMap::default();
    let mut seen: FxHashSet<ExprId> = FxHashSet::default();
    let mut var_defs: FxHashMap<ExprId, u32> = FxHashMap::default();
    let mut stack: Vec<ExprId> = Vec::new();
    for &r in roots {
        if seen.insert(r) {
            stack.push(r);
        }
    }
    while let Some(e) = stack.pop() {
        if is_leaf(e) {
            continue;
        }
        let mut visit = |c: ExprId, count: bool| {
            if count {
                *uses.entry(c).or_insert(0) += 1;
            }
            if seen.insert(c) {
                stack.push(c);
            }
        };
        match ar.node(e) {
            Node::Atom(Atom::Var(v)) => {
                let def = ar.vars()[*v as usize].def;
                var_defs.insert(def, *v);
                visit(def, false);
            }
            Node::Sum { terms, .. } => terms.iter().for_each(|(t, _)| visit(*t, true)),
            Node::Prod(f) => f.iter().for_each(|(b, _)| visit(*b, true)),
            _ => {}
        }
    }
    for r in roots {
        *uses.entry(*r).or_insert(0) += 1;
    }
    let mut seen: Vec<ExprId> = seen.into_iter().collect();
    seen.sort_unstable();
    let mut stmts: Vec<(ExprId, Option<u32>)> = Vec::new();
    for &e in &seen {
        if is_leaf(e) {
            continue;
        }
        if let Some(&v) = var_defs.get(&e) {
            stmts.push((e, Some(v)));
        } else if is_compound(ar.node(e)) && uses.get(&e).copied().unwrap_or(0) >= 2 {
            stmts.push((e, None));
        }
    }
    let Some(order) = order else {
        return stmts;
    };
    // Derivation order, then a depth-first pass that puts every statement after the statements
    // it reads.
    let is_stmt: FxHashMap<ExprId, Option<u32>> = stmts.iter().copied().collect();
    let rank: FxHashMap<ExprId, u32> = order
        .iter()
        .filter(|e| is_stmt.contains_key(e))
        .enumerate()
        .map(|(i, e)| (*e, i as u32))
        .collect();
    stmts.sort_by_key(|(e, _)| (rank.get(e).copied().unwrap_or(u32::MAX), *e));
    let mut placed: FxHashSet<ExprId> = FxHashSet::default();
    let mut out = Vec::with_capacity(stmts.len());
    let mut deps = Vec::new();
    for &(s, _) in &stmts {
        // Iterative post-order over the statements `s` depends on.
        let mut work: Vec<(ExprId, bool)> = vec![(s, false)];
        while let Some((e, expanded)) = work.pop() {
            if expanded {
                if placed.insert(e) {
                    out.push((e, is_stmt[&e]));
                }
                continue;
            }
            if placed.contains(&e) {
                continue;
            }
            work.push((e, true));
            deps.clear();
            statement_deps(ar, e, &is_stmt, is_leaf, &mut deps, true);
            // Reverse, so that dependencies are placed in the order they are read.
            for &d in deps.iter().rev() {
                if !placed.contains(&d) {
                    work.push((d, false));
                }
            }
        }
    }
    out
}

/// The statements that statement `e` reads directly (through inline subexpressions and
/// variables), in reading order.
fn statement_deps(
    ar: &Arena,
    e: ExprId,
    is_stmt: &FxHashMap<ExprId, Option<u32>>,
    is_leaf: &dyn Fn(ExprId) -> bool,
    out: &mut Vec<ExprId>,
    top: bool,
) {
    if !top && is_stmt.contains_key(&e) {
        out.push(e);
        return;
    }
    if is_leaf(e) {
        return;
    }
    match ar.node(e) {
        Node::Atom(Atom::Var(v)) => {
            let def = ar.vars()[*v as usize].def;
            statement_deps(ar, def, is_stmt, is_leaf, out, false);
        }
        Node::Sum { terms, .. } => {
            for (t, _) in terms.iter() {
                statement_deps(ar, *t, is_stmt, is_leaf, out, false);
            }
        }
        Node::Prod(f) => {
            for (b, _) in f.iter() {
                statement_deps(ar, *b, is_stmt, is_leaf, out, false);
            }
        }
        _ => {}
    }
}

fn lower_function(ar: &Arena, f: &Function, hoist: bool, pre: &mut PreSet) -> Program {
    lower_entries(ar, f.id.name(), &f.entries, &f.order, hoist, pre)
}

/// The program computing `entries` (its outputs, in order), statements in `order`.
fn lower_entries(
    ar: &Arena,
    name: &str,
    entries: &[(usize, usize, ExprId)],
    order: &[ExprId],
    hoist: bool,
    pre: &mut PreSet,
) -> Program {
    let roots: Vec<ExprId> = entries.iter().map(|e| e.2).collect();
    let mut b = ProgramBuilder {
        ar,
        hoist,
        local: FxHashMap::default(),
    };
    let is_leaf = |e: ExprId| {
        hoist
            && ar.is_param_only(e)
            && (matches!(ar.node(e), Node::Atom(Atom::Var(_))) || is_compound(ar.node(e)))
    };
    let sched = schedule(ar, &roots, &is_leaf, Some(order));
    let mut stmts = Vec::new();
    let (mut nk, mut nd, mut nt) = (0, 0, 0);
    for (e, var) in sched {
        let (name, comment) = match var {
            Some(v) => {
                let info = &ar.vars()[v as usize];
                match info.kind {
                    VarKind::K => {
                        nk += 1;
                        (format!("k{nk}"), info.label.clone())
                    }
                    VarKind::D => {
                        nd += 1;
                        (format!("d{nd}"), info.label.clone())
                    }
                }
            }
            None => {
                nt += 1;
                (format!("t{nt}"), "common subexpression".to_owned())
            }
        };
        let expr = b.expand(e, true, pre);
        b.local.insert(e, stmts.len());
        stmts.push(Stmt {
            name,
            expr,
            comment,
        });
    }
    let outputs: Vec<(usize, usize, LExpr)> = entries
        .iter()
        .map(|&(r, c, e)| (r, c, b.expand(e, false, pre)))
        .collect();
    let mut p = Program {
        name: name.to_owned(),
        sincos: Vec::new(),
        stmts,
        outputs,
        ops: OpCount::default(),
        k_vars: nk,
        d_vars: nd,
    };
    finish(&mut p);
    p
}

fn lower_precompute(ar: &Arena, pre: &PreSet) -> (Program, Vec<usize>) {
    let mut b = ProgramBuilder {
        ar,
        hoist: false,
        local: FxHashMap::default(),
    };
    // Every requested node is a statement; so is every variable and shared node below them.
    let sched = schedule(ar, &pre.nodes, &|_| false, None);
    let requested: BTreeSet<ExprId> = pre.nodes.iter().copied().collect();
    let mut order: Vec<(ExprId, Option<u32>)> = sched;
    // A requested node that is a variable needs no statement of its own: its slot reads the
    // statement of its definition (which the schedule holds), not an alias `let pc2 = pc1;`.
    let scheduled: BTreeSet<ExprId> = order.iter().map(|(e, _)| *e).collect();
    for &e in &pre.nodes {
        if !scheduled.contains(&e) && !matches!(ar.node(e), Node::Atom(Atom::Var(_))) {
            order.push((e, None));
        }
    }
    order.sort_by_key(|(e, _)| *e);
    let mut stmts = Vec::new();
    let mut node_stmt: FxHashMap<ExprId, usize> = FxHashMap::default();
    let mut dummy = PreSet::default();
    for (i, (e, var)) in order.iter().enumerate() {
        let comment = match var {
            Some(v) => ar.vars()[*v as usize].label.clone(),
            None if requested.contains(e) => "parameter-only term".to_owned(),
            None => "common subexpression".to_owned(),
        };
        let expr = b.expand(*e, true, &mut dummy);
        b.local.insert(*e, i);
        node_stmt.insert(*e, i);
        stmts.push(Stmt {
            name: format!("pc{}", i + 1),
            expr,
            comment,
        });
    }
    // A requested node that is a variable maps to its definition's statement.
    let slots: Vec<usize> = pre
        .nodes
        .iter()
        .map(|e| {
            let key = match ar.node(*e) {
                Node::Atom(Atom::Var(v)) => ar.vars()[*v as usize].def,
                _ => *e,
            };
            node_stmt[&key]
        })
        .collect();
    let mut p = Program {
        name: "precompute".into(),
        sincos: Vec::new(),
        stmts,
        outputs: Vec::new(),
        ops: OpCount::default(),
        k_vars: 0,
        d_vars: 0,
    };
    finish(&mut p);
    // Runs once per parameter set, printed without multiply-add chains.
    p.ops.fmas = 0;
    (p, slots)
}

/// The order in which a sum's terms are printed and added: the first positive term first (`b -
/// a`, not `-a + b`: saves a negation), then the others in order.
pub fn sum_order(terms: &[(f64, LExpr)]) -> impl Iterator<Item = usize> {
    let first = terms.iter().position(|(k, _)| *k > 0.0).unwrap_or(0);
    std::iter::once(first)
        .chain((0..terms.len()).filter(move |&i| i != first))
        .take(terms.len())
}

/// Whether the term `k * t` of a sum is a product `x * y` that a multiply-add can take: a
/// coefficient other than ±1, or a product of at least two factors without a divisor.
pub fn fusable(k: f64, t: &LExpr) -> bool {
    k.abs() != 1.0
        || matches!(t, LExpr::Prod(f)
            if f.iter().all(|(_, p)| *p > 0) && f.iter().map(|(_, p)| *p).sum::<i32>() >= 2)
}

/// Which terms of a sum (in [`sum_order`]) the x86-64-v3 copy fuses into a multiply-add with
/// what is summed before them, the same bits in the baseline copy (`x * y + acc` in the printed
/// order: see `kanegen_runtime::isa::Arith`):
/// - the second and later terms that are [`fusable`] (`acc + x * y`);
/// - the first term, when it is fusable and the second is not (`x * y + t`) or when it is the
///   only term and a constant follows (`x * y + c`).
///
/// The constant is added last, as in the printed sum.
pub fn fused_terms(constant: f64, terms: &[(f64, LExpr)]) -> Vec<bool> {
    let order: Vec<usize> = sum_order(terms).collect();
    let fuse: Vec<bool> = order
        .iter()
        .map(|&i| fusable(terms[i].0, &terms[i].1))
        .collect();
    let mut out = vec![false; terms.len()];
    for (j, &i) in order.iter().enumerate().skip(1) {
        out[i] = fuse[j];
    }
    if let Some(&first) = order.first() {
        out[first] = fuse[0] && order.get(1).map_or(constant != 0.0, |_| !fuse[1]);
    }
    out
}

fn count(e: &LExpr, ops: &mut OpCount, trig: &mut BTreeSet<usize>) {
    match e {
        LExpr::Leaf(Leaf::Sin(s) | Leaf::Cos(s)) => {
            trig.insert(*s);
        }
        LExpr::Leaf(_) => {}
        LExpr::Sum { constant, terms } => {
            ops.adds += terms.len() - 1 + usize::from(*constant != 0.0);
            ops.fmas += fused_terms(*constant, terms).iter().filter(|&&f| f).count();
            for (k, t) in terms {
                if k.abs() != 1.0 {
                    ops.muls += 1;
                }
                count(t, ops, trig);
            }
        }
        LExpr::Prod(f) => {
            let pos: i32 = f.iter().filter(|(_, p)| *p > 0).map(|(_, p)| *p).sum();
            let neg: i32 = f.iter().filter(|(_, p)| *p < 0).map(|(_, p)| -*p).sum();
            ops.muls += (pos.max(1) - 1) as usize + (neg.max(1) - 1) as usize;
            if neg > 0 {
                ops.divs += 1;
            }
            for (b, _) in f {
                count(b, ops, trig);
            }
        }
    }
}

fn finish(p: &mut Program) {
    let mut ops = OpCount::default();
    let mut trig = BTreeSet::new();
    for s in &p.stmts {
        count(&s.expr, &mut ops, &mut trig);
    }
    for (_, _, e) in &p.outputs {
        count(e, &mut ops, &mut trig);
    }
    ops.sincos = trig.len();
    p.ops = ops;
    p.sincos = trig.into_iter().collect();
}

/// Numeric evaluation of lowered programs (an interpreter, for testing the lowering).
impl Lowered {
    /// Values of the precompute slots for parameter values `params`.
    pub fn precompute_values(&self, params: &[f64]) -> Vec<f64> {
        let locals = run(&self.precompute, params, &[], &[], &[], &[]);
        self.pre_slots.iter().map(|&i| locals[i]).collect()
    }

    /// Evaluate function `id`; dense row-major matrix (both triangles of a symmetric one) or
    /// vector. Panics if the module does not have the function (a test helper).
    pub fn evaluate(
        &self,
        id: FunctionId,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        self.evaluate_at(id, None, params, q, u, ud)
    }

    /// [`Lowered::evaluate`] for body frame `frame` (a link index) of a per-frame function
    /// (`None`: frame 0, or a function without frames).
    pub fn evaluate_at(
        &self,
        id: FunctionId,
        frame: Option<usize>,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        let pre = self.precompute_values(params);
        let p = self
            .function_at(id, frame)
            .unwrap_or_else(|| panic!("the lowered model has no function `{id}`"));
        let values = output_values(p, params, &pre, &self.expand_angles(q), u, ud);
        let entries = p
            .outputs
            .iter()
            .zip(values)
            .map(|((r, c, _), v)| (*r, *c, v));
        id.spec().shape.dense_in(&self.sizes, entries)
    }
}

impl Lowered {
    /// The straight-line part of function `id`'s loop form at one state, if it has one: the
    /// `kin` table and the directly stored `(row, column, value)` entries (a test helper; the
    /// loop itself is `kanegen_runtime::regressor`).
    #[allow(clippy::type_complexity)]
    pub fn evaluate_loop_inputs(
        &self,
        id: FunctionId,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Option<(Vec<f64>, Vec<(usize, usize, f64)>)> {
        let lp = self
            .functions
            .iter()
            .find(|f| f.id == id)?
            .looped
            .as_ref()?;
        let pre = self.precompute_values(params);
        let p = &lp.program;
        let values = output_values(p, params, &pre, &self.expand_angles(q), u, ud);
        let kin = values[..lp.kin_len].to_vec();
        let extra = p.outputs[lp.kin_len..]
            .iter()
            .zip(&values[lp.kin_len..])
            .map(|((r, c, _), v)| (*r, *c, *v))
            .collect();
        Some((kin, extra))
    }
}

impl Lowered {
    /// Evaluate combined function `index` (in the order of [`Lowered::combined`]): per part, the
    /// dense value of its shape as [`Lowered::evaluate`] gives it. Panics if there is no such
    /// combined function (a test helper).
    pub fn evaluate_combined(
        &self,
        index: usize,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<Vec<f64>> {
        let pre = self.precompute_values(params);
        let c = &self.combined[index];
        let p = &c.program;
        let values = output_values(p, params, &pre, &self.expand_angles(q), u, ud);
        c.spec
            .parts
            .iter()
            .zip(&c.parts)
            .map(|(part, range)| {
                let entries = p.outputs[range.clone()]
                    .iter()
                    .zip(&values[range.clone()])
                    .map(|((r, col, _), v)| (*r, *col, *v));
                part.function.spec().shape.dense_in(&self.sizes, entries)
            })
            .collect()
    }

    /// `q` extended by the angles of the dependent (mimic) speeds at their indices, which the
    /// programs' `sin`/`cos` leaves of those speeds read.
    pub fn expand_angles(&self, q: &[f64]) -> Vec<f64> {
        let len = self
            .mimic_angles
            .iter()
            .map(|(s, _)| s + 1)
            .max()
            .unwrap_or(0);
        let mut out = q.to_vec();
        if out.len() < len {
            out.resize(len, 0.0);
        }
        for (s, m) in &self.mimic_angles {
            out[*s] = m.multiplier * q[m.master as usize] + m.offset;
        }
        out
    }
}

struct EvalCtx<'a> {
    params: &'a [f64],
    pre: &'a [f64],
    q: &'a [f64],
    u: &'a [f64],
    ud: &'a [f64],
    locals: &'a [f64],
}

impl EvalCtx<'_> {
    fn eval(&self, e: &LExpr) -> f64 {
        match e {
            LExpr::Leaf(l) => match *l {
                Leaf::Const(c) => c,
                Leaf::Param(p) => self.params[p],
                Leaf::Pre(s) => self.pre[s],
                Leaf::Speed(s) => self.u[s],
                Leaf::Accel(s) => self.ud[s],
                Leaf::Sin(s) => self.q[s].sin(),
                Leaf::Cos(s) => self.q[s].cos(),
                Leaf::Coord(s) => self.q[s],
                Leaf::Local(i) => self.locals[i],
            },
            LExpr::Sum { constant, terms } => terms
                .iter()
                .fold(*constant, |acc, (k, t)| acc + k * self.eval(t)),
            LExpr::Prod(f) => f
                .iter()
                .fold(1.0, |acc, (b, p)| acc * self.eval(b).powi(*p)),
        }
    }
}

/// The values of `p`'s outputs, in order, at one input point (`q` with the mimic angles
/// expanded, see [`Lowered::expand_angles`]).
fn output_values(
    p: &Program,
    params: &[f64],
    pre: &[f64],
    q: &[f64],
    u: &[f64],
    ud: &[f64],
) -> Vec<f64> {
    let locals = run(p, params, pre, q, u, ud);
    let ctx = EvalCtx {
        params,
        pre,
        q,
        u,
        ud,
        locals: &locals,
    };
    p.outputs.iter().map(|(_, _, e)| ctx.eval(e)).collect()
}

fn run(p: &Program, params: &[f64], pre: &[f64], q: &[f64], u: &[f64], ud: &[f64]) -> Vec<f64> {
    let mut locals: Vec<f64> = Vec::with_capacity(p.stmts.len());
    for s in &p.stmts {
        let v = EvalCtx {
            params,
            pre,
            q,
            u,
            ud,
            locals: &locals,
        }
        .eval(&s.expr);
        locals.push(v);
    }
    locals
}

/// Puts the statements of `p` in `order` (a permutation of the statement indices in which every
/// statement follows the statements it reads), renumbering the references of statements and
/// results.
fn apply_order(p: &mut Program, order: &[usize]) {
    let mut new_index = vec![0; order.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    let mut stmts: Vec<(usize, Stmt)> = std::mem::take(&mut p.stmts)
        .into_iter()
        .enumerate()
        .map(|(old, mut s)| {
            renumber(&mut s.expr, &new_index);
            (new_index[old], s)
        })
        .collect();
    stmts.sort_unstable_by_key(|(new, _)| *new);
    p.stmts = stmts.into_iter().map(|(_, s)| s).collect();
    for (_, _, e) in &mut p.outputs {
        renumber(e, &new_index);
    }
}
