//! LQR balancing of the full 19-speed Krang, from the generated linearization, against the
//! lab's 4-state wheeled-inverted-pendulum LQR.
//!
//! Both controllers run at 1 kHz (torques held between samples, clamped to
//! `hardware::TORQUE_LIMITS` by `saturate`) on the nonlinear generated dynamics (RK4, four
//! steps per sample), from rest with the base pitched `tilt` from upright (the centre of mass
//! ahead of the axle) — a push:
//!
//! * **full LQR**: `Krang::linearize` at the upright pose with the joints' gravity torques
//!   (38 states `[q; u]`, 18 actuators), discretised exactly for the zero-order hold, gain
//!   from the discrete Riccati equation (solved by the structure-preserving doubling
//!   algorithm below), `a = a₀ − K (x − x₀)`: every wheel and joint torque from one law;
//! * **WIP LQR** (the lab's balancing controller, munzir/18h-krang-utils `linearize_wip.cpp`):
//!   states `[θ_COM, θ̇_COM, θ_wheel, θ̇_wheel]`, `Q = diag(300, 96000, 30000, 90000)`,
//!   `R = 500` on the total wheel torque, split equally between the wheels. Its model is the
//!   robot with every joint locked, built from the full model at the upright pose (as the lab
//!   builds it from the full robot: the locked-joint mass matrix of x and q_imu holds the body
//!   mass, `l_g` and `I_yy`; the gravity stiffness `∂g_imu/∂q_imu`); the lab's rotor inertia
//!   term is not modelled. `θ_COM = q_imu − upright_pitch(q)` (exact: all bodies turn with the
//!   base about the axle), `θ_wheel = x / R`. The waist, torso and arm joints are held at the
//!   pose by a computed-torque servo (`Kp = 100 s⁻²`, `Kd = 20 s⁻¹`) standing in for the real
//!   modules' position servos.
//!
//! ```text
//! cargo run --release -p krang-dynamics --features derivatives,fixed-wheels,kinematics --example lqr -- [DIR]
//! ```
//! writes `lqr_pitch.png`, `lqr_position.png`, `lqr_heading.png` and `lqr_torques.png` to DIR
//! (default `target/plots`; the guide's images: `DIR = docs/plots`).

use std::error::Error;
use std::path::{Path, PathBuf};

use krang_dynamics::{ACTUATOR_COUNT, Krang, actuator, index, saturate};
use nalgebra::{DMatrix, SVector};

// The charts: the `simulate` example's drawing code (also used by `whole_body`).
#[allow(dead_code)]
#[path = "../simulate/main.rs"]
mod simulate;
use simulate::{BLUE_, GREEN_, ORANGE, Panel, RED_, Series, figure};

type Res<T> = Result<T, Box<dyn Error>>;

/// Settings of the run.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// Simulated time (s).
    pub duration: f64,
    /// Control period (s); the plant is integrated with four RK4 steps per period.
    pub control_step: f64,
    /// Initial pitch from upright (rad).
    pub tilt: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            duration: 5.0,
            control_step: 1e-3,
            tilt: 0.1,
        }
    }
}

/// What one closed-loop run found.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Largest `|θ_COM|` over the last second (rad).
    pub final_pitch_error: f64,
    /// Largest `|θ_COM|` over the whole run (rad).
    pub max_pitch_error: f64,
    /// Position `x` at the end (m).
    pub final_position: f64,
    /// Largest `|x|` (m).
    pub max_position: f64,
    /// Largest `|ψ|` (rad).
    pub max_heading: f64,
    /// Largest wheel torque demanded (before clamping) (N·m).
    pub max_wheel_torque: f64,
    /// Control steps with a clamped torque.
    pub saturated_steps: usize,
    /// Largest joint error from the pose over the last second (rad).
    pub final_joint_error: f64,
}

/// What the example found (printed by `main`, checked by the crate's tests).
#[derive(Debug, Clone)]
pub struct Summary {
    /// Base pitch of the upright pose (rad).
    pub upright_pitch: f64,
    /// Spectral radius of the full LQR's discrete closed loop `A_d − B_d K` (< 1: stable).
    pub full_closed_loop_radius: f64,
    /// The same for the WIP LQR on its own 4-state model.
    pub wip_closed_loop_radius: f64,
    /// `‖Aᵀ X A − X − Aᵀ X B K + Q‖ / ‖X‖` of the full LQR's Riccati solution.
    pub full_riccati_residual: f64,
    /// The WIP LQR's gain `[θ_COM, θ̇_COM, θ_wheel, θ̇_wheel] → total wheel torque`.
    pub wip_gain: [f64; 4],
    /// The full LQR's run.
    pub full: RunSummary,
    /// The WIP LQR's run.
    pub wip: RunSummary,
    /// The PNG files written.
    pub files: Vec<PathBuf>,
}

fn main() -> Res<()> {
    let dir = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from("target/plots"), PathBuf::from);
    let s = run(&dir, &Config::default())?;
    println!("{s:#?}");
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Discrete LQR.

/// Exact zero-order-hold discretisation of `ẋ = A x + B a` over `h`: `exp([[A, B], [0, 0]] h)`.
pub fn discretize(a: &DMatrix<f64>, b: &DMatrix<f64>, h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, m) = (a.nrows(), b.ncols());
    let mut aug = DMatrix::<f64>::zeros(n + m, n + m);
    aug.view_mut((0, 0), (n, n)).copy_from(&(a * h));
    aug.view_mut((0, n), (n, m)).copy_from(&(b * h));
    let e = aug.exp();
    (
        e.view((0, 0), (n, n)).into_owned(),
        e.view((0, n), (n, m)).into_owned(),
    )
}

/// The stabilising solution X of the discrete algebraic Riccati equation
/// `X = Aᵀ X A − Aᵀ X B (R + Bᵀ X B)⁻¹ Bᵀ X A + Q` by the structure-preserving doubling
/// algorithm (quadratic convergence; `(A, B)` stabilisable, `(A, Q)` detectable), and the gain
/// `K = (R + Bᵀ X B)⁻¹ Bᵀ X A` of `a = −K x`. `None` if an iterate is singular or it does not
/// converge in 100 doublings.
pub fn dlqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    let n = a.nrows();
    let eye = DMatrix::<f64>::identity(n, n);
    let (mut ak, mut gk, mut hk) = (
        a.clone(),
        b * r.clone().try_inverse()? * b.transpose(),
        q.clone(),
    );
    for _ in 0..100 {
        let w = (&eye + &gk * &hk).lu();
        let wa = w.solve(&ak)?;
        let wg = w.solve(&gk)?;
        let h_next = &hk + ak.transpose() * &hk * &wa;
        let g_next = &gk + &ak * &wg * ak.transpose();
        let a_next = &ak * &wa;
        let change = (&h_next - &hk).norm();
        (ak, gk, hk) = (a_next, g_next, h_next);
        // Keep the iterates symmetric against rounding.
        hk = (&hk + hk.transpose()) * 0.5;
        gk = (&gk + gk.transpose()) * 0.5;
        if change <= 1e-13 * hk.norm() {
            let k = (r + b.transpose() * &hk * b)
                .lu()
                .solve(&(b.transpose() * &hk * a))?;
            return Some((hk, k));
        }
    }
    None
}

/// Largest modulus of the eigenvalues of `m`.
pub fn spectral_radius(m: &DMatrix<f64>) -> f64 {
    m.clone()
        .complex_eigenvalues()
        .iter()
        .fold(0.0, |r, l| r.max(l.norm()))
}

/// `‖Aᵀ X A − X − Aᵀ X B K + Q‖ / ‖X‖`.
pub fn riccati_residual(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    x: &DMatrix<f64>,
    k: &DMatrix<f64>,
) -> f64 {
    let res = a.transpose() * x * a - x - a.transpose() * x * b * k + q;
    res.norm() / x.norm()
}

// ---------------------------------------------------------------------------------------------
// The robot and the two controllers.

type Q = SVector<f64, 19>;
type A = SVector<f64, ACTUATOR_COUNT>;

/// The pose to balance: waist and torso bent, asymmetric arms (so that heading is disturbed).
fn pose(k: &Krang) -> Q {
    let mut q = Q::zeros();
    q[index::Q_W] = 0.4;
    q[index::Q_TORSO] = -0.2;
    for (j, v) in [0.3, -0.5, 0.2, 0.8, 0.0, 0.4, 0.1].iter().enumerate() {
        q[index::Q1L + j] = *v;
        q[index::Q1R + j] = -0.6 * v;
    }
    q[index::Q_IMU] = k.upright_pitch(&q);
    q
}

/// The actuator torques that hold `q` at rest: each joint's gravity torque, wheels idle.
fn holding_torques(k: &Krang, q: &Q) -> A {
    let g = k.gravity(q);
    let mut a = A::zeros();
    for j in actuator::WAIST..ACTUATOR_COUNT {
        a[j] = g[j + 1];
    }
    a
}

/// The full 38-state LQR: `a = a₀ − K ([q; u] − [q₀; 0])`.
struct FullLqr {
    q0: Q,
    a0: A,
    k: DMatrix<f64>,
}

impl FullLqr {
    /// Weights: position and heading like the WIP's wheel angle (30000 per rad of wheel,
    /// i.e. 30000/R² per m), pitch 300 and pitch rate 96000 as the WIP's, joints 1000 rad⁻²
    /// and 10 (rad/s)⁻²; wheel torques 1000 each (R = 500 on the total when split equally),
    /// joint torques by Bryson's rule (the same weight per fraction of the torque limit).
    fn new(k: &Krang, q0: &Q, a0: &A, h: f64) -> (Self, f64, f64) {
        let (am, bm) = k.linearize(q0, &Q::zeros(), a0);
        let a = DMatrix::from_column_slice(38, 38, am.as_slice());
        let b = DMatrix::from_column_slice(38, ACTUATOR_COUNT, bm.as_slice());
        let (ad, bd) = discretize(&a, &b, h);
        let r_wheel = k.params().R;
        let mut qd = vec![1000.0; 19];
        qd[index::X] = 30000.0 / (r_wheel * r_wheel);
        qd[index::PSI] = 30000.0 / (r_wheel * r_wheel);
        qd[index::Q_IMU] = 300.0;
        let mut ud = vec![10.0; 19];
        ud[index::XD] = 90000.0 / (r_wheel * r_wheel);
        ud[index::PSID] = 90000.0 / (r_wheel * r_wheel);
        ud[index::QD_IMU] = 96000.0;
        qd.extend(ud);
        let q = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(qd));
        // Bryson's rule: every torque relative to its limit, the wheels' at 1000 (N·m)⁻².
        let limits = krang_dynamics::hardware::TORQUE_LIMITS;
        let wheel = limits[actuator::WHEEL_L];
        let rd: Vec<f64> = limits
            .iter()
            .map(|l| 1000.0 * (wheel / l).powi(2))
            .collect();
        let r = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(rd));
        let (x, gain) = dlqr(&ad, &bd, &q, &r).expect("the Riccati equation has a solution");
        let radius = spectral_radius(&(&ad - &bd * &gain));
        let residual = riccati_residual(&ad, &bd, &q, &x, &gain);
        (
            Self {
                q0: *q0,
                a0: *a0,
                k: gain,
            },
            radius,
            residual,
        )
    }

    fn control(&self, q: &Q, u: &Q) -> A {
        let mut dx = nalgebra::DVector::<f64>::zeros(38);
        dx.rows_mut(0, 19).copy_from(&(q - self.q0));
        dx.rows_mut(19, 19).copy_from(u);
        let mut a = self.a0;
        a -= A::from_column_slice((&self.k * dx).as_slice());
        a
    }
}

/// The lab's WIP LQR on the total wheel torque, joints held by a computed-torque servo.
struct WipLqr {
    q0: Q,
    gain: [f64; 4],
}

impl WipLqr {
    /// The locked-joint model at the pose: `M₂ [ẍ, θ̈] = −[0, k_θ θ] + [1/R, −1] τ_w` with `M₂`
    /// the mass matrix of x and q_imu and `k_θ = ∂g_imu/∂q_imu` (from the generated
    /// derivatives), in the states `[θ, θ̇, φ = x/R, φ̇]`.
    fn new(k: &Krang, q0: &Q, h: f64) -> (Self, f64) {
        let m = k.mass_matrix(q0);
        let (dg, _) = k.inverse_dynamics_partials(q0, &Q::zeros(), &Q::zeros());
        let (x, p) = (index::X, index::Q_IMU);
        let m2 = nalgebra::Matrix2::new(m[(x, x)], m[(x, p)], m[(p, x)], m[(p, p)]);
        let m2inv = m2.try_inverse().expect("M is positive definite");
        let r_wheel = k.params().R;
        // Accelerations [ẍ, θ̈] per unit of θ and of τ_w.
        let per_theta = m2inv * nalgebra::Vector2::new(-dg[(x, p)], -dg[(p, p)]);
        let per_tau = m2inv * nalgebra::Vector2::new(1.0 / r_wheel, -1.0);
        #[rustfmt::skip]
        let a = DMatrix::from_row_slice(4, 4, &[
            0.0, 1.0, 0.0, 0.0,
            per_theta[1], 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            per_theta[0] / r_wheel, 0.0, 0.0, 0.0,
        ]);
        let b = DMatrix::from_column_slice(4, 1, &[0.0, per_tau[1], 0.0, per_tau[0] / r_wheel]);
        let (ad, bd) = discretize(&a, &b, h);
        let q = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
            300.0, 96000.0, 30000.0, 90000.0,
        ]));
        let r = DMatrix::from_element(1, 1, 500.0);
        let (_, gain) = dlqr(&ad, &bd, &q, &r).expect("the Riccati equation has a solution");
        let radius = spectral_radius(&(&ad - &bd * &gain));
        (
            Self {
                q0: *q0,
                gain: [gain[0], gain[1], gain[2], gain[3]],
            },
            radius,
        )
    }

    fn control(&self, k: &Krang, q: &Q, u: &Q) -> A {
        let r_wheel = k.params().R;
        let theta = q[index::Q_IMU] - k.upright_pitch(q);
        let s = [
            theta,
            u[index::QD_IMU],
            q[index::X] / r_wheel,
            u[index::XD] / r_wheel,
        ];
        let tau_w: f64 = -self.gain.iter().zip(s).map(|(g, x)| g * x).sum::<f64>();
        // Joint servo: τ = M (Kp e − Kd u) + c + g on the joint rows.
        let (kp, kd) = (100.0, 20.0);
        let mut acc = (self.q0 - q) * kp - u * kd;
        for i in [index::XD, index::PSID, index::QD_IMU] {
            acc[i] = 0.0;
        }
        let tau = k.inverse_dynamics(q, u, &acc);
        let mut a = A::zeros();
        a[actuator::WHEEL_L] = tau_w / 2.0;
        a[actuator::WHEEL_R] = tau_w / 2.0;
        for j in actuator::WAIST..ACTUATOR_COUNT {
            a[j] = tau[j + 1];
        }
        a
    }
}

// ---------------------------------------------------------------------------------------------
// Simulation.

struct Trace {
    t: Vec<f64>,
    pitch: Vec<f64>,
    x: Vec<f64>,
    psi: Vec<f64>,
    wheels: Vec<(f64, f64)>,
}

fn simulate(k: &Krang, cfg: &Config, q0: &Q, law: &dyn Fn(&Q, &Q) -> A) -> (Trace, RunSummary) {
    let mut q = *q0;
    q[index::Q_IMU] += cfg.tilt;
    let mut u = Q::zeros();
    let steps = (cfg.duration / cfg.control_step).round() as usize;
    let h = cfg.control_step / 4.0;
    let mut tr = Trace {
        t: Vec::new(),
        pitch: Vec::new(),
        x: Vec::new(),
        psi: Vec::new(),
        wheels: Vec::new(),
    };
    let mut s = RunSummary {
        final_pitch_error: 0.0,
        max_pitch_error: 0.0,
        final_position: 0.0,
        max_position: 0.0,
        max_heading: 0.0,
        max_wheel_torque: 0.0,
        saturated_steps: 0,
        final_joint_error: 0.0,
    };
    for step in 0..=steps {
        let t = step as f64 * cfg.control_step;
        let demand = law(&q, &u);
        let a = saturate(&demand);
        if a != demand {
            s.saturated_steps += 1;
        }
        let theta = q[index::Q_IMU] - k.upright_pitch(&q);
        s.max_pitch_error = s.max_pitch_error.max(theta.abs());
        s.max_position = s.max_position.max(q[index::X].abs());
        s.max_heading = s.max_heading.max(q[index::PSI].abs());
        s.max_wheel_torque = s
            .max_wheel_torque
            .max(demand[actuator::WHEEL_L].abs())
            .max(demand[actuator::WHEEL_R].abs());
        if t >= cfg.duration - 1.0 {
            s.final_pitch_error = s.final_pitch_error.max(theta.abs());
            let joints = (q - q0).rows(index::Q_W, 16).abs().max();
            s.final_joint_error = s.final_joint_error.max(joints);
        }
        if step % 10 == 0 {
            tr.t.push(t);
            tr.pitch.push(theta);
            tr.x.push(q[index::X]);
            tr.psi.push(q[index::PSI]);
            tr.wheels.push((a[actuator::WHEEL_L], a[actuator::WHEEL_R]));
        }
        if step == steps {
            break;
        }
        let tau = k.generalized_forces(&a);
        for _ in 0..4 {
            (q, u) = rk4(k, &q, &u, &tau, h);
        }
    }
    s.final_position = q[index::X];
    (tr, s)
}

/// One RK4 step of `q̇ = u`, `u̇ = FD(q, u, τ)`.
fn rk4(k: &Krang, q: &Q, u: &Q, tau: &Q, h: f64) -> (Q, Q) {
    let f = |q: &Q, u: &Q| (*u, k.forward_dynamics(q, u, tau));
    let (k1q, k1u) = f(q, u);
    let (k2q, k2u) = f(&(q + k1q * (h / 2.0)), &(u + k1u * (h / 2.0)));
    let (k3q, k3u) = f(&(q + k2q * (h / 2.0)), &(u + k2u * (h / 2.0)));
    let (k4q, k4u) = f(&(q + k3q * h), &(u + k3u * h));
    (
        q + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (h / 6.0),
        u + (k1u + k2u * 2.0 + k3u * 2.0 + k4u) * (h / 6.0),
    )
}

/// Runs both controllers and writes the plots to `dir`.
pub fn run(dir: &Path, cfg: &Config) -> Res<Summary> {
    std::fs::create_dir_all(dir)?;
    let k = Krang::default();
    let q0 = pose(&k);
    let a0 = holding_torques(&k, &q0);
    let (full, full_radius, residual) = FullLqr::new(&k, &q0, &a0, cfg.control_step);
    let (wip, wip_radius) = WipLqr::new(&k, &q0, cfg.control_step);
    let (tf, sf) = simulate(&k, cfg, &q0, &|q, u| full.control(q, u));
    let (tw, sw) = simulate(&k, cfg, &q0, &|q, u| wip.control(&k, q, u));

    let pts = |tr: &Trace, v: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
        (0..tr.t.len()).map(|i| (tr.t[i], v(i))).collect()
    };
    let mut files = Vec::new();
    let mut one = |name: &str, title: &str, y: &'static str, series: Vec<Series>| -> Res<()> {
        let path = dir.join(name);
        figure(
            &path,
            (1200, 520),
            &[Panel {
                title: title.into(),
                y_label: y,
                series,
            }],
        )?;
        files.push(path);
        Ok(())
    };
    one(
        "lqr_pitch.png",
        &format!(
            "Pitch of the centre of mass from upright (start {} rad)",
            cfg.tilt
        ),
        "theta_COM (rad)",
        vec![
            Series::line("full LQR (38 states)", BLUE_, pts(&tf, &|i| tf.pitch[i])),
            Series::dashed("WIP LQR (4 states)", RED_, pts(&tw, &|i| tw.pitch[i])),
        ],
    )?;
    one(
        "lqr_position.png",
        "Position x",
        "x (m)",
        vec![
            Series::line("full LQR", BLUE_, pts(&tf, &|i| tf.x[i])),
            Series::dashed("WIP LQR", RED_, pts(&tw, &|i| tw.x[i])),
        ],
    )?;
    one(
        "lqr_heading.png",
        "Heading psi (asymmetric arms)",
        "psi (rad)",
        vec![
            Series::line("full LQR", BLUE_, pts(&tf, &|i| tf.psi[i])),
            Series::dashed("WIP LQR", RED_, pts(&tw, &|i| tw.psi[i])),
        ],
    )?;
    one(
        "lqr_torques.png",
        "Wheel torques (limit +-63.6 N m)",
        "torque (N m)",
        vec![
            Series::line("full LQR, left", BLUE_, pts(&tf, &|i| tf.wheels[i].0)),
            Series::line("full LQR, right", GREEN_, pts(&tf, &|i| tf.wheels[i].1)),
            Series::dashed("WIP LQR, left", RED_, pts(&tw, &|i| tw.wheels[i].0)),
            Series::dashed("WIP LQR, right", ORANGE, pts(&tw, &|i| tw.wheels[i].1)),
        ],
    )?;
    Ok(Summary {
        upright_pitch: q0[index::Q_IMU],
        full_closed_loop_radius: full_radius,
        wip_closed_loop_radius: wip_radius,
        full_riccati_residual: residual,
        wip_gain: wip.gain,
        full: sf,
        wip: sw,
        files,
    })
}
