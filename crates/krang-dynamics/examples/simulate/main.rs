//! Simulations with the generated dynamics: RK4, 5 s, plots as PNG.
//!
//! (a) The 19-speed Krang released at rest 0.3 rad from upright (centre of mass above the
//!     axle) with zero wheel and joint torques. The model has no ground contact, so the body
//!     swings through below the axle like a pendulum on a cart while the free wheels roll.
//!     Total energy `T + V` must be conserved, with the generated `kinetic_energy` (`½ uᵀ M u`)
//!     and `potential_energy`; `V = −Σ g0·(m_k ⁰P_k + ⁰A_k MS_k)` is also computed here by
//!     forward kinematics from `krang.toml` (independently of the generated code) and compared,
//!     and the power balance `Δ(½ uᵀ M u) = −∫ uᵀ g dt` is integrated too.
//! (b) The fixed-wheel model (17 speeds): base pitch held, waist, torso and both arms tracking
//!     sinusoids under computed-torque control `τ = M(q)(q̈_des + Kd ė + Kp e) + c + g`, with
//!     `e = q_des − q` (`_des` for desired: `qd` names a speed everywhere else; one
//!     generated inverse-dynamics pass), computed at 1 kHz and held between samples, from an
//!     initial error of 0.05 rad per joint; once with the exact model and once with a controller
//!     that does not know about a 1 kg payload in each gripper.
//!
//! ```text
//! cargo run --release -p krang-dynamics --features fixed-wheels,kinematics --example simulate -- [DIR]
//! ```
//! writes `pitch.png`, `heading.png`, `energy.png` and `tracking.png` to DIR (default
//! `target/plots`) and prints the energy drift. The README's images are regenerated with
//! `DIR = docs/plots`. Text is drawn from the font8x8 bitmap font, so no system font is
//! needed; legends sit to the right of the plot area, outside the data.

//!
//! Layout: `main.rs` (settings, summary, the printout), `kinematics.rs` (forward kinematics
//! from the model file, for the potential energy), `falling.rs` (run (a)), `tracking.rs` (run
//! (b)), `plot.rs` (the PNG charts, also used by the `whole_body`, `lqr` and `identify`
//! examples).

mod falling;
mod kinematics;
mod plot;
mod tracking;

use std::error::Error;
use std::path::{Path, PathBuf};

use nalgebra::SVector;

use falling::falling;
pub use kinematics::Kinematics;
use krang_dynamics::index;
// The charts, also for the examples that include this file (`whole_body`, `lqr`, `identify`).
#[allow(unused_imports)]
pub use plot::{
    BLACK_, BLUE_, GREEN_, GREY, ORANGE, PALETTE, Panel, RED_, Series, figure, figure_over,
};
use tracking::tracking;

type Res<T> = Result<T, Box<dyn Error>>;

/// Simulation settings.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// Simulated time of both runs (s).
    pub duration: f64,
    /// RK4 step of (a) (s). The zero-torque robot is a frictionless 19-DOF chain whose light
    /// wrist links whip up to several hundred rad/s, so (a) needs a fine step: the energy
    /// error of RK4 falls as h⁴ (1 ms: 3e-4, 0.25 ms: 3e-7 of the energy exchanged).
    pub fall_step: f64,
    /// RK4 step of (b) (s), also its control period (torque held between samples).
    pub control_step: f64,
    /// Initial tilt from upright in (a) (rad).
    pub tilt: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            duration: 5.0,
            fall_step: 1e-4,
            control_step: 1e-3,
            tilt: 0.3,
        }
    }
}

/// What the run found (printed by `main`, checked by the crate's tests).
#[derive(Debug, Clone)]
pub struct Summary {
    /// The upright base pitch `q_imu` of pose (a) (rad).
    pub upright_pitch: f64,
    /// Horizontal distance of the centre of mass from the axle at that pitch (m), by FK.
    pub com_offset_at_upright: f64,
    /// Height of the centre of mass above the axle at that pitch (m), by FK.
    pub com_height_at_upright: f64,
    /// `max |E(t) − E(0)|` (J), `E = ½ uᵀ M u + V` with V by forward kinematics.
    pub energy_drift: f64,
    /// The same, relative to the largest kinetic energy reached (the energy exchanged).
    pub energy_drift_relative: f64,
    /// `max |½uᵀMu − ½u₀ᵀM₀u₀ + ∫ uᵀ g dt|` relative to the largest kinetic energy.
    pub power_balance_relative: f64,
    /// `max |V_FK(q) − V_FK(q₀) − ∫ uᵀ g dt|` relative to the largest kinetic energy: the
    /// generated g is the gradient of the FK potential along the trajectory.
    pub potential_vs_gravity_relative: f64,
    /// `max |V_generated − V_FK|` over run (a), relative to the largest kinetic energy: the
    /// generated `potential_energy` is the FK potential.
    pub potential_generated_vs_fk_relative: f64,
    /// Largest kinetic energy reached in (a) (J).
    pub max_kinetic_energy: f64,
    /// Largest joint speed reached in (a) (rad/s).
    pub max_joint_speed: f64,
    /// Pitch range reached, `(min, max)` of `q_imu − upright` (rad).
    pub tilt_range: (f64, f64),
    /// Final heading ψ (rad).
    pub final_heading: f64,
    /// Largest tracking error over the last fifth of the run, exact model (rad).
    pub tracking_error_exact: f64,
    /// The same with a 1 kg unmodelled payload in each gripper (rad).
    pub tracking_error_payload: f64,
    /// Largest tracking error of each joint over the last fifth, exact model (rad).
    pub tracking_error_per_joint: [f64; 17],
    /// Largest `|τ_i| / limit_i` over the 16 joints (waist, torso, arms) after the first
    /// 0.1 s, exact model (torque demand before clamping).
    pub peak_joint_torque_ratio: f64,
    /// Largest `|τ_imu| / (2 × wheel limit)` after the first 0.1 s: the base pitch torque,
    /// which the wheel motors' reaction `−(τL + τR)` has to supply.
    pub peak_base_torque_ratio: f64,
    /// Control steps in which a torque was clamped to its limit (exact model).
    pub saturated_steps: usize,
    /// Time of the last of them (s).
    pub last_saturated: f64,
    /// The PNG files written.
    pub files: Vec<PathBuf>,
}

fn main() -> Res<()> {
    let dir = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/plots"));
    let cfg = Config::default();
    let start = std::time::Instant::now();
    let s = run(&dir, &cfg)?;
    println!(
        "(a) released at rest {} rad from upright, zero torque; RK4 h = {} s, {} s",
        cfg.tilt, cfg.fall_step, cfg.duration
    );
    println!(
        "    upright q_imu = {:.6} rad: centre of mass {:.3} m above the axle, {:.1e} m ahead of it (FK)",
        s.upright_pitch, s.com_height_at_upright, s.com_offset_at_upright
    );
    println!(
        "    tilt range [{:.3}, {:.3}] rad, final heading {:.4} rad, max KE {:.1} J, max joint speed {:.0} rad/s",
        s.tilt_range.0, s.tilt_range.1, s.final_heading, s.max_kinetic_energy, s.max_joint_speed
    );
    println!(
        "    energy drift max|E − E0| = {:.3e} J = {:.2e} of the largest kinetic energy",
        s.energy_drift, s.energy_drift_relative
    );
    println!(
        "    power balance ½uᵀMu + ∫uᵀg: {:.2e}; V − ∫uᵀg: {:.2e}; V − V_FK: {:.1e} (relative)",
        s.power_balance_relative,
        s.potential_vs_gravity_relative,
        s.potential_generated_vs_fk_relative
    );
    println!(
        "(b) fixed wheels, computed torque every {} s, sinusoids; {} s",
        cfg.control_step, cfg.duration
    );
    println!(
        "    max tracking error over the last fifth: exact model {:.2e} rad, \
         1 kg unmodelled payload per gripper {:.2e} rad",
        s.tracking_error_exact, s.tracking_error_payload
    );
    let per_joint: Vec<String> = s
        .tracking_error_per_joint
        .iter()
        .map(|e| format!("{e:.1e}"))
        .collect();
    println!("    per joint (exact model): [{}]", per_joint.join(", "));
    println!(
        "    peak |τ| / torque limit after 0.1 s: joints {:.2}, base pitch {:.2}; \
         clamped to the limits in {} control steps, the last at t = {:.3} s",
        s.peak_joint_torque_ratio, s.peak_base_torque_ratio, s.saturated_steps, s.last_saturated
    );
    for f in &s.files {
        println!("wrote {}", f.display());
    }
    println!("done in {:.2} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// Runs both simulations and writes the four plots to `dir`.
pub fn run(dir: &Path, cfg: &Config) -> Res<Summary> {
    std::fs::create_dir_all(dir)?;
    let mut files = Vec::new();
    let mut s = falling(dir, cfg, &mut files)?;
    tracking(dir, cfg, &mut files, &mut s)?;
    s.files = files;
    Ok(s)
}

// ---------------------------------------------------------------------------------------------
// Integration.

/// One classic Runge–Kutta step of `ẋ = f(t, x)`.
pub fn rk4<const N: usize>(
    f: impl Fn(f64, &SVector<f64, N>) -> SVector<f64, N>,
    t: f64,
    x: &SVector<f64, N>,
    h: f64,
) -> SVector<f64, N> {
    let k1 = f(t, x);
    let k2 = f(t + h / 2.0, &(x + k1 * (h / 2.0)));
    let k3 = f(t + h / 2.0, &(x + k2 * (h / 2.0)));
    let k4 = f(t + h, &(x + k3 * h));
    x + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
}

/// The pose of (a): waist and torso straight, asymmetric arms (so that the fall also turns).
pub fn pose() -> SVector<f64, 19> {
    let mut q = SVector::<f64, 19>::zeros();
    q[index::Q_W] = 0.4;
    q[index::Q_TORSO] = 0.2;
    let left = [0.9, -0.8, 0.3, -1.2, 0.2, 0.7, 0.0];
    let right = [-0.4, 1.3, -0.2, 0.5, 0.0, -0.3, 0.4];
    for i in 0..7 {
        q[index::Q1L + i] = left[i];
        q[index::Q1R + i] = right[i];
    }
    q
}
