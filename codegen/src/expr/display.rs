//! Printing: leaf names, expressions as text, the substitution listing of the reports.

use std::fmt::Write as _;

use super::arena::{Arena, Atom, ExprId, Node, VarKind};
use crate::naming;

impl Arena {
    /// Name of a leaf for printing.
    pub fn atom_name(&self, a: Atom) -> String {
        let n = &self.names;
        match a {
            Atom::Param(p) => n.params[p as usize].clone(),
            Atom::Speed(s) => n.speeds[s as usize].clone(),
            Atom::Accel(s) => naming::accel(&n.speeds[s as usize]),
            Atom::Sin(s) => naming::sin(&n.coords[s as usize]),
            Atom::Cos(s) => naming::cos(&n.coords[s as usize]),
            Atom::Coord(k) if self.floating && k < 7 => {
                kanegen_model::FLOATING_BASE_COORDINATES[k as usize].to_owned()
            }
            Atom::Coord(k) => n.coords[(k - u32::from(self.floating)) as usize].clone(),
            Atom::Var(v) => {
                let info = &self.vars[v as usize];
                match info.kind {
                    VarKind::K => format!("K{}", v + 1),
                    VarKind::D => format!("D{}", v + 1),
                }
            }
        }
    }

    /// Print an expression (variables by their arena names `K12`, `D7`).
    pub fn display(&self, e: ExprId) -> String {
        let mut s = String::new();
        self.write_expr(&mut s, e, 0);
        s
    }

    pub(super) fn write_expr(&self, s: &mut String, e: ExprId, prec: u8) {
        match self.node(e) {
            Node::Const(c) => {
                let _ = write!(s, "{}", fmt_num(c.get()));
            }
            Node::Atom(a) => s.push_str(&self.atom_name(*a)),
            Node::Sum { constant, terms } => {
                if prec > 0 {
                    s.push('(');
                }
                let mut first = true;
                for (t, k) in terms.iter() {
                    let k = k.get();
                    if first {
                        if k < 0.0 {
                            s.push('-');
                        }
                    } else {
                        s.push_str(if k < 0.0 { " - " } else { " + " });
                    }
                    first = false;
                    if k.abs() != 1.0 {
                        let _ = write!(s, "{}*", fmt_num(k.abs()));
                    }
                    self.write_expr(s, *t, 1);
                }
                let c = constant.get();
                if c != 0.0 {
                    s.push_str(if c < 0.0 { " - " } else { " + " });
                    s.push_str(&fmt_num(c.abs()));
                }
                if prec > 0 {
                    s.push(')');
                }
            }
            Node::Prod(f) => {
                for (i, (b, p)) in f.iter().enumerate() {
                    if i > 0 {
                        s.push('*');
                    }
                    self.write_expr(s, *b, 2);
                    if *p != 1 {
                        let _ = write!(s, "^{p}");
                    }
                }
            }
        }
    }

    /// The substitution listing: every variable reachable from `roots`, in order, one per line.
    pub fn listing(&self, roots: &[ExprId]) -> String {
        let needed = self.reachable_vars(roots);
        let mut s = String::new();
        for (i, info) in self.vars.iter().enumerate() {
            if needed[i] {
                let _ = writeln!(
                    s,
                    "{} = {};  % {}",
                    self.atom_name(Atom::Var(i as u32)),
                    self.display(info.def),
                    info.label
                );
            }
        }
        s
    }

    /// Which variables are needed to compute `roots`.
    pub fn reachable_vars(&self, roots: &[ExprId]) -> Vec<bool> {
        let mut seen = vec![false; self.nodes.len()];
        let mut needed = vec![false; self.vars.len()];
        let mut stack: Vec<ExprId> = roots.to_vec();
        while let Some(e) = stack.pop() {
            if std::mem::replace(&mut seen[e.index()], true) {
                continue;
            }
            match self.node(e) {
                Node::Atom(Atom::Var(v)) => {
                    needed[*v as usize] = true;
                    stack.push(self.vars[*v as usize].def);
                }
                Node::Sum { terms, .. } => stack.extend(terms.iter().map(|(t, _)| *t)),
                Node::Prod(f) => stack.extend(f.iter().map(|(b, _)| *b)),
                _ => {}
            }
        }
        needed
    }
}

/// Shortest round-trip text of a number.
pub fn fmt_num(v: f64) -> String {
    format!("{v:?}")
}
