//! Mimic joints as exact constraints: the derivation runs on the whole tree (one coordinate per
//! moving joint, the dependent ones' leaves being expressions of their masters', see
//! [`Arena::set_mimic`](crate::expr::Arena::set_mimic)), and each result is projected onto the
//! independent speeds with the constant map `T` (`u_all = T u`): generalized forces by `Tᵀ`,
//! speed columns by `T`, so `M = Tᵀ M_all T`, `c = Tᵀ c_all`, `g = Tᵀ g_all`, `τ = Tᵀ τ_all`,
//! `C = Tᵀ C_all T` and Jacobians `J_all T` (exact, since `Ṫ = 0`; Kane's partial velocities of
//! the reduced speeds are these sums).

use std::collections::BTreeMap;

use kanegen_model::Model;

use crate::expr::{Arena, ExprId, MimicLeaf};
use crate::registry::{Dim, Shape};

/// Declares the model's dependent speeds to the arena.
pub(super) fn declare(ar: &mut Arena, model: &Model) {
    for m in &model.mimics {
        ar.set_mimic(
            m.speed as u32,
            MimicLeaf {
                master: m.master as u32,
                multiplier: m.multiplier,
                offset: m.offset,
            },
        );
    }
}

/// The entries of a result of `shape` over all speeds of the tree projected onto the
/// independent ones: every index that counts speeds (`Dim::N`) maps speed `s` to its independent
/// speed with its factor; entries that land on the same place are summed. A symmetric matrix
/// keeps its upper triangle (an off-diagonal entry of the tree whose two speeds land on one
/// diagonal place counts twice: it stands for both triangles).
pub(super) fn project(
    ar: &mut Arena,
    model: &Model,
    shape: Shape,
    entries: Vec<(usize, usize, ExprId)>,
) -> Vec<(usize, usize, ExprId)> {
    if model.mimics.is_empty() {
        return entries;
    }
    let map = model.constraint_map();
    let (rows_n, cols_n) = match shape {
        Shape::SymmetricMatrix | Shape::Matrix => (true, true),
        Shape::Vector => (true, false),
        Shape::Dense { rows, cols } => (rows == Dim::N, cols == Dim::N),
        Shape::Scalar | Shape::Isometry => (false, false),
    };
    if !rows_n && !cols_n {
        return entries;
    }
    let mut acc: BTreeMap<(usize, usize), Vec<ExprId>> = BTreeMap::new();
    for (r, c, e) in entries {
        let (mut r2, mut c2, mut k) = (r, c, 1.0);
        if rows_n {
            r2 = map[r].0;
            k *= map[r].1;
        }
        if cols_n {
            c2 = map[c].0;
            k *= map[c].1;
        }
        if shape == Shape::SymmetricMatrix {
            if r != c && r2 == c2 {
                k *= 2.0;
            }
            (r2, c2) = (r2.min(c2), r2.max(c2));
        }
        let t = ar.scale(e, k);
        acc.entry((r2, c2)).or_default().push(t);
    }
    acc.into_iter()
        .map(|((r, c), terms)| (r, c, ar.sum(terms)))
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::expr::{Arena, Atom, MimicLeaf, Names, Values, VarKind, Wrt};

    /// Speed 1 follows speed 0: `q1 = 0.5 q0 + 0.1` (a leaf of its own), speed 2 with
    /// `q2 = −q0` (identities).
    fn arena() -> Arena {
        let mut ar = Arena::new(Names {
            params: vec!["m".into()],
            speeds: vec!["qd0".into(), "qd1".into(), "qd2".into()],
            coords: vec!["q0".into(), "q1".into(), "q2".into()],
            lengths: vec![false],
        });
        let leaf = |multiplier, offset| MimicLeaf {
            master: 0,
            multiplier,
            offset,
        };
        ar.set_mimic(1, leaf(0.5, 0.1));
        ar.set_mimic(2, leaf(-1.0, 0.0));
        ar
    }

    #[test]
    fn dependent_leaves_evaluate_at_the_constrained_angle_and_differentiate_by_the_chain_rule() {
        let mut ar = arena();
        let m = ar.atom(Atom::Param(0));
        let (s1, c1, s2, c2) = (
            ar.atom(Atom::Sin(1)),
            ar.atom(Atom::Cos(1)),
            ar.atom(Atom::Sin(2)),
            ar.atom(Atom::Cos(2)),
        );
        let (q1, u1, u2) = (
            ar.atom(Atom::Coord(1)),
            ar.atom(Atom::Speed(1)),
            ar.atom(Atom::Speed(2)),
        );
        // e = m (s1 c2 + c1 s2 q1) u1 u2, through a variable.
        let a = ar.mul(s1, c2);
        let b = ar.product([c1, s2, q1]);
        let k = ar.add(a, b);
        let k = ar.subst(k, VarKind::K, "k");
        let e = ar.product([m, k, u1, u2]);
        let (dq, du) = (ar.diff(e, Wrt::Coord(0)), ar.diff(e, Wrt::Speed(0)));
        let value = |q0: f64, u0: f64, ar: &Arena| {
            ar.eval(&Values {
                params: &[1.7],
                q: &[q0],
                u: &[u0],
                ud: &[0.0],
            })
        };
        let (q0, u0) = (0.7, -1.3);
        // By hand: θ1 = 0.5 q0 + 0.1, θ2 = −q0, u1 = 0.5 u0, u2 = −u0.
        let f = |q0: f64, u0: f64| {
            let (t1, t2) = (0.5 * q0 + 0.1, -q0);
            1.7 * (t1.sin() * t2.cos() + t1.cos() * t2.sin() * t1) * (0.5 * u0) * (-u0)
        };
        let v = value(q0, u0, &ar);
        assert!((v[e.index()] - f(q0, u0)).abs() < 1e-14);
        let h = 1e-6;
        let central_q = (f(q0 + h, u0) - f(q0 - h, u0)) / (2.0 * h);
        let central_u = (f(q0, u0 + h) - f(q0, u0 - h)) / (2.0 * h);
        assert!((v[dq.index()] - central_q).abs() < 1e-8, "∂/∂q0");
        assert!((v[du.index()] - central_u).abs() < 1e-8, "∂/∂u0");
        // No speed, acceleration or coordinate leaf of a dependent speed exists.
        assert!(matches!(ar.node(u2), crate::expr::Node::Sum { .. }));
    }
}
