//! Exact symbolic differentiation on the arena (forward mode over the substitution variables).
//!
//! `∂e/∂x` is formed node by node with the usual rules (`∂ sin q = cos q`, `∂ cos q = −sin q`,
//! sums and products by linearity and the product rule), constants folded and zeros dropped as
//! the nodes are built, so structural zeros are known at generation time and cost nothing. The
//! derivative of a substitution variable `K7 = def` is the derivative of its definition, itself
//! given a variable of its own (label `∂(w3.x)/∂q_w`) when it is compound: the derivative of a
//! recursion is again a recursion with substitution variables, and derivatives are shared
//! between every expression that mentions the same variable. Results are memoised per
//! `(node, variable)`; the traversal is iterative, so deep chains of variables do not overflow
//! the stack.

use super::arena::{Arena, Atom, ExprId, Node, Wrt};

impl Arena {
    /// `∂e/∂wrt`, exact, as an expression of the same arena.
    ///
    /// Substitution variables reached from `e` get derivative variables of the same kind (K or
    /// D, see [`Arena::subst`]) labelled `∂(label)/∂name`; identical derivatives are one node.
    pub fn diff(&mut self, e: ExprId, wrt: Wrt) -> ExprId {
        // Post-order over the nodes reachable from `e` whose derivative is not known yet.
        let mut stack: Vec<(ExprId, bool)> = vec![(e, false)];
        while let Some((n, children_done)) = stack.pop() {
            if self.diff_memo.contains_key(&(n, wrt)) {
                continue;
            }
            if !children_done {
                stack.push((n, true));
                match self.node(n) {
                    Node::Sum { terms, .. } => {
                        stack.extend(terms.iter().map(|(t, _)| (*t, false)));
                    }
                    Node::Prod(f) => stack.extend(f.iter().map(|(b, _)| (*b, false))),
                    Node::Atom(Atom::Var(v)) => {
                        stack.push((self.vars[*v as usize].def, false));
                    }
                    Node::Const(_) | Node::Atom(_) => {}
                }
                continue;
            }
            let d = self.diff_node(n, wrt);
            self.diff_memo.insert((n, wrt), d);
        }
        let d = self.diff_memo[&(e, wrt)];
        self.touch(d);
        d
    }

    /// Name of the independent variable for labels.
    fn wrt_name(&self, wrt: Wrt) -> String {
        match wrt {
            Wrt::Coord(i) => self.atom_name(Atom::Coord(self.coordinate_index(i))),
            Wrt::Speed(i) => self.atom_name(Atom::Speed(i)),
            Wrt::Accel(i) => self.atom_name(Atom::Accel(i)),
            Wrt::Param(p) => self.atom_name(Atom::Param(p)),
        }
    }

    /// Derivative of one node whose children's derivatives are memoised.
    fn diff_node(&mut self, n: ExprId, wrt: Wrt) -> ExprId {
        let d = |a: &Arena, c: ExprId| a.diff_memo[&(c, wrt)];
        match self.node(n).clone() {
            Node::Const(_) => self.zero(),
            Node::Atom(a) => match (a, wrt) {
                (Atom::Param(p), Wrt::Param(x))
                | (Atom::Speed(p), Wrt::Speed(x))
                | (Atom::Accel(p), Wrt::Accel(x))
                    if p == x =>
                {
                    self.one()
                }
                // `Wrt::Coord` names the coordinate by its speed, `Atom::Coord` by its index in q.
                (Atom::Coord(p), Wrt::Coord(x)) if p == self.coordinate_index(x) => self.one(),
                (Atom::Sin(i), Wrt::Coord(x)) if i == x => self.atom(Atom::Cos(i)),
                (Atom::Cos(i), Wrt::Coord(x)) if i == x => {
                    let s = self.atom(Atom::Sin(i));
                    self.neg(s)
                }
                // A dependent (mimic) angle `a·q[m] + b`: the chain rule.
                (Atom::Sin(i), Wrt::Coord(x)) if self.mimic(i).is_some_and(|m| m.master == x) => {
                    let k = self.mimic(i).map_or(0.0, |m| m.multiplier);
                    let c = self.atom(Atom::Cos(i));
                    self.scale(c, k)
                }
                (Atom::Cos(i), Wrt::Coord(x)) if self.mimic(i).is_some_and(|m| m.master == x) => {
                    let k = self.mimic(i).map_or(0.0, |m| m.multiplier);
                    let s = self.atom(Atom::Sin(i));
                    self.scale(s, -k)
                }
                (Atom::Var(v), _) => {
                    let info = self.vars[v as usize].clone();
                    let dd = d(self, info.def);
                    let label = format!("∂({})/∂{}", info.label, self.wrt_name(wrt));
                    self.subst(dd, info.kind, &label)
                }
                _ => self.zero(),
            },
            Node::Sum { terms, .. } => {
                let nonzero: Vec<(ExprId, f64)> = terms
                    .iter()
                    .map(|(t, k)| (d(self, *t), k.get()))
                    .filter(|(dt, _)| !self.is_zero(*dt))
                    .collect();
                let parts: Vec<ExprId> = nonzero
                    .into_iter()
                    .map(|(dt, k)| self.scale(dt, k))
                    .collect();
                self.sum(parts)
            }
            Node::Prod(f) => {
                let mut parts = Vec::new();
                for (i, (b, p)) in f.iter().enumerate() {
                    let db = d(self, *b);
                    if self.is_zero(db) {
                        continue;
                    }
                    // p · b^(p−1) · db · Π_{j≠i} b_j^p_j
                    let mut items = Vec::with_capacity(f.len() + 1);
                    for (j, (bj, pj)) in f.iter().enumerate() {
                        let pw = if j == i { pj - 1 } else { *pj };
                        items.push(self.powi(*bj, pw));
                    }
                    items.push(db);
                    let t = self.product(items);
                    parts.push(self.scale(t, f64::from(*p)));
                }
                self.sum(parts)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::arena::{Names, Values, VarKind};

    fn arena() -> Arena {
        Arena::new(Names {
            params: vec!["m".into(), "L".into()],
            speeds: vec!["qd1".into(), "qd2".into()],
            coords: vec!["q1".into(), "q2".into()],
            lengths: vec![false, true],
        })
    }

    /// Central difference of `e` in one input, all other inputs fixed.
    fn central(ar: &Arena, e: ExprId, wrt: Wrt, x: &Values<'_>) -> f64 {
        let h = 1e-6;
        let shifted = |s: f64| {
            let mut params = x.params.to_vec();
            let mut q = x.q.to_vec();
            let mut u = x.u.to_vec();
            let mut ud = x.ud.to_vec();
            match wrt {
                Wrt::Coord(i) => q[i as usize] += s,
                Wrt::Speed(i) => u[i as usize] += s,
                Wrt::Accel(i) => ud[i as usize] += s,
                Wrt::Param(i) => params[i as usize] += s,
            }
            ar.eval(&Values {
                params: &params,
                q: &q,
                u: &u,
                ud: &ud,
            })[e.index()]
        };
        (shifted(h) - shifted(-h)) / (2.0 * h)
    }

    #[test]
    fn derivatives_through_variables_match_central_differences() {
        let mut ar = arena();
        let (m, l) = (ar.atom(Atom::Param(0)), ar.atom(Atom::Param(1)));
        let (s1, c1, c2) = (
            ar.atom(Atom::Sin(0)),
            ar.atom(Atom::Cos(0)),
            ar.atom(Atom::Cos(1)),
        );
        let (u1, u2, q2) = (
            ar.atom(Atom::Speed(0)),
            ar.atom(Atom::Speed(1)),
            ar.atom(Atom::Coord(1)),
        );
        // K1 = L·(s1·u1 + c1·c2·u2); D2 = m·K1² + q2·s1 / c1
        let a = ar.mul(s1, u1);
        let b = ar.product([c1, c2, u2]);
        let ab = ar.add(a, b);
        let k = ar.mul(l, ab);
        let k = ar.subst(k, VarKind::K, "v1.x");
        let k2 = ar.powi(k, 2);
        let mk = ar.mul(m, k2);
        let ic1 = ar.powi(c1, -1);
        let r = ar.product([q2, s1, ic1]);
        let e = ar.add(mk, r);
        let e = ar.subst(e, VarKind::D, "f1.x");
        let x = Values {
            params: &[1.3, 0.7],
            q: &[0.4, -1.1],
            u: &[0.9, -0.6],
            ud: &[0.0, 0.0],
        };
        for wrt in [
            Wrt::Coord(0),
            Wrt::Coord(1),
            Wrt::Speed(0),
            Wrt::Speed(1),
            Wrt::Param(0),
            Wrt::Param(1),
            Wrt::Accel(0),
        ] {
            let d = ar.diff(e, wrt);
            let exact = ar.eval(&x)[d.index()];
            let fd = central(&ar, e, wrt, &x);
            assert!(
                (exact - fd).abs() <= 1e-7 * (1.0 + fd.abs()),
                "{wrt:?}: {exact} vs {fd}"
            );
        }
        let d = ar.diff(e, Wrt::Accel(0));
        assert!(ar.is_zero(d));
    }

    #[test]
    fn derivative_of_a_variable_is_a_variable_and_is_shared() {
        let mut ar = arena();
        let (s1, c1, u1) = (
            ar.atom(Atom::Sin(0)),
            ar.atom(Atom::Cos(0)),
            ar.atom(Atom::Speed(0)),
        );
        let w = ar.add(s1, c1);
        let w = ar.mul(w, u1);
        let k = ar.subst(w, VarKind::K, "w1.x");
        let d1 = ar.diff(k, Wrt::Coord(0));
        let n = ar.len();
        let d2 = ar.diff(k, Wrt::Coord(0));
        assert_eq!(d1, d2);
        assert_eq!(ar.len(), n, "a second request builds nothing");
        assert!(ar.vars().iter().any(|v| v.label == "∂(w1.x)/∂q1"));
        // Linear in u1: the second derivative in u1 vanishes structurally.
        let du = ar.diff(k, Wrt::Speed(0));
        let dd = ar.diff(du, Wrt::Speed(0));
        assert!(ar.is_zero(dd));
    }

    #[test]
    fn deep_chains_do_not_overflow_the_stack() {
        let mut ar = arena();
        let s1 = ar.atom(Atom::Sin(0));
        let c1 = ar.atom(Atom::Cos(0));
        let mut k = ar.add(s1, c1);
        for i in 0..20_000 {
            let t = ar.mul(k, s1);
            let t = ar.add(t, c1);
            k = ar.subst(t, VarKind::K, &format!("k{i}"));
        }
        let d = ar.diff(k, Wrt::Coord(0));
        assert!(!ar.is_zero(d));
    }
}
