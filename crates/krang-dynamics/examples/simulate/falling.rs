//! (a) The 19-speed Krang released at rest from a tilt, zero torque: energy conservation.

use std::path::{Path, PathBuf};

use krang_dynamics::{Krang, index};
use nalgebra::SVector;

use super::{
    BLUE_, Config, GREEN_, GREY, Kinematics, ORANGE, Panel, RED_, Res, Series, Summary, figure,
    pose, rk4,
};

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

pub(super) fn falling(dir: &Path, cfg: &Config, files: &mut Vec<PathBuf>) -> Res<Summary> {
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
