//! Inverse dynamics τ and the Coriolis vector c: a forward pass for the frames' motion and
//! the bodies' inertia forces, then a backward accumulation of Kane's generalized inertia forces.

use kanegen_model::{Joint, JointKind, Mount};

use super::algebra::V3;
use super::ctx::Ctx;
use crate::expr::{Arena, Atom, ExprId, VarKind};

impl Ctx<'_> {
    /// Add the force `f[c]` and moment `n[c]` (about `O_c`) of the complete subtree of `c`
    /// (attached by `mount`) to its parent's.
    pub(super) fn accumulate(
        &mut self,
        c: usize,
        mount: &Mount,
        f: &mut [V3],
        n: &mut [V3],
        tag: &str,
    ) {
        let parent = mount.parent;
        if f[c].iter().chain(n[c].iter()).all(|x| self.ar.is_zero(*x)) {
            return;
        }
        let cname = self.link_name(c).to_owned();
        let pname = self.link_name(parent).to_owned();
        let r = self.rotation(c, &mount.joint);
        let p = self.position(c, &mount.joint);
        let fu = self.rot_up(&r, &f[c]);
        let fu = self.subst3(fu, VarKind::D, &format!("f{cname} in {pname}{tag}"));
        let nu = self.rot_up(&r, &n[c]);
        let pxf = self.cross(&p, &fu);
        let nf = self.add3(&f[parent], &fu);
        let nn = self.add3(&n[parent], &nu);
        let nn = self.add3(&nn, &pxf);
        f[parent] = self.subst3(nf, VarKind::D, &format!("f{pname}{tag}"));
        n[parent] = self.subst3(nn, VarKind::D, &format!("n{pname}{tag}"));
    }

    /// Inertia force and moment about its frame origin of the body on link `l` (if any), from
    /// the frame's angular velocity `w`, angular acceleration `wd` and origin acceleration `a`.
    pub(super) fn body_force(
        &mut self,
        l: usize,
        w: &V3,
        wd: &V3,
        a: &V3,
        tag: &str,
    ) -> Option<(V3, V3)> {
        let (m, ms, j) = self.body(l)?;
        let name = self.link_name(l).to_owned();
        let wxms = self.cross(w, &ms);
        let wxms = self.subst3(wxms, VarKind::D, &format!("w{name}xMS{name}{tag}"));
        let ma = self.scale3(m, a);
        let t1 = self.cross(wd, &ms);
        let t2 = self.cross(w, &wxms);
        let fl = self.add3(&ma, &t1);
        let fl = self.add3(&fl, &t2);
        let fl = self.subst3(fl, VarKind::D, &format!("F{name}{tag}"));
        let jwd = self.sym_mul(&j, wd);
        let jw = self.sym_mul(&j, w);
        let jw = self.subst3(jw, VarKind::D, &format!("J{name}w{name}{tag}"));
        let wxjw = self.cross(w, &jw);
        let msxa = self.cross(&ms, a);
        let nl = self.add3(&jwd, &wxjw);
        let nl = self.add3(&nl, &msxa);
        let nl = self.subst3(nl, VarKind::D, &format!("N{name}{tag}"));
        Some((fl, nl))
    }

    /// τ with the given inputs: `with_accel` keeps u̇ (else u̇ = 0), `with_gravity` folds gravity in.
    pub(super) fn rnea(&mut self, with_accel: bool, with_gravity: bool) -> Vec<ExprId> {
        let (f, n) = self.inertia_forces(Inputs::new(with_accel, with_gravity));
        let out = self.generalized_forces(&f, &n, with_accel);
        let label = match (with_accel, with_gravity) {
            (true, _) => "tau",
            (false, false) => "c",
            (false, true) => "h",
        };
        self.finish(out, label)
    }

    /// `Σ_k m_k a_Gk` over every body at `u̇ = 0` without gravity, in frame 0: the total inertia
    /// force of the motion pass that `c` uses (the bodies only, not the wheels).
    pub(super) fn bias_inertia_force(&mut self) -> V3 {
        self.inertia_forces(Inputs::new(false, false)).0[0]
    }

    /// [`Ctx::bias_inertia_force`] with the moment about frame 0's origin: the whole robot's
    /// inertia wrench `(f, n)` at `u̇ = 0` without gravity, in frame 0's axes.
    pub(super) fn bias_inertia_wrench(&mut self) -> (V3, V3) {
        let (f, n) = self.inertia_forces(Inputs::new(false, false));
        (f[0], n[0])
    }

    /// Every frame's motion at `u̇ = 0` without gravity (the variables `c` uses): `(ω, α, a)`
    /// of each frame in its own axes; `a` is the classical acceleration of its origin.
    pub(super) fn bias_motion(&mut self) -> Motion {
        let inputs = Inputs::new(false, false);
        let mut motion = self.base_motion(inputs);
        let model = self.model;
        for (l, _, mount) in model.mounted_links() {
            self.forward_motion(l, mount, &mut motion, inputs);
        }
        motion
    }

    /// Every frame's motion with u̇ and gravity (τ's motion pass, the same variables): `(ω, α,
    /// a − g)` of each frame in its own axes (the regressor's loop form).
    pub(super) fn full_motion(&mut self) -> Motion {
        let inputs = Inputs::new(true, true);
        let mut motion = self.base_motion(inputs);
        let model = self.model;
        for (l, _, mount) in model.mounted_links() {
            self.forward_motion(l, mount, &mut motion, inputs);
        }
        motion
    }

    /// The subtree inertia forces `f` and moments `n` (about each frame's origin, in its axes)
    /// of every frame for the motion of `inputs`: the forward motion pass, body inertia forces
    /// and the backward accumulation (`f[0]`, `n[0]`: the whole robot's).
    fn inertia_forces(&mut self, inputs: Inputs) -> (Vec<V3>, Vec<V3>) {
        let (_, f, n) = self.motion_and_forces(inputs);
        (f, n)
    }

    /// τ's motion pass and subtree forces (with u̇ and gravity): every frame's `(ω, α, a)` and
    /// the subtree force `f` and moment `n` about its origin (the same nodes as τ's).
    pub(super) fn inverse_dynamics_pass(&mut self) -> (Motion, Vec<V3>, Vec<V3>) {
        self.motion_and_forces(Inputs::new(true, true))
    }

    /// [`Ctx::inertia_forces`] with the motion.
    fn motion_and_forces(&mut self, inputs: Inputs) -> (Motion, Vec<V3>, Vec<V3>) {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let tag = inputs.tag;
        let mut motion = self.base_motion(inputs);
        // Body inertia forces and moments about the frame origins, each formed in the forward
        // pass as soon as its body's motion is known (short live ranges in the generated code).
        let mut f: Vec<V3> = vec![[zero; 3]; links];
        let mut n: Vec<V3> = vec![[zero; 3]; links];
        if let Some((fl, nl)) = self.body_force(0, &motion.w[0], &motion.wd[0], &motion.a[0], tag) {
            (f[0], n[0]) = (fl, nl);
        }
        // Forward: the fixed-wheels report (Zafar 2014) eqs. 3, 4, 6. (A depth-first interleaving of the forward and
        // backward passes keeps fewer values live, but measured for Krang it made the compiled
        // functions larger and slower: their speed is bound by code size.)
        for (l, _, mount) in model.mounted_links() {
            self.forward_motion(l, mount, &mut motion, inputs);
            let (w, wd, a) = (motion.w[l], motion.wd[l], motion.a[l]);
            if let Some((fl, nl)) = self.body_force(l, &w, &wd, &a, tag) {
                (f[l], n[l]) = (fl, nl);
            }
        }
        // Backward accumulation over subtrees.
        for (c, _, mount) in model.mounted_links().rev() {
            self.accumulate(c, mount, &mut f, &mut n, tag);
        }
        (motion, f, n)
    }

    /// The motion of the root frame (the wheeled base's `ω0 = [0,0,ψ̇]`, `α0 = [0,0,ψ̈]`,
    /// `a0 = [ẍ, ẋψ̇, 0]`; the floating base's `ω0 = ω`, `α0 = ω̇`, `a0 = v̇ + ω × v`; minus
    /// gravity if asked); the other frames' are zero until the forward
    /// pass forms them.
    fn base_motion(&mut self, inputs: Inputs) -> Motion {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let tag = inputs.tag;
        let mut w: Vec<V3> = vec![[zero; 3]; links];
        let mut wd: Vec<V3> = vec![[zero; 3]; links];
        let mut a: Vec<V3> = vec![[zero; 3]; links];
        if let Some(wb) = model.wheeled_base() {
            let xd = inputs.speed(self.ar, wb.x_speed);
            let psid = inputs.speed(self.ar, wb.psi_speed);
            let xdd = inputs.accel(self.ar, wb.x_speed);
            let psidd = inputs.accel(self.ar, wb.psi_speed);
            w[0] = [zero, zero, psid];
            wd[0] = [zero, zero, psidd];
            // a0 = [ẍ, ẋψ̇, 0]: the centripetal term ẋψ̇ along y0.
            let xp = self.ar.mul(xd, psid);
            a[0] = [xdd, xp, zero];
        }
        if model.is_floating() {
            // The base twist (v, ω) in the base frame: α0 = ω̇, a0 = v̇ + ω × v (the classical
            // acceleration of the base origin, in the base frame).
            let v = [0, 1, 2].map(|s| inputs.speed(self.ar, s));
            w[0] = [3, 4, 5].map(|s| inputs.speed(self.ar, s));
            wd[0] = [3, 4, 5].map(|s| inputs.accel(self.ar, s));
            let vd = [0, 1, 2].map(|s| inputs.accel(self.ar, s));
            let wxv = self.cross(&w[0], &v);
            let root = self.link_name(0).to_owned();
            let wxv = self.subst3(wxv, VarKind::K, &format!("w{root}xv{root}"));
            a[0] = self.add3(&vd, &wxv);
        }
        if inputs.gravity {
            let g0 = self.gravity_vector();
            a[0] = self.sub3(&a[0], &g0);
        }
        let root = self.link_name(0).to_owned();
        a[0] = self.subst3(a[0], VarKind::K, &format!("a{root}{tag}"));
        Motion { w, wd, a }
    }

    /// The forward step to link `l` from its parent (the fixed-wheels report (Zafar 2014) eqs. 3, 4, 6): its `ω`, `α` and
    /// origin acceleration.
    fn forward_motion(&mut self, l: usize, mount: &Mount, motion: &mut Motion, inputs: Inputs) {
        let tag = inputs.tag;
        let (i, joint) = (mount.parent, &mount.joint);
        let name = self.link_name(l).to_owned();
        let r = self.rotation(l, joint);
        let p = self.position(l, joint);
        let e = self.axis(l);
        let wi = self.rot_down(&r, &motion.w[i]);
        let wi = self.subst3(
            wi,
            VarKind::K,
            &format!("w{} in {name}{tag}", self.link_name(i)),
        );
        let wdi = self.rot_down(&r, &motion.wd[i]);
        let (wj, wdj, extra_a) = self.joint_motion(joint, &e, &wi, &wdi, inputs);
        motion.w[l] = self.subst3(wj, VarKind::K, &format!("w{name}{tag}"));
        motion.wd[l] = self.subst3(wdj, VarKind::K, &format!("wd{name}{tag}"));
        // a_j = jAi (a_i + α_i × P + ω_i × (ω_i × P)) (+ prismatic terms)
        let wxp = self.cross(&motion.w[i], &p);
        let wxp = self.subst3(
            wxp,
            VarKind::K,
            &format!("w{}xP{name}{tag}", self.link_name(i)),
        );
        let t1 = self.cross(&motion.wd[i], &p);
        let t2 = self.cross(&motion.w[i], &wxp);
        let t = self.add3(&motion.a[i], &t1);
        let t = self.add3(&t, &t2);
        let t = self.subst3(
            t,
            VarKind::K,
            &format!("a{name} in {}{tag}", self.link_name(i)),
        );
        let aj = self.rot_down(&r, &t);
        let aj = self.add3(&aj, &extra_a);
        motion.a[l] = self.subst3(aj, VarKind::K, &format!("a{name}{tag}"));
    }

    /// What the joint adds, in the child's frame, to the parent's `ω` and `α` (`wi`, `wdi`,
    /// already rotated into it) about the axis `e`: `(ω, α, extra a)`. Revolute: `ω + u e`,
    /// `α + u̇ e + u ω × e`; prismatic: `u̇ e + 2 u ω × e` on the origin acceleration.
    fn joint_motion(
        &mut self,
        joint: &Joint,
        e: &V3,
        wi: &V3,
        wdi: &V3,
        inputs: Inputs,
    ) -> (V3, V3, V3) {
        let zero = self.ar.zero();
        match joint.kind {
            JointKind::Revolute { speed: s } => {
                let u = inputs.speed(self.ar, s);
                let ud = inputs.accel(self.ar, s);
                let ue = self.scale3(u, e);
                let ude = self.scale3(ud, e);
                let wxe = self.cross(wi, e);
                let uwxe = self.scale3(u, &wxe);
                let wj = self.add3(wi, &ue);
                let t = self.add3(wdi, &ude);
                let wdj = self.add3(&t, &uwxe);
                (wj, wdj, [zero; 3])
            }
            JointKind::Prismatic { speed: s } => {
                let u = inputs.speed(self.ar, s);
                let ud = inputs.accel(self.ar, s);
                let ude = self.scale3(ud, e);
                let wxe = self.cross(wi, e);
                let two_u = self.ar.scale(u, 2.0);
                let cor = self.scale3(two_u, &wxe);
                let extra = self.add3(&ude, &cor);
                (*wi, *wdi, extra)
            }
            JointKind::Fixed => (*wi, *wdi, [zero; 3]),
        }
    }

    /// The generalized forces from the accumulated subtree forces `f` and moments `n`: `e · f`
    /// (prismatic) or `e · n` (revolute) per joint, and the root's `f_x`, `n_z` plus the wheel
    /// terms (times ẍ, ψ̈ with `with_accel`) on the base's ẋ and ψ̇ rows; a floating base's rows
    /// are the root's `f` and `n`.
    fn generalized_forces(&mut self, f: &[V3], n: &[V3], with_accel: bool) -> Vec<ExprId> {
        let model = self.model;
        let zero = self.ar.zero();
        let mut out = vec![zero; model.dof()];
        for (l, _, mount) in model.mounted_links() {
            let Some(row) = mount.joint.speed() else {
                continue;
            };
            let e = self.axis(l);
            out[row] = match mount.joint.kind {
                JointKind::Prismatic { .. } => self.dot(&e, &f[l]),
                _ => self.dot(&e, &n[l]),
            };
        }
        if model.is_floating() {
            // The base speeds' partial velocities are the base frame's unit vectors: the whole
            // robot's inertia force (v rows) and moment about the base origin (ω rows).
            out[..3].copy_from_slice(&f[0]);
            out[3..6].copy_from_slice(&n[0]);
        }
        if let Some((xs, kx, ps, kp)) = self.wheel_terms() {
            out[xs] = f[0][0];
            out[ps] = n[0][2];
            if with_accel {
                let xdd = self.ar.atom(Atom::Accel(xs as u32));
                let psidd = self.ar.atom(Atom::Accel(ps as u32));
                let tx = self.ar.mul(kx, xdd);
                let tp = self.ar.mul(kp, psidd);
                out[xs] = self.ar.add(out[xs], tx);
                out[ps] = self.ar.add(out[ps], tp);
            }
        }
        out
    }
}

/// Which inputs the recursion keeps, and the label tag that tells its variables apart.
#[derive(Clone, Copy)]
struct Inputs {
    /// Keep u̇ (else u̇ = 0).
    accel: bool,
    /// Fold gravity into the base acceleration.
    gravity: bool,
    tag: &'static str,
}

impl Inputs {
    fn new(accel: bool, gravity: bool) -> Self {
        let tag = match (accel, gravity) {
            (true, true) => "",
            (false, false) => "|ud=0,g=0",
            (true, false) => "|g=0",
            (false, true) => "|ud=0",
        };
        Self {
            accel,
            gravity,
            tag,
        }
    }

    fn speed(self, ar: &mut Arena, s: usize) -> ExprId {
        ar.atom(Atom::Speed(s as u32))
    }

    /// `u̇_s`, or zero without accelerations.
    fn accel(self, ar: &mut Arena, s: usize) -> ExprId {
        if self.accel {
            ar.atom(Atom::Accel(s as u32))
        } else {
            ar.zero()
        }
    }
}

/// Every frame's angular velocity `w`, angular acceleration `wd` and origin acceleration `a`,
/// in its own frame.
pub(super) struct Motion {
    pub(super) w: Vec<V3>,
    pub(super) wd: Vec<V3>,
    pub(super) a: Vec<V3>,
}
