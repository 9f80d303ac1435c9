//! Frame kinematics, the numeric baseline of the generated `frame_pose`, `frame_jacobian` and
//! `frame_bias_acceleration`: one pass down the path from the root to the frame (only the joints
//! on it), in frame 0's axes, with the conventions of the generated functions (velocities and
//! accelerations relative to the ground, classical; rows 0–2 linear, 3–5 angular; the wheeled
//! base's `ẋ`, `ψ̇` columns included).

use kanegen_model::{JointKind, Model};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::build::{canonical_frame, classify};
use crate::scalar::{M3, V3, add, cross, rot, scale};
use crate::{ROOT, Rbd, RbdError, Scalar};

/// A frame of the model (body, merged or operational) as the numeric passes see it: the moving
/// link it is rigidly fixed to, its pose in that link's `+z`-axis frame, and the moving links
/// from the root down to it. Built once ([`RbdFrame::new`]); the passes then allocate nothing.
#[derive(Debug, Clone)]
pub struct RbdFrame<T> {
    /// The frame's axes in the link's `+z` frame (columns).
    r: M3<T>,
    /// The frame's origin in the link's `+z` frame.
    t: V3<T>,
    /// The moving links from the root down to the link the frame is fixed to (empty: fixed to
    /// frame 0).
    path: Vec<usize>,
}

impl<T: Scalar> RbdFrame<T> {
    /// Frame `frame` (an index into `model.links`) with the lengths of `params` (one value per
    /// model parameter, as for [`Rbd::new`]).
    pub fn new(model: &Model, params: &[T], frame: usize) -> Result<Self, RbdError> {
        if frame >= model.links.len() || params.len() != model.params.len() {
            return Err(RbdError::BadTree {
                link: format!("#{frame}"),
                detail: format!(
                    "no such frame among {} (or {} parameter values for {} parameters)",
                    model.links.len(),
                    params.len(),
                    model.params.len()
                ),
            });
        }
        let cv = |x: f64| -> T { nalgebra::convert(x) };
        // As `build::moving_links`: per model link, the moving link it is fixed to and the
        // transform `x_that = A x_this + t` into that link's +z frame.
        let mut eff: Vec<(usize, Matrix3<f64>, Vector3<T>)> = Vec::with_capacity(frame + 1);
        let mut parent_of: Vec<usize> = Vec::new();
        for (k, link) in model.links.iter().enumerate().take(frame + 1) {
            let Some(m) = link.mount.as_ref().filter(|m| m.parent < k) else {
                if k == 0 {
                    eff.push((ROOT, Matrix3::identity(), Vector3::zeros()));
                    continue;
                }
                return Err(RbdError::BadTree {
                    link: link.name.clone(),
                    detail: "links must be in topological order".into(),
                });
            };
            let (r_par, a_par, t_par) = eff[m.parent];
            let a0 = Matrix3::from_fn(|r, c| m.joint.rotation[r][c]);
            let p0 = Vector3::from_fn(|r, _| {
                let s = m.joint.translation[r];
                match s.symbol {
                    Some(id) => cv(s.coef) * params[id],
                    None => cv(s.coef),
                }
            });
            let p_eff = a_par.map(cv) * p0 + t_par;
            match m.joint.kind {
                JointKind::Fixed => eff.push((r_par, a_par * a0, p_eff)),
                _ => {
                    let c = canonical_frame(classify(m.joint.axis), m.joint.axis);
                    parent_of.push(r_par);
                    eff.push((parent_of.len() - 1, c.transpose(), Vector3::zeros()));
                }
            }
        }
        let (link, a, t) = eff[frame];
        let mut path = Vec::new();
        let mut at = link;
        while at != ROOT {
            path.push(at);
            at = parent_of[at];
        }
        path.reverse();
        Ok(Self {
            r: [0, 1, 2].map(|c| [0, 1, 2].map(|r| cv(a[(r, c)]))),
            t: [t.x, t.y, t.z],
            path,
        })
    }
}

const fn identity<T: Scalar>(z: T, o: T) -> M3<T> {
    [[o, z, z], [z, o, z], [z, z, o]]
}

impl<const N: usize, T: Scalar> Rbd<N, T> {
    /// Calls `visit(link, W, o)` with the rotation (columns) and origin in frame 0 of each moving
    /// link on `f`'s path, root first; returns the last (frame 0's for an empty path).
    #[inline(always)]
    fn walk(
        &self,
        q: &SVector<T, N>,
        f: &RbdFrame<T>,
        mut visit: impl FnMut(usize, &M3<T>, V3<T>),
    ) -> (M3<T>, V3<T>) {
        let (mut w, mut o) = (identity(T::zero(), T::one()), [T::zero(); 3]);
        for &j in &f.path {
            let l = &self.links[j];
            let (s, c) = if l.prismatic {
                (T::zero(), T::one())
            } else {
                q[l.speed].sin_cos_joint()
            };
            let jr = l.jr(s, c);
            if l.offset {
                o = add(o, rot(&w, l.trans(q)));
            }
            w = l.right(&jr, &w);
            visit(j, &w, o);
        }
        (w, o)
    }

    /// The pose of frame `f` relative to frame 0: `(⁰A, ⁰p)`.
    pub fn frame_pose(&self, q: &SVector<T, N>, f: &RbdFrame<T>) -> (Matrix3<T>, Vector3<T>) {
        let (w, o) = self.walk(q, f, |_, _, _| {});
        let r = [rot(&w, f.r[0]), rot(&w, f.r[1]), rot(&w, f.r[2])];
        let p = add(o, rot(&w, f.t));
        (
            Matrix3::from_fn(|i, j| r[j][i]),
            Vector3::new(p[0], p[1], p[2]),
        )
    }

    /// The Jacobian of frame `f`: rows 0–2 the partial velocities of its origin, rows 3–5 its
    /// partial angular velocities, in frame 0's axes (as the generated `frame_jacobian`).
    pub fn frame_jacobian(&self, q: &SVector<T, N>, f: &RbdFrame<T>) -> SMatrix<T, 6, N> {
        // Joint axes and origins on the path, then the frame's origin.
        let z = T::zero();
        let mut axes = [[z; 3]; N];
        let mut origins = [[z; 3]; N];
        let (w, o) = self.walk(q, f, |j, w, o| {
            axes[j] = w[2];
            origins[j] = o;
        });
        let p = add(o, rot(&w, f.t));
        let mut jac = SMatrix::<T, 6, N>::zeros();
        for &j in &f.path {
            let (l, a) = (&self.links[j], axes[j]);
            let lin = if l.prismatic {
                a
            } else {
                let d = [
                    p[0] - origins[j][0],
                    p[1] - origins[j][1],
                    p[2] - origins[j][2],
                ];
                for (r, x) in a.iter().enumerate() {
                    jac[(3 + r, l.speed)] = *x;
                }
                cross(a, d)
            };
            for (r, x) in lin.iter().enumerate() {
                jac[(r, l.speed)] = *x;
            }
        }
        if let Some(wh) = &self.root.wheels {
            jac[(0, wh.x)] = T::one();
            jac[(0, wh.psi)] = -p[1];
            jac[(1, wh.psi)] = p[0];
            jac[(5, wh.psi)] = T::one();
        }
        jac
    }

    /// The acceleration of frame `f` at `u̇ = 0` (rows 0–2 the classical acceleration of its
    /// origin, 3–5 its angular acceleration, frame 0's axes), so that acceleration =
    /// `J u̇ + bias` (as the generated `frame_bias_acceleration`).
    pub fn frame_bias_acceleration(
        &self,
        q: &SVector<T, N>,
        u: &SVector<T, N>,
        f: &RbdFrame<T>,
    ) -> SVector<T, 6> {
        let z = T::zero();
        let two: T = nalgebra::convert(2.0);
        // ω, α, a of the current link's origin (frame 0's to start).
        let (mut w, mut al, mut acc) = match &self.root.wheels {
            Some(wh) => ([z, z, u[wh.psi]], [z; 3], [z, u[wh.x] * u[wh.psi], z]),
            None => ([z; 3], [z; 3], [z; 3]),
        };
        let mut o_prev = [z; 3];
        let (rw, _) = self.walk(q, f, |j, wj, oj| {
            let l = &self.links[j];
            let r = [oj[0] - o_prev[0], oj[1] - o_prev[1], oj[2] - o_prev[2]];
            acc = add(add(acc, cross(al, r)), cross(w, cross(w, r)));
            let axis = scale(wj[2], u[l.speed]);
            if l.prismatic {
                acc = add(acc, scale(cross(w, axis), two));
            } else {
                al = add(al, cross(w, axis));
                w = add(w, axis);
            }
            o_prev = oj;
        });
        let r = rot(&rw, f.t);
        let a = add(add(acc, cross(al, r)), cross(w, cross(w, r)));
        SVector::<T, 6>::from_column_slice(&[a[0], a[1], a[2], al[0], al[1], al[2]])
    }
}
