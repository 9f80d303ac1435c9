//! The floating-base tests' oracle: thin adapters over the independent free-flyer recursion
//! [`kanegen_reference::FreeFlyer`] (written from the spatial-vector formulation, independent of
//! the generator's Kane derivation), in the form the tests call it: free functions of the model,
//! the parameter values and the state. The root is a free flyer laid out as Pinocchio's:
//! `q = [x, y, z, qx, qy, qz, qw, joints]`, `u = [v, ω, joint speeds]` (base frame), gravity
//! along the world's −z (the tests' models all have it so).

#![allow(dead_code)]

use kanegen::model::{JointKind, Model};
use kanegen_reference::FreeFlyer;
use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, UnitQuaternion, Vector3};

fn reference(model: &Model, p: &[f64]) -> FreeFlyer<f64> {
    FreeFlyer::with_params(model, p).expect("a fixed or floating model")
}

/// Rotation base → world of the configuration `q` (unit quaternion `q[3..7]`, `(x, y, z, w)`).
pub fn base_rotation(q: &[f64]) -> Matrix3<f64> {
    kanegen_reference::se3::quaternion_to_rotation([q[3], q[4], q[5], q[6]])
}

/// Per link: its rotation relative to the base frame and its origin in the base frame.
pub fn link_poses(model: &Model, q: &[f64], p: &[f64]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
    let ff = reference(model, p);
    let zero = vec![0.0; ff.dof()];
    let (r0, p0) = ff.base_pose(q);
    ff.frame_states(q, &zero, &zero)
        .iter()
        .map(|s| {
            (
                r0.transpose() * s.rotation,
                r0.transpose() * (s.position - p0),
            )
        })
        .collect()
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
    let ff = reference(model, p);
    let tau = ff.inverse_dynamics(q, u, ud);
    if gravity { tau } else { tau - ff.gravity(q) }
}

/// The mass matrix M(q).
pub fn mass_matrix(model: &Model, p: &[f64], q: &[f64]) -> DMatrix<f64> {
    reference(model, p).mass_matrix(q)
}

/// The potential energy (zero at the world origin).
pub fn potential_energy(model: &Model, p: &[f64], q: &[f64]) -> f64 {
    reference(model, p).potential_energy(q)
}

/// The kinetic energy, summed over the bodies.
pub fn kinetic_energy(model: &Model, p: &[f64], q: &[f64], u: &[f64]) -> f64 {
    reference(model, p).kinetic_energy(q, u)
}

/// A random configuration: base position in [−1, 1)³, a random unit quaternion, joint angles in
/// [−π, π) (prismatic joints in [−0.3, 0.3)).
pub fn random_configuration(model: &Model, uniform: &mut dyn FnMut() -> f64) -> Vec<f64> {
    let mut q = vec![0.0; model.nq()];
    for x in q.iter_mut().take(3) {
        *x = 2.0 * uniform() - 1.0;
    }
    let quat = UnitQuaternion::from_quaternion(Quaternion::new(
        uniform() - 0.5,
        uniform() - 0.5,
        uniform() - 0.5,
        uniform() - 0.5,
    ));
    q[3..7].copy_from_slice(&[quat.i, quat.j, quat.k, quat.w]);
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

/// `q ⊕ δ`: the base moves by the SE(3) exponential of its body twist `δ[0..6]`, the joints by
/// `δ[6..]`.
pub fn integrate(_model: &Model, q: &[f64], delta: &[f64]) -> Vec<f64> {
    kanegen_reference::se3::integrate(q, delta, 1.0)
}

/// The centre of mass in the world frame.
pub fn center_of_mass(model: &Model, p: &[f64], q: &[f64]) -> Vector3<f64> {
    reference(model, p).center_of_mass(q)
}

/// The centroidal momentum `(linear, angular about the centre of mass)` in world axes, summed
/// over the bodies.
pub fn centroidal_momentum(
    model: &Model,
    p: &[f64],
    q: &[f64],
    u: &[f64],
) -> (Vector3<f64>, Vector3<f64>) {
    let h = reference(model, p).centroidal_momentum(q, u);
    (
        Vector3::new(h[0], h[1], h[2]),
        Vector3::new(h[3], h[4], h[5]),
    )
}
