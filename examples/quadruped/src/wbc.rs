//! The whole-body inverse-dynamics QP, solved with `clarabel`.
//!
//! Unknowns `x = [u̇ (18), λ (12)]` (the four feet's contact forces, world axes). Constraints:
//!
//! * the base's six rows of the dynamics, `M_b u̇ + h_b = J_bᵀ λ` (no actuator acts on the base);
//! * the feet do not accelerate, `J_c u̇ + J̇_c u = −k_d J_c u`;
//! * each foot's force in its friction cone, `‖(λx, λy)‖ ≤ μ λz` (a second-order cone), and
//!   `λz ≥ f_min`;
//! * joint torques `τ = (M u̇ + h − J_cᵀ λ)_joints` within `±τ_max`.
//!
//! Cost: weighted least squares of the tasks — the centre of mass's acceleration through the
//! linear rows of the centroidal momentum (`A_G,lin u̇ + (Ȧ_G u)_lin = m c̈_des`), the angular
//! momentum damped (`A_G,ang u̇ + (Ȧ_G u)_ang = −k_L L`), the base level (its angular
//! acceleration), a posture for the joints, and small forces.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use nalgebra::{SMatrix, SVector, Vector3};

use crate::robot::{DOF, Q, U, WholeBodyModel};

/// Joints.
pub const JOINTS: usize = DOF - 6;
/// Contact rows: four point contacts.
pub const ROWS: usize = 12;
const X: usize = DOF + ROWS;

/// The controller's gains, weights and limits.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Friction coefficient of the cones.
    pub mu: f64,
    /// Smallest normal force per foot (N).
    pub min_normal: f64,
    /// Joint torque limit (N m), every joint.
    pub torque_limit: f64,
    /// Centre-of-mass task: stiffness (1/s²) and damping (1/s).
    pub com_gains: (f64, f64),
    /// Base orientation task: stiffness and damping.
    pub orientation_gains: (f64, f64),
    /// Joint posture task: stiffness and damping.
    pub posture_gains: (f64, f64),
    /// Angular momentum damping `k_L` (1/s).
    pub angular_momentum_gain: f64,
    /// Contact velocity damping `k_d` in the feet's acceleration constraint (1/s).
    pub contact_damping: f64,
    /// Task weights: centre of mass, angular momentum, orientation, posture, forces.
    pub weights: [f64; 5],
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mu: 0.6,
            min_normal: 0.5,
            // Solo 12's actuators: 0.025 N m/A × 12 A × gear ratio 9.
            torque_limit: 2.7,
            com_gains: (400.0, 40.0),
            orientation_gains: (400.0, 40.0),
            posture_gains: (100.0, 20.0),
            angular_momentum_gain: 10.0,
            contact_damping: 50.0,
            weights: [100.0, 1.0, 10.0, 1e-3, 1e-6],
        }
    }
}

/// What the centre of mass should do now.
#[derive(Debug, Clone, Copy)]
pub struct ComTarget {
    /// Position (world).
    pub position: Vector3<f64>,
    /// Velocity.
    pub velocity: Vector3<f64>,
    /// Acceleration (feed-forward).
    pub acceleration: Vector3<f64>,
}

/// The frames the controller uses.
#[derive(Debug, Clone, Copy)]
pub struct Frames<F> {
    /// The four feet (point contacts), in the order of the contact rows.
    pub feet: [F; 4],
    /// The base link (kept level).
    pub base: F,
}

/// The QP's answer.
#[derive(Debug, Clone, Copy)]
pub struct Command {
    /// Planned `u̇`.
    pub ud: U,
    /// Planned contact forces.
    pub lambda: SVector<f64, ROWS>,
    /// Joint torques to apply.
    pub tau: SVector<f64, JOINTS>,
}

/// The QP had no solution (infeasible, or the solver stopped).
#[derive(Debug, Clone)]
pub struct QpError(pub String);

impl std::fmt::Display for QpError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "whole-body QP: {}", self.0)
    }
}

impl std::error::Error for QpError {}

/// The contact rows of the four feet: `(J_c, J̇_c u)`.
pub fn contact_terms<R: WholeBodyModel>(
    robot: &R,
    feet: &[R::Frame; 4],
    q: &Q,
    u: &U,
) -> (SMatrix<f64, ROWS, DOF>, SVector<f64, ROWS>) {
    let mut j = SMatrix::<f64, ROWS, DOF>::zeros();
    let mut b = SVector::<f64, ROWS>::zeros();
    for (k, &foot) in feet.iter().enumerate() {
        let jf = robot.frame_jacobian(q, foot);
        let bf = robot.frame_bias_acceleration(q, u, foot);
        j.fixed_rows_mut::<3>(3 * k)
            .copy_from(&jf.fixed_rows::<3>(0));
        b.fixed_rows_mut::<3>(3 * k)
            .copy_from(&bf.fixed_rows::<3>(0));
    }
    (j, b)
}

/// One least-squares task `‖A x − b‖²` with weight `w`, added to `P` (upper triangle used)
/// and `p`.
fn add_task(p_mat: &mut [[f64; X]; X], p_vec: &mut [f64; X], w: f64, rows: &[([f64; X], f64)]) {
    for (a, b) in rows {
        for i in 0..X {
            if a[i] == 0.0 {
                continue;
            }
            p_vec[i] -= w * a[i] * b;
            for j in i..X {
                p_mat[i][j] += w * a[i] * a[j];
            }
        }
    }
}

fn row_of_ud(v: impl Iterator<Item = f64>) -> [f64; X] {
    let mut r = [0.0; X];
    for (x, y) in r.iter_mut().zip(v) {
        *x = y;
    }
    r
}

/// Solves the QP at `(q, u)` for the centre-of-mass target `com` and the joint posture
/// `posture`.
pub fn solve<R: WholeBodyModel>(
    robot: &R,
    frames: &Frames<R::Frame>,
    q: &Q,
    u: &U,
    com: &ComTarget,
    posture: &SVector<f64, JOINTS>,
    s: &Settings,
) -> Result<Command, QpError> {
    let m = robot.mass_matrix(q);
    let h = robot.nonlinear_effects(q, u);
    let (jc, jcu) = contact_terms(robot, &frames.feet, q, u);
    let ag = robot.centroidal_momentum_matrix(q);
    let agu = robot.centroidal_momentum_bias(q, u);
    let mass = m[(0, 0)];
    let c = robot.center_of_mass(q);

    // Cost.
    let mut pm = [[0.0; X]; X];
    let mut pv = [0.0; X];
    let momentum = ag * u;
    let com_vel = Vector3::new(momentum[0], momentum[1], momentum[2]) / mass;
    let (kp, kd) = s.com_gains;
    let acc = com.acceleration + (com.position - c) * kp + (com.velocity - com_vel) * kd;
    let com_rows: Vec<_> = (0..3)
        .map(|i| (row_of_ud(ag.row(i).iter().copied()), mass * acc[i] - agu[i]))
        .collect();
    add_task(&mut pm, &mut pv, s.weights[0], &com_rows);
    let ang_rows: Vec<_> = (3..6)
        .map(|i| {
            let target = -s.angular_momentum_gain * momentum[i] - agu[i];
            (row_of_ud(ag.row(i).iter().copied()), target)
        })
        .collect();
    add_task(&mut pm, &mut pv, s.weights[1], &ang_rows);
    // Base level: ω̇_des = −k_p φ − k_d ω (world), φ the base's rotation vector.
    let phi = kanegen_reference::se3::quaternion_log([q[3], q[4], q[5], q[6]]);
    let jb = robot.frame_jacobian(q, frames.base);
    let bb = robot.frame_bias_acceleration(q, u, frames.base);
    let omega = jb.fixed_rows::<3>(3) * u;
    let (okp, okd) = s.orientation_gains;
    let wd = -phi * okp - omega * okd;
    let orient_rows: Vec<_> = (0..3)
        .map(|i| (row_of_ud(jb.row(3 + i).iter().copied()), wd[i] - bb[3 + i]))
        .collect();
    add_task(&mut pm, &mut pv, s.weights[2], &orient_rows);
    let (pkp, pkd) = s.posture_gains;
    let posture_rows: Vec<_> = (0..JOINTS)
        .map(|j| {
            let mut r = [0.0; X];
            r[6 + j] = 1.0;
            (r, pkp * (posture[j] - q[7 + j]) - pkd * u[6 + j])
        })
        .collect();
    add_task(&mut pm, &mut pv, s.weights[3], &posture_rows);
    for (i, row) in pm.iter_mut().enumerate().skip(DOF) {
        row[i] += s.weights[4];
    }

    // Constraints A x + s = b, s in the cones, rows in the order of the cones.
    let mut a_rows: Vec<Vec<f64>> = Vec::new();
    let mut b: Vec<f64> = Vec::new();
    let jct = jc.transpose();
    for i in 0..6 {
        let mut r: Vec<f64> = m.row(i).iter().copied().collect();
        r.extend(jct.row(i).iter().map(|x| -x));
        a_rows.push(r);
        b.push(-h[i]);
    }
    let ju = jc * u;
    for i in 0..ROWS {
        let mut r: Vec<f64> = jc.row(i).iter().copied().collect();
        r.extend([0.0; ROWS]);
        a_rows.push(r);
        b.push(-jcu[i] - s.contact_damping * ju[i]);
    }
    let unit = |k: usize, scale: f64| {
        let mut r = vec![0.0; X];
        r[k] = scale;
        r
    };
    for foot in 0..4 {
        a_rows.push(unit(DOF + 3 * foot + 2, -1.0));
        b.push(-s.min_normal);
    }
    for j in 0..JOINTS {
        let mut r: Vec<f64> = m.row(6 + j).iter().copied().collect();
        r.extend(jct.row(6 + j).iter().map(|x| -x));
        let neg: Vec<f64> = r.iter().map(|x| -x).collect();
        a_rows.push(r);
        b.push(s.torque_limit - h[6 + j]);
        a_rows.push(neg);
        b.push(s.torque_limit + h[6 + j]);
    }
    for foot in 0..4 {
        let k = DOF + 3 * foot;
        a_rows.push(unit(k + 2, -s.mu));
        a_rows.push(unit(k, -1.0));
        a_rows.push(unit(k + 1, -1.0));
        b.extend([0.0; 3]);
    }
    let mut cones = vec![
        SupportedConeT::ZeroConeT(6 + ROWS),
        SupportedConeT::NonnegativeConeT(4 + 2 * JOINTS),
    ];
    cones.extend((0..4).map(|_| SupportedConeT::SecondOrderConeT(3)));

    let p_csc = CscMatrix::from(pm.iter().map(|r| r.iter()));
    let a_csc = CscMatrix::from(&a_rows);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| QpError(e.to_string()))?;
    let mut solver = DefaultSolver::new(&p_csc, &pv, &a_csc, &b, &cones, settings)
        .map_err(|e| QpError(e.to_string()))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {}
        other => return Err(QpError(format!("{other:?}"))),
    }
    let x = &solver.solution.x;
    let ud = U::from_iterator(x[..DOF].iter().copied());
    let lambda = SVector::<f64, ROWS>::from_iterator(x[DOF..].iter().copied());
    let full = m * ud + h - jct * lambda;
    Ok(Command {
        ud,
        lambda,
        tau: full.fixed_rows::<JOINTS>(6).into_owned(),
    })
}
