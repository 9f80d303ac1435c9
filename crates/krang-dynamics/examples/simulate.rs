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

use std::error::Error;
use std::path::{Path, PathBuf};

use kanegen_model::{JointKind, Model};
use krang_dynamics::fixed_wheels::{self, KrangFixedWheels};
use krang_dynamics::{ACTUATOR_COUNT, Krang, actuator, hardware, index, saturate};
use nalgebra::{Matrix3, SVector, Vector3};
use plotters::coord::Shift;
use plotters::prelude::*;

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
// Forward kinematics from the model description (for the potential energy).

struct FkLink {
    parent: Option<usize>,
    rotation: Matrix3<f64>,
    axis: Vector3<f64>,
    translation: Vector3<f64>,
    coordinate: Option<usize>,
    /// `(m, MS)` of the body in this frame.
    body: Option<(f64, Vector3<f64>)>,
}

/// Frames of `krang.toml` with the parameter values of a [`Krang`].
pub struct Kinematics {
    links: Vec<FkLink>,
    gravity: Vector3<f64>,
}

impl Kinematics {
    /// Loads `krang.toml` (next to this crate's manifest) and takes the lengths and inertial
    /// parameters from `params`.
    pub fn new(params: &krang_dynamics::Params) -> Res<Self> {
        let model = Model::from_toml_file(concat!(env!("CARGO_MANIFEST_DIR"), "/krang.toml"))?;
        let value = |id: usize| -> Res<f64> {
            let name = &model.params[id].name;
            params
                .get(name)
                .ok_or_else(|| format!("parameter {name} not in Params").into())
        };
        let mut links = Vec::new();
        for link in &model.links {
            let (rotation, axis, translation, coordinate) = match link.joint() {
                None => (
                    Matrix3::identity(),
                    Vector3::zeros(),
                    Vector3::zeros(),
                    None,
                ),
                Some(j) => {
                    let r = j.rotation;
                    let mut t = Vector3::zeros();
                    for (k, s) in j.translation.iter().enumerate() {
                        t[k] = match s.symbol {
                            Some(p) => s.coef * value(p)?,
                            None => s.coef,
                        };
                    }
                    let coordinate = match j.kind {
                        JointKind::Revolute { speed } => Some(speed),
                        JointKind::Fixed => None,
                        JointKind::Prismatic { .. } => {
                            return Err("prismatic joint in krang.toml".into());
                        }
                    };
                    (
                        Matrix3::from_fn(|i, k| r[i][k]),
                        Vector3::from(j.axis),
                        t,
                        coordinate,
                    )
                }
            };
            let body = match &link.body {
                None => None,
                Some(b) => Some((
                    value(b.mass)?,
                    Vector3::new(
                        value(b.first_moment[0])?,
                        value(b.first_moment[1])?,
                        value(b.first_moment[2])?,
                    ),
                )),
            };
            links.push(FkLink {
                parent: link.parent(),
                rotation,
                axis,
                translation,
                coordinate,
                body,
            });
        }
        let gravity = Vector3::from(model.gravity.direction) * value(model.gravity.symbol)?;
        Ok(Self { links, gravity })
    }

    /// Rotation and origin of every frame in frame 0.
    fn frames(&self, q: &SVector<f64, 19>) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        let mut out: Vec<(Matrix3<f64>, Vector3<f64>)> = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let local = match l.coordinate {
                Some(c) => {
                    // Rot(e, θ) = 1 + sin θ [e]× + (1 − cos θ) [e]×².
                    let k = l.axis.cross_matrix();
                    let (s, c) = q[c].sin_cos();
                    l.rotation * (Matrix3::identity() + k * s + k * k * (1.0 - c))
                }
                None => l.rotation,
            };
            out.push(match l.parent {
                None => (Matrix3::identity(), Vector3::zeros()),
                Some(p) => {
                    let (rp, pp) = out[p];
                    (rp * local, pp + rp * l.translation)
                }
            });
        }
        out
    }

    /// `(Σ m, Σ (m ⁰P + ⁰A MS))`: total mass and first moment in frame 0 (wheels excluded:
    /// their centres are on the axle, at frame 0's height).
    fn first_moment(&self, q: &SVector<f64, 19>) -> (f64, Vector3<f64>) {
        let mut mass = 0.0;
        let mut ms = Vector3::zeros();
        for (l, (r, p)) in self.links.iter().zip(self.frames(q)) {
            if let Some((m, msb)) = l.body {
                mass += m;
                ms += p * m + r * msb;
            }
        }
        (mass, ms)
    }

    /// Potential energy `V = −Σ g0·(m ⁰P + ⁰A MS)` relative to the axle height.
    pub fn potential(&self, q: &SVector<f64, 19>) -> f64 {
        -self.gravity.dot(&self.first_moment(q).1)
    }

    /// Centre of mass in frame 0 (heading frame at the axle midpoint, z up).
    pub fn centre_of_mass(&self, q: &SVector<f64, 19>) -> Vector3<f64> {
        let (m, ms) = self.first_moment(q);
        ms / m
    }
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

struct Sample {
    t: f64,
    tilt: f64,
    psi: f64,
    x: f64,
    y: f64,
    kinetic: f64,
    potential: f64,
    potential_fk: f64,
    work_gravity: f64,
}

/// Reference energies of run (a), for its plots.
struct Energies {
    k0: f64,
    v0: f64,
    e0: f64,
    ke_max: f64,
    drift: f64,
}

/// The plots of run (a): pitch, heading and position, energy.
fn falling_plots(
    dir: &Path,
    cfg: &Config,
    log: &[Sample],
    energies: Energies,
    files: &mut Vec<PathBuf>,
) -> Res<()> {
    let Energies {
        k0,
        v0,
        e0,
        ke_max,
        drift,
    } = energies;
    let time = |f: &dyn Fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        log.iter().map(|p| (p.t, f(p))).collect()
    };
    let (half_pi, end) = (std::f64::consts::FRAC_PI_2, cfg.duration);
    let path = dir.join("pitch.png");
    figure(
        &path,
        (1000, 520),
        &[Panel {
            title: format!("(a) released {} rad from upright, zero torque", cfg.tilt),
            y_label: "base pitch from upright, q_imu - q_imu,upright (rad)",
            series: vec![
                Series::line("base pitch from upright", BLUE_, time(&|p| p.tilt)),
                Series::dashed(
                    "base horizontal (+-pi/2)",
                    GREY,
                    vec![(0.0, half_pi), (end, half_pi)],
                ),
                Series::dashed("", GREY, vec![(0.0, -half_pi), (end, -half_pi)]),
            ],
        }],
    )?;
    files.push(path);

    let path = dir.join("heading.png");
    figure(
        &path,
        (1000, 760),
        &[
            Panel {
                title: "(a) heading".into(),
                y_label: "heading ψ (rad)",
                series: vec![Series::line("heading ψ", BLUE_, time(&|p| p.psi))],
            },
            Panel {
                title: "(a) axle midpoint on the ground".into(),
                y_label: "position in the ground plane (m)",
                series: vec![
                    Series::line("x of the axle midpoint", RED_, time(&|p| p.x)),
                    Series::line("y of the axle midpoint", GREEN_, time(&|p| p.y)),
                ],
            },
        ],
    )?;
    files.push(path);

    let path = dir.join("energy.png");
    figure(
        &path,
        (1000, 760),
        &[
            Panel {
                title: "(a) energy (generated T and V)".into(),
                y_label: "energy (J)",
                series: vec![
                    Series::line("kinetic ½u'Mu", RED_, time(&|p| p.kinetic)),
                    Series::line("potential V - V(0)", GREEN_, time(&|p| p.potential - v0)),
                    Series::line(
                        "total E - E(0)",
                        BLUE_,
                        time(&|p| p.kinetic + p.potential - e0),
                    ),
                ],
            },
            Panel {
                title: format!(
                    "(a) relative drift, max {:.1e} (h = {} ms)",
                    drift / ke_max,
                    cfg.fall_step * 1e3
                ),
                y_label: "(E - E(0)) / max kinetic energy (dimensionless)",
                series: vec![
                    Series::line(
                        "total energy",
                        BLUE_,
                        time(&|p| (p.kinetic + p.potential - e0) / ke_max),
                    ),
                    Series::dashed(
                        "power balance: ½u'Mu + int u'g dt",
                        ORANGE,
                        time(&|p| (p.kinetic - k0 + p.work_gravity) / ke_max),
                    ),
                ],
            },
        ],
    )?;
    files.push(path);
    Ok(())
}

/// State of (a): `[q (19), u (19), ∫ uᵀg dt, X0, Y0]`.
type StateA = SVector<f64, 41>;

fn falling(dir: &Path, cfg: &Config, files: &mut Vec<PathBuf>) -> Res<Summary> {
    let k = Krang::default();
    let fk = Kinematics::new(k.params())?;
    let mut q0 = pose();
    let up = k.upright_pitch(&q0);
    q0[index::Q_IMU] = up;
    let com = fk.centre_of_mass(&q0);
    q0[index::Q_IMU] = up + cfg.tilt;

    let rhs = |_t: f64, s: &StateA| -> StateA {
        let q: SVector<f64, 19> = s.fixed_rows::<19>(0).into_owned();
        let u: SVector<f64, 19> = s.fixed_rows::<19>(19).into_owned();
        let ud = k.forward_dynamics(&q, &u, &SVector::zeros());
        let mut d = StateA::zeros();
        d.fixed_rows_mut::<19>(0).copy_from(&u); // q̇ = u (x, ψ: quasi-coordinates)
        d.fixed_rows_mut::<19>(19).copy_from(&ud);
        d[38] = u.dot(&k.gravity(&q));
        let psi = q[index::PSI];
        d[39] = u[index::XD] * psi.cos();
        d[40] = u[index::XD] * psi.sin();
        d
    };
    let sample = |t: f64, s: &StateA| -> Sample {
        let q: SVector<f64, 19> = s.fixed_rows::<19>(0).into_owned();
        let u: SVector<f64, 19> = s.fixed_rows::<19>(19).into_owned();
        Sample {
            t,
            tilt: q[index::Q_IMU] - up,
            psi: q[index::PSI],
            x: s[39],
            y: s[40],
            kinetic: k.kinetic_energy(&q, &u),
            potential: k.potential_energy(&q),
            potential_fk: fk.potential(&q),
            work_gravity: s[38],
        }
    };

    let mut s = StateA::zeros();
    s.fixed_rows_mut::<19>(0).copy_from(&q0);
    let steps = (cfg.duration / cfg.fall_step).round() as usize;
    // Record about every millisecond.
    let every = ((1e-3 / cfg.fall_step).round() as usize).max(1);
    let mut log = vec![sample(0.0, &s)];
    let mut max_speed: f64 = 0.0;
    for n in 0..steps {
        s = rk4(rhs, n as f64 * cfg.fall_step, &s, cfg.fall_step);
        max_speed = max_speed.max(s.fixed_rows::<14>(19 + index::QD1L).amax());
        max_speed = max_speed.max(s.fixed_rows::<3>(19 + index::QD_IMU).amax());
        if (n + 1) % every == 0 || n + 1 == steps {
            log.push(sample((n + 1) as f64 * cfg.fall_step, &s));
        }
    }

    let (k0, v0) = (log[0].kinetic, log[0].potential);
    let e0 = k0 + v0;
    let ke_max = log.iter().map(|p| p.kinetic).fold(0.0, f64::max);
    let worst = |f: &dyn Fn(&Sample) -> f64| log.iter().map(|p| f(p).abs()).fold(0.0, f64::max);
    let drift = worst(&|p| p.kinetic + p.potential - e0);
    let power = worst(&|p| p.kinetic - k0 + p.work_gravity);
    let grad = worst(&|p| p.potential - v0 - p.work_gravity);
    let generated_vs_fk = worst(&|p| p.potential - p.potential_fk);
    let tilt_min = log.iter().map(|p| p.tilt).fold(f64::INFINITY, f64::min);
    let tilt_max = log.iter().map(|p| p.tilt).fold(f64::NEG_INFINITY, f64::max);

    falling_plots(
        dir,
        cfg,
        &log,
        Energies {
            k0,
            v0,
            e0,
            ke_max,
            drift,
        },
        files,
    )?;

    Ok(Summary {
        upright_pitch: up,
        com_offset_at_upright: com.x,
        com_height_at_upright: com.z,
        energy_drift: drift,
        energy_drift_relative: drift / ke_max,
        power_balance_relative: power / ke_max,
        potential_vs_gravity_relative: grad / ke_max,
        potential_generated_vs_fk_relative: generated_vs_fk / ke_max,
        max_kinetic_energy: ke_max,
        max_joint_speed: max_speed,
        tilt_range: (tilt_min, tilt_max),
        final_heading: log.last().map_or(0.0, |p| p.psi),
        tracking_error_exact: f64::NAN,
        tracking_error_payload: f64::NAN,
        tracking_error_per_joint: [f64::NAN; 17],
        peak_joint_torque_ratio: f64::NAN,
        peak_base_torque_ratio: f64::NAN,
        saturated_steps: 0,
        last_saturated: f64::NAN,
        files: Vec::new(),
    })
}

// ---------------------------------------------------------------------------------------------
// (b) Computed-torque tracking on fixed wheels.

/// Desired trajectory of the 17 fixed-wheel joints: `(q_des, q̇_des, q̈_des)`. Waist, torso and arm
/// joints follow sinusoids about `q_home`; the base pitch leans so that the centre of mass
/// of the desired pose stays above the axle (else holding the base would take several times
/// what the wheel motors can give).
fn desired(
    upright: &Krang,
    q_home: &SVector<f64, 17>,
    t: f64,
) -> (SVector<f64, 17>, SVector<f64, 17>, SVector<f64, 17>) {
    use fixed_wheels::index as fw;
    let joints = |t: f64| {
        let mut q = *q_home;
        let mut rate = SVector::<f64, 17>::zeros();
        let mut accel = SVector::<f64, 17>::zeros();
        for j in fw::Q_W..17 {
            // Amplitude 0.15–0.45 rad, frequency 0.2–0.6 Hz, a different phase per joint.
            let a = 0.15 + 0.3 * ((j * 7) % 5) as f64 / 4.0;
            let w = 2.0 * std::f64::consts::PI * (0.2 + 0.1 * ((j * 3) % 5) as f64);
            let phi = j as f64;
            let (s, c) = (w * t + phi).sin_cos();
            q[j] += a * (s - phi.sin());
            rate[j] = a * w * c;
            accel[j] = -a * w * w * s;
        }
        (q, rate, accel)
    };
    let pitch = |q: &SVector<f64, 17>| {
        let q19 = SVector::<f64, 19>::from_fn(|i, _| if i < 2 { 0.0 } else { q[i - 2] });
        upright.upright_pitch(&q19)
    };
    let (mut q, mut rate, mut accel) = joints(t);
    // Central differences for the pitch's rates (smooth; error ~1e-7 rad/s²).
    let dt = 1e-3;
    let (p0, pm, pp) = (
        pitch(&q),
        pitch(&joints(t - dt).0),
        pitch(&joints(t + dt).0),
    );
    q[fw::Q_IMU] = p0;
    rate[fw::Q_IMU] = (pp - pm) / (2.0 * dt);
    accel[fw::Q_IMU] = (pp - 2.0 * p0 + pm) / (dt * dt);
    (q, rate, accel)
}

/// The result of one tracking run.
struct Track {
    /// `(t, q_des − q)` samples.
    log: Vec<(f64, SVector<f64, 17>)>,
    /// Largest `|τ_i| / limit_i` of each joint after the first 0.1 s (demand, before clamping).
    ratio: [f64; 17],
    /// Control steps in which some torque was clamped to its limit.
    saturated_steps: usize,
    /// Time of the last clamped step (s).
    last_saturated: f64,
}

/// Simulates computed-torque tracking; the plant may differ from the controller's model.
/// The commanded torques are clamped to the hardware limits: the 16 joints directly, the
/// base pitch through the wheel motors, whose reaction `−(τL + τR)` drives it on fixed wheels.
fn track(
    cfg: &Config,
    controller: &KrangFixedWheels,
    plant: &KrangFixedWheels,
    upright: &Krang,
    q_home: &SVector<f64, 17>,
) -> Track {
    let (kp, kd) = (100.0, 20.0); // ω_n = 10 rad/s, critically damped
    let mut limits = [0.0; 17];
    limits[0] = 2.0 * hardware::TORQUE_LIMITS[actuator::WHEEL_L];
    limits[1..].copy_from_slice(&hardware::TORQUE_LIMITS[actuator::WAIST..]);
    // Start 0.05 rad off the trajectory in every joint (not in the base pitch).
    let mut x = SVector::<f64, 34>::zeros();
    let (q0, _, _) = desired(upright, q_home, 0.0);
    for j in 0..17 {
        let offset = match j {
            0 => 0.0,
            _ if j % 2 == 0 => 0.05,
            _ => -0.05,
        };
        x[j] = q0[j] + offset;
    }
    let h = cfg.control_step;
    let steps = (cfg.duration / h).round() as usize;
    let every = ((1e-3 / h).round() as usize).max(1);
    let mut log = Vec::with_capacity(steps / every + 1);
    let mut ratio = [0.0f64; 17];
    let mut saturated_steps = 0;
    let mut last_saturated = f64::NAN;
    for n in 0..=steps {
        let t = n as f64 * h;
        let q: SVector<f64, 17> = x.fixed_rows::<17>(0).into_owned();
        let u: SVector<f64, 17> = x.fixed_rows::<17>(17).into_owned();
        let (q_des, u_des, ud_des) = desired(upright, q_home, t);
        let e = q_des - q;
        if n % every == 0 || n == steps {
            log.push((t, e));
        }
        if n == steps {
            break;
        }
        // τ = M(q)(q̈_des + Kd ė + Kp e) + c(q, u) + g(q): one inverse-dynamics pass.
        let v = ud_des + (u_des - u) * kd + e * kp;
        let demand = controller.inverse_dynamics(&q, &u, &v);
        if t >= 0.1 {
            for j in 0..17 {
                ratio[j] = ratio[j].max(demand[j].abs() / limits[j]);
            }
        }
        // As actuator torques: equal wheel torques give the base pitch torque −(τL + τR).
        let mut a = SVector::<f64, ACTUATOR_COUNT>::zeros();
        a[actuator::WHEEL_L] = -demand[0] / 2.0;
        a[actuator::WHEEL_R] = -demand[0] / 2.0;
        a.fixed_rows_mut::<16>(actuator::WAIST)
            .copy_from(&demand.fixed_rows::<16>(1));
        let a = saturate(&a);
        let mut tau = demand;
        tau[0] = -(a[actuator::WHEEL_L] + a[actuator::WHEEL_R]);
        tau.fixed_rows_mut::<16>(1)
            .copy_from(&a.fixed_rows::<16>(actuator::WAIST));
        if tau != demand {
            saturated_steps += 1;
            last_saturated = t;
        }
        // The torque is held over one control period.
        x = rk4(
            |_t, x: &SVector<f64, 34>| {
                let q: SVector<f64, 17> = x.fixed_rows::<17>(0).into_owned();
                let u: SVector<f64, 17> = x.fixed_rows::<17>(17).into_owned();
                let ud = plant.forward_dynamics(&q, &u, &tau);
                let mut d = SVector::<f64, 34>::zeros();
                d.fixed_rows_mut::<17>(0).copy_from(&u);
                d.fixed_rows_mut::<17>(17).copy_from(&ud);
                d
            },
            t,
            &x,
            h,
        );
    }
    Track {
        log,
        ratio,
        saturated_steps,
        last_saturated,
    }
}

fn tracking(dir: &Path, cfg: &Config, files: &mut Vec<PathBuf>, summary: &mut Summary) -> Res<()> {
    let model = KrangFixedWheels::default();
    // Home pose: the arms of (a), base pitch upright for it.
    let k19 = Krang::default();
    let mut q19 = pose();
    q19[index::Q_IMU] = k19.upright_pitch(&q19);
    let q_home = SVector::<f64, 17>::from_fn(|i, _| q19[i + 2]);

    let exact = track(cfg, &model, &model, &k19, &q_home);
    // The plant carries 1 kg more in each gripper, at the gripper frame origin (MS and the
    // inertia about the origin are unchanged); the controller does not know.
    let mut p = *model.params();
    p.m10l += 1.0;
    p.m10r += 1.0;
    let payload = track(cfg, &model, &KrangFixedWheels::new(p), &k19, &q_home);

    let tail = 0.8 * cfg.duration;
    let worst = |log: &[(f64, SVector<f64, 17>)], j: Option<usize>| {
        log.iter()
            .filter(|(t, _)| *t >= tail)
            .map(|(_, e)| j.map_or(e.amax(), |j| e[j].abs()))
            .fold(0.0, f64::max)
    };
    summary.tracking_error_exact = worst(&exact.log, None);
    summary.tracking_error_payload = worst(&payload.log, None);
    for j in 0..17 {
        summary.tracking_error_per_joint[j] = worst(&exact.log, Some(j));
    }
    summary.peak_base_torque_ratio = exact.ratio[0];
    summary.peak_joint_torque_ratio = exact.ratio[1..].iter().copied().fold(0.0, f64::max);
    summary.saturated_steps = exact.saturated_steps;
    summary.last_saturated = exact.last_saturated;

    // One panel per group, a distinct colour per joint (tab10 colours).
    let per_joint = |names: &[&'static str], first: usize| -> Vec<Series> {
        names
            .iter()
            .enumerate()
            .map(|(n, name)| {
                let j = first + n;
                Series::line(
                    name,
                    PALETTE[n % PALETTE.len()],
                    exact.log.iter().map(|(t, e)| (*t, e[j])).collect(),
                )
            })
            .collect()
    };
    let trunk = per_joint(&["base pitch q_imu", "waist q_w", "torso q_torso"], 0);
    // (font8x8's `l` is hard to tell from `1`: the panel titles name the coordinates.)
    let joints = [
        "joint 1", "joint 2", "joint 3", "joint 4", "joint 5", "joint 6", "joint 7",
    ];
    let left = per_joint(&joints, 3);
    let right = per_joint(&joints, 10);
    let log10_max = |log: &[(f64, SVector<f64, 17>)]| -> Vec<(f64, f64)> {
        log.iter()
            .map(|(t, e)| (*t, e.amax().max(1e-16).log10()))
            .collect()
    };
    let path = dir.join("tracking.png");
    let hz = 1.0 / cfg.control_step;
    figure(
        &path,
        (1000, 1400),
        &[
            Panel {
                title: format!("(b) fixed wheels, computed torque at {hz:.0} Hz: trunk"),
                y_label: "tracking error q_des - q (rad), exact model",
                series: trunk,
            },
            Panel {
                title: "(b) left arm, joints 1-7 = q1l..q7l".into(),
                y_label: "tracking error q_des - q (rad), exact model",
                series: left,
            },
            Panel {
                title: "(b) right arm, joints 1-7 = q1r..q7r".into(),
                y_label: "tracking error q_des - q (rad), exact model",
                series: right,
            },
            Panel {
                title: "(b) largest joint error; exact model: 1 kHz hold only".into(),
                y_label: "log10 of max |q_des - q| over the joints (q in rad)",
                series: vec![
                    Series::line("exact model", BLUE_, log10_max(&exact.log)),
                    Series::line(
                        "1 kg unmodelled payload per hand",
                        RED_,
                        log10_max(&payload.log),
                    ),
                ],
            },
        ],
    )?;
    files.push(path);
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Plotting: plotters draws the lines; all text comes from the font8x8 bitmap font, so no
// font feature (and no system font) is needed.

/// A chart colour.
pub const BLUE_: RGBColor = RGBColor(31, 119, 180);
/// A chart colour.
pub const RED_: RGBColor = RGBColor(214, 39, 40);
/// A chart colour.
pub const GREEN_: RGBColor = RGBColor(44, 160, 44);
/// A chart colour.
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// A chart colour.
pub const BLACK_: RGBColor = RGBColor(0, 0, 0);
/// A chart colour.
pub const GREY: RGBColor = RGBColor(140, 140, 140);
const GRID: RGBColor = RGBColor(225, 225, 225);
/// Distinct line colours (matplotlib's tab10 without grey), one per joint of a panel.
pub const PALETTE: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// One line of a chart (also used by the `whole_body` example).
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: &'static str,
    /// Line colour.
    pub color: RGBColor,
    /// Dashed instead of solid.
    pub dashed: bool,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A solid line.
    pub fn line(label: &'static str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label,
            color,
            dashed: false,
            points,
        }
    }

    /// A dashed line.
    pub fn dashed(label: &'static str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label,
            color,
            dashed: true,
            points,
        }
    }
}

/// One chart of a figure: title, y-axis label (time is the x axis) and lines.
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// The y-axis label, with units.
    pub y_label: &'static str,
    /// The lines.
    pub series: Vec<Series>,
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Pixel scale of the 8×8 glyphs.
const TEXT: i32 = 2;

fn glyph(c: char) -> [u8; 8] {
    use font8x8::UnicodeFonts;
    font8x8::BASIC_FONTS
        .get(c)
        .or_else(|| font8x8::LATIN_FONTS.get(c))
        .or_else(|| font8x8::GREEK_FONTS.get(c))
        .unwrap_or([0; 8])
}

fn text_width(s: &str) -> i32 {
    s.chars().count() as i32 * 8 * TEXT
}

/// Draws `s` with its top-left corner at `(x, y)` (absolute pixels of `root`).
fn text(root: &Area, s: &str, (x, y): (i32, i32), color: &RGBColor) -> Res<()> {
    for (n, c) in s.chars().enumerate() {
        let x0 = x + n as i32 * 8 * TEXT;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    let px = x0 + col * TEXT;
                    let py = y + row as i32 * TEXT;
                    for dy in 0..TEXT {
                        for dx in 0..TEXT {
                            root.draw_pixel((px + dx, py + dy), color)?;
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// About five round tick values covering `[lo, hi]`, and the step.
fn ticks(lo: f64, hi: f64) -> (Vec<f64>, f64) {
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    ((first..=last).map(|i| i as f64 * step).collect(), step)
}

fn tick_label(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if step < 1e-3 || v.abs() >= 1e5 {
        let s = format!("{v:.1e}");
        return s.replace(".0e", "e");
    }
    // Decimals of the step: 0.25 needs two, 0.2 one, 5 none.
    let k = step.log10().floor();
    let mantissa = step / 10f64.powf(k);
    let extra = usize::from((mantissa - 2.5).abs() < 1e-9);
    let decimals = (-k).max(0.0) as usize + extra;
    format!("{v:.decimals$}")
}

/// Writes `panels`, stacked, as a PNG of `size` pixels (time on the x axis).
pub fn figure(path: &Path, size: (u32, u32), panels: &[Panel]) -> Res<()> {
    figure_over(path, size, panels, "time (s)")
}

/// Writes `panels`, stacked, as a PNG of `size` pixels, with `x_label` under each x axis.
pub fn figure_over(path: &Path, size: (u32, u32), panels: &[Panel], x_label: &str) -> Res<()> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((panels.len(), 1));
    for (panel, area) in panels.iter().zip(&areas) {
        draw_panel(&root, area, panel, x_label)?;
    }
    root.present()?;
    Ok(())
}

/// Legend entries laid out in rows below the plot, within `width` pixels: `(row, x offset)`
/// of each labelled series.
fn legend_layout(panel: &Panel, width: i32) -> Vec<(&Series, i32, i32)> {
    let (mut row, mut x) = (0, 0);
    let mut out = Vec::new();
    for s in panel.series.iter().filter(|s| !s.label.is_empty()) {
        let w = text_width(s.label) + 64;
        if x > 0 && x + w > width {
            (row, x) = (row + 1, 0);
        }
        out.push((s, row, x));
        x += w;
    }
    out
}

/// One panel: the plot, its axes, and the legend in rows below the time axis (outside the
/// data).
fn draw_panel(root: &Area, area: &Area, panel: &Panel, x_label: &str) -> Res<()> {
    let (ax, ay) = area.get_base_pixel();
    let (aw, _) = area.dim_in_pixel();
    // Data ranges.
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &panel.series {
        for &(x, y) in &s.points {
            if y.is_finite() {
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
            x0 = x0.min(x);
            x1 = x1.max(x);
        }
    }
    if (y1 - y0).abs() < 1e-300 {
        let m = if y0 == 0.0 { 1.0 } else { y0.abs() * 0.1 };
        y0 -= m;
        y1 += m;
    }
    let pad = 0.06 * (y1 - y0);
    let (y0, y1) = (y0 - pad, y1 + pad);

    // The legend goes in rows below the time axis, outside the data.
    let h = 8 * TEXT;
    let legend = legend_layout(panel, aw as i32 - 180);
    let rows = legend.iter().map(|(_, r, _)| r + 1).max().unwrap_or(0);
    let mut chart = ChartBuilder::on(area)
        .margin_left(150)
        .margin_right(40)
        .margin_top(72)
        .margin_bottom(62 + rows as u32 * (h as u32 + 8))
        .build_cartesian_2d(x0..x1, y0..y1)?;

    let (xt, xs) = ticks(x0, x1);
    let (yt, ys) = ticks(y0, y1);
    for &t in &xt {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(t, y0), (t, y1)],
            GRID.stroke_width(1),
        )))?;
    }
    for &t in &yt {
        let style = if t == 0.0 { GREY } else { GRID };
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x0, t), (x1, t)],
            style.stroke_width(1),
        )))?;
    }
    for s in &panel.series {
        let style = s.color.stroke_width(2);
        if s.dashed {
            chart.draw_series(DashedLineSeries::new(
                s.points.iter().copied(),
                10,
                6,
                style,
            ))?;
        } else {
            chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
        }
    }
    chart.draw_series(std::iter::once(Rectangle::new(
        [(x0, y0), (x1, y1)],
        BLACK.stroke_width(1),
    )))?;

    // Text: title, tick labels, axis labels, legend.
    text(root, &panel.title, (ax + 16, ay + 12), &BLACK_)?;
    for &t in &xt {
        let (px, py) = chart.backend_coord(&(t, y0));
        let s = tick_label(t, xs);
        text(root, &s, (px - text_width(&s) / 2, py + 8), &BLACK_)?;
    }
    for &t in &yt {
        let (px, py) = chart.backend_coord(&(x0, t));
        let s = tick_label(t, ys);
        text(root, &s, (px - 10 - text_width(&s), py - h / 2), &BLACK_)?;
    }
    let label = x_label;
    let (_, bottom) = chart.backend_coord(&(x0, y0));
    text(
        root,
        label,
        (
            ax + aw as i32 / 2 - text_width(label) / 2 + 60,
            bottom + 14 + h,
        ),
        &BLACK_,
    )?;
    // y label above the tick labels, left-aligned at the panel edge.
    let (_, top) = chart.backend_coord(&(x0, y1));
    text(root, panel.y_label, (ax + 16, top - h - 8), &BLACK_)?;

    // Legend: rows below the time axis label.
    for (s, row, x) in legend {
        let (lx, y) = (ax + 150 + x, bottom + 24 + 2 * h + row * (h + 8));
        root.draw(&PathElement::new(
            vec![(lx, y + h / 2), (lx + 32, y + h / 2)],
            s.color.stroke_width(3),
        ))?;
        text(root, s.label, (lx + 40, y), &BLACK_)?;
    }
    Ok(())
}
