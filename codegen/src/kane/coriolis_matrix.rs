//! The Coriolis matrix C(q, u) (c = C u, Ṁ − 2C skew-symmetric), in spatial vectors.

use std::collections::BTreeMap;

use kanegen_model::JointKind;

use super::algebra::{V3, V6, join3, split3};
use super::composite::Composite;
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};

impl Ctx<'_> {
    /// `C(q, u)` with `c = C u` and `Ṁ − 2C` skew-symmetric, as `(row, col, expr)` entries.
    ///
    /// Spatial vectors in body coordinates: motion `V = (ω; v)` (v of the frame origin), force
    /// `f = (n; f)` (n about the frame origin). Body k's spatial inertia `I_k` is constant in its
    /// frame, its body Jacobian `J_k` (`V_k = J_k u`) has the column `ᵏX_j S_j` for every speed j
    /// on its path to the root (`S_j` constant in the frame of joint j: `(e; 0)` revolute,
    /// `(0; e)` prismatic, `(0; x̂)` and `(ẑ; 0)` for ẋ, ψ̇ in frame 0), and
    /// `J̇_k,j = −(V_k − ᵏX_j V_j) × J_k,j`. With `M = Σ J_kᵀ I_k J_k` (plus constant wheel terms),
    ///
    /// `C = Σ_k J_kᵀ (I_k J̇_k + B_k J_k)`, `B_k = ½ [(I_k V_k)×̄* + I_k (V_k×) + (V_k×*) I_k]`
    ///
    /// (`(h×̄*) m := m ×* h`). B_k is skew-symmetric and `B_k V_k = V_k ×* I_k V_k`, so
    /// `C u = c` and `C + Cᵀ = Σ (J̇ᵀ I J + Jᵀ I J̇) = Ṁ`. This choice of B (the average of
    /// `(I V)×̄*` and `I (V×) − (I (V×))ᵀ`) makes `I_k J̇_k,j + B_k J_k,j = I_k ᵏX_j (V_j × S_j) +
    /// ½ (I_k V_k)×̄* J_k,j + ½ D_k J_k,j` with `D_k = (V_k×*) I_k − I_k (V_k×)`, the rate of
    /// the inertia in a fixed frame: symmetric, of the inertia form `[[J̇, [ċ]×], [−[ċ]×, 0]]`
    /// (`J̇ = [ω]× J − J [ω]× + 2 (c·v) 1 − c vᵀ − v cᵀ`, `ċ = ω × c + m v`, c = MS), so it is
    /// summed over subtrees exactly like composite inertias (with mass 0). Over the subtree of
    /// the link of speed i, in its frame: `I^c_i` (composite inertia), `h^c_i = Σ I_k V_k`
    /// (subtree momentum), `D^c_i = Σ D_k`; then
    ///
    /// * `h_i = I^c_i (V_i × S_i) + ½ S_i ×* h^c_i + ½ D^c_i S_i`: `C[j, i] = S_j · h_i` for i
    ///   and every speed j above it (h_i carried up as a force);
    /// * `G1_i = ½ D^c_i S_i − ½ S_i ×* h^c_i`, `G2_i = I^c_i S_i` (M's column force):
    ///   `C[i, j] = S_j · G1_i + (V_j × S_j) · G2_i` for every speed j strictly above i
    ///   (identity `a · (m ×* f) = −(m × a) · f`).
    ///
    /// Three force vectors carried per (descendant, ancestor) pair: the cost grows with the sum
    /// of depths, like M's.
    pub(super) fn coriolis_matrix(&mut self, comp: &[Composite]) -> Vec<(usize, usize, ExprId)> {
        let links = self.model.links.len();
        // Velocities of the frames, in their own frames.
        let vel = self.velocities();
        // Body momenta h_k = I_k V_k and inertia rates D_k = (ċ_k, J̇_k), summed over subtrees.
        let (mut hc, mut dc) = self.body_momenta(&vel);
        self.subtree_momenta(&mut hc, &mut dc);
        let cols = self.speed_columns();
        let vxs = self.bias_columns(&vel, &cols);
        let sub = Subtrees {
            comp,
            hc: &hc,
            dc: &dc,
            cols: &cols,
            vxs: &vxs,
        };
        let mut entries: BTreeMap<(usize, usize), ExprId> = BTreeMap::new();
        for l in 0..links {
            for k in 0..cols[l].len() {
                let forces = self.column_forces(l, k, &sub);
                self.put_column(l, k, forces, &sub, &mut entries);
            }
        }
        let mut out = Vec::with_capacity(entries.len());
        for ((a, b), e) in entries {
            if self.ar.is_zero(e) {
                continue;
            }
            let e = if self.ar.hoist_params {
                self.ar.hoist(e, &format!("C[{a},{b}]"))
            } else {
                e
            };
            out.push((a, b, e));
        }
        out
    }

    /// Every body's momentum `h_k = I_k V_k` and inertia rate `D_k = (ċ_k, J̇_k)`, in its frame
    /// (zero for links without a body).
    pub(super) fn body_momenta(&mut self, vel: &[V6]) -> (Vec<V6>, Vec<Rate>) {
        let links = self.model.links.len();
        let zero = self.ar.zero();
        let mut hc: Vec<V6> = vec![[zero; 6]; links];
        let mut dc: Vec<Rate> = vec![([zero; 3], [zero; 6]); links];
        for l in 0..links {
            let Some((m, ms, j)) = self.body(l) else {
                continue;
            };
            let name = self.link_name(l).to_owned();
            let (w, v) = split3(&vel[l]);
            // h = (J ω + MS × v; m v + ω × MS); its linear part is also ċ of the inertia rate.
            let tag = "|ud=0,g=0";
            let wxms = self.cross(&w, &ms);
            let wxms = self.subst3(wxms, VarKind::D, &format!("w{name}xMS{name}{tag}"));
            let jw = self.sym_mul(&j, &w);
            let jw = self.subst3(jw, VarKind::D, &format!("J{name}w{name}{tag}"));
            let msxv = self.cross(&ms, &v);
            let n = self.add3(&jw, &msxv);
            let mv = self.scale3(m, &v);
            let f = self.add3(&mv, &wxms);
            hc[l] = self.subst_force(join3(&n, &f), &format!("h{name}"));
            let jd = self.inertia_rate(&name, &w, &v, &ms, &j);
            // ċ = ω × MS + m v: the linear momentum.
            let cd = split3(&hc[l]).1;
            dc[l] = (cd, jd);
        }
        (hc, dc)
    }

    /// `J̇ = W + Wᵀ + 2 (c·v) 1 − (c vᵀ + v cᵀ)`, `W = [ω]× J` (c = MS), of the body `name`
    /// with inertia `j` moving with `(ω; v) = (w; v)`, as `[XX, XY, XZ, YY, YZ, ZZ]`.
    fn inertia_rate(
        &mut self,
        name: &str,
        w: &V3,
        v: &V3,
        ms: &V3,
        j: &[ExprId; 6],
    ) -> [ExprId; 6] {
        let zero = self.ar.zero();
        let jm = Self::sym(j);
        let mut wj = [[zero; 3]; 3];
        for b in 0..3 {
            let col = [jm[0][b], jm[1][b], jm[2][b]];
            let x = self.cross(w, &col);
            for a in 0..3 {
                wj[a][b] = x[a];
            }
        }
        let cv = self.dot(ms, v);
        let two_cv = self.ar.scale(cv, 2.0);
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        let mut jd = [zero; 6];
        for (k, &(a, b)) in idx.iter().enumerate() {
            let cva = self.ar.mul(ms[a], v[b]);
            let vca = self.ar.mul(v[a], ms[b]);
            let sym = self.ar.add(cva, vca);
            let sym = self.ar.neg(sym);
            let diag = if a == b { two_cv } else { zero };
            let e = self.ar.sum([wj[a][b], wj[b][a], diag, sym]);
            jd[k] = self
                .ar
                .subst(e, VarKind::D, &format!("Jd{name}.{}", LABELS[k]));
        }
        jd
    }

    /// Subtree sums, backward: momenta as forces, inertia rates as inertias of mass 0. The
    /// first-moment rate ċ of a subtree is its linear momentum (both move up as R·x).
    pub(super) fn subtree_momenta(&mut self, hc: &mut [V6], dc: &mut [Rate]) {
        let zero = self.ar.zero();
        let model = self.model;
        for (c, _, mount) in model.mounted_links().rev() {
            let parent = mount.parent;
            let name = self.link_name(c).to_owned();
            let pname = self.link_name(parent).to_owned();
            self.finish_subtree(c, hc, dc);
            let jd = dc[c].1;
            if hc[c].iter().chain(jd.iter()).all(|x| self.ar.is_zero(*x)) {
                continue;
            }
            let r = self.rotation(c, &mount.joint);
            let p = self.position(c, &mount.joint);
            let up = self.force_up(c, &mount.joint, &hc[c], &format!("hC{name} in {pname}"));
            hc[parent] = self.add6(&hc[parent], &up);
            let u = split3(&up).1;
            let mut pjd = dc[parent].1;
            let joint = &mount.joint;
            self.add_inertia_to_parent(joint, &r, &p, zero, &u, &jd, &name, "JdC", &mut pjd);
            dc[parent].1 = pjd;
        }
        self.finish_subtree(0, hc, dc);
    }

    /// Link `l`'s subtree momentum (`hC{name}`) and inertia rate (`JdC{name}.xx` …; the root's
    /// six components share the label `JdC{name}`) as substitution variables, once complete;
    /// `ċ` is the momentum's linear part.
    fn finish_subtree(&mut self, l: usize, hc: &mut [V6], dc: &mut [Rate]) {
        let name = self.link_name(l).to_owned();
        hc[l] = self.subst_force(hc[l], &format!("hC{name}"));
        let jd = dc[l].1;
        let jd = [0, 1, 2, 3, 4, 5].map(|k| {
            let label = if l == 0 {
                format!("JdC{name}")
            } else {
                format!("JdC{name}.{}", LABELS[k])
            };
            self.ar.subst(jd[k], VarKind::D, &label)
        });
        dc[l] = (split3(&hc[l]).1, jd);
    }

    /// The columns (speeds) of every link and their motion subspaces `S` in its frame: a
    /// joint's, or the base's ẋ and ψ̇ (a floating base's v and ω) at the root.
    pub(super) fn speed_columns(&mut self) -> Vec<Vec<(usize, V6)>> {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let mut cols: Vec<Vec<(usize, V6)>> = vec![Vec::new(); links];
        if let Some(w) = model.wheeled_base() {
            let one = self.ar.one();
            cols[0].push((w.x_speed, [zero, zero, zero, one, zero, zero]));
            cols[0].push((w.psi_speed, [zero, zero, one, zero, zero, zero]));
        }
        if model.is_floating() {
            // The base's v (linear) and ω (angular) speeds: unit vectors of frame 0.
            let one = self.ar.one();
            for i in 0..6 {
                let mut s = [zero; 6];
                s[(i + 3) % 6] = one;
                cols[0].push((i, s));
            }
        }
        for (l, _, mount) in model.mounted_links() {
            let Some(s) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(l);
            let axis = match mount.joint.kind {
                JointKind::Prismatic { .. } => [zero, zero, zero, e[0], e[1], e[2]],
                _ => [e[0], e[1], e[2], zero, zero, zero],
            };
            cols[l].push((s, axis));
        }
        cols
    }

    /// `V_l × S` for every column, in its frame (the Coriolis bias of a unit speed).
    pub(super) fn bias_columns(&mut self, vel: &[V6], cols: &[Vec<(usize, V6)>]) -> Vec<Vec<V6>> {
        let mut vxs: Vec<Vec<V6>> = vec![Vec::new(); cols.len()];
        for l in 0..cols.len() {
            for k in 0..cols[l].len() {
                let (sp, s) = cols[l][k];
                let x = self.motion_cross(&vel[l], &s);
                let label = format!("V{}xS({})", self.link_name(l), self.model.speeds[sp].name);
                let x = self.subst_motion(x, &label);
                vxs[l].push(x);
            }
        }
        vxs
    }

    /// The three forces of column `k` of link `l` (speed i), in its frame:
    /// `h_i = I^c_i (V_i × S_i) + ½ S_i ×* h^c_i + ½ D^c_i S_i`,
    /// `G1_i = ½ D^c_i S_i − ½ S_i ×* h^c_i` and `G2_i = I^c_i S_i`.
    fn column_forces(&mut self, l: usize, k: usize, sub: &Subtrees) -> [V6; 3] {
        let zero = self.ar.zero();
        let half = 0.5;
        let (sp, s) = sub.cols[l][k];
        let sname = self.model.speeds[sp].name.clone();
        let name = self.link_name(l).to_owned();
        let c = &sub.comp[l];
        let jc = c.inertia.expect("inertia computed");
        let ic_vxs = self.inertia_mul(c.mass, &c.first_moment, &jc, &sub.vxs[l][k]);
        let ic_vxs = self.subst_force(ic_vxs, &format!("IC{name}(VxS({sname}))"));
        let sxh = self.force_cross(&s, &sub.hc[l]);
        let sxh = self.subst_force(sxh, &format!("S({sname})x*hC{name}"));
        let (cd, jd) = sub.dc[l];
        let ds = self.inertia_mul(zero, &cd, &jd, &s);
        let ds = self.subst_force(ds, &format!("DC{name}S({sname})"));
        let mut h = [zero; 6];
        let mut g1 = [zero; 6];
        for i in 0..6 {
            let a = self.ar.scale(sxh[i], half);
            let b = self.ar.scale(ds[i], half);
            h[i] = self.ar.sum([ic_vxs[i], a, b]);
            g1[i] = self.ar.sub(b, a);
        }
        let h = self.subst_force(h, &format!("h(C col {sname}) at {name}"));
        let g1 = self.subst_force(g1, &format!("G1(C row {sname}) at {name}"));
        let g2 = self.inertia_mul(c.mass, &c.first_moment, &jc, &s);
        let g2 = self.subst_force(g2, &format!("G2(C row {sname}) at {name}"));
        [h, g1, g2]
    }

    /// The entries of column `k` of link `l` (speed i) from its forces `[h, G1, G2]`:
    /// `C[j, i] = S_j · h_i` for the speeds j of the same frame, then, carrying the forces up
    /// to the root, `C[j, i]` and `C[i, j] = S_j · G1_i + (V_j × S_j) · G2_i` for every speed j
    /// above.
    fn put_column(
        &mut self,
        l: usize,
        k: usize,
        [mut h, mut g1, mut g2]: [V6; 3],
        sub: &Subtrees,
        entries: &mut BTreeMap<(usize, usize), ExprId>,
    ) {
        let sp = sub.cols[l][k].0;
        let sname = self.model.speeds[sp].name.clone();
        // Speeds of the same frame (the base's ẋ, ψ̇; or the joint itself).
        for &(sa, sv) in &sub.cols[l] {
            let e = self.dot6(&sv, &h);
            put(entries, sa, sp, e);
        }
        let model = self.model;
        for (child, mount) in model.path_to_base(l) {
            let (at, joint) = (mount.parent, &mount.joint);
            let pname = self.link_name(at).to_owned();
            h = self.force_up(child, joint, &h, &format!("h(C col {sname}) at {pname}"));
            g1 = self.force_up(child, joint, &g1, &format!("G1(C row {sname}) at {pname}"));
            g2 = self.force_up(child, joint, &g2, &format!("G2(C row {sname}) at {pname}"));
            for (ka, &(sa, sv)) in sub.cols[at].iter().enumerate() {
                let e = self.dot6(&sv, &h);
                put(entries, sa, sp, e);
                let t1 = self.dot6(&sv, &g1);
                let t2 = self.dot6(&sub.vxs[at][ka], &g2);
                let e = self.ar.add(t1, t2);
                put(entries, sp, sa, e);
            }
        }
    }

    /// Spatial velocities `(ω; v)` of every frame in its own frame (`v` of the origin).
    pub(super) fn velocities(&mut self) -> Vec<V6> {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let mut w: Vec<V3> = vec![[zero; 3]; links];
        let mut v: Vec<V3> = vec![[zero; 3]; links];
        if let Some(wb) = model.wheeled_base() {
            w[0] = [zero, zero, self.ar.atom(Atom::Speed(wb.psi_speed as u32))];
            v[0] = [self.ar.atom(Atom::Speed(wb.x_speed as u32)), zero, zero];
        }
        if model.is_floating() {
            v[0] = [0u32, 1, 2].map(|s| self.ar.atom(Atom::Speed(s)));
            w[0] = [3u32, 4, 5].map(|s| self.ar.atom(Atom::Speed(s)));
        }
        let tag = "|ud=0,g=0";
        for (l, _, mount) in model.mounted_links() {
            let i = mount.parent;
            let name = self.link_name(l).to_owned();
            let iname = self.link_name(i).to_owned();
            let r = self.rotation(l, &mount.joint);
            let p = self.position(l, &mount.joint);
            let e = self.axis(l);
            // ω as in the inverse dynamics (same variables).
            let wi = self.rot_down(&r, &w[i]);
            let wi = self.subst3(wi, VarKind::K, &format!("w{iname} in {name}{tag}"));
            let mut vl = {
                let wxp = self.cross(&w[i], &p);
                let wxp = self.subst3(wxp, VarKind::K, &format!("w{iname}xP{name}{tag}"));
                let t = self.add3(&v[i], &wxp);
                let t = self.subst3(t, VarKind::K, &format!("v{name} in {iname}"));
                self.rot_down(&r, &t)
            };
            let mut wl = wi;
            match mount.joint.kind {
                JointKind::Revolute { speed: s } => {
                    let u = self.ar.atom(Atom::Speed(s as u32));
                    let ue = self.scale3(u, &e);
                    wl = self.add3(&wi, &ue);
                }
                JointKind::Prismatic { speed: s } => {
                    let u = self.ar.atom(Atom::Speed(s as u32));
                    let ue = self.scale3(u, &e);
                    vl = self.add3(&vl, &ue);
                }
                JointKind::Fixed => {}
            }
            w[l] = self.subst3(wl, VarKind::K, &format!("w{name}{tag}"));
            v[l] = self.subst3(vl, VarKind::K, &format!("v{name}"));
        }
        (0..links)
            .map(|l| [w[l][0], w[l][1], w[l][2], v[l][0], v[l][1], v[l][2]])
            .collect()
    }
}

/// An inertia rate `D = (ċ, J̇)`: first-moment rate and `[XX, XY, XZ, YY, YZ, ZZ]` rate.
pub(super) type Rate = (V3, [ExprId; 6]);

/// Component suffixes of `[XX, XY, XZ, YY, YZ, ZZ]` labels.
const LABELS: [&str; 6] = ["xx", "xy", "xz", "yy", "yz", "zz"];

/// What the columns of C are formed from, per link (in its frame): composite inertias, subtree
/// momenta `h^c` and inertia rates `D^c`, the speed columns `(speed, S)` and their biases `V × S`.
struct Subtrees<'s> {
    comp: &'s [Composite],
    hc: &'s [V6],
    dc: &'s [Rate],
    cols: &'s [Vec<(usize, V6)>],
    vxs: &'s [Vec<V6>],
}

fn put(entries: &mut BTreeMap<(usize, usize), ExprId>, a: usize, b: usize, e: ExprId) {
    let old = entries.insert((a, b), e);
    debug_assert!(old.is_none(), "C[{a},{b}] set twice");
}
