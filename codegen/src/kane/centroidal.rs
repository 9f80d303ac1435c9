//! Centroidal dynamics: the centroidal momentum matrix `A_G` (Pinocchio's `ccrba` `Ag`), its
//! bias `Ȧ_G u` and the centroidal composite inertia `I_G`.
//!
//! The momentum of the whole robot per unit speed is what M's columns carry to the root: for
//! the speed of a joint on link l, the subtree of l moving at unit speed has linear momentum
//! `e × MSC_l` (revolute; `mC_l e` prismatic) and angular momentum about `O_l` `JC_l e`
//! (`MSC_l × e`), carried to frame 0 like a force (the very variables of M's columns). A
//! floating base's `v` and `ω` move the whole robot: `(m eᵢ, MSC0 × eᵢ)` and
//! `(eᵢ × MSC0, JC0 eᵢ)`; a wheeled base's `ẋ` and `ψ̇` add the wheels (point masses `mw` at
//! `(0, ±L/2, 0)` spinning at `ẋ/R` about the axle: `2 mw x̂` and `2 YYw/R ŷ` per `ẋ`,
//! `(mw L²/2 + 2 ZZw) ẑ` per `ψ̇`). With the centre of mass `r_G = MSC0 / m`, the angular
//! momentum about it is `L_G = L_O − r_G × P`.
//!
//! `Ȧ_G u` is the momentum's rate at `u̇ = 0` without gravity: the inertia wrench of the
//! bodies (the motion pass of `c`) plus the wheels', its moment taken about the centre of mass
//! (`n_G = n_O − r_G × f`: the rate of the angular momentum about the moving centre of mass is
//! the moment of the inertia forces about it).
//!
//! Rows: linear momentum, then angular momentum about the centre of mass, in world axes (frame
//! 0's for a fixed or wheeled base; rotated by the floating base's `R0`).

use super::algebra::{M3, V3};
use super::composite::Composite;
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};
use kanegen_model::JointKind;

impl Ctx<'_> {
    /// Per speed, the momentum `(P, L_O)` of the whole robot at unit speed, in frame 0's axes
    /// (`L_O` about frame 0's origin).
    fn column_momenta(&mut self, comp: &[Composite]) -> Vec<(usize, V3, V3)> {
        let model = self.model;
        let mut out = Vec::new();
        for (l, _, mount) in model.mounted_links() {
            let Some(col) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(l);
            let c = &comp[l];
            let jc = c.inertia.expect("inertia computed");
            let name = self.link_name(l).to_owned();
            let (f, n) = match mount.joint.kind {
                JointKind::Prismatic { .. } => {
                    (self.scale3(c.mass, &e), self.cross(&c.first_moment, &e))
                }
                _ => (self.cross(&e, &c.first_moment), self.sym_mul(&jc, &e)),
            };
            let mut f = self.subst3(f, VarKind::D, &format!("F(M col {name}) at {name}"));
            let mut n = self.subst3(n, VarKind::D, &format!("N(M col {name}) at {name}"));
            for (k, mount) in model.path_to_base(l) {
                let r = self.rotation(k, &mount.joint);
                let p = self.position(k, &mount.joint);
                let pname = self.link_name(mount.parent).to_owned();
                let fu = self.rot_up(&r, &f);
                f = self.subst3(fu, VarKind::D, &format!("F(M col {name}) at {pname}"));
                let nu = self.rot_up(&r, &n);
                let pxf = self.cross(&p, &f);
                let nn = self.add3(&nu, &pxf);
                n = self.subst3(nn, VarKind::D, &format!("N(M col {name}) at {pname}"));
            }
            out.push((col, f, n));
        }
        let c0 = &comp[0];
        let j0 = c0.inertia.expect("inertia computed");
        let (zero, one) = (self.ar.zero(), self.ar.one());
        let units = [[one, zero, zero], [zero, one, zero], [zero, zero, one]];
        if model.is_floating() {
            for (i, e) in units.iter().enumerate() {
                let p = self.scale3(c0.mass, e);
                let l = self.cross(&c0.first_moment, e);
                out.push((i, p, l));
            }
            for (i, e) in units.iter().enumerate() {
                let p = self.cross(e, &c0.first_moment);
                let l = self.sym_mul(&j0, e);
                out.push((3 + i, p, l));
            }
        }
        if let Some(w) = model.wheeled_base().cloned() {
            let mw2 = self.wheel_mass().expect("wheeled");
            let (r, yy) = (self.param(w.radius), self.param(w.wheel_axle_inertia));
            let m = self.ar.add(c0.mass, mw2);
            let p = [m, zero, zero];
            let l = self.cross(&c0.first_moment, &units[0]);
            let rinv = self.ar.powi(r, -1);
            let yy2 = self.ar.scale(yy, 2.0);
            let spin = self.ar.mul(yy2, rinv);
            let l = [l[0], self.ar.add(l[1], spin), l[2]];
            out.push((w.x_speed, p, l));
            let p = self.cross(&units[2], &c0.first_moment);
            let l = self.sym_mul(&j0, &units[2]);
            let yaw = self.wheel_yaw_inertia(&w);
            let l = [l[0], l[1], self.ar.add(l[2], yaw)];
            out.push((w.psi_speed, p, l));
        }
        out
    }

    /// `mw L²/2 + 2 ZZw`: the wheels' moment of inertia about frame 0's z axis.
    fn wheel_yaw_inertia(&mut self, w: &kanegen_model::WheeledBase) -> ExprId {
        let (l, mw, zz) = (
            self.param(w.track),
            self.param(w.wheel_mass),
            self.param(w.wheel_diametral_inertia),
        );
        let l2 = self.ar.powi(l, 2);
        let half = self.ar.constant(0.5);
        let a = self.ar.product([half, mw, l2]);
        let b = self.ar.scale(zz, 2.0);
        self.ar.add(a, b)
    }

    /// The centre of mass relative to frame 0's origin, in frame 0's axes (`MSC0 / m`).
    fn centroid_in_base(&mut self, comp: &[Composite]) -> V3 {
        let inv = self.inverse_total_mass(comp);
        let rg = self.scale3(inv, &comp[0].first_moment);
        self.subst3(rg, VarKind::D, "rG in 0")
    }

    /// A vector in frame 0's axes in world axes (rotated by a floating base's `R0`).
    fn world_axes(&mut self, x: &V3) -> V3 {
        if !self.model.is_floating() {
            return *x;
        }
        let r0 = self.base_rotation();
        self.rot_up(&r0, x)
    }

    /// `A_G`: column j the centroidal momentum `(P; L_G)` per unit speed j, world axes.
    pub(super) fn centroidal_momentum_matrix(
        &mut self,
        comp: &[Composite],
    ) -> Vec<(usize, usize, ExprId)> {
        let rg = self.centroid_in_base(comp);
        let mut entries = Vec::new();
        for (col, p, lo) in self.column_momenta(comp) {
            let rxp = self.cross(&rg, &p);
            let lg = self.sub3(&lo, &rxp);
            let p = self.world_axes(&p);
            let lg = self.world_axes(&lg);
            let v = self.finish(p.into_iter().chain(lg).collect(), &format!("AG[:,{col}]"));
            entries.extend(v.into_iter().enumerate().map(|(r, x)| (r, col, x)));
        }
        entries
    }

    /// `Ȧ_G u`: the centroidal momentum's rate at `u̇ = 0` without gravity, world axes.
    pub(super) fn centroidal_momentum_bias(&mut self, comp: &[Composite]) -> V3x2 {
        let rg = self.centroid_in_base(comp);
        let (mut f, mut n) = self.bias_inertia_wrench();
        if let Some(w) = self.model.wheeled_base().cloned() {
            // The wheels at u̇ = 0: 2 mw ẋψ̇ along y0, and their spin turning with the yaw,
            // −2 YYw ẋψ̇ / R along x0.
            let mw2 = self.wheel_mass().expect("wheeled");
            let xd = self.ar.atom(Atom::Speed(w.x_speed as u32));
            let psid = self.ar.atom(Atom::Speed(w.psi_speed as u32));
            let (r, yy) = (self.param(w.radius), self.param(w.wheel_axle_inertia));
            let fy = self.ar.product([mw2, xd, psid]);
            f[1] = self.ar.add(f[1], fy);
            let rinv = self.ar.powi(r, -1);
            let nx = self.ar.product([yy, xd, psid, rinv]);
            let nx = self.ar.scale(nx, -2.0);
            n[0] = self.ar.add(n[0], nx);
        }
        let rxf = self.cross(&rg, &f);
        let ng = self.sub3(&n, &rxf);
        let f = self.world_axes(&f);
        let ng = self.world_axes(&ng);
        let v = self.finish(f.into_iter().chain(ng).collect(), "dAGu");
        [[v[0], v[1], v[2]], [v[3], v[4], v[5]]]
    }

    /// `I_G = [[m 1, 0], [0, J_G]]`: the centroidal composite inertia, `J_G` the whole robot's
    /// inertia about its centre of mass in world axes, as `(row, col, expr)` of the 6×6 matrix.
    pub(super) fn centroidal_inertia(&mut self, comp: &[Composite]) -> Vec<(usize, usize, ExprId)> {
        let rg = self.centroid_in_base(comp);
        let c0 = &comp[0];
        let j0 = c0.inertia.expect("inertia computed");
        let mut m = c0.mass;
        let mut j: M3 = [
            [j0[0], j0[1], j0[2]],
            [j0[1], j0[3], j0[4]],
            [j0[2], j0[4], j0[5]],
        ];
        if let Some(w) = self.model.wheeled_base().cloned() {
            // Point masses mw at (0, ±L/2, 0), axle moments YYw, diametral moments ZZw.
            let mw2 = self.wheel_mass().expect("wheeled");
            m = self.ar.add(m, mw2);
            let (l, mw) = (self.param(w.track), self.param(w.wheel_mass));
            let (yy, zz) = (
                self.param(w.wheel_axle_inertia),
                self.param(w.wheel_diametral_inertia),
            );
            let yaw = self.wheel_yaw_inertia(&w);
            let l2 = self.ar.powi(l, 2);
            let roll = self.ar.product([mw, l2]);
            let roll = self.ar.scale(roll, 0.5);
            let zz2 = self.ar.scale(zz, 2.0);
            let roll = self.ar.add(roll, zz2);
            let yy2 = self.ar.scale(yy, 2.0);
            j[0][0] = self.ar.add(j[0][0], roll);
            j[1][1] = self.ar.add(j[1][1], yy2);
            j[2][2] = self.ar.add(j[2][2], yaw);
        }
        // J_G = J_O − m (|r|² 1 − r rᵀ).
        for a in 0..3 {
            for b in 0..3 {
                let rr = self.ar.mul(rg[a], rg[b]);
                let mut t = self.ar.neg(rr);
                if a == b {
                    let r2 = self.dot(&rg, &rg);
                    t = self.ar.add(t, r2);
                }
                let mt = self.ar.mul(m, t);
                j[a][b] = self.ar.sub(j[a][b], mt);
            }
        }
        if self.model.is_floating() {
            // R0 J_G R0ᵀ.
            let r0 = self.base_rotation();
            let rj = self.matmul(&r0, &j);
            let r0t = [0, 1, 2].map(|a| [0, 1, 2].map(|b| r0[b][a]));
            j = self.matmul(&rj, &r0t);
        }
        let mut entries: Vec<(usize, usize, ExprId)> = (0..3).map(|i| (i, i, m)).collect();
        for a in 0..3 {
            for b in 0..3 {
                entries.push((3 + a, 3 + b, j[a][b]));
            }
        }
        let flat: Vec<ExprId> = entries.iter().map(|e| e.2).collect();
        let flat = self.finish(flat, "IG");
        entries
            .into_iter()
            .zip(flat)
            .map(|((r, c, _), e)| (r, c, e))
            .collect()
    }
}

/// Two 3-vectors: linear and angular.
pub(super) type V3x2 = [V3; 2];
