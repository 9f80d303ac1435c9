//! 3-vector and 3×3 algebra, and spatial (6-vector) algebra: motions `(ω; v)`, forces `(n; f)`.

use kanegen_model::Joint;

pub(super) use super::ctx::{AXES, Ctx, M3, V3, V6, join3, split3};
use crate::expr::{ExprId, VarKind};

impl Ctx<'_> {
    pub(super) fn matmul(&mut self, a: &M3, b: &M3) -> M3 {
        let mut out = [[self.ar.zero(); 3]; 3];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(a[r][k], b[k][c])).collect();
                *x = self.ar.sum(t);
            }
        }
        out
    }

    /// `R x`.
    pub(super) fn rot_up(&mut self, r: &M3, x: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(r[i][k], x[k])).collect();
            self.ar.sum(t)
        })
    }

    /// `Rᵀ x`.
    pub(super) fn rot_down(&mut self, r: &M3, x: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(r[k][i], x[k])).collect();
            self.ar.sum(t)
        })
    }

    pub(super) fn add3(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.add(a[i], b[i]))
    }

    pub(super) fn sub3(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.sub(a[i], b[i]))
    }

    pub(super) fn scale3(&mut self, k: ExprId, a: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.mul(k, a[i]))
    }

    pub(super) fn cross(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = self.ar.mul(a[j], b[k]);
            let m = self.ar.mul(a[k], b[j]);
            self.ar.sub(p, m)
        })
    }

    pub(super) fn dot(&mut self, a: &V3, b: &V3) -> ExprId {
        let t: Vec<ExprId> = (0..3).map(|i| self.ar.mul(a[i], b[i])).collect();
        self.ar.sum(t)
    }

    pub(super) fn subst3(&mut self, v: V3, kind: VarKind, label: &str) -> V3 {
        [0, 1, 2].map(|i| self.ar.subst(v[i], kind, &format!("{label}.{}", AXES[i])))
    }

    /// Symmetric 3×3 from `[XX, XY, XZ, YY, YZ, ZZ]`.
    pub(super) fn sym(j: &[ExprId; 6]) -> M3 {
        [[j[0], j[1], j[2]], [j[1], j[3], j[4]], [j[2], j[4], j[5]]]
    }

    pub(super) fn sym_mul(&mut self, j: &[ExprId; 6], x: &V3) -> V3 {
        let m = Self::sym(j);
        self.rot_up(&m, x)
    }

    /// Spatial inertia with mass `m`, first moment `c`, inertia `j` about the origin, times the
    /// motion `x`: `(J x_ω + c × x_v; m x_v − c × x_ω)`. With `m = 0` and `(c, j) = (ċ, J̇)`: D x.
    pub(super) fn inertia_mul(&mut self, m: ExprId, c: &V3, j: &[ExprId; 6], x: &V6) -> V6 {
        let (xw, xv) = split3(x);
        let jw = self.sym_mul(j, &xw);
        let cxv = self.cross(c, &xv);
        let n = self.add3(&jw, &cxv);
        let mv = self.scale3(m, &xv);
        let cxw = self.cross(c, &xw);
        let f = self.sub3(&mv, &cxw);
        join3(&n, &f)
    }

    /// Motion cross product `a × b = (ω_a × ω_b; ω_a × v_b + v_a × ω_b)`.
    pub(super) fn motion_cross(&mut self, a: &V6, b: &V6) -> V6 {
        let (aw, av) = split3(a);
        let (bw, bv) = split3(b);
        let w = self.cross(&aw, &bw);
        let t1 = self.cross(&aw, &bv);
        let t2 = self.cross(&av, &bw);
        let v = self.add3(&t1, &t2);
        join3(&w, &v)
    }

    /// Force cross product `m ×* f = (ω × n + v × f; ω × f)`.
    pub(super) fn force_cross(&mut self, m: &V6, f: &V6) -> V6 {
        let (w, v) = split3(m);
        let (n, ff) = split3(f);
        let t1 = self.cross(&w, &n);
        let t2 = self.cross(&v, &ff);
        let top = self.add3(&t1, &t2);
        let bot = self.cross(&w, &ff);
        join3(&top, &bot)
    }

    pub(super) fn dot6(&mut self, a: &V6, b: &V6) -> ExprId {
        let t: Vec<ExprId> = (0..6).map(|i| self.ar.mul(a[i], b[i])).collect();
        self.ar.sum(t)
    }

    pub(super) fn add6(&mut self, a: &V6, b: &V6) -> V6 {
        [0, 1, 2, 3, 4, 5].map(|i| self.ar.add(a[i], b[i]))
    }

    /// Substitution variables (kind D) for a force: `{label}.n.x` … `{label}.f.z`.
    pub(super) fn subst_force(&mut self, x: V6, label: &str) -> V6 {
        let (a, b) = split3(&x);
        let a = self.subst3(a, VarKind::D, &format!("{label}.n"));
        let b = self.subst3(b, VarKind::D, &format!("{label}.f"));
        join3(&a, &b)
    }

    /// Substitution variables (kind K) for a motion: `{label}.w.x` … `{label}.v.z`.
    pub(super) fn subst_motion(&mut self, x: V6, label: &str) -> V6 {
        let (a, b) = split3(&x);
        let a = self.subst3(a, VarKind::K, &format!("{label}.w"));
        let b = self.subst3(b, VarKind::K, &format!("{label}.v"));
        join3(&a, &b)
    }

    /// A force of frame `child` moved to its parent: `(R n + P × R f; R f)`.
    pub(super) fn force_up(&mut self, child: usize, joint: &Joint, x: &V6, label: &str) -> V6 {
        let r = self.rotation(child, joint);
        let p = self.position(child, joint);
        let (n, f) = split3(x);
        let fu = self.rot_up(&r, &f);
        let fu = self.subst3(fu, VarKind::D, &format!("{label}.f"));
        let nu = self.rot_up(&r, &n);
        let pxf = self.cross(&p, &fu);
        let nn = self.add3(&nu, &pxf);
        let nn = self.subst3(nn, VarKind::D, &format!("{label}.n"));
        join3(&nn, &fu)
    }
}
