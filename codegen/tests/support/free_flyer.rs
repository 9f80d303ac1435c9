//! A numeric free-flyer recursion for the floating-base tests, written from the spatial-vector
//! formulation (Featherstone's recursive Newton–Euler algorithm), independent of the generator's
//! Kane derivation: body-frame spatial velocities and accelerations `(ω, v)` carried outward,
//! spatial forces `(n, f)` carried inward. The root is a free flyer laid out as Pinocchio's:
//! `q = [x, y, z, qx, qy, qz, qw, joints]`, `u = [v, ω, joint speeds]` (base frame), gravity
//! along the model's direction in the world frame.

#![allow(dead_code, clippy::needless_range_loop)]

use kanegen::model::{JointKind, Model};
use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Rotation base → world of the configuration `q` (unit quaternion `q[3..7]`, `(x, y, z, w)`).
pub fn base_rotation(q: &[f64]) -> Matrix3<f64> {
    let quat = Quaternion::new(q[6], q[3], q[4], q[5]);
    UnitQuaternion::new_unchecked(quat)
        .to_rotation_matrix()
        .into_inner()
}

/// Per link: its rotation relative to the base frame and its origin in the base frame.
pub fn link_poses(model: &Model, q: &[f64], p: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
    let mut out = vec![(Matrix3::identity(), Vector3::zeros()); model.links.len()];
    for (i, _, m) in model.mounted_links() {
        let (r, c) = joint_transform(model, i, q, p);
        let (rp, pp) = out[m.parent];
        out[i] = (rp * r, pp + rp * c);
    }
    out
}

/// `iAj(q)` and `iPj(q)` of link `l` (rotation of the child in the parent, child origin).
fn joint_transform(model: &Model, l: usize, q: &[f64], p: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
    let j = model.links[l].joint().expect("mounted");
    let a = Matrix3::from_fn(|r, c| j.rotation[r][c]);
    let e = Vector3::from(j.axis);
    let mut pos = Vector3::from_fn(|r, _| j.translation[r].eval(p));
    let mut rot = a;
    match j.kind {
        JointKind::Revolute { speed } => {
            let angle = q[model.coordinate_index(speed)];
            rot =
                a * nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(e), angle)
                    .into_inner();
        }
        JointKind::Prismatic { speed } => pos += a * e * q[model.coordinate_index(speed)],
        JointKind::Fixed => {}
    }
    (rot, pos)
}

/// Body `(m, MS, J)` of link `l` (zero if it has none).
fn body(model: &Model, l: usize, p: &[f64]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    match &model.links[l].body {
        None => (0.0, Vector3::zeros(), Matrix3::zeros()),
        Some(b) => {
            let [xx, xy, xz, yy, yz, zz] = b.inertia.map(|k| p[k]);
            (
                p[b.mass],
                Vector3::from_fn(|k, _| p[b.first_moment[k]]),
                Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
            )
        }
    }
}

/// Gravity in the base frame: `Rᵀ g d`.
pub fn gravity_in_base(model: &Model, q: &[f64], p: &[f64]) -> Vector3<f64> {
    let g = p[model.gravity.symbol] * Vector3::from(model.gravity.direction);
    base_rotation(q).transpose() * g
}

/// Inverse dynamics τ(q, u, u̇) of the floating model, gravity included if `gravity`.
pub fn rnea(
    model: &Model,
    p: &[f64],
    q: &[f64],
    u: &[f64],
    ud: &[f64],
    gravity: bool,
) -> DVector<f64> {
    let n = model.links.len();
    let mut w = vec![Vector3::zeros(); n];
    let mut v = vec![Vector3::zeros(); n];
    let mut wd = vec![Vector3::zeros(); n];
    let mut vd = vec![Vector3::zeros(); n];
    // Root: the spatial acceleration (ω̇, v̇) of the base (body-frame coordinates), gravity as a
    // fictitious upward acceleration.
    w[0] = Vector3::new(u[3], u[4], u[5]);
    v[0] = Vector3::new(u[0], u[1], u[2]);
    wd[0] = Vector3::new(ud[3], ud[4], ud[5]);
    vd[0] = Vector3::new(ud[0], ud[1], ud[2]);
    if gravity {
        vd[0] -= gravity_in_base(model, q, p);
    }
    let mut nf = vec![(Vector3::zeros(), Vector3::zeros()); n];
    for i in 0..n {
        if let Some(m) = &model.links[i].mount {
            let (r, c) = joint_transform(model, i, q, p);
            let rt = r.transpose();
            let pi = m.parent;
            // X V_parent, X A_parent (spatial transform into the child frame).
            let wi = rt * w[pi];
            let vi = rt * (v[pi] + w[pi].cross(&c));
            let wdi = rt * wd[pi];
            let vdi = rt * (vd[pi] + wd[pi].cross(&c));
            let e = Vector3::from(m.joint.axis);
            let (sw, sv) = match m.joint.kind {
                JointKind::Revolute { .. } => (e, Vector3::zeros()),
                JointKind::Prismatic { .. } => (Vector3::zeros(), e),
                JointKind::Fixed => (Vector3::zeros(), Vector3::zeros()),
            };
            let (qd, qdd) = m.joint.speed().map_or((0.0, 0.0), |s| (u[s], ud[s]));
            w[i] = wi + sw * qd;
            v[i] = vi + sv * qd;
            // A = X A_p + S q̈ + V × (S q̇)   (motion cross product).
            let (cw, cv) = (sw * qd, sv * qd);
            wd[i] = wdi + sw * qdd + w[i].cross(&cw);
            vd[i] = vdi + sv * qdd + w[i].cross(&cv) + v[i].cross(&cw);
        }
        let (mass, h, j) = body(model, i, p);
        // Momentum (n, f) = I V with I = [[J, [h]×], [−[h]×, m]]; force I A + V ×* (I V).
        let (hn, hf) = (j * w[i] + h.cross(&v[i]), mass * v[i] - h.cross(&w[i]));
        let (an, af) = (j * wd[i] + h.cross(&vd[i]), mass * vd[i] - h.cross(&wd[i]));
        nf[i] = (an + w[i].cross(&hn) + v[i].cross(&hf), af + w[i].cross(&hf));
    }
    let mut tau = DVector::zeros(model.dof());
    for i in (1..n).rev() {
        let m = model.links[i].mount.as_ref().expect("mounted");
        let (nn, ff) = nf[i];
        if let Some(s) = m.joint.speed() {
            let e = Vector3::from(m.joint.axis);
            tau[s] = match m.joint.kind {
                JointKind::Prismatic { .. } => e.dot(&ff),
                _ => e.dot(&nn),
            };
        }
        let (r, c) = joint_transform(model, i, q, p);
        let (rn, rf) = (r * nn, r * ff);
        nf[m.parent].0 += rn + c.cross(&rf);
        nf[m.parent].1 += rf;
    }
    for k in 0..3 {
        tau[k] = nf[0].1[k];
        tau[3 + k] = nf[0].0[k];
    }
    tau
}

/// The mass matrix by columns of the recursion: `M eᵢ = τ(q, 0, eᵢ)` without gravity.
pub fn mass_matrix(model: &Model, p: &[f64], q: &[f64]) -> DMatrix<f64> {
    let n = model.dof();
    let zero = vec![0.0; n];
    let mut m = DMatrix::zeros(n, n);
    for i in 0..n {
        let mut e = zero.clone();
        e[i] = 1.0;
        m.set_column(i, &rnea(model, p, q, &zero, &e, false));
    }
    m
}

/// Potential energy `V = −Σ m_k g · p_Gk` (world frame, origin at the world's origin).
pub fn potential_energy(model: &Model, p: &[f64], q: &[f64]) -> f64 {
    let g = p[model.gravity.symbol] * Vector3::from(model.gravity.direction);
    let r0 = base_rotation(q);
    let p0 = Vector3::new(q[0], q[1], q[2]);
    let poses = link_poses(model, q, p);
    let mut v = 0.0;
    for (l, (r, o)) in poses.iter().enumerate() {
        let (mass, h, _) = body(model, l, p);
        // m p_G = m (p0 + R0 o) + R0 r h
        let mp = mass * (p0 + r0 * o) + r0 * r * h;
        v -= g.dot(&mp);
    }
    v
}

/// Kinetic energy `Σ ½ Vᵀ I V` of the bodies at `(q, u)`.
pub fn kinetic_energy(model: &Model, p: &[f64], q: &[f64], u: &[f64]) -> f64 {
    // τ(q, u, 0) without gravity has the velocities; recompute them here directly.
    let n = model.links.len();
    let mut w = vec![Vector3::zeros(); n];
    let mut v = vec![Vector3::zeros(); n];
    w[0] = Vector3::new(u[3], u[4], u[5]);
    v[0] = Vector3::new(u[0], u[1], u[2]);
    let mut t = 0.0;
    for i in 0..n {
        if let Some(m) = &model.links[i].mount {
            let (r, c) = joint_transform(model, i, q, p);
            let rt = r.transpose();
            let pi = m.parent;
            w[i] = rt * w[pi];
            v[i] = rt * (v[pi] + w[pi].cross(&c));
            let e = Vector3::from(m.joint.axis);
            if let Some(s) = m.joint.speed() {
                match m.joint.kind {
                    JointKind::Prismatic { .. } => v[i] += e * u[s],
                    _ => w[i] += e * u[s],
                }
            }
        }
        let (mass, h, j) = body(model, i, p);
        t += 0.5 * (w[i].dot(&(j * w[i])) + mass * v[i].dot(&v[i])) + v[i].dot(&w[i].cross(&h));
    }
    t
}

/// A random configuration: position in a box, a random unit quaternion, joint coordinates
/// uniform in `[-π, π]` (prismatic ones in `[-0.3, 0.3]`).
pub fn random_configuration(model: &Model, uniform: &mut dyn FnMut() -> f64) -> Vec<f64> {
    let mut q = vec![0.0; model.nq()];
    for k in 0..3 {
        q[k] = 2.0 * uniform() - 1.0;
    }
    let quat = UnitQuaternion::from_quaternion(Quaternion::new(
        uniform() - 0.5,
        uniform() - 0.5,
        uniform() - 0.5,
        uniform() - 0.5,
    ));
    q[3] = quat.i;
    q[4] = quat.j;
    q[5] = quat.k;
    q[6] = quat.w;
    for s in 6..model.independent_dof() {
        let prismatic = model
            .links
            .iter()
            .filter_map(|l| l.joint())
            .any(|j| matches!(j.kind, JointKind::Prismatic { speed } if speed == s));
        let range = if prismatic { 0.3 } else { std::f64::consts::PI };
        q[model.coordinate_index(s)] = range * (2.0 * uniform() - 1.0);
    }
    q
}

/// `q ⊕ δ` to first order exactly as the tangent space of Pinocchio's free flyer: the base moves
/// by the SE(3) exponential of the body twist `δ[0..6]`, the joints add `δ[6..]`.
pub fn integrate(model: &Model, q: &[f64], delta: &[f64]) -> Vec<f64> {
    let mut out = q.to_vec();
    let r = base_rotation(q);
    let quat = UnitQuaternion::new_unchecked(Quaternion::new(q[6], q[3], q[4], q[5]));
    let v = Vector3::new(delta[0], delta[1], delta[2]);
    let w = Vector3::new(delta[3], delta[4], delta[5]);
    // SE(3) exponential: rotation exp(ω), translation V(ω) v.
    let th = w.norm();
    let wx = w.cross_matrix();
    let vmat = if th < 1e-12 {
        Matrix3::identity() + 0.5 * wx
    } else {
        Matrix3::identity()
            + (1.0 - th.cos()) / (th * th) * wx
            + (th - th.sin()) / (th * th * th) * wx * wx
    };
    let dp = r * vmat * v;
    for k in 0..3 {
        out[k] += dp[k];
    }
    let nq = quat * UnitQuaternion::from_scaled_axis(w);
    out[3] = nq.i;
    out[4] = nq.j;
    out[5] = nq.k;
    out[6] = nq.w;
    for s in 6..model.independent_dof() {
        out[model.coordinate_index(s)] += delta[s];
    }
    out
}

/// The centre of mass in the world frame.
pub fn center_of_mass(model: &Model, p: &[f64], q: &[f64]) -> Vector3<f64> {
    let r0 = base_rotation(q);
    let p0 = Vector3::new(q[0], q[1], q[2]);
    let (mut m, mut mp) = (0.0, Vector3::zeros());
    for (l, (r, o)) in link_poses(model, q, p).iter().enumerate() {
        let (mass, h, _) = body(model, l, p);
        m += mass;
        mp += mass * (p0 + r0 * o) + r0 * r * h;
    }
    mp / m
}

/// The whole robot's momentum at `(q, u)` in world axes: linear `P` and angular about the
/// centre of mass `L_G`, summed over the bodies.
pub fn centroidal_momentum(
    model: &Model,
    p: &[f64],
    q: &[f64],
    u: &[f64],
) -> (Vector3<f64>, Vector3<f64>) {
    let n = model.links.len();
    let r0 = base_rotation(q);
    let p0 = Vector3::new(q[0], q[1], q[2]);
    let poses = link_poses(model, q, p);
    let mut w = vec![Vector3::zeros(); n];
    let mut v = vec![Vector3::zeros(); n];
    w[0] = Vector3::new(u[3], u[4], u[5]);
    v[0] = Vector3::new(u[0], u[1], u[2]);
    let g = center_of_mass(model, p, q);
    let (mut lin, mut ang) = (Vector3::zeros(), Vector3::zeros());
    for i in 0..n {
        if let Some(m) = &model.links[i].mount {
            let (r, c) = joint_transform(model, i, q, p);
            let rt = r.transpose();
            let pi = m.parent;
            w[i] = rt * w[pi];
            v[i] = rt * (v[pi] + w[pi].cross(&c));
            let e = Vector3::from(m.joint.axis);
            if let Some(s) = m.joint.speed() {
                match m.joint.kind {
                    JointKind::Prismatic { .. } => v[i] += e * u[s],
                    _ => w[i] += e * u[s],
                }
            }
        }
        let (mass, h, j) = body(model, i, p);
        // Body momentum about its origin, in its frame: (J ω + h × v, m v − h × ω).
        let (nb, fb) = (j * w[i] + h.cross(&v[i]), mass * v[i] - h.cross(&w[i]));
        let rw = r0 * poses[i].0;
        let origin = p0 + r0 * poses[i].1;
        let (nw, fw) = (rw * nb, rw * fb);
        lin += fw;
        ang += nw + (origin - g).cross(&fw);
    }
    (lin, ang)
}
