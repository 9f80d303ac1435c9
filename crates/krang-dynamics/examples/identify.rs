//! Identification of Krang's inertial parameters from simulated measurements, with plots.
//!
//! * **(a) The beta vector from static poses**, as the lab learned it on hardware
//!   (the Krang project's CoM-learning programs, munzir/18c-ParameterConvergence: 104 poses). At
//!   each of `poses` random poses of the waist, torso and arms the robot balances: its pitch
//!   `q_imu` is the one that puts the centre of mass above the wheel axle (the pitch row of
//!   g(q) vanishes; found in closed form, g_imu = a cos q_imu + b sin q_imu). Measured: the
//!   joints' gravity torques with `torque_noise`, the balance condition (zero pitch torque, with
//!   the same noise), and the pitch from the IMU with `pitch_noise`. Least squares on the
//!   identifiable combinations β_b (`base_gravity_regressor`, `BASE_BETA_NAMES`: 34 of the 68
//!   masses and first moments) gives the estimate and its standard deviations, compared with
//!   the truth (the model file's values, i.e. `Krang.urdf`) and with the lab's hardware-trained
//!   vector.
//! * **(b) The base parameters of the fixed-wheel tree from an exciting trajectory**: every
//!   joint follows a sum of three sinusoids (a Fourier excitation, period `period`), the
//!   measured torques are τ(q, u, u̇) + `trajectory_noise`, and least squares on the base
//!   regressor (`fixed_wheels::base_regressor`, 111 of 170 parameters) gives π_b; the report
//!   lists the arm's (bodies 4l–10l).
//!
//! **The lab's vectors** (`models/krang/params/`, provenance in `models/krang/README.md`):
//! `idealBetaVector.txt` (24 bodies: Base, the two wheels, Spine, Bracket, Kinect, L1–L6, lGripper and its two motor plates, the same on
//! the right) and `convergedBetaVector104PosesHardwareTrained.txt` (23 bodies: no Kinect). Each
//! body's `[m, m·cx, m·cy, m·cz]` is in its URDF link frame, which is the model's body frame
//! (`models/krang.toml`: "The URDF link frames are the report frames"; the gripper's inertia
//! needs no rotation). Mapped to the model's β: the wheels are left out (their centres are on the
//! axle, the origin of body 1: they only add to `m1`, which has no effect on g), so is the
//! Kinect (not in the model), and each motor plate is merged into its gripper (`m·p + R·MS` with
//! the plate joint's origin `p` and rotation `R` from `Krang.urdf`). The ideal vector mapped so
//! equals the model's β to the plates' 0.1 g: a check of the mapping. The hardware vector is a
//! fit (negative masses on the plates), so only its identifiable combinations mean anything;
//! they are compared with the truth.
//!
//! ```text
//! cargo run --release -p krang-dynamics --features regressors,fixed-wheels,kinematics --example identify -- [DIR]
//! ```
//! writes `identify_beta.png`, `identify_beta_residuals.png`, `identify_trajectory.png` and
//! `identify_trajectory_errors.png` to DIR (default `target/plots`).

use std::error::Error;
use std::path::{Path, PathBuf};

use krang_dynamics::fixed_wheels;
use krang_dynamics::{BASE_BETA_NAMES, BETA_NAMES, Krang, Params, index};
use nalgebra::{DMatrix, DVector, SVector};

// The charts: the `simulate` example's drawing code.
#[allow(dead_code)]
#[path = "simulate/main.rs"]
mod simulate;
use simulate::{BLUE_, GREEN_, GREY, ORANGE, PALETTE, Panel, RED_, Series, figure_over};

type Res<T> = Result<T, Box<dyn Error>>;

/// Settings of the run.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// Static poses of (a).
    pub poses: usize,
    /// Joint-torque noise of (a), standard deviation (N·m).
    pub torque_noise: f64,
    /// Pitch (IMU) noise of (a), standard deviation (rad).
    pub pitch_noise: f64,
    /// Samples of the trajectory of (b).
    pub samples: usize,
    /// Duration of the trajectory of (b) (s): one period of its lowest harmonic.
    pub period: f64,
    /// Torque noise of (b), standard deviation (N·m).
    pub trajectory_noise: f64,
    /// Seed of the random poses, trajectory and noise.
    pub seed: u64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            poses: 104,
            torque_noise: 0.5,
            pitch_noise: 2e-3,
            samples: 500,
            period: 10.0,
            trajectory_noise: 0.2,
            seed: 2018,
        }
    }
}

/// A least-squares estimate.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// The estimate.
    pub value: Vec<f64>,
    /// Standard deviations from the residual variance.
    pub std: Vec<f64>,
    /// The truth.
    pub truth: Vec<f64>,
    /// Residuals of the fit, measurement by measurement.
    pub residuals: Vec<f64>,
    /// RMS of the residuals.
    pub residual_rms: f64,
    /// Largest `|estimate − truth| / σ`.
    pub worst_sigma: f64,
    /// Largest `|estimate − truth| / max(|truth|, floor)` (floor 1e-2 of the parameter's unit).
    pub worst_relative: f64,
}

/// What (a) found.
#[derive(Debug, Clone)]
pub struct BetaResult {
    /// β_b identified from the simulated poses, against the model's.
    pub estimate: Estimate,
    /// β_b of the lab's hardware-trained vector (mapped to the model's bodies).
    pub hardware: Vec<f64>,
    /// β_b of the lab's ideal vector (mapped), which should be the truth.
    pub ideal: Vec<f64>,
    /// Largest |β − β_ideal mapped| over the 68 entries: the mapping's check.
    pub ideal_vs_model: f64,
    /// Pitches of the poses (rad).
    pub pitches: Vec<f64>,
}

/// What (b) found.
#[derive(Debug, Clone)]
pub struct ArmResult {
    /// π_b identified from the trajectory.
    pub estimate: Estimate,
    /// Indices (into `fixed_wheels::BASE_PARAMETER_NAMES`) of the left arm's base parameters.
    pub arm: Vec<usize>,
    /// Sample times (s).
    pub times: Vec<f64>,
}

/// A small deterministic generator (SplitMix64) and Gaussian draws (Box–Muller).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    fn gauss(&mut self, sigma: f64) -> f64 {
        if sigma == 0.0 {
            return 0.0;
        }
        let (a, b) = (self.uniform().max(1e-300), self.uniform());
        sigma * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

/// Least squares `A x = b` by QR, with the standard deviations of `x` from the residual
/// variance, compared with `truth`.
pub fn least_squares(a: &DMatrix<f64>, b: &DVector<f64>, truth: &[f64]) -> Res<Estimate> {
    let n = a.ncols();
    if a.nrows() <= n {
        return Err(format!("{} measurements for {n} parameters", a.nrows()).into());
    }
    let qr = a.clone().qr();
    let r = qr.r();
    let qtb = qr.q().transpose() * b;
    let x = r
        .solve_upper_triangular(&qtb)
        .ok_or("the regressor stack is rank deficient")?;
    let res = a * &x - b;
    let sigma2 = res.norm_squared() / (a.nrows() - n) as f64;
    let rinv = r
        .solve_upper_triangular(&DMatrix::identity(n, n))
        .ok_or("the regressor stack is rank deficient")?;
    let std: Vec<f64> = (0..n)
        .map(|i| (sigma2 * rinv.row(i).norm_squared()).sqrt())
        .collect();
    let value: Vec<f64> = x.iter().copied().collect();
    let worst_sigma = value
        .iter()
        .zip(truth)
        .zip(&std)
        .map(|((e, t), s)| (e - t).abs() / s.max(1e-300))
        .fold(0.0, f64::max);
    let worst_relative = value
        .iter()
        .zip(truth)
        .map(|(e, t)| (e - t).abs() / t.abs().max(1e-2))
        .fold(0.0, f64::max);
    Ok(Estimate {
        residual_rms: (res.norm_squared() / res.len() as f64).sqrt(),
        residuals: res.iter().copied().collect(),
        value,
        std,
        truth: truth.to_vec(),
        worst_sigma,
        worst_relative,
    })
}

/// The pitch at which Krang balances at pose `q` (its `q_imu` ignored): the root of
/// g_imu = a cos q_imu + b sin q_imu where the pendulum is inverted (dg_imu/dq_imu < 0).
pub fn balance_pitch(k: &Krang, q: &SVector<f64, 19>) -> f64 {
    let at = |pitch: f64| {
        let mut q = *q;
        q[index::Q_IMU] = pitch;
        k.gravity(&q)[index::QD_IMU]
    };
    let (a, b) = (at(0.0), at(std::f64::consts::FRAC_PI_2));
    let root = (-a).atan2(b);
    // root and root + π are both equilibria; the inverted one has a negative slope.
    let slope = -a * root.sin() + b * root.cos();
    if slope < 0.0 {
        root
    } else {
        let r = root + std::f64::consts::PI;
        (r + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    }
}

/// A lab beta file: whitespace-separated numbers, four per body.
pub fn read_beta_file(path: &Path) -> Res<Vec<[f64; 4]>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: {e} (the lab's beta vectors)", path.display()))?;
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|s| s.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{}: not a list of numbers: {e}", path.display()))?;
    if !v.len().is_multiple_of(4) {
        return Err(format!("{}: {} numbers, not four per body", path.display(), v.len()).into());
    }
    Ok(v.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
}

/// The motor plates' joints on the grippers (`Krang.urdf`: LMotorPlate1/2, RMotorPlate1/2):
/// origin in the gripper frame and the rotation's diagonal (rpy (π, 0, 0) and (π, 0, π)).
const PLATES: [([f64; 3], [f64; 3]); 2] = [
    ([-0.045, 0.0, 0.127], [1.0, -1.0, -1.0]),
    ([0.045, 0.0, 0.127], [-1.0, 1.0, -1.0]),
];

/// A lab beta vector (24 bodies with the Kinect, 23 without) as the model's β (`BETA_NAMES`:
/// bodies 1, 2, 3, 4l–10l, 4r–10r): wheels and Kinect left out, motor plates merged into the
/// grippers.
pub fn lab_beta_to_model(bodies: &[[f64; 4]]) -> Res<SVector<f64, 68>> {
    let kinect = match bodies.len() {
        24 => true,
        23 => false,
        n => return Err(format!("{n} bodies: expected 24 (with Kinect) or 23").into()),
    };
    // Lab order: Base, LWheel, RWheel, Spine, Bracket, [Kinect], L1–L6, lGripper, 2 plates,
    // R1–R6, rGripper, 2 plates.
    let arm0 = if kinect { 6 } else { 5 };
    let mut out: Vec<[f64; 4]> = vec![bodies[0], bodies[3], bodies[4]];
    for side in 0..2 {
        let s = arm0 + 9 * side;
        out.extend_from_slice(&bodies[s..s + 6]);
        let mut gripper = bodies[s + 6];
        for (plate, (p, r)) in bodies[s + 7..s + 9].iter().zip(PLATES) {
            gripper[0] += plate[0];
            for i in 0..3 {
                gripper[1 + i] += plate[0] * p[i] + r[i] * plate[1 + i];
            }
        }
        out.push(gripper);
    }
    Ok(SVector::from_iterator(out.into_iter().flatten()))
}

/// (a): β_b from `cfg.poses` balanced static poses; `lab`: the directory of the lab's vectors.
pub fn identify_beta(cfg: &Config, lab: &Path) -> Res<BetaResult> {
    let truth_params = Params::default();
    let k = Krang::new(truth_params);
    let truth = krang_dynamics::base_beta(&truth_params);
    let nb = BASE_BETA_NAMES.len();
    let mut rng = Rng(cfg.seed);
    // Rows: the pitch (balance) and the 17 joints; ẋ and ψ̇ carry no gravity.
    let rows: Vec<usize> = (index::QD_IMU..19).collect();
    let mut a = DMatrix::zeros(cfg.poses * rows.len(), nb);
    let mut b = DVector::zeros(cfg.poses * rows.len());
    let mut pitches = Vec::with_capacity(cfg.poses);
    for s in 0..cfg.poses {
        let mut q = SVector::<f64, 19>::zeros();
        q[index::Q_W] = rng.range(0.3, 1.6);
        q[index::Q_TORSO] = rng.range(-0.8, 0.8);
        for i in index::Q1L..19 {
            q[i] = rng.range(-1.5, 1.5);
        }
        q[index::Q_IMU] = balance_pitch(&k, &q);
        pitches.push(q[index::Q_IMU]);
        let g = k.gravity(&q);
        let mut measured = q;
        measured[index::Q_IMU] += rng.gauss(cfg.pitch_noise);
        let y = k.base_gravity_regressor(&measured);
        for (j, &r) in rows.iter().enumerate() {
            let row = s * rows.len() + j;
            for c in 0..nb {
                a[(row, c)] = y[(r, c)];
            }
            b[row] = g[r] + rng.gauss(cfg.torque_noise);
        }
    }
    let estimate = least_squares(&a, &b, truth.as_slice())?;
    let ideal = lab_beta_to_model(&read_beta_file(&lab.join("idealBetaVector.txt"))?)?;
    let hardware = lab_beta_to_model(&read_beta_file(
        &lab.join("convergedBetaVector104PosesHardwareTrained.txt"),
    )?)?;
    let ideal_vs_model = (ideal - truth_params.beta_vector()).amax();
    Ok(BetaResult {
        estimate,
        hardware: krang_dynamics::base_beta_of(&hardware)
            .iter()
            .copied()
            .collect(),
        ideal: krang_dynamics::base_beta_of(&ideal)
            .iter()
            .copied()
            .collect(),
        ideal_vs_model,
        pitches,
    })
}

/// (b): the fixed-wheel tree's base parameters from a Fourier trajectory.
pub fn identify_trajectory(cfg: &Config) -> Res<ArmResult> {
    use fixed_wheels::{BASE_PARAMETER_NAMES, DOF, KrangFixedWheels};
    let truth_params = fixed_wheels::Params::default();
    let k = KrangFixedWheels::new(truth_params);
    let truth = fixed_wheels::base_parameters(&truth_params);
    let nb = BASE_PARAMETER_NAMES.len();
    let mut rng = Rng(cfg.seed ^ 0x5eed);
    // q_j(t) = c_j + Σ_h a_jh sin(h ω t + φ_jh), h = 1, 2, 3: amplitudes within ±1.2 rad.
    let w = std::f64::consts::TAU / cfg.period;
    let coef: Vec<(f64, [(f64, f64); 3])> = (0..DOF)
        .map(|_| {
            let centre = rng.range(-0.3, 0.3);
            let h = [0; 3].map(|_| (rng.range(0.1, 0.4), rng.range(0.0, std::f64::consts::TAU)));
            (centre, h)
        })
        .collect();
    let mut a = DMatrix::zeros(cfg.samples * DOF, nb);
    let mut b = DVector::zeros(cfg.samples * DOF);
    let mut times = Vec::with_capacity(cfg.samples);
    for s in 0..cfg.samples {
        let t = cfg.period * s as f64 / cfg.samples as f64;
        times.push(t);
        let (mut q, mut u, mut ud) = (
            SVector::<f64, DOF>::zeros(),
            SVector::<f64, DOF>::zeros(),
            SVector::<f64, DOF>::zeros(),
        );
        for (j, (c, h)) in coef.iter().enumerate() {
            q[j] = *c;
            for (n, &(amp, phase)) in h.iter().enumerate() {
                let f = (n + 1) as f64 * w;
                let arg = f * t + phase;
                q[j] += amp * arg.sin();
                u[j] += amp * f * arg.cos();
                ud[j] -= amp * f * f * arg.sin();
            }
        }
        let tau = k.inverse_dynamics(&q, &u, &ud);
        let y = k.base_regressor(&q, &u, &ud);
        for r in 0..DOF {
            let row = s * DOF + r;
            for c in 0..nb {
                a[(row, c)] = y[(r, c)];
            }
            b[row] = tau[r] + rng.gauss(cfg.trajectory_noise);
        }
    }
    let estimate = least_squares(&a, &b, truth.as_slice())?;
    // Names end with the body: `…4l` to `…10l` are the left arm's.
    let arm = BASE_PARAMETER_NAMES
        .iter()
        .enumerate()
        .filter(|(_, n)| n.ends_with('l'))
        .map(|(i, _)| i)
        .collect();
    Ok(ArmResult {
        estimate,
        arm,
        times,
    })
}

/// What `run` found, and the files it wrote.
pub struct Summary {
    /// (a).
    pub beta: BetaResult,
    /// (b).
    pub trajectory: ArmResult,
    /// The PNG files.
    pub files: Vec<PathBuf>,
}

/// Points `(i, v_i)`.
fn indexed(v: impl IntoIterator<Item = f64>) -> Vec<(f64, f64)> {
    v.into_iter()
        .enumerate()
        .map(|(i, x)| (i as f64, x))
        .collect()
}

/// Runs (a) and (b) and writes the plots to `dir`; `lab`: the lab's parameter directory.
pub fn run(dir: &Path, lab: &Path, cfg: &Config) -> Res<Summary> {
    std::fs::create_dir_all(dir)?;
    let beta = identify_beta(cfg, lab)?;
    let trajectory = identify_trajectory(cfg)?;
    let mut files = Vec::new();

    // (a) values and errors per identifiable combination.
    let e = &beta.estimate;
    let path = dir.join("identify_beta.png");
    figure_over(
        &path,
        (1400, 1200),
        &[
            Panel {
                title: format!(
                    "(a) identifiable combinations of beta (34 of 68), {} balanced poses",
                    cfg.poses
                ),
                y_label: "value (kg, kg m)",
                series: vec![
                    Series::line(
                        "truth (Krang.urdf)",
                        BLUE_,
                        indexed(e.truth.iter().copied()),
                    ),
                    Series::dashed("identified", RED_, indexed(e.value.iter().copied())),
                    Series::line(
                        "lab, hardware-trained (104 poses)",
                        GREEN_,
                        indexed(beta.hardware.iter().copied()),
                    ),
                ],
            },
            Panel {
                title: "(a) identified - truth, with 2 standard deviations".into(),
                y_label: "error (kg, kg m)",
                series: vec![
                    Series::line(
                        "identified - truth",
                        RED_,
                        indexed(e.value.iter().zip(&e.truth).map(|(v, t)| v - t)),
                    ),
                    Series::dashed("+2 sigma", GREY, indexed(e.std.iter().map(|s| 2.0 * s))),
                    Series::dashed("-2 sigma", GREY, indexed(e.std.iter().map(|s| -2.0 * s))),
                ],
            },
            Panel {
                title: "(a) lab hardware-trained - truth".into(),
                y_label: "error (kg, kg m)",
                series: vec![Series::line(
                    "hardware - truth",
                    GREEN_,
                    indexed(beta.hardware.iter().zip(&e.truth).map(|(v, t)| v - t)),
                )],
            },
        ],
        "index into BASE_BETA_NAMES",
    )?;
    files.push(path);

    let rows = 19 - index::QD_IMU;
    let path = dir.join("identify_beta_residuals.png");
    let pitch_res: Vec<(f64, f64)> = (0..cfg.poses)
        .map(|s| (s as f64, e.residuals[s * rows]))
        .collect();
    let joint_res: Vec<(f64, f64)> = (0..cfg.poses)
        .map(|s| {
            let r = &e.residuals[s * rows + 1..(s + 1) * rows];
            (
                s as f64,
                (r.iter().map(|x| x * x).sum::<f64>() / r.len() as f64).sqrt(),
            )
        })
        .collect();
    figure_over(
        &path,
        (1400, 900),
        &[
            Panel {
                title: format!(
                    "(a) residuals per pose (noise: {} N m torque, {} rad pitch)",
                    cfg.torque_noise, cfg.pitch_noise
                ),
                y_label: "residual (N m)",
                series: vec![
                    Series::line("pitch (balance) row", ORANGE, pitch_res),
                    Series::line("RMS over the 16 joint rows", BLUE_, joint_res),
                ],
            },
            Panel {
                title: "(a) balance pitch of each pose".into(),
                y_label: "q_imu (rad)",
                series: vec![Series::line(
                    "q_imu",
                    BLUE_,
                    indexed(beta.pitches.iter().copied()),
                )],
            },
        ],
        "pose",
    )?;
    files.push(path);

    // (b) residuals over time for the left arm's joints, parameter errors.
    let t = &trajectory;
    let e = &t.estimate;
    let dof = fixed_wheels::DOF;
    let path = dir.join("identify_trajectory.png");
    use fixed_wheels::index as fw;
    let arm_joints = [
        ("q1l", fw::QD1L),
        ("q2l", fw::QD2L),
        ("q3l", fw::QD3L),
        ("q4l", fw::QD4L),
        ("q5l", fw::QD5L),
        ("q6l", fw::QD6L),
        ("q7l", fw::QD7L),
    ];
    let series = arm_joints
        .iter()
        .zip(PALETTE)
        .map(|(&(name, j), color)| {
            Series::line(
                name,
                color,
                t.times
                    .iter()
                    .enumerate()
                    .map(|(s, &time)| (time, e.residuals[s * dof + j]))
                    .collect(),
            )
        })
        .collect();
    figure_over(
        &path,
        (1400, 700),
        &[Panel {
            title: format!(
                "(b) residuals of the left arm's joints, Fourier trajectory, {} N m noise",
                cfg.trajectory_noise
            ),
            y_label: "residual (N m)",
            series,
        }],
        "time (s)",
    )?;
    files.push(path);

    let path = dir.join("identify_trajectory_errors.png");
    figure_over(
        &path,
        (1400, 900),
        &[
            Panel {
                title: format!(
                    "(b) {} base parameters: (identified - truth) / sigma",
                    e.value.len()
                ),
                y_label: "error (sigma)",
                series: vec![Series::line(
                    "",
                    RED_,
                    indexed(
                        e.value
                            .iter()
                            .zip(&e.truth)
                            .zip(&e.std)
                            .map(|((v, t), s)| (v - t) / s),
                    ),
                )],
            },
            Panel {
                title: "(b) the left arm's base parameters, in their order: identified and truth"
                    .into(),
                y_label: "value (SI)",
                series: vec![
                    Series::line("truth", BLUE_, indexed(t.arm.iter().map(|&i| e.truth[i]))),
                    Series::dashed(
                        "identified",
                        RED_,
                        indexed(t.arm.iter().map(|&i| e.value[i])),
                    ),
                ],
            },
        ],
        "index into BASE_PARAMETER_NAMES",
    )?;
    files.push(path);
    Ok(Summary {
        beta,
        trajectory,
        files,
    })
}

fn main() -> Res<()> {
    let dir = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/plots"));
    let lab = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/krang/params");
    let cfg = Config::default();
    let s = run(&dir, &lab, &cfg)?;
    let e = &s.beta.estimate;
    println!(
        "(a) beta: {} of {} combinations identifiable, {} balanced poses (pitch {:.3} … {:.3} rad), noise {} N·m, {} rad",
        BASE_BETA_NAMES.len(),
        BETA_NAMES.len(),
        cfg.poses,
        s.beta.pitches.iter().copied().fold(f64::INFINITY, f64::min),
        s.beta
            .pitches
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max),
        cfg.torque_noise,
        cfg.pitch_noise
    );
    println!(
        "    residual RMS {:.3} N·m; worst error {:.2} σ, {:.1e} relative",
        e.residual_rms, e.worst_sigma, e.worst_relative
    );
    println!(
        "    the lab's ideal vector mapped to the model's bodies: max |Δβ| = {:.1e} (the motor plates' 0.1 g)",
        s.beta.ideal_vs_model
    );
    println!(
        "    {:<8} {:>10} {:>10} {:>8} {:>10}",
        "", "truth", "identified", "σ", "hardware"
    );
    for (i, name) in BASE_BETA_NAMES.iter().enumerate() {
        println!(
            "    {name:<8} {:>10.4} {:>10.4} {:>8.4} {:>10.4}",
            e.truth[i], e.value[i], e.std[i], s.beta.hardware[i]
        );
    }
    let e = &s.trajectory.estimate;
    println!(
        "(b) fixed-wheel tree: {} base parameters from {} samples over {} s, noise {} N·m",
        e.value.len(),
        cfg.samples,
        cfg.period,
        cfg.trajectory_noise
    );
    println!(
        "    residual RMS {:.3} N·m; worst error {:.2} σ, {:.1e} relative",
        e.residual_rms, e.worst_sigma, e.worst_relative
    );
    println!(
        "    the left arm's: {:<8} {:>10} {:>10} {:>8}",
        "", "truth", "identified", "σ"
    );
    for &i in &s.trajectory.arm {
        println!(
            "    {:<8} {:>10.4} {:>10.4} {:>8.4}",
            fixed_wheels::BASE_PARAMETER_NAMES[i],
            e.truth[i],
            e.value[i],
            e.std[i]
        );
    }
    for f in &s.files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
