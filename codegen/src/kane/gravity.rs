//! The gravity vector g(q): composite first moments against each frame's gravity acceleration.

use kanegen_model::JointKind;

use super::algebra::V3;
use super::composite::Composite;
use super::ctx::Ctx;
use crate::expr::{ExprId, VarKind};

impl Ctx<'_> {
    pub(super) fn gravity(&mut self, comp: &[Composite]) -> Vec<ExprId> {
        let n = self.model.dof();
        let zero = self.ar.zero();
        let mut out = vec![zero; n];
        let g0 = self.gravity_vector();
        let mut acc: Vec<V3> = vec![[zero; 3]; self.model.links.len()];
        acc[0] = [0, 1, 2].map(|i| self.ar.neg(g0[i]));
        let model = self.model;
        for (l, _, mount) in model.mounted_links() {
            let r = self.rotation(l, &mount.joint);
            let a = self.rot_down(&r, &acc[mount.parent]);
            let name = self.link_name(l).to_owned();
            acc[l] = self.subst3(a, VarKind::D, &format!("gravity acceleration in {name}"));
        }
        for (l, _, mount) in model.mounted_links() {
            let Some(row) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(l);
            let c = &comp[l];
            out[row] = match mount.joint.kind {
                JointKind::Prismatic { .. } => {
                    let d = self.dot(&e, &acc[l]);
                    self.ar.mul(c.mass, d)
                }
                _ => {
                    let x = self.cross(&c.first_moment, &acc[l]);
                    self.dot(&e, &x)
                }
            };
        }
        if self.model.is_floating() {
            let c = &comp[0];
            let x = self.cross(&c.first_moment, &acc[0]);
            for i in 0..3 {
                out[i] = self.ar.mul(c.mass, acc[0][i]);
                out[3 + i] = x[i];
            }
        }
        if let Some(w) = self.model.wheeled_base().cloned() {
            let c = &comp[0];
            out[w.x_speed] = self.ar.mul(c.mass, acc[0][0]);
            let x = self.cross(&c.first_moment, &acc[0]);
            out[w.psi_speed] = x[2];
        }
        self.finish(out, "g")
    }

    pub(super) fn finish(&mut self, v: Vec<ExprId>, label: &str) -> Vec<ExprId> {
        v.into_iter()
            .enumerate()
            .map(|(i, e)| {
                if self.ar.hoist_params {
                    self.ar.hoist(e, &format!("{label}[{i}]"))
                } else {
                    e
                }
            })
            .collect()
    }
}
