//! Numeric evaluation of every node of the arena at given leaf values.

use super::arena::{Arena, Atom, Node, Values};

impl Arena {
    /// Evaluate every node; returns values indexed by node.
    pub fn eval(&self, v: &Values<'_>) -> Vec<f64> {
        let mut out = vec![0.0; self.nodes.len()];
        for i in 0..self.nodes.len() {
            out[i] = self.eval_node(i, v, &out);
        }
        out
    }

    /// The value of node `i` from the values `out` of the nodes before it (a node only reads
    /// nodes with smaller indices).
    pub(super) fn eval_node(&self, i: usize, v: &Values<'_>, out: &[f64]) -> f64 {
        match &self.nodes[i] {
            Node::Const(c) => c.get(),
            Node::Atom(a) => match *a {
                Atom::Param(p) => v.params[p as usize],
                Atom::Speed(s) => v.u[s as usize],
                Atom::Accel(s) => v.ud[s as usize],
                Atom::Sin(s) => self.angle(v.q, s).sin(),
                Atom::Cos(s) => self.angle(v.q, s).cos(),
                Atom::Coord(s) => v.q[s as usize],
                Atom::Var(k) => out[self.vars[k as usize].def.index()],
            },
            Node::Sum { constant, terms } => terms
                .iter()
                .fold(constant.get(), |acc, (t, k)| acc + k.get() * out[t.index()]),
            Node::Prod(f) => f
                .iter()
                .fold(1.0, |acc, (b, p)| acc * out[b.index()].powi(*p)),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::expr::arena::{Atom, Values, VarKind};

    use crate::expr::arena::test_arena as arena;

    #[test]
    fn evaluator_matches_direct_computation() {
        let mut ar = arena();
        let a = ar.atom(Atom::Param(0));
        let b = ar.atom(Atom::Param(1));
        let s = ar.atom(Atom::Sin(0));
        let u = ar.atom(Atom::Speed(0));
        let ab = ar.add(a, b);
        let sab = ar.mul(s, ab);
        let v = ar.subst(sab, VarKind::D, "v");
        let vu = ar.mul(v, u);
        let vu2 = ar.powi(vu, 2);
        let e = ar.sub(vu2, a);
        let vals = ar.eval(&Values {
            params: &[0.3, -1.2],
            q: &[0.7],
            u: &[2.5],
            ud: &[0.0],
        });
        let expect = (0.7f64.sin() * (0.3 - 1.2) * 2.5f64).powi(2) - 0.3;
        assert!((vals[e.index()] - expect).abs() < 1e-14);
    }
}
