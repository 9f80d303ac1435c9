//! Lowering a derivation: the arena's expressions scheduled into straight-line programs of
//! numbered locals, with dead code removed, the precompute program of parameter-only values,
//! and the operation counts.

use std::collections::BTreeSet;

use rustc_hash::{FxHashMap, FxHashSet};

use super::order::{SUBTREE_ORDER, in_subtree_order_if_fewer_live};
use super::program::*;
use crate::expr::{Arena, Atom, ExprId, Node, VarKind};
use crate::kane::{Derivation, Function};
use crate::options::{DerivativesForm, LOOPED_ABOVE_FLOPS};
use crate::registry::FunctionId;

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
        nq: d.nq,
        floating: d.floating,
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
