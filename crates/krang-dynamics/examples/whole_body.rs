//! Whole-body control of Krang in simulation, built only from the generated functions: the mass
//! matrix `M`, `c + g` (inverse dynamics at `u̇ = 0`), the centre-of-mass Jacobian and bias
//! acceleration, and the hands' poses, Jacobians and bias accelerations (`left_hand`,
//! `right_hand`, the operational frames of `krang.toml`).
//!
//! Every control step reads them from **one** generated call, `Krang::whole_body_terms` (a
//! combined function, see `build.rs`): the sines and cosines, rotations, positions and motion
//! pass are computed once for all of them (the values are those of the separate functions: bit
//! for bit in the baseline copy, to 10⁻¹² in the dispatched x86-64-v3 copy, where a product
//! shared in one program and written inline in the other is fused in only one; docs/kinematics.md).
//!
//! The 19-speed robot (wheeled base, no ground contact other than rolling) starts at rest,
//! balanced (centre of mass above the axle), arms in the pose of the `simulate` example. The
//! controller, a task-priority inverse dynamics law run at 1 kHz (torque held between samples),
//! chooses `u̇` by four levels, each solved in the null space of the ones before with
//! dynamically consistent (`M⁻¹`-weighted) pseudo-inverses:
//!
//! 1. **what the actuators can do**: the 18 actuators span all generalized forces but one
//!    direction `n = R e_ẋ + e_imu` (`nᵀ B = 0`: no actuator creates a moment about the wheels'
//!    contact line), so `nᵀ (M u̇ + c + g) = 0`;
//! 2. **balance**: the centre of mass's forward offset from the axle, `x_G` in frame 0, follows
//!    `ẍ_G = −k_p x_G − k_d ẋ_G` (relative to frame 0);
//! 3. **hands**: the right hand tracks a circle (radius 8 cm, period 4 s, in frame 0's y–z plane,
//!    starting where the hand is, the angular speed ramped up over 1 s) and keeps its
//!    orientation; the left hand holds its pose (12 rows, `p̈ = p̈_d + K_d (ṗ_d − ṗ) + K_p e`);
//! 4. **posture**: every coordinate back to its initial value (`ẋ` damped, heading held).
//!
//! The actuator torques are then `a = B⁺ (M u̇ + c + g)` (exact: level 1 puts it in the range of
//! `B`), clamped to [`hardware::TORQUE_LIMITS`] by [`saturate`], and the robot is integrated by
//! RK4 with the generated forward dynamics. Tasks are relative to frame 0 (the heading frame at
//! the axle midpoint): the generated Jacobians and biases are inertial, so the base's `ẋ`, `ψ̇`
//! columns are dropped and the bias loses the frame's own motion terms (`a₀ = [ẍ, ẋψ̇, 0]`,
//! Coriolis and centripetal terms of the heading rate), see [`relative_bias`].
//!
//! ```text
//! cargo run --release -p krang-dynamics --features fixed-wheels,kinematics --example whole_body -- [DIR]
//! ```
//! writes `whole_body.png` to DIR (default `target/plots`): hand errors, the CoM offset, the
//! pitch, and every actuator torque relative to its limit.

use std::error::Error;
use std::path::{Path, PathBuf};

use krang_dynamics::{ACTUATOR_COUNT, Frame, Krang, actuator, hardware, index, saturate};
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector, Vector3};

#[allow(dead_code)]
#[path = "simulate/main.rs"]
mod simulate;
use simulate::{BLUE_, GREEN_, ORANGE, PALETTE, Panel, RED_, Series, figure, rk4};

type Res<T> = Result<T, Box<dyn Error>>;
type V19 = SVector<f64, 19>;

/// Settings of the run.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// Simulated time (s).
    pub duration: f64,
    /// Control period and RK4 step (s).
    pub step: f64,
    /// Radius of the right hand's circle (m).
    pub radius: f64,
    /// Period of the circle (s).
    pub period: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            duration: 8.0,
            step: 1e-3,
            radius: 0.08,
            period: 4.0,
        }
    }
}

/// What the run shows (printed by `main`, checked by `tests/whole_body.rs`).
#[derive(Debug, Clone)]
pub struct Summary {
    /// Largest right-hand position error after the first second (m).
    pub right_hand_error: f64,
    /// Largest left-hand position error (m).
    pub left_hand_error: f64,
    /// Largest orientation error of either hand (rad, `|e_o|`).
    pub orientation_error: f64,
    /// Largest forward offset of the centre of mass from the axle (m).
    pub com_offset: f64,
    /// Range of the base pitch `q_imu` (rad).
    pub pitch_range: (f64, f64),
    /// Largest `|a_i| / limit_i` over the run and the actuators.
    pub max_torque_ratio: f64,
    /// Control steps in which an actuator was clamped.
    pub saturated_steps: usize,
    /// Largest residual of level 1 (`|nᵀ(M u̇ + c + g)|`, N·m) before clamping.
    pub underactuation_residual: f64,
    /// Final forward position and heading `(x, ψ)`.
    pub base_drift: (f64, f64),
    /// The PNG written.
    pub file: PathBuf,
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
        "whole-body control, {} s at {} Hz: right hand on a {} m circle (period {} s), left hand held",
        cfg.duration,
        1.0 / cfg.step,
        cfg.radius,
        cfg.period
    );
    println!(
        "  hand errors: right {:.2e} m (after 1 s), left {:.2e} m, orientation {:.2e} rad",
        s.right_hand_error, s.left_hand_error, s.orientation_error
    );
    println!(
        "  CoM ahead of the axle: max {:.2e} m; pitch in [{:.4}, {:.4}] rad; base x {:.3e} m, ψ {:.3e} rad",
        s.com_offset, s.pitch_range.0, s.pitch_range.1, s.base_drift.0, s.base_drift.1
    );
    println!(
        "  torques: max {:.0} % of the limits, {} clamped steps; underactuation residual {:.1e} N·m",
        100.0 * s.max_torque_ratio,
        s.saturated_steps,
        s.underactuation_residual
    );
    println!(
        "  wrote {} ({:.2} s)",
        s.file.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// One level of the hierarchy: `A u̇ = b`.
struct Task {
    a: DMatrix<f64>,
    b: DVector<f64>,
}

/// `u̇` from the tasks in priority order: each level's least-squares solution in the null space
/// of the levels before, with `M⁻¹`-weighted (dynamically consistent) pseudo-inverses
/// `Â⁺ = M⁻¹Âᵀ(ÂM⁻¹Âᵀ)⁺`, `Â = A N`, `N ← N − Â⁺Â`.
fn prioritized(minv: &DMatrix<f64>, tasks: &[Task]) -> DVector<f64> {
    let n = minv.nrows();
    let mut x = DVector::zeros(n);
    let mut null = DMatrix::identity(n, n);
    for t in tasks {
        let a = &t.a * &null;
        let g = &a * minv * a.transpose();
        let g_inv = g
            .clone()
            .pseudo_inverse(1e-9 * g.norm().max(1e-300))
            .expect("non-negative tolerance");
        let pinv = minv * a.transpose() * g_inv;
        x += &pinv * (&t.b - &t.a * &x);
        null -= &pinv * &a;
    }
    x
}

/// The acceleration of a point (or the angular acceleration of a frame) relative to frame 0,
/// at `u̇ = 0`, from the generated inertial bias: with frame 0 moving by `a₀ = [ẍ, ẋψ̇, 0]` and
/// turning at `ψ̇ ẑ`, the inertial acceleration of a point at `p` moving at `v` relative to
/// frame 0 is `a₀ + ψ̈ ẑ × p + ψ̇² ẑ × (ẑ × p) + 2 ψ̇ ẑ × v + a_rel`, and the inertial angular
/// acceleration `ψ̈ ẑ + ψ̇ ẑ × ω_rel + α_rel`.
fn relative_bias(
    bias: Vector3<f64>,
    u: &V19,
    rel_vel: Vector3<f64>,
    point: Option<Vector3<f64>>,
) -> Vector3<f64> {
    let (xd, psid) = (u[index::XD], u[index::PSID]);
    let z = Vector3::z();
    match point {
        Some(p) => {
            bias - Vector3::new(0.0, xd * psid, 0.0)
                - z.cross(&z.cross(&p)) * (psid * psid)
                - z.cross(&rel_vel) * (2.0 * psid)
        }
        None => bias - z.cross(&rel_vel) * psid,
    }
}

/// `J` without the base's `ẋ`, `ψ̇` columns: the Jacobian relative to frame 0.
fn relative<const R: usize>(j: &SMatrix<f64, R, 19>) -> SMatrix<f64, R, 19> {
    let mut j = *j;
    j.column_mut(index::XD).fill(0.0);
    j.column_mut(index::PSID).fill(0.0);
    j
}

/// `½ Σ rᵢ × r_dᵢ` over the columns: the rotation error, about an axis in frame 0.
fn orientation_error(r: &Matrix3<f64>, rd: &Matrix3<f64>) -> Vector3<f64> {
    (0..3)
        .map(|i| r.column(i).cross(&rd.column(i)))
        .fold(Vector3::zeros(), |s, c| s + c)
        * 0.5
}

/// Desired right-hand position, velocity and acceleration (frame 0): a circle in the y–z
/// plane through `start`, its angle `θ(t)` with `θ̇ = Ω s(t/T)`, `s` a smoothstep over `T = 1 s`.
fn circle(cfg: &Config, start: Vector3<f64>, t: f64) -> [Vector3<f64>; 3] {
    let w = 2.0 * std::f64::consts::PI / cfg.period;
    let ramp = 1.0;
    let (th, thd, thdd) = if t < ramp {
        let x = t / ramp;
        (
            w * ramp * (x.powi(3) - 0.5 * x.powi(4)),
            w * (3.0 * x * x - 2.0 * x.powi(3)),
            w * (6.0 * x - 6.0 * x * x) / ramp,
        )
    } else {
        (w * (t - 0.5 * ramp), w, 0.0)
    };
    let r = cfg.radius;
    let centre = start - Vector3::new(0.0, r, 0.0);
    let (s, c) = th.sin_cos();
    let p = centre + Vector3::new(0.0, r * c, r * s);
    let v = Vector3::new(0.0, -r * s, r * c) * thd;
    let a =
        Vector3::new(0.0, -r * c, -r * s) * (thd * thd) + Vector3::new(0.0, -r * s, r * c) * thdd;
    [p, v, a]
}

/// Gains (natural frequency `ω`, critically damped: `K_p = ω²`, `K_d = 2ω`).
const BALANCE: f64 = 6.0;
const HANDS: f64 = 12.0;
const POSTURE: f64 = 4.0;

/// The controller's output at one sample.
struct Control {
    actuators: SVector<f64, ACTUATOR_COUNT>,
    residual: f64,
    errors: [f64; 3],
    com: f64,
}

/// The desired poses and the initial posture.
struct Targets {
    q0: V19,
    right_start: Vector3<f64>,
    right_rotation: Matrix3<f64>,
    left: (Vector3<f64>, Matrix3<f64>),
}

/// The task-priority law at `(q, u)`, time `t`.
fn control(k: &Krang, cfg: &Config, goal: &Targets, t: f64, q: &V19, u: &V19) -> Control {
    // Everything the tasks read at this state, from one generated program: sines, cosines,
    // rotations and the motion pass computed once for M, c + g, the CoM and both hands.
    let w = k.whole_body_terms(q, u);
    let m = w.mass_matrix;
    let h = w.nonlinear_effects; // c + g
    let minv = m.cholesky().expect("M is positive definite").inverse();
    let minv = DMatrix::from_column_slice(19, 19, minv.as_slice());
    let mut tasks = Vec::new();

    // 1. The direction no actuator reaches: n = R e_ẋ + e_imu.
    let mut n = V19::zeros();
    n[index::XD] = k.params().R;
    n[index::QD_IMU] = 1.0;
    tasks.push(Task {
        a: DMatrix::from_row_slice(1, 19, (n.transpose() * m).as_slice()),
        b: DVector::from_element(1, -n.dot(&h)),
    });

    // 2. Balance: the CoM's forward offset from the axle, relative to frame 0.
    let com = w.center_of_mass;
    let jg = relative(&w.com_jacobian);
    let vg = jg * u;
    let bg = relative_bias(w.com_bias_acceleration, u, vg, Some(com));
    let (kp, kd) = (BALANCE * BALANCE, 2.0 * BALANCE);
    tasks.push(Task {
        a: DMatrix::from_row_slice(1, 19, jg.row(0).transpose().as_slice()),
        b: DVector::from_element(1, -kp * com.x - kd * vg.x - bg.x),
    });

    // 3. Hands: position and orientation, right on the circle, left held.
    let (kp, kd) = (HANDS * HANDS, 2.0 * HANDS);
    let [pd, vd, ad] = circle(cfg, goal.right_start, t);
    let mut a = DMatrix::zeros(12, 19);
    let mut b = DVector::zeros(12);
    let mut errors = [0.0; 3];
    let hands = [
        (
            (
                w.frame_pose_right_hand,
                w.frame_jacobian_right_hand,
                w.frame_bias_acceleration_right_hand,
            ),
            (pd, goal.right_rotation),
            vd,
            ad,
        ),
        (
            (
                w.frame_pose_left_hand,
                w.frame_jacobian_left_hand,
                w.frame_bias_acceleration_left_hand,
            ),
            goal.left,
            Vector3::zeros(),
            Vector3::zeros(),
        ),
    ];
    for (i, ((pose, jacobian, bias), (p_goal, r_goal), v_goal, a_goal)) in
        hands.into_iter().enumerate()
    {
        let (p, r) = (
            pose.translation.vector,
            *pose.rotation.to_rotation_matrix().matrix(),
        );
        let j = relative(&jacobian);
        let twist = j * u;
        let (v, w) = (
            twist.fixed_rows::<3>(0).into_owned(),
            twist.fixed_rows::<3>(3).into_owned(),
        );
        let bl = relative_bias(bias.fixed_rows::<3>(0).into_owned(), u, v, Some(p));
        let ba = relative_bias(bias.fixed_rows::<3>(3).into_owned(), u, w, None);
        let e = p_goal - p;
        let eo = orientation_error(&r, &r_goal);
        errors[i] = e.norm();
        errors[2] = errors[2].max(eo.norm());
        let lin = a_goal + (v_goal - v) * kd + e * kp - bl;
        let ang = eo * kp - w * kd - ba;
        for row in 0..6 {
            for col in 0..19 {
                a[(6 * i + row, col)] = j[(row, col)];
            }
            b[6 * i + row] = if row < 3 { lin[row] } else { ang[row - 3] };
        }
    }
    tasks.push(Task { a, b });

    // 4. Posture: every coordinate back to q0, ẋ damped.
    let (kp, kd) = (POSTURE * POSTURE, 2.0 * POSTURE);
    let mut posture = (goal.q0 - q) * kp - u * kd;
    posture[index::X] = -kd * u[index::XD];
    tasks.push(Task {
        a: DMatrix::identity(19, 19),
        b: DVector::from_column_slice(posture.as_slice()),
    });

    let ud = prioritized(&minv, &tasks);
    let ud = V19::from_column_slice(ud.as_slice());
    let tau = m * ud + h;
    // a = B⁺ τ: the joints drive their own speeds; the wheels share ẋ and ψ̇.
    let (rr, ll) = (k.params().R, k.params().L);
    let mut act = SVector::<f64, ACTUATOR_COUNT>::zeros();
    let sum = rr * tau[index::XD];
    let diff = 2.0 * rr / ll * tau[index::PSID];
    act[actuator::WHEEL_L] = 0.5 * (sum - diff);
    act[actuator::WHEEL_R] = 0.5 * (sum + diff);
    for j in actuator::WAIST..ACTUATOR_COUNT {
        act[j] = tau[j + 1];
    }
    Control {
        actuators: act,
        residual: n.dot(&tau).abs(),
        errors,
        com: com.x,
    }
}

/// One recorded control sample.
struct Sample {
    t: f64,
    errors: [f64; 3],
    com: f64,
    pitch: f64,
    ratios: [f64; ACTUATOR_COUNT],
}

/// Runs the simulation and writes the plot to `dir`.
pub fn run(dir: &Path, cfg: &Config) -> Res<Summary> {
    let k = Krang::default();
    let mut q = simulate::pose();
    q[index::Q_IMU] = k.upright_pitch(&q);
    let mut u = V19::zeros();
    let right = k.frame_pose(&q, Frame::from_name("right_hand").ok_or("no right_hand")?);
    let left = k.frame_pose(&q, Frame::from_name("left_hand").ok_or("no left_hand")?);
    let goal = Targets {
        q0: q,
        right_start: right.translation.vector,
        right_rotation: *right.rotation.to_rotation_matrix().matrix(),
        left: (
            left.translation.vector,
            *left.rotation.to_rotation_matrix().matrix(),
        ),
    };
    let limits = hardware::TORQUE_LIMITS;
    let steps = (cfg.duration / cfg.step).round() as usize;
    let mut log = Vec::with_capacity(steps);
    let (mut saturated, mut residual) = (0, 0.0f64);
    for n in 0..steps {
        let t = n as f64 * cfg.step;
        let c = control(&k, cfg, &goal, t, &q, &u);
        let applied = saturate(&c.actuators);
        if applied != c.actuators {
            saturated += 1;
        }
        residual = residual.max(c.residual);
        let mut ratios = [0.0; ACTUATOR_COUNT];
        for (i, r) in ratios.iter_mut().enumerate() {
            *r = c.actuators[i] / limits[i];
        }
        log.push(Sample {
            t,
            errors: c.errors,
            com: c.com,
            pitch: q[index::Q_IMU],
            ratios,
        });
        let tau = k.generalized_forces(&applied);
        let mut s = SVector::<f64, 38>::zeros();
        s.fixed_rows_mut::<19>(0).copy_from(&q);
        s.fixed_rows_mut::<19>(19).copy_from(&u);
        let rhs = |_t: f64, s: &SVector<f64, 38>| {
            let (q, u) = (
                s.fixed_rows::<19>(0).into_owned(),
                s.fixed_rows::<19>(19).into_owned(),
            );
            let mut d = SVector::<f64, 38>::zeros();
            d.fixed_rows_mut::<19>(0).copy_from(&u);
            d.fixed_rows_mut::<19>(19)
                .copy_from(&k.forward_dynamics(&q, &u, &tau));
            d
        };
        s = rk4(rhs, t, &s, cfg.step);
        q = s.fixed_rows::<19>(0).into_owned();
        u = s.fixed_rows::<19>(19).into_owned();
        if !q.iter().chain(u.iter()).all(|x| x.is_finite()) {
            return Err(format!("the simulation diverged at t = {t} s").into());
        }
    }

    let worst = |f: &dyn Fn(&Sample) -> f64, from: f64| {
        log.iter()
            .filter(|s| s.t >= from)
            .map(|s| f(s).abs())
            .fold(0.0, f64::max)
    };
    let pitch = |f: fn(f64, f64) -> f64, init: f64| log.iter().map(|s| s.pitch).fold(init, f);
    std::fs::create_dir_all(dir)?;
    let file = dir.join("whole_body.png");
    plots(&file, &log)?;
    Ok(Summary {
        right_hand_error: worst(&|s| s.errors[0], 1.0),
        left_hand_error: worst(&|s| s.errors[1], 0.0),
        orientation_error: worst(&|s| s.errors[2], 0.0),
        com_offset: worst(&|s| s.com, 0.0),
        pitch_range: (
            pitch(f64::min, f64::INFINITY),
            pitch(f64::max, f64::NEG_INFINITY),
        ),
        max_torque_ratio: worst(
            &|s| s.ratios.iter().fold(0.0f64, |m, r| m.max(r.abs())),
            0.0,
        ),
        saturated_steps: saturated,
        underactuation_residual: residual,
        base_drift: (q[index::X], q[index::PSI]),
        file,
    })
}

fn plots(file: &Path, log: &[Sample]) -> Res<()> {
    let time = |f: &dyn Fn(&Sample) -> f64| log.iter().map(|s| (s.t, f(s))).collect::<Vec<_>>();
    let names = [
        "wheel L", "wheel R", "waist", "torso", "1l", "2l", "3l", "4l", "5l", "6l", "7l", "1r",
        "2r", "3r", "4r", "5r", "6r", "7r",
    ];
    let torque = |range: std::ops::Range<usize>| {
        range
            .enumerate()
            .map(|(c, i)| {
                Series::line(names[i], PALETTE[c % PALETTE.len()], time(&|s| s.ratios[i]))
            })
            .collect::<Vec<_>>()
    };
    figure(
        file,
        (1200, 1800),
        &[
            Panel {
                title: "hand errors (right: circle r = 8 cm, period 4 s; left: hold)".into(),
                y_label: "error (mm, mrad)",
                series: vec![
                    Series::line("right position", RED_, time(&|s| 1e3 * s.errors[0])),
                    Series::line("left position", BLUE_, time(&|s| 1e3 * s.errors[1])),
                    Series::line("orientation (worst)", GREEN_, time(&|s| 1e3 * s.errors[2])),
                ],
            },
            Panel {
                title: "centre of mass ahead of the axle".into(),
                y_label: "x_G in frame 0 (mm)",
                series: vec![Series::line("x_G", BLUE_, time(&|s| 1e3 * s.com))],
            },
            Panel {
                title: "base pitch".into(),
                y_label: "q_imu (rad)",
                series: vec![Series::line("q_imu", ORANGE, time(&|s| s.pitch))],
            },
            Panel {
                title: "wheel, waist and torso torques / TORQUE_LIMITS".into(),
                y_label: "a / limit",
                series: torque(0..4),
            },
            Panel {
                title: "left arm torques / TORQUE_LIMITS".into(),
                y_label: "a / limit",
                series: torque(4..11),
            },
            Panel {
                title: "right arm torques / TORQUE_LIMITS".into(),
                y_label: "a / limit",
                series: torque(11..18),
            },
        ],
    )
}
