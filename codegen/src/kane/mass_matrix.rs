//! The mass matrix M(q): one column per joint, formed inside the composite pass.

use kanegen_model::{Joint, JointKind};

use super::composite::Composite;
use super::ctx::Ctx;
use crate::expr::{ExprId, VarKind};

impl Ctx<'_> {
    /// Column `l`'s entries of M (the joint of link `l`, `joint`, against itself and its
    /// ancestors): the inertia force and moment of the subtree of `l` for a unit acceleration of
    /// its joint at rest, carried up to the root.
    pub(super) fn mass_matrix_column(
        &mut self,
        l: usize,
        joint: &Joint,
        c: &Composite,
        entries: &mut Vec<(usize, usize, ExprId)>,
    ) {
        let put = |entries: &mut Vec<(usize, usize, ExprId)>, a: usize, b: usize, e: ExprId| {
            entries.push((a.min(b), a.max(b), e));
        };
        let model = self.model;
        let wheeled = model.wheeled_base();
        let Some(col) = joint.speed() else { return };
        let e = self.axis(l);
        let jc = c.inertia.expect("inertia computed");
        let name = self.link_name(l).to_owned();
        // Inertia force and moment about O_l for a unit acceleration of this joint.
        let (mut f, mut n) = match joint.kind {
            JointKind::Prismatic { .. } => {
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
            JointKind::Prismatic { .. } => self.dot(&e, &f),
            _ => self.dot(&e, &n),
        };
        put(entries, col, col, diag);
        for (k, mount) in model.path_to_base(l) {
            let parent = mount.parent;
            let r = self.rotation(k, &mount.joint);
            let p = self.position(k, &mount.joint);
            let fu = self.rot_up(&r, &f);
            let pname = self.link_name(parent).to_owned();
            f = self.subst3(fu, VarKind::D, &format!("F(M col {name}) at {pname}"));
            let nu = self.rot_up(&r, &n);
            let pxf = self.cross(&p, &f);
            let nn = self.add3(&nu, &pxf);
            n = self.subst3(nn, VarKind::D, &format!("N(M col {name}) at {pname}"));
            match model.links[parent].joint() {
                Some(pj) => {
                    if let Some(row) = pj.speed() {
                        let ek = self.axis(parent);
                        let v = match pj.kind {
                            JointKind::Prismatic { .. } => self.dot(&ek, &f),
                            _ => self.dot(&ek, &n),
                        };
                        put(entries, row, col, v);
                    }
                }
                None => {
                    if let Some(w) = wheeled {
                        put(entries, w.x_speed, col, f[0]);
                        put(entries, w.psi_speed, col, n[2]);
                    }
                    if model.is_floating() {
                        for i in 0..3 {
                            put(entries, i, col, f[i]);
                            put(entries, 3 + i, col, n[i]);
                        }
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
        // The base quasi-velocities.
        if let Some((xs, kx, ps, kp)) = self.wheel_terms() {
            let c = &comp[0];
            let jc = c.inertia.expect("inertia computed");
            let mxx = self.ar.add(c.mass, kx);
            // x̂ · (ẑ × MS) = −MS_y
            let mxp = self.ar.neg(c.first_moment[1]);
            let mpp = self.ar.add(jc[5], kp);
            put(&mut entries, xs, xs, mxx);
            put(&mut entries, xs, ps, mxp);
            put(&mut entries, ps, ps, mpp);
        }
        if self.model.is_floating() {
            // The base block: `[[m 1, −[MS]×], [[MS]×, J]]` of the whole robot's composite.
            let c = &comp[0];
            let jc = c.inertia.expect("inertia computed");
            let ms = c.first_moment;
            for i in 0..3 {
                put(&mut entries, i, i, c.mass);
            }
            let neg = |s: &mut Self, e: ExprId| s.ar.neg(e);
            let v_w = [
                (0, 4, ms[2]),
                (0, 5, neg(self, ms[1])),
                (1, 3, neg(self, ms[2])),
                (1, 5, ms[0]),
                (2, 3, ms[1]),
                (2, 4, neg(self, ms[0])),
            ];
            for (a, b, e) in v_w {
                put(&mut entries, a, b, e);
            }
            let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
            for (k, (a, b)) in idx.into_iter().enumerate() {
                put(&mut entries, 3 + a, 3 + b, jc[k]);
            }
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
