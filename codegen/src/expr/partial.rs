//! Evaluation of only the nodes some roots need.
//!
//! A module's arena holds every function's expressions; the base-parameter search evaluates one
//! regressor at many states and geometries, and evaluating the whole arena each time (with the
//! derivatives or the Coriolis matrix in the module, most of it unrelated) would dominate
//! generation time.

use super::arena::{Arena, Atom, ExprId, Node, Values};

impl Arena {
    /// Per node: whether `roots` read it (through substitution variables too).
    pub fn needed_nodes(&self, roots: &[ExprId]) -> Vec<bool> {
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<ExprId> = roots.to_vec();
        while let Some(e) = stack.pop() {
            if std::mem::replace(&mut seen[e.index()], true) {
                continue;
            }
            match self.node(e) {
                Node::Atom(Atom::Var(v)) => stack.push(self.vars[*v as usize].def),
                Node::Sum { terms, .. } => stack.extend(terms.iter().map(|(t, _)| *t)),
                Node::Prod(f) => stack.extend(f.iter().map(|(b, _)| *b)),
                _ => {}
            }
        }
        seen
    }

    /// [`Arena::eval`] of the nodes marked in `needed` (see [`Arena::needed_nodes`]); the
    /// others are left at 0.
    pub fn eval_needed(&self, v: &Values<'_>, needed: &[bool]) -> Vec<f64> {
        let mut out = vec![0.0; self.nodes.len()];
        for i in (0..self.nodes.len()).filter(|&i| needed[i]) {
            out[i] = self.eval_node(i, v, &out);
        }
        out
    }
}
