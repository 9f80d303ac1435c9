//! Analytic derivatives of inverse dynamics, `∂τ/∂q` and `∂τ/∂u`, in the structure of
//! Carpentier & Mansard's RNEA derivatives (RSS 2018), derived here in body coordinates and
//! generated with K/D substitution variables.
//!
//! Spatial vectors in the frame of each link, as in `coriolis_matrix.rs`: motion `V = (ω; v)`
//! (v of the frame origin), force `F = (n; f)` (n about the origin), `S_j` the motion subspace
//! of speed j (constant in its frame), `V_λ(j)` and `A_λ(j)` the spatial velocity and
//! acceleration (gravity folded in) of the parent body of joint j, `F_j` the subtree force of
//! τ's recursion (`τ_j = S_j · F_j`), and over the subtree of j: composite inertia `I^c_j`,
//! momentum `h^c_j = Σ I_k V_k` and inertia rate `D^c_j = Σ (V_k×*) I_k − I_k (V_k×)`
//! (symmetric, the same quantities as the Coriolis matrix). Turning q_j turns the whole subtree
//! of j about S_j; what does not turn with it is the parent's motion, which enters the subtree as
//! `Ψ̇_j = V_λ(j) × S_j` (velocity) and `Ψ̈_j = A_λ(j) × S_j + V_λ(j) × Ψ̇_j` (acceleration), so a
//! body k below j has `∂V_k/∂q_j = S_j × V_k + Ψ̇_j`, `∂A_k/∂q_j = S_j × A_k + Ψ̈_j + Ψ̇_j × V_k`
//! and its force `∂f_k/∂q_j = S_j ×* f_k + I_k Ψ̈_j + D_k Ψ̇_j + Ψ̇_j ×* h_k`; in u_j,
//! `∂V_k/∂u_j = S_j`, `∂A_k/∂u_j = 2 Ψ̇_j + S_j × V_k` and `∂f_k/∂u_j = 2 I_k Ψ̇_j + D_k S_j +
//! S_j ×* h_k`. Summed over subtrees (the `S_j ×*` and `S_j ×` parts cancel in `S_i · F_i` for i
//! below j), for a speed i and a speed j on its path to the root (j above i or j = i):
//!
//! * row j, column i (`G_i`, `H_i` carried up from i as forces):
//!   `∂τ_j/∂q_i = S_j · G_i`, `G_i = S_i ×* F_i + I^c_i Ψ̈_i + D^c_i Ψ̇_i + Ψ̇_i ×* h^c_i`;
//!   `∂τ_j/∂u_i = S_j · H_i`, `H_i = 2 I^c_i Ψ̇_i + D^c_i S_i + S_i ×* h^c_i`;
//! * row i, column j above i (`Φ_i`, `Ξ_i` carried up from i):
//!   `∂τ_i/∂q_j = Φ_i · Ψ̈_j + Ξ_i · Ψ̇_j`, `∂τ_i/∂u_j = 2 Φ_i · Ψ̇_j + Ξ_i · S_j`, with
//!   `Φ_i = I^c_i S_i` (M's column force) and `Ξ_i = D^c_i S_i − S_i ×* h^c_i`.
//!
//! (So ∂τ/∂u is twice the Coriolis matrix of `coriolis_matrix.rs` on a tree: `H = 2h`,
//! `Ξ = 2 G1`.) The wheeled base's ẋ and ψ̇ are speeds of frame 0 whose `S` is constant in
//! frame 0 (quasi-velocities): nothing depends on x or ψ, and their u-columns take `V_0 × S`
//! where a joint has `2 Ψ̇` (`∂A_k/∂u = S × V_k + V_0 × S`: there is no parent motion, and the
//! bias `V_0 × V_0` of the base vanishes identically).
//! A floating base's six speeds `(v, ω)` are such quasi-velocities too (`S` the unit vectors of
//! frame 0, spatial acceleration `(ω̇; v̇)` of frame 0 with no velocity term). Its position does
//! not enter τ; its orientation enters only through gravity `g_b = Rᵀ g`, folded into frame 0's
//! acceleration, and `q ⊕ δ e_k` along `ω_k` turns `g_b` by `g_b × e_k`: a motion
//! `Ψ̈ = (0; e_k × g_b)` applied to the whole tree without turning any frame, so column `ω_k`
//! of ∂τ/∂q reads `Φ_i · Ψ̈` from every column's `Φ_i` at the root ([`Column::rotation`]).
//!
//! Four forces are carried per (speed, ancestor speed) pair, like the three of C, instead of
//! forward mode's derivative of the whole subtree's motion and forces per input.

use std::collections::BTreeMap;

use kanegen_model::{JointKind, Mount};

use super::algebra::{V3, V6, join3, split3};
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};

/// The quantities both forms of the derivatives start from ([`Ctx::derivative_setup`]).
pub(super) struct Setup {
    /// Per link, its speeds.
    pub(super) columns: Vec<Vec<Column>>,
    /// Composite inertias.
    pub(super) comp: Vec<super::composite::Composite>,
    /// Subtree momenta `h^c`.
    pub(super) hc: Vec<V6>,
    /// Subtree inertia rates `D^c`.
    pub(super) dc: Vec<super::coriolis_matrix::Rate>,
    /// τ's subtree forces.
    pub(super) f: Vec<V3>,
    /// τ's subtree moments.
    pub(super) n: Vec<V3>,
}

/// What the entries of the speed columns above a link read, per speed of a link, in its frame.
#[derive(Clone, Copy)]
pub(super) struct Column {
    /// The speed index (of the tree).
    pub(super) speed: usize,
    /// Its motion subspace `S`.
    pub(super) s: V6,
    /// `Ψ̇ = V_λ × S` (joints) or `V_0 × S` (the base's speeds).
    pub(super) psid: V6,
    /// `Ψ̈ = A_λ × S + V_λ × Ψ̇`; `None` for the base's speeds (no coordinate of theirs enters τ
    /// through the recursion).
    pub(super) psidd: Option<V6>,
    /// A floating base's rotation speed `ω_k`: `(0; e_k × g_b)`, the derivative of the base
    /// acceleration `a_0 − g_b` along the tangent rotation `q ⊕ δ e_k` (`∂g_b/∂δ = g_b × e_k`),
    /// whose column reads `∂τ_i/∂q_k = Φ_i · (0; e_k × g_b)` (`−M[i, v] · (g_b × e_k)`); `None`
    /// for every other speed.
    pub(super) rotation: Option<V6>,
}

/// The four forces of a column on its way up to the root.
#[derive(Clone, Copy)]
pub(super) struct Carried {
    /// `Φ = I^c S`.
    pub(super) phi: V6,
    /// `Ξ = D^c S − S ×* h^c`.
    pub(super) xi: V6,
    /// `H`: `S_j · H = ∂τ_j/∂u_i`.
    pub(super) h: V6,
    /// `G`: `S_j · G = ∂τ_j/∂q_i` (`None` for the base's speeds).
    pub(super) g: Option<V6>,
}

impl Ctx<'_> {
    /// `[∂τ/∂q | ∂τ/∂u]` as `(row, col, expr)` by the analytic recursion of this module: rows are
    /// the tree's speeds (projected afterwards like τ's), columns the `N` independent speeds (a
    /// mimic joint's column is added to its master's with the constraint's factor).
    pub(super) fn inverse_dynamics_derivatives_analytic(&mut self) -> Vec<(usize, usize, ExprId)> {
        let model = self.model;
        let links = model.links.len();
        let Setup {
            columns,
            comp,
            hc,
            dc,
            f,
            n,
        } = self.derivative_setup();
        // (column group, row, tree speed of the column, u-block?, entry) in derivation order.
        let mut raw: Vec<(usize, usize, usize, bool, ExprId)> = Vec::new();
        let mut group = 0;
        for l in 0..links {
            for k in 0..columns[l].len() {
                group += 1;
                let col = columns[l][k];
                let sname = self.model.speeds[col.speed].name.clone();
                let mut carried = self.derivative_forces(l, &col, &comp, &hc, &dc, &f, &n);
                // Rows of the same frame (and a floating base's rotation columns of the base's
                // rows).
                for a in &columns[l] {
                    if let Some(g) = carried.g {
                        let e = self.dot6(&a.s, &g);
                        raw.push((group, a.speed, col.speed, false, e));
                    }
                    let e = self.dot6(&a.s, &carried.h);
                    raw.push((group, a.speed, col.speed, true, e));
                    if let Some(r) = a.rotation {
                        let e = self.dot6(&carried.phi, &r);
                        raw.push((group, col.speed, a.speed, false, e));
                    }
                }
                for (child, mount) in model.path_to_base(l) {
                    let (at, joint) = (mount.parent, &mount.joint);
                    let pname = self.link_name(at).to_owned();
                    let up = |cx: &mut Self, x: &V6, what: &str| {
                        cx.force_up(child, joint, x, &format!("{what}({sname}) at {pname}"))
                    };
                    carried = Carried {
                        phi: up(self, &carried.phi, "Phi"),
                        xi: up(self, &carried.xi, "Xi"),
                        h: up(self, &carried.h, "H"),
                        g: carried.g.map(|g| up(self, &g, "G")),
                    };
                    for a in &columns[at] {
                        if let Some(g) = carried.g {
                            let e = self.dot6(&a.s, &g);
                            raw.push((group, a.speed, col.speed, false, e));
                        }
                        let e = self.dot6(&a.s, &carried.h);
                        raw.push((group, a.speed, col.speed, true, e));
                        if let Some(psidd) = a.psidd {
                            let t1 = self.dot6(&carried.phi, &psidd);
                            let t2 = self.dot6(&carried.xi, &a.psid);
                            let e = self.ar.add(t1, t2);
                            raw.push((group, col.speed, a.speed, false, e));
                        }
                        if let Some(r) = a.rotation {
                            let e = self.dot6(&carried.phi, &r);
                            raw.push((group, col.speed, a.speed, false, e));
                        }
                        // 2 Φ·Ψ̇ for a joint, Φ·(V_0 × S) for the base.
                        let t1 = self.dot6(&carried.phi, &a.psid);
                        let t1 = if a.psidd.is_some() {
                            self.ar.scale(t1, 2.0)
                        } else {
                            t1
                        };
                        let t2 = self.dot6(&carried.xi, &a.s);
                        let e = self.ar.add(t1, t2);
                        raw.push((group, col.speed, a.speed, true, e));
                    }
                }
            }
        }
        raw.retain(|x| !self.ar.is_zero(x.4));
        // Schedule: the statements follow the derivation's first requests (`Arena::phase_order`),
        // and the passes above asked for every subtree quantity before any column. Asking again,
        // column by column from the last link (leaves first), each column's statements right
        // after what it reads, keeps Krang's largest number of live values at 259 instead of 767.
        raw.sort_by_key(|x| std::cmp::Reverse(x.0));
        self.ar.begin_phase();
        for x in &raw {
            self.ar.touch_tree(x.4);
        }
        let map = model.constraint_map();
        let nind = model.independent_dof();
        let mut acc: BTreeMap<(usize, usize), Vec<ExprId>> = BTreeMap::new();
        for (_, row, col, u, e) in raw {
            let (c, k) = map[col];
            let e = self.ar.scale(e, k);
            acc.entry((row, c + if u { nind } else { 0 }))
                .or_default()
                .push(e);
        }
        let mut out = Vec::with_capacity(acc.len());
        for ((r, c), terms) in acc {
            let e = self.ar.sum(terms);
            if self.ar.is_zero(e) {
                continue;
            }
            let e = if self.ar.hoist_params {
                self.ar.hoist(e, &format!("dtau[{r},{c}]"))
            } else {
                e
            };
            out.push((r, c, e));
        }
        out
    }

    /// What both forms of the derivatives read, in this order (the arena's order is the
    /// generated code's): τ's pass, the composite inertias, the subtree momenta and inertia
    /// rates, and per link its speeds with `S`, `Ψ̇`, `Ψ̈`.
    pub(super) fn derivative_setup(&mut self) -> Setup {
        let model = self.model;
        let links = model.links.len();
        let (motion, f, n) = self.inverse_dynamics_pass();
        let comp = self.composites(true, None);
        let vel = self.velocities();
        let (mut hc, mut dc) = self.body_momenta(&vel);
        self.subtree_momenta(&mut hc, &mut dc);
        let cols = self.speed_columns();
        let vxs = self.bias_columns(&vel, &cols);
        let rotations = self.base_rotation_columns();
        // Ψ̇ and Ψ̈ of every speed.
        let mut columns: Vec<Vec<Column>> = vec![Vec::new(); links];
        for l in 0..links {
            for (k, &(speed, s)) in cols[l].iter().enumerate() {
                let psidd = model.links[l]
                    .mount
                    .as_ref()
                    .map(|mount| self.psidd(l, mount, speed, &s, &vxs[l][k], &motion, &vel));
                let rotation = match (l, &rotations) {
                    (0, Some(r)) if (3..6).contains(&speed) => Some(r[speed - 3]),
                    _ => None,
                };
                columns[l].push(Column {
                    speed,
                    s,
                    psid: vxs[l][k],
                    psidd,
                    rotation,
                });
            }
        }
        Setup {
            columns,
            comp,
            hc,
            dc,
            f,
            n,
        }
    }

    /// A floating base's `(0; e_k × g_b)` for its rotation speeds `ω_x, ω_y, ω_z` (see
    /// [`Column::rotation`]); `None` for a fixed or wheeled base (nothing asked of the arena).
    fn base_rotation_columns(&mut self) -> Option<[V6; 3]> {
        if !self.model.is_floating() {
            return None;
        }
        let g = self.gravity_vector();
        let zero = self.ar.zero();
        Some([0, 1, 2].map(|k| {
            let mut e = [zero; 3];
            e[k] = self.ar.one();
            let x = self.cross(&e, &g);
            join3(&[zero; 3], &x)
        }))
    }

    /// `Ψ̈ = A_λ × S + V_λ × Ψ̇` of the speed of link `l` (its joint's), in its frame: `A_λ`, `V_λ`
    /// are the parent body's spatial acceleration and velocity at the origin of `l`.
    #[allow(clippy::too_many_arguments)]
    fn psidd(
        &mut self,
        l: usize,
        mount: &Mount,
        speed: usize,
        s: &V6,
        psid: &V6,
        motion: &super::rnea::Motion,
        vel: &[V6],
    ) -> V6 {
        let (i, joint) = (mount.parent, &mount.joint);
        let name = self.link_name(l).to_owned();
        let iname = self.link_name(i).to_owned();
        let r = self.rotation(l, joint);
        let e = self.axis(l);
        let u = self.ar.atom(Atom::Speed(speed as u32));
        // ω and α of the parent in this frame (ω: τ's variable "w{i} in {l}").
        let wi = self.rot_down(&r, &motion.w[i]);
        let wi = self.subst3(wi, VarKind::K, &format!("w{iname} in {name}"));
        let wdi = self.rot_down(&r, &motion.wd[i]);
        // Velocity and classical acceleration of the parent's point at the origin of l.
        let (_, vl) = split3(&vel[l]);
        let (vp, ap): (V3, V3) = match joint.kind {
            JointKind::Prismatic { .. } => {
                let ue = self.scale3(u, &e);
                let vp = self.sub3(&vl, &ue);
                let ud = self.ar.atom(Atom::Accel(speed as u32));
                let ude = self.scale3(ud, &e);
                let wxe = self.cross(&wi, &e);
                let two_u = self.ar.scale(u, 2.0);
                let cor = self.scale3(two_u, &wxe);
                let extra = self.add3(&ude, &cor);
                (vp, self.sub3(&motion.a[l], &extra))
            }
            _ => (vl, motion.a[l]),
        };
        // Spatial acceleration of the parent: (α; a − ω × v).
        let wxv = self.cross(&wi, &vp);
        let alin = self.sub3(&ap, &wxv);
        let a_par = join3(&wdi, &alin);
        let v_par = join3(&wi, &vp);
        let t1 = self.motion_cross(&a_par, s);
        let t2 = self.motion_cross(&v_par, psid);
        let x = self.add6(&t1, &t2);
        let label = format!("Psidd({})", self.model.speeds[speed].name);
        self.subst_motion(x, &label)
    }

    /// The carried forces of column `col` of link `l`, in its frame.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn derivative_forces(
        &mut self,
        l: usize,
        col: &Column,
        comp: &[super::composite::Composite],
        hc: &[V6],
        dc: &[super::coriolis_matrix::Rate],
        f: &[V3],
        n: &[V3],
    ) -> Carried {
        let zero = self.ar.zero();
        let sname = self.model.speeds[col.speed].name.clone();
        let name = self.link_name(l).to_owned();
        let c = &comp[l];
        let jc = c.inertia.expect("inertia computed");
        let s = col.s;
        let phi = self.inertia_mul(c.mass, &c.first_moment, &jc, &s);
        let phi = self.subst_force(phi, &format!("Phi({sname}) at {name}"));
        let sxh = self.force_cross(&s, &hc[l]);
        let (cd, jd) = dc[l];
        let ds = self.inertia_mul(zero, &cd, &jd, &s);
        let xi = self.sub6(&ds, &sxh);
        let xi = self.subst_force(xi, &format!("Xi({sname}) at {name}"));
        let p = self.add6(&ds, &sxh);
        let ic_psid = self.inertia_mul(c.mass, &c.first_moment, &jc, &col.psid);
        let ic_psid = self.subst_force(ic_psid, &format!("IC{name}(Psid({sname}))"));
        // 2 I^c Ψ̇ for a joint, I^c (V_0 × S) for the base.
        let k = if col.psidd.is_some() { 2.0 } else { 1.0 };
        let h: V6 = [0, 1, 2, 3, 4, 5].map(|i| {
            let t = self.ar.scale(ic_psid[i], k);
            self.ar.add(t, p[i])
        });
        let h = self.subst_force(h, &format!("H({sname}) at {name}"));
        let g = col.psidd.map(|psidd| {
            let fl = join3(&n[l], &f[l]);
            let sxf = self.force_cross(&s, &fl);
            let icpsidd = self.inertia_mul(c.mass, &c.first_moment, &jc, &psidd);
            let dpsid = self.inertia_mul(zero, &cd, &jd, &col.psid);
            let psidxh = self.force_cross(&col.psid, &hc[l]);
            let a = self.add6(&sxf, &icpsidd);
            let b = self.add6(&dpsid, &psidxh);
            let g = self.add6(&a, &b);
            self.subst_force(g, &format!("G({sname}) at {name}"))
        });
        Carried { phi, xi, h, g }
    }

    fn sub6(&mut self, a: &V6, b: &V6) -> V6 {
        [0, 1, 2, 3, 4, 5].map(|i| self.ar.sub(a[i], b[i]))
    }
}
