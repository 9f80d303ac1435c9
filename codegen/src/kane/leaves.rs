//! Leaves and model data: parameters, joint rotations and positions (cached K variables),
//! bodies, gravity, joint axes and the wheel terms.

use kanegen_model::{Base, Joint, JointKind, Length};

use super::algebra::{M3, V3};
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};
use crate::options::ParamMode;

impl Ctx<'_> {
    pub(super) fn param(&mut self, p: usize) -> ExprId {
        match self.options.params {
            ParamMode::Runtime => self.ar.atom(Atom::Param(p as u32)),
            ParamMode::Baked
                if self.keep_inertial && super::regressor::is_regression_param(self.model, p) =>
            {
                self.ar.atom(Atom::Param(p as u32))
            }
            ParamMode::Baked => self.ar.constant(self.model.params[p].value),
        }
    }

    pub(super) fn length(&mut self, s: &Length) -> ExprId {
        let c = self.ar.constant(s.coef);
        match s.symbol {
            None => c,
            Some(p) => {
                let p = self.param(p);
                self.ar.mul(c, p)
            }
        }
    }

    pub(super) fn consts(&mut self, v: [f64; 3]) -> V3 {
        v.map(|x| self.ar.constant(x))
    }

    pub(super) fn link_name(&self, l: usize) -> &str {
        &self.model.links[l].name
    }

    /// `iAj(q)` of link `l`, attached to its parent by `j` (rows), cached.
    pub(super) fn rotation(&mut self, l: usize, j: &Joint) -> M3 {
        if let Some(r) = self.rot[l] {
            return r;
        }
        let a0: M3 = j.rotation.map(|row| row.map(|x| self.ar.constant(x)));
        let r = match j.kind {
            JointKind::Revolute { speed: s } => {
                let sn = self.ar.atom(Atom::Sin(s as u32));
                let cs = self.ar.atom(Atom::Cos(s as u32));
                let e = j.axis;
                // Rot(e, q) = c·I + s·[e]× + (1 − c)·e eᵀ
                let one = self.ar.one();
                let omc = self.ar.sub(one, cs);
                let ex = [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]];
                let mut rot = [[self.ar.zero(); 3]; 3];
                for r in 0..3 {
                    for c in 0..3 {
                        let id = if r == c { cs } else { self.ar.zero() };
                        let k1 = self.ar.constant(ex[r][c]);
                        let t1 = self.ar.mul(k1, sn);
                        let k2 = self.ar.constant(e[r] * e[c]);
                        let t2 = self.ar.mul(k2, omc);
                        rot[r][c] = self.ar.sum([id, t1, t2]);
                    }
                }
                self.matmul(&a0, &rot)
            }
            _ => a0,
        };
        let name = self.link_name(l).to_owned();
        let mut out = r;
        for (ri, row) in out.iter_mut().enumerate() {
            for (ci, x) in row.iter_mut().enumerate() {
                *x = self
                    .ar
                    .subst(*x, VarKind::K, &format!("A{name}({},{})", ri + 1, ci + 1));
            }
        }
        self.rot[l] = Some(out);
        out
    }

    /// `iPj(q)` of link `l`, attached to its parent by `j`, cached.
    pub(super) fn position(&mut self, l: usize, j: &Joint) -> V3 {
        if let Some(p) = self.pos[l] {
            return p;
        }
        let mut p = j.translation.map(|s| self.length(&s));
        if let JointKind::Prismatic { speed: s } = j.kind {
            let q = self
                .ar
                .atom(Atom::Coord(self.ar.coordinate_index(s as u32)));
            let dir = [0, 1, 2].map(|r| (0..3).map(|c| j.rotation[r][c] * j.axis[c]).sum::<f64>());
            for (r, pr) in p.iter_mut().enumerate() {
                let k = self.ar.constant(dir[r]);
                let t = self.ar.mul(k, q);
                *pr = self.ar.add(*pr, t);
            }
        }
        let name = self.link_name(l).to_owned();
        let p = self.subst3(p, VarKind::K, &format!("P{name}"));
        self.pos[l] = Some(p);
        p
    }

    pub(super) fn body(&mut self, l: usize) -> Option<(ExprId, V3, [ExprId; 6])> {
        let b = self.model.links[l].body.clone()?;
        let m = self.param(b.mass);
        let ms = b.first_moment.map(|p| self.param(p));
        let j = b.inertia.map(|p| self.param(p));
        Some((m, ms, j))
    }

    /// Gravity `g · direction` in the base frame: constant for a fixed or wheeled base; for a
    /// floating base `g_b = Rᵀ(quat) · g · direction`, polynomial in the quaternion (formed once,
    /// as the variables `g_b`).
    pub(super) fn gravity_vector(&mut self) -> V3 {
        let g = self.param(self.model.gravity.symbol);
        let d = self.consts(self.model.gravity.direction);
        if !self.model.is_floating() {
            return self.scale3(g, &d);
        }
        let r = self.base_rotation();
        let dir = self.model.gravity.direction;
        let mut gb = [self.ar.zero(); 3];
        for (i, gi) in gb.iter_mut().enumerate() {
            // (Rᵀ d)_i = Σ_j R[j][i] d_j, only over the non-zero d_j.
            let terms: Vec<ExprId> = (0..3)
                .filter(|&j| dir[j] != 0.0)
                .map(|j| self.ar.mul(r[j][i], d[j]))
                .collect();
            let s = self.ar.sum(terms);
            *gi = self.ar.mul(g, s);
        }
        self.subst3(gb, VarKind::D, "g_b")
    }

    /// The floating base's rotation base → world from its unit quaternion `(qx, qy, qz, qw)` =
    /// `q[3..7]`: `R = (2w² − 1)·1 + 2 w [v]× + 2 v vᵀ` written as Eigen and Pinocchio do,
    /// `R[0][0] = 1 − 2(y² + z²)`, `R[0][1] = 2(xy − zw)`, … (polynomial: no trigonometry).
    pub(super) fn base_rotation(&mut self) -> M3 {
        let [x, y, z, w] = [3u32, 4, 5, 6].map(|k| self.ar.atom(Atom::Coord(k)));
        let sq = |s: &mut Self, a: ExprId, b: ExprId| {
            let p = s.ar.mul(a, b);
            s.ar.scale(p, 2.0)
        };
        let one = self.ar.one();
        let (xx, yy, zz) = (sq(self, x, x), sq(self, y, y), sq(self, z, z));
        let (xy, xz, yz) = (sq(self, x, y), sq(self, x, z), sq(self, y, z));
        let (xw, yw, zw) = (sq(self, x, w), sq(self, y, w), sq(self, z, w));
        let diag = |s: &mut Self, a: ExprId, b: ExprId| {
            let t = s.ar.add(a, b);
            s.ar.sub(one, t)
        };
        let r = [
            [diag(self, yy, zz), self.ar.sub(xy, zw), self.ar.add(xz, yw)],
            [self.ar.add(xy, zw), diag(self, xx, zz), self.ar.sub(yz, xw)],
            [self.ar.sub(xz, yw), self.ar.add(yz, xw), diag(self, xx, yy)],
        ];
        let mut out = r;
        for (ri, row) in out.iter_mut().enumerate() {
            for (ci, e) in row.iter_mut().enumerate() {
                *e = self
                    .ar
                    .subst(*e, VarKind::K, &format!("R0({},{})", ri + 1, ci + 1));
            }
        }
        out
    }

    pub(super) fn axis(&mut self, l: usize) -> V3 {
        let e = self.model.links[l]
            .joint()
            .map(|j| j.axis)
            .unwrap_or([0.0; 3]);
        self.consts(e)
    }

    /// Wheel inertia added to `M[ẋ,ẋ]` and `M[ψ̇,ψ̇]`.
    pub(super) fn wheel_terms(&mut self) -> Option<(usize, ExprId, usize, ExprId)> {
        let Base::Wheeled(w) = &self.model.base else {
            return None;
        };
        let w = w.clone();
        let (r, l, mw, yy, zz) = (
            self.param(w.radius),
            self.param(w.track),
            self.param(w.wheel_mass),
            self.param(w.wheel_axle_inertia),
            self.param(w.wheel_diametral_inertia),
        );
        let two = self.ar.constant(2.0);
        let half = self.ar.constant(0.5);
        let r_2 = self.ar.powi(r, -2);
        let l2 = self.ar.powi(l, 2);
        // 2 mw + 2 YYw / R²
        let a = self.ar.mul(two, mw);
        let b = self.ar.product([two, yy, r_2]);
        let kx = self.ar.add(a, b);
        let kx = self.ar.subst(kx, VarKind::D, "wheels: 2 mw + 2 YYw/R^2");
        // mw L²/2 + YYw L²/(2R²) + 2 ZZw
        let a = self.ar.product([half, mw, l2]);
        let b = self.ar.product([half, yy, l2, r_2]);
        let c = self.ar.mul(two, zz);
        let kp = self.ar.sum([a, b, c]);
        let kp = self
            .ar
            .subst(kp, VarKind::D, "wheels: mw L^2/2 + YYw L^2/(2R^2) + 2 ZZw");
        Some((w.x_speed, kx, w.psi_speed, kp))
    }
}
