//! The mass matrix from the kinetic energy, for validation only: single bodies may carry no
//! inertia in some direction (point masses, rods, zero-mass rotors), so the loaders check that
//! the mass matrix as a whole is positive definite.
//!
//! The kinetic energy is `T = ½ Σ_b Vᵀ I_b V` with each body's spatial velocity `V = (ω, v₀)`
//! (`v₀`: the velocity of the body point at the base frame's origin) and its spatial inertia
//! about that origin, from Khalil's parameters (mass `m`, first moment `MS`, inertia `J` about
//! the frame origin `o`, all rotated into the base frame):
//! `I_b = [[J_O, [h]×], [−[h]×, m·1]]` with `h = m·o + MS` and
//! `J_O = J − [o]×[MS]× − [MS]×[o]× − m [o]×[o]×`. A joint's motion is the spatial vector
//! `S = (e, o_j × e)` (revolute about the world axis `e` through `o_j`) or `(0, e)` (prismatic);
//! a wheeled base's `ẋ`, `ψ̇` move everything by `(0, x̂)` and `(ẑ, 0)` and add the wheel terms;
//! a floating base's `v`, `ω` (in the base frame) move everything by `(0, eᵢ)` and `(eᵢ, 0)`,
//! and its base frame's body counts.
//! Then `M[a, b] = S_aᵀ I_c(b) S_b` for `a` on the path from `b` to the base, with `I_c(b)` the
//! composite inertia of everything `b` moves (the composite-rigid-body algorithm: O(n·depth)).
//! This is independent of the generator and of `kanegen-reference` (which builds M from inverse
//! dynamics); a test compares the three.

use nalgebra::{DMatrix, Matrix3, Matrix6, Vector3, Vector6};

use crate::error::ModelErrorKind as K;
use crate::ir::{Body, JointKind, Model};

/// Pose of every link in the base frame for coordinates `q` (indexed like the speeds) and
/// parameter values `p`: rotation and origin.
fn poses(model: &Model, q: &[f64], p: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
    let mut out = vec![(Matrix3::identity(), Vector3::zeros()); model.links.len()];
    for (i, _, m) in model.mounted_links() {
        let (rp, pp) = out[m.parent];
        let j = &m.joint;
        let a = Matrix3::from_fn(|r, c| j.rotation[r][c]);
        let e = Vector3::from(j.axis);
        let mut offset = Vector3::from_fn(|r, _| j.translation[r].eval(p));
        let mut turn = Matrix3::identity();
        match j.kind {
            JointKind::Revolute { speed } => {
                turn = nalgebra::Rotation3::from_axis_angle(
                    &nalgebra::Unit::new_normalize(e),
                    q[speed],
                )
                .into_inner();
            }
            JointKind::Prismatic { speed } => offset += a * e * q[speed],
            JointKind::Fixed => {}
        }
        out[i] = (rp * a * turn, pp + rp * offset);
    }
    out
}

/// The spatial inertia about the base origin of body `b` whose frame has the pose `(r, o)`.
fn spatial_inertia(b: &Body, (r, o): (Matrix3<f64>, Vector3<f64>), p: &[f64]) -> Matrix6<f64> {
    let m = p[b.mass];
    let ms = r * Vector3::from_fn(|k, _| p[b.first_moment[k]]);
    let [xx, xy, xz, yy, yz, zz] = b.inertia.map(|k| p[k]);
    let j = r * Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz) * r.transpose();
    let (ox, msx) = (o.cross_matrix(), ms.cross_matrix());
    let j_o = j - ox * msx - msx * ox - ox * ox * m;
    let hx = (o * m + ms).cross_matrix();
    let mut i = Matrix6::zeros();
    i.fixed_view_mut::<3, 3>(0, 0).copy_from(&j_o);
    i.fixed_view_mut::<3, 3>(0, 3).copy_from(&hx);
    i.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hx));
    i.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() * m));
    i
}

/// `(ω, v)` as one spatial vector.
fn spatial(w: Vector3<f64>, v: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(w.x, w.y, w.z, v.x, v.y, v.z)
}

/// The mass matrix at coordinates `q` (indexed like the speeds; a wheeled base's `x`, `psi`
/// entries and a floating base's first six are not read) for parameter values `p`, from the kinetic energy by the
/// composite-rigid-body algorithm (this crate's `src/mass_matrix.rs` describes it). Used by
/// validation; the generated code and `kanegen-reference` compute M independently.
pub fn kinetic_energy_mass_matrix(model: &Model, q: &[f64], p: &[f64]) -> DMatrix<f64> {
    let n = model.dof();
    let pose = poses(model, q, p);
    // Composite inertias: each link's body plus everything below it (links are parents first).
    let mut ic: Vec<Matrix6<f64>> = model
        .links
        .iter()
        .zip(&pose)
        .map(|(l, &x)| {
            l.body
                .as_ref()
                .map_or(Matrix6::zeros(), |b| spatial_inertia(b, x, p))
        })
        .collect();
    for (i, link) in model.links.iter().enumerate().rev() {
        if let Some(parent) = link.parent() {
            let child = ic[i];
            ic[parent] += child;
        }
    }
    // The motion of each moving joint (and of the base's quasi-velocities).
    let mut motion: Vec<Option<(usize, Vector6<f64>)>> = vec![None; model.links.len()];
    for (i, _, m) in model.mounted_links() {
        let (r, o) = pose[i];
        let e = r * Vector3::from(m.joint.axis);
        motion[i] = match m.joint.kind {
            JointKind::Revolute { speed } => Some((speed, spatial(e, o.cross(&e)))),
            JointKind::Prismatic { speed } => Some((speed, spatial(Vector3::zeros(), e))),
            JointKind::Fixed => None,
        };
    }
    let mut base: Vec<(usize, Vector6<f64>)> = model.wheeled_base().map_or(Vec::new(), |w| {
        vec![
            (w.x_speed, spatial(Vector3::zeros(), Vector3::x())),
            (w.psi_speed, spatial(Vector3::z(), Vector3::zeros())),
        ]
    });
    if model.is_floating() {
        let e = [Vector3::x(), Vector3::y(), Vector3::z()];
        base.extend((0..3).map(|i| (i, spatial(Vector3::zeros(), e[i]))));
        base.extend((0..3).map(|i| (3 + i, spatial(e[i], Vector3::zeros()))));
    }
    let mut mm = DMatrix::zeros(n, n);
    let mut set = |a: usize, b: usize, v: f64| {
        mm[(a, b)] = v;
        mm[(b, a)] = v;
    };
    for (i, _, _) in model.mounted_links() {
        let Some((si, s)) = motion[i] else { continue };
        let f = ic[i] * s;
        for (k, _) in model.path_to_base(i) {
            if let Some((sk, sv)) = motion[k] {
                set(sk, si, sv.dot(&f));
            }
        }
        for &(sb, sv) in &base {
            set(sb, si, sv.dot(&f));
        }
    }
    for &(sa, va) in &base {
        for &(sb, vb) in &base {
            set(sa, sb, va.dot(&(ic[0] * vb)));
        }
    }
    if let Some(w) = model.wheeled_base() {
        let (r, l, mw) = (p[w.radius], p[w.track], p[w.wheel_mass]);
        let (yy, zz) = (p[w.wheel_axle_inertia], p[w.wheel_diametral_inertia]);
        mm[(w.x_speed, w.x_speed)] += 2.0 * mw + 2.0 * yy / (r * r);
        mm[(w.psi_speed, w.psi_speed)] += mw * l * l / 2.0 + yy * l * l / (2.0 * r * r) + 2.0 * zz;
    }
    mm
}

/// Relative size below which a Cholesky pivot counts as zero.
const PIVOT_TOLERANCE: f64 = 1e-10;

/// The first speed whose Cholesky pivot of `mm` vanishes (relative to the largest diagonal
/// entry), with the pivot; `None` if `mm` is positive definite.
fn vanishing_pivot(mm: &DMatrix<f64>) -> Option<(usize, f64)> {
    let n = mm.nrows();
    let scale = (0..n).fold(0.0f64, |s, i| s.max(mm[(i, i)].abs()));
    let mut l = DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        let d = mm[(j, j)] - (0..j).map(|k| l[(j, k)] * l[(j, k)]).sum::<f64>();
        if d.is_nan() || d <= PIVOT_TOLERANCE * scale {
            return Some((j, d));
        }
        l[(j, j)] = d.sqrt();
        for i in j + 1..n {
            let s = mm[(i, j)] - (0..j).map(|k| l[(i, k)] * l[(j, k)]).sum::<f64>();
            l[(i, j)] = s / l[(j, j)];
        }
    }
    None
}

/// Checks that the mass matrix is positive definite at two generic configurations (fixed
/// pseudo-random angles in [−π, π)). A model whose M is singular there is singular almost
/// everywhere: some speed moves nothing (a massless subtree, a point mass on its own axis).
pub(crate) fn check_positive_definite(model: &Model) -> Result<(), K> {
    let p = model.param_values();
    let n = model.dof();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut found = None;
    for _ in 0..2 {
        let q: Vec<f64> = (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * std::f64::consts::TAU
            })
            .collect();
        match vanishing_pivot(&kinetic_energy_mass_matrix(model, &q, &p)) {
            None => return Ok(()),
            Some(v) => found = found.or(Some((v, q))),
        }
    }
    let Some(((s, pivot), q)) = found else {
        return Ok(());
    };
    Err(K::SingularMassMatrix {
        speed: model.speeds[s].name.clone(),
        detail: format!("pivot {pivot:.3e} at q = {q:.3?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A planar two-link arm of point masses m1, m2 at the link ends (lengths l1, l2), about
    /// parallel axes: M = [[m1 l1² + m2 (l1² + l2² + 2 l1 l2 cos q2), m2 (l2² + l1 l2 cos q2)],
    /// [·, m2 l2²]].
    #[test]
    fn point_mass_arm_matches_the_textbook_mass_matrix() {
        let text = r#"<robot name="arm"><link name="b"/>
          <link name="l1"><inertial><origin xyz="0.5 0 0"/><mass value="2"/>
            <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
          <link name="l2"><inertial><origin xyz="0.3 0 0"/><mass value="1.5"/>
            <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
          <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><axis xyz="0 0 1"/></joint>
          <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
            <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/></joint></robot>"#;
        let model = Model::from_urdf_str(text, "arm.urdf", &Default::default()).unwrap();
        let (m1, m2, l1, l2, q2) = (2.0, 1.5, 0.5, 0.3, 0.7f64);
        let mm = kinetic_energy_mass_matrix(&model, &[0.4, q2], &model.param_values());
        let c = q2.cos();
        let expected = [
            m1 * l1 * l1 + m2 * (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * c),
            m2 * (l2 * l2 + l1 * l2 * c),
            m2 * l2 * l2,
        ];
        for (got, want) in [mm[(0, 0)], mm[(0, 1)], mm[(1, 1)]]
            .into_iter()
            .zip(expected)
        {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        assert_eq!(mm[(0, 1)], mm[(1, 0)]);
    }
}
