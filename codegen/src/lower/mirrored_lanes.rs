//! Arms in lanes: the statements of a model's two mirrored subtrees (Krang's arms, see
//! [`Mirror`]) paired, so that the emitter computes each pair once in two SIMD lanes
//! (`kanegen_runtime::pair::F64x2`).
//!
//! **Pairing.** Statement `j` is the *mirror* of statement `i` when `j`'s expression is `i`'s
//! with every leaf replaced by its mirror (a body's parameters by the mirrored body's, a joint's
//! sine, cosine, speed by the mirrored joint's; shared parameters stay) and every statement it
//! reads replaced by that statement's mirror — up to the order of terms and up to signs: the
//! two subtrees hang from the trunk in different orientations, so a mirrored quantity is often
//! the negative of the mirrored expression (`wd8r.y = −qdd7r + …` where `wd8l.y = qdd7l + …`).
//! The signs are unknowns `σ` (one per pair: the right value is `σ` times the mirrored left
//! expression), and each matched term is a parity equation over them, solved incrementally
//! with a union-find over parities; a candidate whose equations contradict earlier ones is
//! not paired. Where the subtrees meet the trunk (their roots' velocities, formed with
//! different rotations) no expression matches; there statements with mirrored labels
//! (`w3 in 4l`, `w3 in 4r`) are paired as *packed* pairs, computed as scalars and then put in
//! lanes, so that everything below them matches again. Statements of the trunk read by both
//! subtrees are their own mirror (shared).
//!
//! **Rewriting.** The program is then rewritten so that each pair's two statements are the
//! same expression of mirrored operands, term for term: every right statement of a pair holds
//! `σ` times its old value (its readers absorb the sign, which is exact: IEEE negation commutes
//! with rounding), a lane pair's right statement *is* the mirrored left expression (same terms,
//! same order), and the statements are reordered so that each lane pair is adjacent (left,
//! right) and after everything either side reads. The rewritten program computes every entry
//! as before up to the order of additions in the right subtree; it is what every form of the
//! function (single state, batched, listing, evaluator) uses, so a lane pair computes exactly
//! the bits of its two scalar statements, and the batched functions stay equal to the
//! single-state ones bit for bit. The rewrite is checked by evaluation against the original
//! program on random inputs before it is kept.

use rustc_hash::FxHashMap;

use super::eval::output_values;
use super::order::apply_order;
use super::program::{LExpr, Leaf, Lowered, Program, Stmt, locals};
pub use super::program::{LaneLeaves, LanePlan, Role};
use crate::kane::{Derivation, Mirror};
use crate::registry::FunctionId;

/// The functions whose single-state form gets lanes (when [`apply`] finds pairs): M, c, g, τ,
/// C, the nonlinear effects and the centre of mass's position, Jacobian and bias acceleration
/// (the per-frame functions compute one frame, which has no mirror within the function).
pub const LANE_FUNCTIONS: [FunctionId; 9] = [
    FunctionId::MassMatrix,
    FunctionId::Coriolis,
    FunctionId::Gravity,
    FunctionId::InverseDynamics,
    FunctionId::CoriolisMatrix,
    FunctionId::NonlinearEffects,
    FunctionId::CenterOfMass,
    FunctionId::ComJacobian,
    FunctionId::ComBiasAcceleration,
];

/// Pairs the programs of [`LANE_FUNCTIONS`] of `low` (and the straight-line part of the looped
/// `inverse_dynamics_derivatives`) where `d`'s model has mirrored subtrees: rewrites each
/// program (see the module docs) and sets its [`super::FunctionProgram::lanes`]
/// ([`super::LoopedProgram::lanes`]).
/// A program with no lane pair, or whose rewrite does not evaluate to the original's values,
/// stays as it is.
pub fn apply(low: &mut Lowered, d: &Derivation) {
    let Some(mirror) = &d.mirror else {
        return;
    };
    let mut leaves = LaneLeaves {
        mirror: mirror.clone(),
        pre: Vec::new(),
    };
    leaves.pre = pre_mirror(low, &leaves);
    let params: Vec<f64> = test_inputs(mirror.params.len(), 1.0);
    let pre_values = low.precompute_values(&params);
    // `p` paired, if it has a lane pair and the rewrite computes what `p` does.
    let paired = |p: &Program| {
        pair(p, &leaves).filter(|(q, plan)| {
            plan.lane_pairs() > 0 && same_values(p, q, d.dof, &params, &pre_values)
        })
    };
    let mut any = false;
    for f in &mut low.functions {
        if f.frame.is_some() || f.looped.is_some() || !LANE_FUNCTIONS.contains(&f.id) {
            continue;
        }
        if let Some((program, plan)) = paired(&f.program) {
            (f.program, f.lanes, any) = (program, Some(plan), true);
        }
    }
    // The combined functions (a controller's terms in one program).
    for c in &mut low.combined {
        if let Some((program, plan)) = paired(&c.program) {
            (c.program, c.lanes, any) = (program, Some(plan), true);
        }
    }
    // The straight-line part of the looped derivatives (its outputs: the workspace).
    if let Some(looped) = &mut low.derivative_loop
        && let Some((program, plan)) = paired(&looped.program)
    {
        (looped.program, looped.lanes, any) = (program, Some(plan), true);
    }
    if any {
        low.lane_leaves = Some(leaves);
    }
}

/// Deterministic inputs for the rewrite check: `n` values spread over ±`scale`.
fn test_inputs(n: usize, scale: f64) -> Vec<f64> {
    (0..n)
        .map(|i| scale * (0.37 + 0.61 * i as f64).sin())
        .collect()
}

/// Whether `a` and `b` compute the same results (to rounding) at two input points.
fn same_values(a: &Program, b: &Program, n: usize, params: &[f64], pre: &[f64]) -> bool {
    (0..2).all(|k| {
        let shift = 1.3 * k as f64;
        let q: Vec<f64> = test_inputs(n, 2.0).iter().map(|v| v + shift).collect();
        let u: Vec<f64> = test_inputs(n, 1.5)
            .iter()
            .rev()
            .map(|v| v - shift)
            .collect();
        let ud: Vec<f64> = test_inputs(n, 3.0)
            .iter()
            .map(|v| v * 0.7 + shift)
            .collect();
        let oa = output_values(a, params, pre, &q, &q, &u, &ud);
        let ob = output_values(b, params, pre, &q, &q, &u, &ud);
        let scale = oa.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        oa.iter()
            .zip(&ob)
            .all(|(x, y)| (x - y).abs() <= 1e-9 * scale && x.is_finite() == y.is_finite())
    })
}

/// `e` with its leaves mapped by `leaf` (statements by `local`); `None` if one has no image.
fn map_expr(
    e: &LExpr,
    leaf: &dyn Fn(Leaf) -> Option<Leaf>,
    local: &dyn Fn(usize) -> Option<usize>,
) -> Option<LExpr> {
    Some(match e {
        LExpr::Leaf(Leaf::Local(i)) => LExpr::Leaf(Leaf::Local(local(*i)?)),
        LExpr::Leaf(l) => LExpr::Leaf(leaf(*l)?),
        LExpr::Sum { constant, terms } => LExpr::Sum {
            constant: *constant,
            terms: terms
                .iter()
                .map(|(k, t)| Some((*k, map_expr(t, leaf, local)?)))
                .collect::<Option<_>>()?,
        },
        LExpr::Prod(f) => LExpr::Prod(
            f.iter()
                .map(|(b, p)| Some((map_expr(b, leaf, local)?, *p)))
                .collect::<Option<_>>()?,
        ),
    })
}

/// A key of `e` that ignores the order of terms and factors, and with `signed == false` also
/// the signs of coefficients and constants.
fn sorted_key(e: &LExpr, signed: bool, out: &mut String) {
    use std::fmt::Write;
    let num = |v: f64| if signed { v } else { v.abs() };
    match e {
        LExpr::Leaf(l) => {
            let _ = match l {
                Leaf::Const(c) => write!(out, "c{}", num(*c)),
                other => write!(out, "{other:?}"),
            };
        }
        LExpr::Sum { constant, terms } => {
            let mut parts: Vec<String> = terms
                .iter()
                .map(|(k, t)| {
                    let mut s = format!("{}*", num(*k));
                    sorted_key(t, signed, &mut s);
                    s
                })
                .collect();
            parts.sort_unstable();
            let _ = write!(out, "S{}[{}]", num(*constant), parts.join(","));
        }
        LExpr::Prod(f) => {
            let mut parts: Vec<String> = f
                .iter()
                .map(|(b, p)| {
                    let mut s = String::new();
                    sorted_key(b, signed, &mut s);
                    format!("{s}^{p}")
                })
                .collect();
            parts.sort_unstable();
            let _ = write!(out, "P[{}]", parts.join(","));
        }
    }
}

/// A key of `e` that ignores signs and the order of terms and factors.
fn key(e: &LExpr) -> String {
    let mut s = String::new();
    sorted_key(e, false, &mut s);
    s
}

/// The statements whose sign is a factor of term `t` (each once per odd power), or `None` when
/// the term's sign does not factor (a sum inside, a negative constant inside a product).
fn sign_vars(t: &LExpr, out: &mut Vec<usize>) -> bool {
    match t {
        LExpr::Leaf(Leaf::Local(i)) => {
            out.push(*i);
            true
        }
        LExpr::Leaf(Leaf::Const(c)) => *c >= 0.0,
        LExpr::Leaf(_) => true,
        LExpr::Prod(f) => f.iter().all(|(b, p)| {
            let mut inner = Vec::new();
            let ok = sign_vars(b, &mut inner);
            if p % 2 != 0 {
                out.extend(inner);
            }
            ok
        }),
        LExpr::Sum { .. } => false,
    }
}

/// Parities over statement signs: a union-find whose edges carry the parity between a node
/// and its parent. Node `n` (the last) is the constant `+1`.
struct Parity {
    parent: Vec<usize>,
    flip: Vec<bool>,
}

impl Parity {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..=n).collect(),
            flip: vec![false; n + 1],
        }
    }

    fn one(&self) -> usize {
        self.parent.len() - 1
    }

    /// The root of `a` and the parity of `a` against it.
    fn find(&mut self, a: usize) -> (usize, bool) {
        let mut path = Vec::new();
        let mut x = a;
        while self.parent[x] != x {
            path.push(x);
            x = self.parent[x];
        }
        // Compress: parities to the root, from the node nearest the root down.
        let mut acc = false;
        for &y in path.iter().rev() {
            acc ^= self.flip[y];
            self.flip[y] = acc;
            self.parent[y] = x;
        }
        (x, if path.is_empty() { false } else { self.flip[a] })
    }

    /// Adds `σ_a ⊕ σ_b = v`; false if it contradicts what is known.
    fn union(&mut self, a: usize, b: usize, v: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return (pa ^ pb) == v;
        }
        self.parent[ra] = rb;
        self.flip[ra] = pa ^ pb ^ v;
        true
    }

    /// Adds `σ_i ⊕ (⊕ σ_v for v in vars) = v`, when it can be said as one pairwise relation
    /// (every variable but at most one has a sign known relative to another or to `+1`).
    fn term(&mut self, i: usize, vars: &[usize], v: bool) -> bool {
        let one = self.one();
        let (r1, p1) = self.find(one);
        let mut parity = v;
        // Known signs (relative to +1) fold into the parity; pairs with a common root cancel.
        let mut open: Vec<(usize, bool)> = Vec::new();
        for &x in vars {
            let (r, p) = self.find(x);
            if r == r1 {
                parity ^= p ^ p1;
            } else if let Some(pos) = open.iter().position(|(o, _)| *o == r) {
                parity ^= open[pos].1 ^ p;
                open.swap_remove(pos);
            } else {
                open.push((r, p));
            }
        }
        match open.as_slice() {
            [] => self.union(i, one, parity),
            [(r, p)] => self.union(i, *r, parity ^ p),
            _ => false,
        }
    }

    /// The sign of `a` (`true`: −1); +1 where nothing fixes it.
    fn sign(&mut self, a: usize) -> bool {
        let one = self.one();
        let (r, p) = self.find(a);
        let (r1, p1) = self.find(one);
        if r == r1 { p ^ p1 } else { p }
    }
}

/// The parity equations that make `right` = σ_i · (`left` with leaves and statements mapped),
/// term by term, or `None` when the terms do not correspond.
fn equations(left_mapped: &LExpr, right: &LExpr) -> Option<Vec<(Vec<usize>, bool)>> {
    let mut eqs = Vec::new();
    match (left_mapped, right) {
        (
            LExpr::Sum {
                constant: c1,
                terms: t1,
            },
            LExpr::Sum {
                constant: c2,
                terms: t2,
            },
        ) => {
            if t1.len() != t2.len() || c1.abs() != c2.abs() {
                return None;
            }
            if *c1 != 0.0 {
                eqs.push((Vec::new(), (*c1 < 0.0) != (*c2 < 0.0)));
            }
            let keys: Vec<String> = t2.iter().map(|(_, t)| key(t)).collect();
            let mut used = vec![false; t2.len()];
            for (k, t) in t1 {
                let kt = key(t);
                let pos = (0..t2.len())
                    .find(|&q| !used[q] && keys[q] == kt && t2[q].0.abs() == k.abs())?;
                used[pos] = true;
                let mut vars = Vec::new();
                if !sign_vars(t, &mut vars) || !sign_vars(&t2[pos].1, &mut Vec::new()) {
                    return None;
                }
                // The right term's own statements are the left's mirrors: their signs are
                // the same variables (indexed by the left statement).
                eqs.push((vars, (*k < 0.0) != (t2[pos].0 < 0.0)));
            }
        }
        (a, b) => {
            if key(a) != key(b) {
                return None;
            }
            let mut vars = Vec::new();
            if !sign_vars(a, &mut vars) || !sign_vars(b, &mut Vec::new()) {
                return None;
            }
            eqs.push((vars, false));
        }
    }
    Some(eqs)
}

/// The mirror of each precomputed slot: slots whose statements are each other's exact
/// mirror (same terms and signs), or their own.
fn pre_mirror(low: &Lowered, map: &LaneLeaves) -> Vec<Option<usize>> {
    let p = &low.precompute;
    let mut by_text: FxHashMap<String, usize> = FxHashMap::default();
    for (j, s) in p.stmts.iter().enumerate() {
        by_text.entry(exact_key(&s.expr)).or_insert(j);
    }
    let mut stmt_mirror: Vec<Option<usize>> = vec![None; p.stmts.len()];
    for (i, s) in p.stmts.iter().enumerate() {
        let mapped = map_expr(&s.expr, &|l| map.leaf(l), &|k| stmt_mirror[k]);
        stmt_mirror[i] = mapped.and_then(|m| by_text.get(&exact_key(&m)).copied());
    }
    let slot_of: FxHashMap<usize, usize> = low
        .pre_slots
        .iter()
        .enumerate()
        .map(|(slot, &i)| (i, slot))
        .collect();
    low.pre_slots
        .iter()
        .map(|&i| stmt_mirror[i].and_then(|j| slot_of.get(&j).copied()))
        .collect()
}

/// A key of `e` that ignores only the order of terms and factors.
fn exact_key(e: &LExpr) -> String {
    let mut s = String::new();
    sorted_key(e, true, &mut s);
    s
}

/// What [`pair`] found for one statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Found {
    /// No mirror.
    None,
    /// Its own mirror (shared by both subtrees).
    Shared,
    /// Left of a lane pair with the statement.
    Lane(usize),
    /// Left of a packed pair with the statement.
    Packed(usize),
    /// Right of a pair whose left is the statement.
    RightOf(usize),
}

/// The statement a pair's sign variable is kept under: a right statement's left, else the
/// statement itself.
fn sign_var(found: &[Found], k: usize) -> usize {
    match found[k] {
        Found::RightOf(l) => l,
        _ => k,
    }
}

/// The program `p` rewritten and reordered for two lanes, and its plan (see the module docs);
/// `None` when no statement pairs.
pub fn pair(p: &Program, map: &LaneLeaves) -> Option<(Program, LanePlan)> {
    let n = p.stmts.len();
    let mirror = &map.mirror;
    let mut by_key: FxHashMap<String, Vec<usize>> = FxHashMap::default();
    for (j, s) in p.stmts.iter().enumerate() {
        by_key.entry(key(&s.expr)).or_default().push(j);
    }
    let mut by_label: FxHashMap<&str, usize> = FxHashMap::default();
    for (j, s) in p.stmts.iter().enumerate() {
        if !s.comment.is_empty() && s.comment != "common subexpression" {
            by_label.entry(s.comment.as_str()).or_insert(j);
        }
    }
    let mut found = vec![Found::None; n];
    // The statement a statement maps to (itself when shared, its partner in a pair).
    let mut image: Vec<Option<usize>> = vec![None; n];
    let mut parity = Parity::new(n);
    for i in 0..n {
        if found[i] != Found::None {
            continue;
        }
        let e = &p.stmts[i].expr;
        let mapped = map_expr(e, &|l| map.leaf(l), &|k| image[k]);
        let label = {
            let m = mirror.label(&p.stmts[i].comment);
            (m != p.stmts[i].comment)
                .then(|| by_label.get(m.as_str()).copied())
                .flatten()
                .filter(|&j| j != i && found[j] == Found::None)
        };
        let mut chosen = None;
        if let Some(m) = &mapped {
            let mut candidates: Vec<usize> = by_key
                .get(&key(m))
                .map(|v| {
                    v.iter()
                        .copied()
                        .filter(|&j| j == i || found[j] == Found::None)
                        .collect()
                })
                .unwrap_or_default();
            // Itself first (shared), then the labelled mirror, then the rest in order.
            candidates.sort_by_key(|&j| (j != i, Some(j) != label, j));
            for j in candidates {
                let Some(eqs) = equations(m, &p.stmts[j].expr) else {
                    continue;
                };
                // The variables of the mapped expression are the images; the sign of a pair
                // is kept under its left statement: map each image back.
                let saved = (parity.parent.clone(), parity.flip.clone());
                let mut ok = j != i || parity.union(i, parity.one(), false);
                for (vars, v) in &eqs {
                    if !ok {
                        break;
                    }
                    let vars: Vec<usize> = vars.iter().map(|&k| sign_var(&found, k)).collect();
                    ok = parity.term(i, &vars, *v);
                }
                if ok {
                    chosen = Some(j);
                    break;
                }
                parity.parent = saved.0;
                parity.flip = saved.1;
            }
        }
        match chosen {
            Some(j) if j == i => {
                found[i] = Found::Shared;
                image[i] = Some(i);
            }
            Some(j) => {
                found[i] = Found::Lane(j);
                found[j] = Found::RightOf(i);
                image[i] = Some(j);
                image[j] = Some(i);
            }
            None => {
                if let Some(j) = label {
                    found[i] = Found::Packed(j);
                    found[j] = Found::RightOf(i);
                    image[i] = Some(j);
                    image[j] = Some(i);
                }
            }
        }
    }
    if !found.iter().any(|f| matches!(f, Found::Lane(_))) {
        return None;
    }
    // Each pair's sign variable is its first statement's; the sign is carried by its right
    // statement, which is the one of the second subtree: pairs found second subtree first
    // are turned around, so that the low lane always holds the first subtree.
    let var: Vec<usize> = (0..n).map(|k| sign_var(&found, k)).collect();
    let side = sides(p, map);
    for i in 0..n {
        let (j, lane) = match found[i] {
            Found::Lane(j) => (j, true),
            Found::Packed(j) => (j, false),
            _ => continue,
        };
        if side[i] == Some(true) && side[j] == Some(false) {
            found[j] = if lane {
                Found::Lane(i)
            } else {
                Found::Packed(i)
            };
            found[i] = Found::RightOf(j);
        }
    }
    let flip: Vec<bool> = (0..n)
        .map(|k| matches!(found[k], Found::RightOf(_)) && parity.sign(var[k]))
        .collect();
    let mut stmts = p.stmts.clone();
    for (k, s) in stmts.iter_mut().enumerate() {
        s.expr = match found[k] {
            // The left statement as rewritten (it may read right statements, whose signs
            // it absorbs), mirrored.
            Found::RightOf(l) if matches!(found[l], Found::Lane(_)) => map_expr(
                &with_signs(&p.stmts[l].expr, &flip),
                &|x| map.leaf(x),
                &|x| image[x],
            )
            .expect("a lane pair's left statement maps"),
            _ => {
                let e = with_signs(&s.expr, &flip);
                if flip[k] { negated(e) } else { e }
            }
        };
    }
    let outputs: Vec<(usize, usize, LExpr)> = p
        .outputs
        .iter()
        .map(|(r, c, e)| (*r, *c, with_signs(e, &flip)))
        .collect();
    let order = lane_order(&stmts, &found)?;
    let mut out = Program {
        stmts,
        outputs,
        sincos: interleaved(&p.sincos, mirror),
        ..p.clone()
    };
    apply_order(&mut out, &order);
    let mut new_index = vec![0; n];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    let mut roles = vec![Role::Scalar; n];
    let mut partner = vec![None; n];
    let mut packed = Vec::new();
    for (old, f) in found.iter().enumerate() {
        let at = new_index[old];
        match *f {
            Found::Lane(j) => {
                debug_assert_eq!(new_index[j], at + 1);
                roles[at] = Role::Left;
                roles[at + 1] = Role::Right;
                partner[at] = Some(at + 1);
                partner[at + 1] = Some(at);
            }
            Found::Packed(j) => {
                packed.push((at, new_index[j]));
                partner[at] = Some(new_index[j]);
                partner[new_index[j]] = Some(at);
            }
            _ => {}
        }
    }
    packed.sort_unstable();
    Some((
        out,
        LanePlan {
            roles,
            packed,
            partner,
        },
    ))
}

/// Which subtree each statement belongs to (`Some(false)`: the first, `Some(true)`: the
/// second, `None`: neither, or both): that of the first leaf it reads that has another
/// mirror (a lower speed or parameter index is the first subtree's), else that of the first
/// statement it reads that has one.
fn sides(p: &Program, map: &LaneLeaves) -> Vec<Option<bool>> {
    fn walk(e: &LExpr, map: &LaneLeaves, sides: &[Option<bool>]) -> Option<bool> {
        match e {
            LExpr::Leaf(Leaf::Local(k)) => sides[*k],
            LExpr::Leaf(l) => {
                let index = |l: Leaf| match l {
                    Leaf::Param(i)
                    | Leaf::Pre(i)
                    | Leaf::Speed(i)
                    | Leaf::Accel(i)
                    | Leaf::Sin(i)
                    | Leaf::Cos(i)
                    | Leaf::Coord(i) => Some(i),
                    _ => None,
                };
                let (a, b) = (index(*l)?, index(map.leaf(*l)?)?);
                (a != b).then_some(a > b)
            }
            LExpr::Sum { terms, .. } => terms.iter().find_map(|(_, t)| walk(t, map, sides)),
            LExpr::Prod(f) => f.iter().find_map(|(b, _)| walk(b, map, sides)),
        }
    }
    let mut sides = Vec::with_capacity(p.stmts.len());
    for s in &p.stmts {
        let side = walk(&s.expr, map, &sides);
        sides.push(side);
    }
    sides
}

/// The joint angles `sincos` with each mirrored pair next to each other (first subtree's
/// first), so that a pair's sines (and cosines) are adjacent in the batched `sin_cos_n`
/// result and one 16-byte load fills both lanes.
fn interleaved(sincos: &[usize], mirror: &Mirror) -> Vec<usize> {
    let mut out = Vec::with_capacity(sincos.len());
    for &s in sincos {
        let m = mirror.speeds[s];
        if out.contains(&s) {
            continue;
        }
        out.push(s);
        if m != s && sincos.contains(&m) {
            out.push(m);
        }
    }
    out
}

/// `e` with every statement `k` read with its sign flipped where `flip[k]`.
fn with_signs(e: &LExpr, flip: &[bool]) -> LExpr {
    let (negative, e) = signed(e, flip);
    if negative { negated(e) } else { e }
}

/// `e` with flipped statements' signs pulled out: `(negative, expression)`.
fn signed(e: &LExpr, flip: &[bool]) -> (bool, LExpr) {
    match e {
        LExpr::Leaf(Leaf::Local(k)) => (flip[*k], e.clone()),
        LExpr::Leaf(_) => (false, e.clone()),
        LExpr::Sum { constant, terms } => (
            false,
            LExpr::Sum {
                constant: *constant,
                terms: terms
                    .iter()
                    .map(|(c, t)| {
                        let (neg, t) = signed(t, flip);
                        (if neg { -c } else { *c }, t)
                    })
                    .collect(),
            },
        ),
        LExpr::Prod(f) => {
            let mut negative = false;
            let factors = f
                .iter()
                .map(|(b, p)| {
                    let (neg, b) = signed(b, flip);
                    negative ^= neg && p % 2 != 0;
                    (b, *p)
                })
                .collect();
            (negative, LExpr::Prod(factors))
        }
    }
}

/// `−e`: a sum's coefficients and constant negated, anything else as `−1 · e`.
fn negated(e: LExpr) -> LExpr {
    match e {
        LExpr::Sum { constant, terms } => LExpr::Sum {
            constant: -constant,
            terms: terms.into_iter().map(|(k, t)| (-k, t)).collect(),
        },
        other => LExpr::Sum {
            constant: 0.0,
            terms: vec![(-1.0, other)],
        },
    }
}

/// A statement order in which each lane pair is adjacent (left, right), every statement
/// follows what it reads, and statements otherwise keep their order (a lane pair at the later
/// of its two places).
fn lane_order(stmts: &[Stmt], found: &[Found]) -> Option<Vec<usize>> {
    let n = stmts.len();
    // Nodes: a statement, or a lane pair (under its left statement).
    let node = |k: usize| match found[k] {
        Found::RightOf(l) if matches!(found[l], Found::Lane(_)) => l,
        _ => k,
    };
    let mut indegree = vec![0usize; n];
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut priority = vec![0usize; n];
    let mut reads = Vec::new();
    for (k, s) in stmts.iter().enumerate() {
        let me = node(k);
        priority[me] = priority[me].max(k);
        reads.clear();
        locals(&s.expr, &mut reads);
        for &r in &reads {
            let from = node(r);
            if from != me {
                users[from].push(me);
                indegree[me] += 1;
            }
        }
    }
    let mut ready = std::collections::BinaryHeap::new();
    for k in 0..n {
        if node(k) == k && indegree[k] == 0 {
            ready.push(std::cmp::Reverse((priority[k], k)));
        }
    }
    let mut order = Vec::with_capacity(n);
    while let Some(std::cmp::Reverse((_, k))) = ready.pop() {
        order.push(k);
        if let Found::Lane(j) = found[k] {
            order.push(j);
        }
        for &u in &users[k] {
            indegree[u] -= 1;
            if indegree[u] == 0 {
                ready.push(std::cmp::Reverse((priority[u], u)));
            }
        }
    }
    // A pair that would have to come both before and after another statement: no lanes.
    (order.len() == n).then_some(order)
}

#[cfg(test)]
mod tests;
