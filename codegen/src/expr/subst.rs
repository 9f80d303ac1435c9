//! Substitution variables: K (kinematic) and D (inertial/gravity) variables naming compound
//! subexpressions, and the hoisting of parameter-only factors into variables of their own.

use super::arena::{Arena, Atom, ExprId, Node, VarInfo, VarKind};

impl Arena {
    fn new_var(&mut self, def: ExprId, kind: VarKind, label: &str) -> ExprId {
        if let Some(&v) = self.var_by_def.get(&def) {
            return self.vars[v as usize].node;
        }
        let v = self.vars.len() as u32;
        // The definition must exist before the variable node (topological order).
        self.vars.push(VarInfo {
            def,
            node: ExprId(u32::MAX),
            kind,
            label: label.to_owned(),
        });
        let node = self.atom(Atom::Var(v));
        self.vars[v as usize].node = node;
        self.var_by_def.insert(def, v);
        node
    }

    /// Replace a compound expression by a substitution variable (the reports' K/D method).
    ///
    /// Simple expressions are returned unchanged. A numeric factor (or sign) is kept outside the
    /// variable so that `−(a+b)` and `a+b` share one variable, and identical definitions share
    /// one variable. With [`Arena::hoist_params`], parameter-only parts of the definition get
    /// variables of their own (kind D) so that they can be computed once, outside the hot path.
    pub fn subst(&mut self, e: ExprId, kind: VarKind, label: &str) -> ExprId {
        if self.is_simple(e) {
            return e;
        }
        let (k, core) = self.split_scale(e);
        let core = if self.hoist_params {
            self.hoist(core, label)
        } else {
            core
        };
        if self.is_simple(core) {
            return self.scale(core, k);
        }
        let kind = if self.involves_inertia(core) {
            VarKind::D
        } else {
            kind
        };
        let v = self.new_var(core, kind, label);
        self.scale(v, k)
    }

    /// Does `e` mention a parameter other than a length, or a D variable?
    pub(super) fn involves_inertia(&self, e: ExprId) -> bool {
        match self.node(e) {
            Node::Const(_) => false,
            Node::Atom(Atom::Param(p)) => !self
                .names
                .lengths
                .get(*p as usize)
                .copied()
                .unwrap_or(false),
            Node::Atom(Atom::Var(v)) => self.vars[*v as usize].kind == VarKind::D,
            Node::Atom(_) => false,
            Node::Sum { terms, .. } => terms.iter().any(|(t, _)| self.involves_inertia(*t)),
            Node::Prod(f) => f.iter().any(|(b, _)| self.involves_inertia(*b)),
        }
    }

    /// Split `e = k · core` with `core` having a positive leading coefficient.
    pub(super) fn split_scale(&mut self, e: ExprId) -> (f64, ExprId) {
        match self.node(e).clone() {
            Node::Sum { constant, terms } if constant.get() == 0.0 && terms.len() == 1 => {
                (terms[0].1.get(), terms[0].0)
            }
            Node::Sum { terms, .. } => {
                let lead = terms[0].1.get();
                if lead < 0.0 {
                    let core = self.scale(e, -1.0);
                    (-1.0, core)
                } else {
                    (1.0, e)
                }
            }
            _ => (1.0, e),
        }
    }

    /// Give the parameter-only parts of a sum or product variables of their own.
    pub fn hoist(&mut self, e: ExprId, label: &str) -> ExprId {
        if self.is_param_only(e) {
            return e;
        }
        match self.node(e).clone() {
            Node::Sum { constant, terms } => {
                let mut fixed: Vec<ExprId> = Vec::new();
                let mut rest: Vec<ExprId> = Vec::new();
                let c = self.constant(constant.get());
                fixed.push(c);
                for (t, k) in terms.iter() {
                    let kt = self.scale(*t, k.get());
                    if self.is_param_only(*t) {
                        fixed.push(kt);
                    } else {
                        let h = self.hoist_prod(*t, label);
                        let h = self.scale(h, k.get());
                        rest.push(h);
                    }
                }
                let fixed = self.sum(fixed);
                let fixed = self.subst(fixed, VarKind::K, &format!("{label} (parameters)"));
                rest.push(fixed);
                self.sum(rest)
            }
            Node::Prod(_) => self.hoist_prod(e, label),
            _ => e,
        }
    }

    pub(super) fn hoist_prod(&mut self, e: ExprId, label: &str) -> ExprId {
        let Node::Prod(f) = self.node(e).clone() else {
            return e;
        };
        let (fixed, rest): (Vec<_>, Vec<_>) = f.iter().partition(|(b, _)| self.is_param_only(*b));
        if fixed.len() < 2 {
            return e;
        }
        let fixed: Vec<ExprId> = fixed.into_iter().map(|(b, p)| self.powi(b, p)).collect();
        let fixed = self.product(fixed);
        let fixed = self.subst(fixed, VarKind::K, &format!("{label} (parameters)"));
        let mut items = vec![fixed];
        for (b, p) in rest {
            let x = self.powi(b, p);
            items.push(x);
        }
        self.product(items)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::arena::Names;

    use crate::expr::arena::test_arena as arena;

    #[test]
    fn kinematic_variables_with_lengths_stay_k_and_inertial_ones_are_d() {
        // Parameter 0 is a length (`L1`), parameter 1 a mass.
        let mut ar = Arena::new(Names {
            params: vec!["L1".into(), "m1".into()],
            speeds: vec!["qd1".into()],
            coords: vec!["q1".into()],
            lengths: vec![true, false],
        });
        ar.hoist_params = true;
        let l = ar.atom(Atom::Param(0));
        let m = ar.atom(Atom::Param(1));
        let s = ar.atom(Atom::Sin(0));
        let u = ar.atom(Atom::Speed(0));
        let su = ar.mul(s, u);
        let v = ar.mul(l, su);
        let vl = ar.add(v, u);
        let k = ar.subst(vl, VarKind::K, "v1.x");
        let Node::Atom(Atom::Var(kv)) = *ar.node(k) else {
            panic!("a variable")
        };
        assert_eq!(
            ar.vars()[kv as usize].kind,
            VarKind::K,
            "lengths are kinematic"
        );
        let f = ar.mul(m, k);
        let f = ar.add(f, s);
        let d = ar.subst(f, VarKind::K, "f1.x");
        let Node::Atom(Atom::Var(dv)) = *ar.node(d) else {
            panic!("a variable")
        };
        assert_eq!(
            ar.vars()[dv as usize].kind,
            VarKind::D,
            "a mass is inertial"
        );
    }

    #[test]
    fn substitution_shares_negated_definitions() {
        let mut ar = arena();
        let a = ar.atom(Atom::Param(0));
        let s = ar.atom(Atom::Sin(0));
        let e = ar.add(a, s);
        let ne = ar.neg(e);
        let v1 = ar.subst(e, VarKind::K, "x");
        let v2 = ar.subst(ne, VarKind::K, "y");
        assert_eq!(ar.vars().len(), 1);
        assert_eq!(ar.neg(v1), v2);
        assert_eq!(ar.vars()[0].kind, VarKind::D, "mentions a parameter");
    }

    #[test]
    fn hoisting_moves_parameter_products_out() {
        let mut ar = arena();
        ar.hoist_params = true;
        let a = ar.atom(Atom::Param(0));
        let b = ar.atom(Atom::Param(1));
        let c = ar.atom(Atom::Cos(0));
        let abc = ar.product([a, b, c]);
        let e = ar.add(abc, a);
        let e = ar.add(e, b);
        let v = ar.subst(e, VarKind::K, "x");
        // a*b and a + b become parameter-only variables.
        let params_only = ar
            .vars()
            .iter()
            .filter(|i| ar.is_param_only(i.node))
            .count();
        assert_eq!(params_only, 2, "{}", ar.listing(&[v]));
    }
}
