//! The closed loop: every `dt` the QP ([`crate::wbc`]) picks joint torques, and the
//! contact-constrained forward dynamics (`kanegen_runtime::contact`) advances the robot by
//! semi-implicit Euler on its configuration space (`u ← u + u̇ dt`, `q ← q ⊕ u dt`).

use kanegen_runtime::contact::{ContactJacobian, ContactSettings, constrained_forward_dynamics};
use nalgebra::{SVector, Vector3};

use crate::robot::{DOF, Q, U, WholeBodyModel};
use crate::wbc::{self, ComTarget, Frames, JOINTS, ROWS, Settings};

/// The feet of Solo 12, in the order of the contact rows.
pub const FEET: [&str; 4] = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"];
/// The base link.
pub const BASE: &str = "base_link";
/// Joint posture of the stance (hip abduction, hip flexion, knee per leg: FL, FR, HL, HR).
pub const POSTURE: [f64; JOINTS] = [
    0.1, 0.8, -1.6, -0.1, 0.8, -1.6, 0.1, -0.8, 1.6, -0.1, -0.8, 1.6,
];

/// The motion asked for: the centre of mass along a horizontal circle through its start point.
#[derive(Debug, Clone, Copy)]
pub struct Scenario {
    /// Circle radius (m).
    pub radius: f64,
    /// Time per turn (s).
    pub period: f64,
    /// The radius grows from 0 over this time (s), with a continuous acceleration.
    pub ramp: f64,
    /// Simulated time (s).
    pub duration: f64,
    /// Control and integration step (s).
    pub dt: f64,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            radius: 0.03,
            period: 1.5,
            ramp: 1.0,
            duration: 4.5,
            dt: 1e-3,
        }
    }
}

impl Scenario {
    /// The reference offset from the start point at time `t`.
    fn offset(&self, t: f64) -> Vector3<f64> {
        let s = (t / self.ramp).clamp(0.0, 1.0);
        // Smootherstep: position, velocity and acceleration continuous at both ends.
        let r = self.radius * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        let a = 2.0 * std::f64::consts::PI * t / self.period;
        Vector3::new(r * (a.cos() - 1.0), r * a.sin(), 0.0)
    }

    /// Position, velocity and acceleration of the reference at `t` (derivatives by central
    /// differences of the offset from the start point, exact to ~1e-8).
    pub fn target(&self, start: &Vector3<f64>, t: f64) -> ComTarget {
        let h = 1e-4;
        let (m, z, p) = (self.offset(t - h), self.offset(t), self.offset(t + h));
        ComTarget {
            position: start + z,
            velocity: (p - m) / (2.0 * h),
            acceleration: (p - z * 2.0 + m) / (h * h),
        }
    }
}

/// One sample of the simulation.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// Centre of mass.
    pub com: Vector3<f64>,
    /// Its reference.
    pub com_ref: Vector3<f64>,
    /// Contact forces of the simulation (the four feet, world axes).
    pub lambda: SVector<f64, ROWS>,
    /// Joint torques applied.
    pub tau: SVector<f64, JOINTS>,
    /// Largest drift of a foot from its touchdown point (m).
    pub foot_drift: f64,
}

/// The stance: [`POSTURE`], base level, at the height that puts the feet on the ground `z = 0`.
pub fn stance<R: WholeBodyModel>(robot: &R, feet: &[R::Frame; 4]) -> Q {
    let mut q = Q::zeros();
    q[6] = 1.0;
    q.fixed_rows_mut::<JOINTS>(7).copy_from_slice(&POSTURE);
    let z: f64 = feet
        .iter()
        .map(|&f| robot.frame_position(&q, f).z)
        .sum::<f64>()
        / 4.0;
    q[2] = -z;
    q
}

/// Looks the feet and the base up.
pub fn frames<R: WholeBodyModel>(robot: &R) -> Result<Frames<R::Frame>, String> {
    let find = |name: &str| robot.frame(name).ok_or(format!("no frame `{name}`"));
    Ok(Frames {
        feet: [
            find(FEET[0])?,
            find(FEET[1])?,
            find(FEET[2])?,
            find(FEET[3])?,
        ],
        base: find(BASE)?,
    })
}

/// Runs `scenario` from the stance at rest, with the controller `settings`; contact drift is
/// corrected in the simulation by Baumgarte terms (`k_p = 2500/s²`, `k_d = 100/s`).
pub fn run<R: WholeBodyModel>(
    robot: &R,
    scenario: &Scenario,
    settings: &Settings,
) -> Result<Vec<Sample>, Box<dyn std::error::Error>> {
    let frames = frames(robot)?;
    let feet = frames.feet;
    let mut q = stance(robot, &feet);
    let mut u = U::zeros();
    let touchdown: Vec<Vector3<f64>> = feet.iter().map(|&f| robot.frame_position(&q, f)).collect();
    let start = robot.center_of_mass(&q);
    let posture = SVector::<f64, JOINTS>::from_column_slice(&POSTURE);
    let contact = ContactSettings {
        damping: 0.0,
        baumgarte_position: 2500.0,
        baumgarte_velocity: 100.0,
    };
    let steps = (scenario.duration / scenario.dt).round() as usize;
    let mut log = Vec::with_capacity(steps);
    for step in 0..steps {
        let t = step as f64 * scenario.dt;
        let target = scenario.target(&start, t);
        let cmd = wbc::solve(robot, &frames, &q, &u, &target, &posture, settings)?;
        // The robot: M u̇ + h = Sᵀτ + J_cᵀλ with the feet held.
        let m = robot.mass_matrix(&q);
        let h = robot.nonlinear_effects(&q, &u);
        let (jc, bias) = wbc::contact_terms(robot, &feet, &q, &u);
        let mut error = SVector::<f64, ROWS>::zeros();
        let mut drift: f64 = 0.0;
        for (k, &f) in feet.iter().enumerate() {
            let e = robot.frame_position(&q, f) - touchdown[k];
            drift = drift.max(e.norm());
            error.fixed_rows_mut::<3>(3 * k).copy_from(&e);
        }
        let c = ContactJacobian::<f64, DOF, ROWS> {
            jacobian: jc,
            bias,
            velocity: jc * u,
            position_error: error,
        };
        let mut f = U::zeros();
        f.fixed_rows_mut::<JOINTS>(6).copy_from(&cmd.tau);
        let sol = constrained_forward_dynamics(m, &h, &f, &c, &contact)?;
        log.push(Sample {
            t,
            com: robot.center_of_mass(&q),
            com_ref: target.position,
            lambda: sol.lambda,
            tau: cmd.tau,
            foot_drift: drift,
        });
        u += sol.ud * scenario.dt;
        q = robot.integrate(&q, &u, scenario.dt);
    }
    Ok(log)
}

/// Figures of merit of a run.
#[derive(Debug, Clone, Copy)]
pub struct Summary {
    /// Largest centre-of-mass error (m) once the circle has its full radius.
    pub max_com_error: f64,
    /// Root-mean-square of the same.
    pub rms_com_error: f64,
    /// Largest `‖λ_t‖ / λ_n` over feet and time.
    pub max_friction_ratio: f64,
    /// Smallest normal force (N).
    pub min_normal: f64,
    /// Largest `|τ|` (N m).
    pub max_torque: f64,
    /// Largest foot drift (m).
    pub max_foot_drift: f64,
}

/// Summarises `log` after `settle` seconds.
pub fn summarize(log: &[Sample], settle: f64) -> Summary {
    let mut s = Summary {
        max_com_error: 0.0,
        rms_com_error: 0.0,
        max_friction_ratio: 0.0,
        min_normal: f64::INFINITY,
        max_torque: 0.0,
        max_foot_drift: 0.0,
    };
    let mut n = 0;
    for x in log {
        for k in 0..4 {
            let (fx, fy, fz) = (x.lambda[3 * k], x.lambda[3 * k + 1], x.lambda[3 * k + 2]);
            s.min_normal = s.min_normal.min(fz);
            s.max_friction_ratio = s.max_friction_ratio.max(fx.hypot(fy) / fz);
        }
        s.max_torque = s.max_torque.max(x.tau.amax());
        s.max_foot_drift = s.max_foot_drift.max(x.foot_drift);
        if x.t >= settle {
            let e = (x.com - x.com_ref).norm();
            s.max_com_error = s.max_com_error.max(e);
            s.rms_com_error += e * e;
            n += 1;
        }
    }
    s.rms_com_error = (s.rms_com_error / n.max(1) as f64).sqrt();
    s
}
