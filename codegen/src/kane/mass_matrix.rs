//! The mass matrix M(q): one column per joint, formed inside the composite pass.

use kanegen_model::JointKind;

use super::Ctx;
use super::composite::Composite;
use crate::expr::{ExprId, VarKind};

impl Ctx<'_> {
    /// Column `l`'s entries of M (the joint of link `l` against itself and its ancestors): the
    /// inertia force and moment of the subtree of `l` for a unit acceleration of its joint at
    /// rest, carried up to the root.
    pub(super) fn mass_matrix_column(
        &mut self,
        l: usize,
        c: &Composite,
        entries: &mut Vec<(usize, usize, ExprId)>,
    ) {
        let put = |entries: &mut Vec<(usize, usize, ExprId)>, a: usize, b: usize, e: ExprId| {
            entries.push((a.min(b), a.max(b), e));
        };
        let wheeled = self.model.wheeled_base().cloned();
        let joint = self.model.links[l].joint.clone().expect("non-root");
        let Some(col) = joint.speed else { return };
        let e = self.axis(l);
        let jc = c.inertia.expect("inertia computed");
        let name = self.link_name(l).to_owned();
        // Inertia force and moment about O_l for a unit acceleration of this joint.
        let (mut f, mut n) = match joint.kind {
            JointKind::Prismatic => {
                let f = self.scale3(c.mass, &e);
                let n = self.cross(&c.first_moment, &e);
                (f, n)
            }
            _ => {
                let f = self.cross(&e, &c.first_moment);
                let n = self.sym_mul(&jc, &e);
                (f, n)
            }
        };
        f = self.subst3(f, VarKind::D, &format!("F(M col {name}) at {name}"));
        n = self.subst3(n, VarKind::D, &format!("N(M col {name}) at {name}"));
        let diag = match joint.kind {
            JointKind::Prismatic => self.dot(&e, &f),
            _ => self.dot(&e, &n),
        };
        put(entries, col, col, diag);
        let mut k = l;
        while let Some(parent) = self.model.links[k].parent {
            let r = self.rotation(k);
            let p = self.position(k);
            let fu = self.rot_up(&r, &f);
            let pname = self.link_name(parent).to_owned();
            f = self.subst3(fu, VarKind::D, &format!("F(M col {name}) at {pname}"));
            let nu = self.rot_up(&r, &n);
            let pxf = self.cross(&p, &f);
            let nn = self.add3(&nu, &pxf);
            n = self.subst3(nn, VarKind::D, &format!("N(M col {name}) at {pname}"));
            k = parent;
            match self.model.links[k].joint.as_ref() {
                Some(pj) if pj.speed.is_some() => {
                    let row = pj.speed.expect("checked");
                    let ek = self.axis(k);
                    let v = match pj.kind {
                        JointKind::Prismatic => self.dot(&ek, &f),
                        _ => self.dot(&ek, &n),
                    };
                    put(entries, row, col, v);
                }
                Some(_) => {}
                None => {
                    if let Some(w) = &wheeled {
                        put(entries, w.x_speed, col, f[0]);
                        put(entries, w.psi_speed, col, n[2]);
                    }
                }
            }
        }
    }

    pub(super) fn mass_matrix(
        &mut self,
        comp: &[Composite],
        mut entries: Vec<(usize, usize, ExprId)>,
    ) -> Vec<(usize, usize, ExprId)> {
        let put = |entries: &mut Vec<(usize, usize, ExprId)>, a: usize, b: usize, e: ExprId| {
            entries.push((a.min(b), a.max(b), e));
        };
        let wheeled = self.model.wheeled_base().cloned();
        // The base quasi-velocities.
        if let Some(w) = &wheeled {
            let c = &comp[0];
            let jc = c.inertia.expect("inertia computed");
            let (_, kx, _, kp) = self.wheel_terms().expect("wheeled");
            let mxx = self.ar.add(c.mass, kx);
            // x̂ · (ẑ × MS) = −MS_y
            let mxp = self.ar.neg(c.first_moment[1]);
            let mpp = self.ar.add(jc[5], kp);
            put(&mut entries, w.x_speed, w.x_speed, mxx);
            put(&mut entries, w.x_speed, w.psi_speed, mxp);
            put(&mut entries, w.psi_speed, w.psi_speed, mpp);
        }
        let mut entries: Vec<(usize, usize, ExprId)> = entries
            .into_iter()
            .map(|(a, b, e)| {
                let e = if self.ar.hoist_params {
                    self.ar.hoist(e, &format!("M[{a},{b}]"))
                } else {
                    e
                };
                (a, b, e)
            })
            .collect();
        entries.sort_by_key(|&(a, b, _)| (a, b));
        entries
    }
}
