//! The lowered form: leaves, expressions and statements of a straight-line [`Program`], its
//! operation counts, the programs of a module ([`Lowered`]) and the two-lane plan of mirrored
//! statements ([`LanePlan`]); the order in which sums are printed and fused.

use std::collections::BTreeSet;
use std::fmt;

use crate::expr::MimicLeaf;
use crate::kane::Mirror;
use crate::options::ParamMode;
use crate::registry::FunctionId;

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
pub(super) fn locals(e: &LExpr, out: &mut Vec<usize>) {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => out.push(*i),
        LExpr::Leaf(_) => {}
        LExpr::Sum { terms, .. } => terms.iter().for_each(|(_, t)| locals(t, out)),
        LExpr::Prod(f) => f.iter().for_each(|(b, _)| locals(b, out)),
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
    /// The two-lane form of `program` (arms in lanes, see [`lanes`](super::lanes)), when
    /// [`lanes::apply`](super::mirrored_lanes::apply) paired its statements: `program` is then the rewritten program.
    pub lanes: Option<LanePlan>,
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
    /// Number of coordinates (the length of `q`): `dof`, or `dof + 1` for a floating base.
    pub nq: usize,
    /// Whether the base is floating: `q` starts with the base's seven coordinates and the
    /// coordinate of joint speed `s ≥ 6` is `q[s + 1]` (`Leaf::Coord` indexes `q`, `Leaf::Sin` and
    /// `Leaf::Cos` index speeds).
    pub floating: bool,
    /// Parameter mode.
    pub params: ParamMode,
    /// The dependent (mimic) speeds whose `sin`/`cos` leaves the programs may read: speed index
    /// and its angle `a·q[master] + b` (see [`Arena::set_mimic`](crate::expr::Arena::set_mimic)).
    pub mimic_angles: Vec<(usize, MimicLeaf)>,
    /// Result sizes (speeds, regressor columns).
    pub sizes: crate::registry::Sizes,
    /// The regressors' parameters and base parameters (see [`Derivation::regressors`](crate::kane::Derivation::regressors)).
    pub regressors: crate::kane::Regressors,
    /// The combined functions (see [`crate::combined`]).
    pub combined: Vec<CombinedProgram>,
    /// The looped form of `inverse_dynamics_derivatives` (see
    /// [`Derivation::derivative_loop`](crate::kane::Derivation::derivative_loop)): the program filling its workspace and the tables;
    /// `Some` when that form is chosen (see [`lower_with`](super::lower_with)) and emitted instead of the
    /// straight-line program of [`Lowered::functions`] (which the batched form, `listing` and
    /// the interpreter keep using).
    pub derivative_loop: Option<LoopedProgram>,
    /// The mirrors of the leaves, when [`lanes::apply`](super::mirrored_lanes::apply) paired a function's statements (what
    /// the emitter prints for a leaf in two lanes).
    pub lane_leaves: Option<LaneLeaves>,
}

/// The program of the looped `inverse_dynamics_derivatives`: its outputs `(offset, 0, value)`
/// are the workspace entries that `kanegen_runtime::derivatives_loop::run` reads with `plan`.
#[derive(Clone, Debug)]
pub struct LoopedProgram {
    /// The straight-line part.
    pub program: Program,
    /// The tables of the loop.
    pub plan: crate::kane::DerivativeLoop,
    /// The two-lane form of `program` (see [`lanes`](super::lanes)), when [`lanes::apply`](super::mirrored_lanes::apply) paired it.
    pub lanes: Option<LanePlan>,
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
    /// The two-lane form of `program` (see [`lanes`](super::lanes)), when [`lanes::apply`](super::mirrored_lanes::apply) paired it.
    pub lanes: Option<LanePlan>,
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

/// A statement's part in the two-lane form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Computed alone.
    Scalar,
    /// The left (low-lane) statement of a lane pair; the next statement is its right one.
    Left,
    /// The right (high-lane) statement of a lane pair: computed with the statement before it.
    Right,
}

/// How a rewritten program is emitted in two lanes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LanePlan {
    /// Per statement.
    pub roles: Vec<Role>,
    /// The packed pairs `(left, right)`: two scalar statements put in lanes (after the later
    /// of the two) for the lane statements that read them.
    pub packed: Vec<(usize, usize)>,
    /// Per statement, its partner in a lane or packed pair (`None` for the others); shared
    /// statements (their own mirror) are `None`.
    pub partner: Vec<Option<usize>>,
}

impl LanePlan {
    /// The number of lane pairs.
    pub fn lane_pairs(&self) -> usize {
        self.roles.iter().filter(|r| **r == Role::Left).count()
    }
}

/// The mirror of every leaf a paired statement reads: the model's [`Mirror`] and the
/// precomputed slots' mirrors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LaneLeaves {
    /// Parameters and speeds.
    pub mirror: Mirror,
    /// `pre[slot]`: the mirror slot (`None`: none; a paired statement does not read it).
    pub pre: Vec<Option<usize>>,
}

impl LaneLeaves {
    /// The leaf of the other subtree in `l`'s place (`l` itself when shared; `None` for a
    /// statement or a slot without a mirror).
    pub fn leaf(&self, l: Leaf) -> Option<Leaf> {
        let s = |i: usize| self.mirror.speeds[i];
        Some(match l {
            Leaf::Const(c) => Leaf::Const(c),
            Leaf::Param(p) => Leaf::Param(self.mirror.params[p]),
            Leaf::Pre(k) => Leaf::Pre(self.pre.get(k).copied().flatten()?),
            Leaf::Speed(i) => Leaf::Speed(s(i)),
            Leaf::Accel(i) => Leaf::Accel(s(i)),
            Leaf::Sin(i) => Leaf::Sin(s(i)),
            Leaf::Cos(i) => Leaf::Cos(s(i)),
            Leaf::Coord(i) => Leaf::Coord(s(i)),
            Leaf::Local(_) => return None,
        })
    }
}

pub(super) fn count(e: &LExpr, ops: &mut OpCount, trig: &mut BTreeSet<usize>) {
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

pub(super) fn finish(p: &mut Program) {
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
