//! Statement order: a program restricted to some result entries ([`restrict`]), statements
//! grouped per subtree ([`subtree_order`]) where that keeps fewer values live, and which
//! functions get that order.

use super::program::{LExpr, Leaf, OpCount, Program, Stmt, finish, locals};
use crate::registry::FunctionId;

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
pub(super) fn renumber(e: &mut LExpr, new_index: &[usize]) {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => *i = new_index[*i],
        LExpr::Leaf(_) => {}
        LExpr::Sum { terms, .. } => terms.iter_mut().for_each(|(_, t)| renumber(t, new_index)),
        LExpr::Prod(f) => f.iter_mut().for_each(|(b, _)| renumber(b, new_index)),
    }
}

/// The functions whose statements are put in [`subtree_order`] after lowering (where that
/// lowers the values live at once). Only the Coriolis matrix: measured on Krang
/// (Nov 2026, Intel Xeon with AVX-512), it
/// cut C's values live from 455 to 236 (144 since entries go by their deeper speed), its
/// instructions per call by 2.5 % and its time by 1–2 %; for c and τ (111 → 83 and 87 live)
/// the instructions moved by −1.8 % and +1.6 % and the time not at all or up, so they keep the
/// derivation's order.
pub const SUBTREE_ORDER: [FunctionId; 1] = [FunctionId::CoriolisMatrix];

/// The functions whose batched bodies (`emit::batch`: the statements in a loop over the states,
/// vectorized across them, 32 vector registers in the x86-64-v4 copy) run their statements in
/// [`subtree_order`] where that lowers the values live at once ([`batch_program`]), although
/// their single-state form keeps its own order. Measured on Krang with mirrored lanes (whose
/// pairing reorders the single-state program; Nov 2026, Intel Xeon with AVX-512): 8 states of τ 403 → 352 ns (121 → 87 values live), g 152 → 148 ns (34 →
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
pub(super) fn in_subtree_order_if_fewer_live(p: &Program) -> Option<Program> {
    let mut reordered = p.clone();
    subtree_order(&mut reordered);
    (reordered.max_live() < p.max_live()).then_some(reordered)
}

/// Puts the statements of `p` in `order` (a permutation of the statement indices in which every
/// statement follows the statements it reads), renumbering the references of statements and
/// results.
pub(super) fn apply_order(p: &mut Program, order: &[usize]) {
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
