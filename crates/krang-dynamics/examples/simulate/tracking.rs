//! (b) Computed-torque tracking on fixed wheels.

use std::path::{Path, PathBuf};

use krang_dynamics::fixed_wheels::{self, KrangFixedWheels};
use krang_dynamics::{ACTUATOR_COUNT, Krang, actuator, hardware, index, saturate};
use nalgebra::SVector;

use super::{BLUE_, Config, PALETTE, Panel, RED_, Res, Series, Summary, figure, pose, rk4};

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

pub(super) fn tracking(
    dir: &Path,
    cfg: &Config,
    files: &mut Vec<PathBuf>,
    summary: &mut Summary,
) -> Res<()> {
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
