//! Kinematics from the same derivation: every frame's rotation and origin in frame 0, the
//! whole robot's centre of mass, its Jacobian and bias acceleration, and the energies.
//!
//! Conventions (the same for every function): positions are relative to frame 0 (for a wheeled
//! base the heading frame at the axle midpoint, so `x` and `ψ` do not enter), velocities and
//! accelerations are relative to the ground (inertial) and expressed in frame 0's axes, and
//! accelerations are classical (`d²p/dt²`, not spatial). The columns of a Jacobian are the
//! partial velocities (Kane's), so acceleration = `J u̇ + bias` with the bias the acceleration at
//! `u̇ = 0`; the wheeled base's `ẋ` and `ψ̇` columns carry the base's motion.
//!
//! The wheels of a wheeled base are point masses `mw` at `(0, ±L/2, 0)` of frame 0 (their
//! centres on the axle): they add `2 mw` to the total mass, nothing to the first moment about
//! frame 0's origin (so nothing to the potential energy, which is zero at that origin's
//! height), `2 mw · [1, 0, 0]` to the momentum per `ẋ` and `2 mw · [0, ẋψ̇, 0]` to the bias.
//! Their rotational inertia enters only the kinetic energy (through `M`).
//!
//! A floating base: frame poses, the centre of mass and the potential energy are in the world
//! frame (the base pose `p0`, `R0` of the coordinates composed in); Jacobians and bias
//! accelerations keep the convention above (velocities and classical accelerations relative to
//! the world, in frame 0's axes), the base's `v` columns being the unit vectors `(eᵢ; 0)` and its
//! `ω` columns `(eᵢ × ⁰p; eᵢ)`.

use super::algebra::{M3, V3};
use super::composite::Composite;
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};
use kanegen_model::JointKind;

impl Ctx<'_> {
    /// `⁰A_l(q)`: the rotation of frame `l` relative to frame 0 (rows in frame 0), cached as
    /// K variables `0A{l}(r,c)`.
    pub(super) fn root_rotation(&mut self, l: usize) -> M3 {
        if let Some(r) = self.root_rot[l] {
            return r;
        }
        let model = self.model;
        let out = match &model.links[l].mount {
            None => {
                let (zero, one) = (self.ar.zero(), self.ar.one());
                [[one, zero, zero], [zero, one, zero], [zero, zero, one]]
            }
            Some(mount) => {
                let parent = self.root_rotation(mount.parent);
                let r = self.rotation(l, &mount.joint);
                let a = self.matmul(&parent, &r);
                let name = self.link_name(l).to_owned();
                let mut out = a;
                for (ri, row) in out.iter_mut().enumerate() {
                    for (ci, x) in row.iter_mut().enumerate() {
                        let label = format!("0A{name}({},{})", ri + 1, ci + 1);
                        *x = self.ar.subst(*x, VarKind::K, &label);
                    }
                }
                out
            }
        };
        self.root_rot[l] = Some(out);
        out
    }

    /// `⁰p_l(q)`: the origin of frame `l` in frame 0, cached as K variables `0P{l}`.
    pub(super) fn root_position(&mut self, l: usize) -> V3 {
        if let Some(p) = self.root_pos[l] {
            return p;
        }
        let model = self.model;
        let out = match &model.links[l].mount {
            None => [self.ar.zero(); 3],
            Some(mount) => {
                let parent = self.root_position(mount.parent);
                let a = self.root_rotation(mount.parent);
                let p = self.position(l, &mount.joint);
                let ap = self.rot_up(&a, &p);
                let sum = self.add3(&parent, &ap);
                let name = self.link_name(l).to_owned();
                self.subst3(sum, VarKind::K, &format!("0P{name}"))
            }
        };
        self.root_pos[l] = Some(out);
        out
    }

    /// The wheels' total mass `2 mw` (none without a wheeled base).
    pub(super) fn wheel_mass(&mut self) -> Option<ExprId> {
        let mw = self.model.wheeled_base()?.wheel_mass;
        let mw = self.param(mw);
        Some(self.ar.scale(mw, 2.0))
    }

    /// `1 / m` for the total mass `m` (wheels included), a D variable (parameter-only: computed
    /// once per parameter set with runtime parameters).
    pub(super) fn inverse_total_mass(&mut self, comp: &[Composite]) -> ExprId {
        let mut m = comp[0].mass;
        if let Some(mw) = self.wheel_mass() {
            m = self.ar.add(m, mw);
        }
        let m = self.ar.subst(m, VarKind::D, "total mass");
        let inv = self.ar.powi(m, -1);
        self.ar.subst(inv, VarKind::D, "1 / total mass")
    }

    /// The centre of mass in frame 0: `MSC0 / m` (composite first moment about frame 0's origin
    /// over the total mass).
    pub(super) fn center_of_mass(&mut self, comp: &[Composite]) -> V3 {
        let inv = self.inverse_total_mass(comp);
        let mut c = self.scale3(inv, &comp[0].first_moment);
        if self.model.is_floating() {
            c = self.in_world(&c);
        }
        self.finish(c.to_vec(), "rG")
            .try_into()
            .expect("three entries")
    }

    /// The Jacobian of the centre of mass, `(row, col, expr)`: column j is the partial velocity
    /// `Σ_k m_k (v_Gk)_j / m`. For a revolute joint that is `⁰A_j (e_j × MSC_j) / m` (the
    /// composite first moment of its subtree about its origin), for a prismatic one
    /// `⁰A_j (mC_j e_j) / m`; the wheeled base's `ẋ` column is `[1, 0, 0]` and its `ψ̇` column
    /// `ẑ × r_G`.
    pub(super) fn com_jacobian(&mut self, comp: &[Composite]) -> Vec<(usize, usize, ExprId)> {
        let inv = self.inverse_total_mass(comp);
        let mut entries = Vec::new();
        let model = self.model;
        for (l, _, mount) in model.mounted_links() {
            let Some(col) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(l);
            let c = &comp[l];
            let local = match mount.joint.kind {
                JointKind::Prismatic { .. } => self.scale3(c.mass, &e),
                _ => self.cross(&e, &c.first_moment),
            };
            let a = self.root_rotation(l);
            let v = self.rot_up(&a, &local);
            let v = self.scale3(inv, &v);
            let v = self.finish(v.to_vec(), &format!("JG[:,{col}]"));
            entries.extend(v.into_iter().enumerate().map(|(r, x)| (r, col, x)));
        }
        if let Some(w) = model.wheeled_base() {
            let (xs, ps) = (w.x_speed, w.psi_speed);
            let one = self.ar.one();
            entries.push((0, xs, one));
            let ms = comp[0].first_moment;
            let gx = self.ar.mul(inv, ms[0]);
            let gy = self.ar.mul(inv, ms[1]);
            let gy = self.ar.neg(gy);
            let v = self.finish(vec![gy, gx], &format!("JG[:,{ps}]"));
            entries.extend([(0, ps, v[0]), (1, ps, v[1])]);
        }
        if model.is_floating() {
            // v columns: the unit vectors; ω columns: eᵢ × r_G (r_G about the base origin).
            let one = self.ar.one();
            let rg = self.scale3(inv, &comp[0].first_moment);
            let rg = self.subst3(rg, VarKind::D, "rG in 0");
            for i in 0..3 {
                entries.push((i, i, one));
            }
            let nz = self.ar.neg(rg[2]);
            let ny = self.ar.neg(rg[1]);
            let nx = self.ar.neg(rg[0]);
            entries.extend([(1, 3, nz), (2, 3, rg[1]), (0, 4, rg[2]), (2, 4, nx)]);
            entries.extend([(0, 5, ny), (1, 5, rg[0])]);
        }
        entries
    }

    /// The acceleration of the centre of mass at `u̇ = 0`: `(Σ_k m_k a_Gk + 2 mw a_0) / m`,
    /// with the bodies' sum from the motion pass of `c` (their inertia forces at `u̇ = 0` without
    /// gravity, carried to frame 0) and the wheels' at frame 0's origin, `a_0 = [0, ẋψ̇, 0]`.
    pub(super) fn com_bias_acceleration(&mut self, comp: &[Composite]) -> V3 {
        let inv = self.inverse_total_mass(comp);
        let mut f = self.bias_inertia_force();
        if let (Some(w), Some(mw)) = (self.model.wheeled_base().cloned(), self.wheel_mass()) {
            let xd = self.ar.atom(Atom::Speed(w.x_speed as u32));
            let psid = self.ar.atom(Atom::Speed(w.psi_speed as u32));
            let a0y = self.ar.product([mw, xd, psid]);
            f[1] = self.ar.add(f[1], a0y);
        }
        let a = self.scale3(inv, &f);
        self.finish(a.to_vec(), "aG0")
            .try_into()
            .expect("three entries")
    }

    /// `T = ½ uᵀ M u`, from the upper triangle of M (the same expressions as `mass_matrix`,
    /// wheels included), as `Σ_a u_a (½ M_aa u_a + Σ_{b>a} M_ab u_b)`.
    pub(super) fn kinetic_energy(&mut self) -> ExprId {
        let mut columns = Vec::new();
        let comp = self.composites(true, Some(&mut columns));
        let m = self.mass_matrix(&comp, columns);
        let mut rows: Vec<Vec<ExprId>> = vec![Vec::new(); self.model.dof()];
        for (a, b, e) in m {
            let ub = self.ar.atom(Atom::Speed(b as u32));
            let t = self.ar.mul(e, ub);
            rows[a].push(if a == b { self.ar.scale(t, 0.5) } else { t });
        }
        let terms: Vec<ExprId> = rows
            .into_iter()
            .enumerate()
            .map(|(a, row)| {
                let ua = self.ar.atom(Atom::Speed(a as u32));
                let s = self.ar.sum(row);
                self.ar.mul(ua, s)
            })
            .collect();
        let t = self.ar.sum(terms);
        self.finish(vec![t], "T")[0]
    }

    /// `V = −g0 · MSC0`: minus the gravity vector (in frame 0) against the first moment of the
    /// whole robot about frame 0's origin (the wheels' is zero).
    pub(super) fn potential_energy(&mut self, comp: &[Composite]) -> ExprId {
        let g0 = self.gravity_vector();
        let mut v = self.dot(&g0, &comp[0].first_moment);
        if self.model.is_floating() {
            // The base origin's height: `m g · p0` (world frame) on top of `g_b · MSC0`.
            let g = self.param(self.model.gravity.symbol);
            let d = self.consts(self.model.gravity.direction);
            let p0 = self.base_position();
            let dp = self.dot(&d, &p0);
            let mgp = self.ar.product([comp[0].mass, g, dp]);
            v = self.ar.add(v, mgp);
        }
        let v = self.ar.neg(v);
        self.finish(vec![v], "V")[0]
    }

    /// The pose of frame `l` relative to frame 0 ([`Shape::Isometry`](crate::registry::Shape)
    /// entries): `(r, c)` of `⁰A_l` and `(r, 3)` of `⁰p_l`.
    pub(super) fn frame_pose(&mut self, l: usize) -> Vec<(usize, usize, ExprId)> {
        let mut a = self.root_rotation(l);
        let mut p = self.root_position(l);
        if self.model.is_floating() {
            // In the world: `R0 ⁰A_l`, `p0 + R0 ⁰p_l`.
            let r0 = self.base_rotation();
            a = self.matmul(&r0, &a);
            p = self.in_world(&p);
        }
        (0..3)
            .flat_map(|r| (0..3).map(move |c| (r, c, a[r][c])).chain([(r, 3, p[r])]))
            .collect()
    }

    /// The Jacobian of frame `l`, `(row, col, expr)`: rows 0–2 the partial velocities of its
    /// origin, rows 3–5 its partial angular velocities, in frame 0's axes. A revolute joint k on
    /// the path to the root gives `(⁰e_k × (⁰p_l − ⁰p_k); ⁰e_k)`, a prismatic one `(⁰e_k; 0)`
    /// with `⁰e_k = ⁰A_k e_k`; the wheeled base's `ẋ` column is `([1, 0, 0]; 0)` and its `ψ̇`
    /// column `(ẑ × ⁰p_l; ẑ)`.
    pub(super) fn frame_jacobian(&mut self, l: usize) -> Vec<(usize, usize, ExprId)> {
        let model = self.model;
        let p = self.root_position(l);
        let (zero, one) = (self.ar.zero(), self.ar.one());
        let mut entries = Vec::new();
        let mut column = |col: usize, lin: V3, ang: V3| {
            let rows = lin.into_iter().chain(ang).enumerate();
            entries.extend(rows.map(|(r, e)| (r, col, e)));
        };
        for (k, mount) in model.path_to_base(l) {
            let Some(col) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(k);
            let a = self.root_rotation(k);
            let e0 = self.rot_up(&a, &e);
            if let JointKind::Prismatic { .. } = mount.joint.kind {
                column(col, e0, [zero; 3]);
            } else {
                let pk = self.root_position(k);
                let d = self.sub3(&p, &pk);
                let d = self.subst3(
                    d,
                    VarKind::K,
                    &format!("0P{} − 0P{}", self.link_name(l), self.link_name(k)),
                );
                let lin = self.cross(&e0, &d);
                column(col, lin, e0);
            }
        }
        if let Some(w) = model.wheeled_base() {
            column(w.x_speed, [one, zero, zero], [zero; 3]);
            let py = self.ar.neg(p[1]);
            column(w.psi_speed, [py, p[0], zero], [zero, zero, one]);
        }
        if model.is_floating() {
            let (nx, ny, nz) = (self.ar.neg(p[0]), self.ar.neg(p[1]), self.ar.neg(p[2]));
            column(0, [one, zero, zero], [zero; 3]);
            column(1, [zero, one, zero], [zero; 3]);
            column(2, [zero, zero, one], [zero; 3]);
            column(3, [zero, nz, p[1]], [one, zero, zero]);
            column(4, [p[2], zero, nx], [zero, one, zero]);
            column(5, [ny, p[0], zero], [zero, zero, one]);
        }
        entries
    }

    /// The floating base's origin in the world, `q[0..3]`.
    pub(super) fn base_position(&mut self) -> V3 {
        [0u32, 1, 2].map(|k| self.ar.atom(Atom::Coord(k)))
    }

    /// A point given in frame 0 (`x`), in the world: `p0 + R0 x` (floating base).
    pub(super) fn in_world(&mut self, x: &V3) -> V3 {
        let r0 = self.base_rotation();
        let p0 = self.base_position();
        let rx = self.rot_up(&r0, x);
        self.add3(&p0, &rx)
    }

    /// The acceleration of frame `l` at `u̇ = 0` (the motion pass of `c`: classical origin
    /// acceleration and angular acceleration in frame `l`), rotated into frame 0's axes: rows
    /// 0–2 linear, 3–5 angular.
    pub(super) fn frame_bias_acceleration(&mut self, l: usize) -> Vec<(usize, usize, ExprId)> {
        let motion = self.bias_motion();
        let a = self.root_rotation(l);
        let lin = self.rot_up(&a, &motion.a[l]);
        let ang = self.rot_up(&a, &motion.wd[l]);
        lin.into_iter()
            .chain(ang)
            .enumerate()
            .map(|(r, e)| (r, 0, e))
            .collect()
    }
}
