//! The actuator map (DynamicModeling.tex, Kane's right-hand side) and the hardware constants
//! (`models/krang/hardware/*.cfg`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use krang_dynamics::hardware::{self, Drive, JointDrive, WheelDrive};
use krang_dynamics::{
    ACTUATOR_COUNT, ACTUATOR_NAMES, Krang, Params, SPEED_NAMES, actuator, index, saturate,
    saturate_to,
};
use nalgebra::SVector;

fn wheels(tl: f64, tr: f64) -> SVector<f64, ACTUATOR_COUNT> {
    let mut a = SVector::zeros();
    a[actuator::WHEEL_L] = tl;
    a[actuator::WHEEL_R] = tr;
    a
}

#[test]
fn equal_wheel_torques_drive_forward_and_pitch_the_base_back_without_turning() {
    let k = Krang::default();
    let (r, l) = (k.params().R, k.params().L);
    for t in [1.0, -3.5, 20.0] {
        let f = k.generalized_forces(&wheels(t, t));
        assert_eq!(f[index::PSI], 0.0);
        assert!((f[index::X] - 2.0 * t / r).abs() < 1e-15 * t.abs() / r);
        // The reaction on the base equals −(τL + τR).
        assert_eq!(f[index::Q_IMU], -2.0 * t);
        assert!(f.rows(3, 16).iter().all(|&x| x == 0.0));
        // Opposite torques turn: no forward force, no base reaction.
        let f = k.generalized_forces(&wheels(-t, t));
        assert_eq!(f[index::X], 0.0);
        assert_eq!(f[index::Q_IMU], 0.0);
        assert!((f[index::PSI] - l / r * t).abs() < 1e-15 * (l / r * t).abs());
    }
    // τR > τL turns left (positive ψ̇ about z up).
    assert!(k.generalized_forces(&wheels(0.0, 1.0))[index::PSI] > 0.0);
}

#[test]
fn q_imu_reaction_is_minus_the_wheel_torque_sum_for_any_torques() {
    let k = Krang::default();
    let a = SVector::<f64, ACTUATOR_COUNT>::from_fn(|i, _| (i as f64 * 1.7).sin() * 10.0);
    let f = k.generalized_forces(&a);
    assert_eq!(
        f[index::Q_IMU],
        -(a[actuator::WHEEL_L] + a[actuator::WHEEL_R])
    );
    // ẋ row times R equals minus the q_imu row: only 18 of 19 generalized forces are free.
    assert!((f[index::X] * k.params().R + f[index::Q_IMU]).abs() < 1e-12);
}

#[test]
fn each_joint_torque_acts_on_its_own_row_only() {
    let k = Krang::default();
    for j in actuator::WAIST..ACTUATOR_COUNT {
        let mut a = SVector::<f64, ACTUATOR_COUNT>::zeros();
        a[j] = 7.0;
        let f = k.generalized_forces(&a);
        let row = j + 1;
        for (i, &x) in f.iter().enumerate() {
            assert_eq!(x, if i == row { 7.0 } else { 0.0 }, "actuator {j}, row {i}");
        }
        // Names line up: tau_waist → qd_w, tau_1l → qd1l, …
        let speed = SPEED_NAMES[row]
            .trim_start_matches("qd")
            .trim_start_matches('_');
        let act = ACTUATOR_NAMES[j].trim_start_matches("tau_");
        assert_eq!(
            if act == "waist" { "w" } else { act },
            speed,
            "{j}: {} vs {}",
            ACTUATOR_NAMES[j],
            SPEED_NAMES[row]
        );
    }
    assert_eq!(ACTUATOR_NAMES[actuator::LEFT_ARM.start], "tau_1l");
    assert_eq!(ACTUATOR_NAMES[actuator::RIGHT_ARM.end - 1], "tau_7r");
    assert_eq!(
        SPEED_NAMES[krang_dynamics::forward::RIGHT_ARM.start],
        "qd1r"
    );
}

#[test]
fn matrix_and_direct_map_agree_and_are_power_consistent() {
    let k = Krang::new(Params {
        R: 0.3,
        L: 0.9,
        ..Params::default()
    });
    let b = k.actuator_matrix();
    assert_eq!(b[(index::PSI, actuator::WHEEL_R)], 0.9 / 0.6);
    assert_eq!(b[(index::X, actuator::WHEEL_L)], 1.0 / 0.3);
    for s in 0..20 {
        let a = SVector::<f64, ACTUATOR_COUNT>::from_fn(|i, _| ((i + 3 * s) as f64).cos() * 40.0);
        let u = SVector::<f64, 19>::from_fn(|i, _| ((2 * i + s) as f64).sin());
        let f = k.generalized_forces(&a);
        assert!((f - b * a).abs().max() < 1e-12);
        let v = k.actuator_velocities(&u);
        assert!((v - b.transpose() * u).abs().max() < 1e-12);
        // Actuator power = generalized power.
        assert!((a.dot(&v) - f.dot(&u)).abs() < 1e-10 * (a.norm() * v.norm()));
        // The left wheel turns relative to the base at θ̇L − q̇_imu.
        let theta_l = u[index::X] / 0.3 - 0.9 / 0.6 * u[index::PSI];
        assert!((v[actuator::WHEEL_L] - (theta_l - u[index::Q_IMU])).abs() < 1e-12);
    }
    assert_eq!(nalgebra::SMatrix::<f64, 19, 18>::zeros().rank(0.0), 0);
    assert_eq!(b.rank(1e-12), 18);
}

#[test]
fn wheel_torques_accelerate_an_upright_krang_forward_and_pitch_it_back() {
    let k = Krang::default();
    let mut q = SVector::<f64, 19>::zeros();
    q[index::Q_IMU] = k.upright_pitch(&q);
    let u = SVector::<f64, 19>::zeros();
    let ud0 = k.forward_dynamics(&q, &u, &SVector::zeros());
    let ud = k.forward_dynamics(&q, &u, &k.generalized_forces(&wheels(10.0, 10.0)));
    assert!(ud[index::X] > 0.0);
    // q_imu is a rotation about +y0 (the axle, pointing left); pitching back is negative.
    assert!(ud[index::Q_IMU] < ud0[index::Q_IMU]);
    // Differential torque τR > τL turns left (M⁻¹ is positive definite, so the ψ̈ response to
    // a pure ψ̇ force has the force's sign).
    let ud = k.forward_dynamics(&q, &u, &k.generalized_forces(&wheels(-10.0, 10.0)));
    assert!(ud[index::PSI] > ud0[index::PSI]);
}

#[test]
fn saturate_clamps_to_the_peak_torques() {
    let limits = hardware::TORQUE_LIMITS;
    let big = SVector::<f64, ACTUATOR_COUNT>::from_fn(|i, _| if i % 2 == 0 { 1e4 } else { -1e4 });
    let s = saturate(&big);
    for i in 0..ACTUATOR_COUNT {
        assert_eq!(s[i].abs(), limits[i]);
        assert_eq!(s[i].signum(), big[i].signum());
    }
    let small = SVector::<f64, ACTUATOR_COUNT>::from_element(0.5);
    assert_eq!(saturate(&small), small);
    let mut nan = small;
    nan[3] = f64::NAN;
    assert!(saturate(&nan)[3].is_nan());
    let s = saturate_to(&big, &hardware::NOMINAL_TORQUES);
    assert_eq!(s[actuator::WAIST], 432.0);
    assert_eq!(s[actuator::TORSO], -216.0);
    assert_eq!(s[actuator::LEFT_ARM.end - 1], 4.5);
}

#[test]
fn derived_limits_have_the_documented_values() {
    let w = hardware::BLY343D;
    // 12 oz-in/A = 0.08474 N·m/A; × 50 A × 15 = 63.55 N·m at the wheel.
    assert!((w.torque_constant_si() - 0.084_738_6).abs() < 1e-7);
    assert!((w.peak_wheel_torque() - 63.553_97).abs() < 1e-4);
    assert!((w.rated_wheel_torque() - 27.010_436).abs() < 1e-4);
    // The gearbox would take more than the current limit gives.
    assert!(w.max_output_torque_si() > w.peak_wheel_torque());
    assert!((w.max_output_torque_si() - 504.02).abs() < 0.01);
    let expect = [
        63.553_97, 63.553_97, 744.0, 372.0, 372.0, 372.0, 176.0, 176.0, 41.4, 41.4, 9.6, 372.0,
        372.0, 176.0, 176.0, 41.4, 41.4, 9.6,
    ];
    for (i, (&l, e)) in hardware::TORQUE_LIMITS.iter().zip(expect).enumerate() {
        assert!((l - e).abs() < 1e-4, "{}: {l} vs {e}", ACTUATOR_NAMES[i]);
    }
    assert!((hardware::PRL120.torque_per_amp() - 37.2).abs() < 1e-12);
    assert!((hardware::PRL60.max_angular_velocity_si() - 50f64.to_radians()).abs() < 1e-15);
}

/// `key = "value"; # comment` lines of a krang cfg file.
fn parse_cfg(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter_map(|line| {
            let line = line.split('#').next()?.trim();
            let (key, value) = line.split_once('=')?;
            let value = value.trim().trim_end_matches(';').trim().trim_matches('"');
            Some((key.trim().to_string(), value.to_string()))
        })
        .collect()
}

fn wheel_fields(w: &WheelDrive) -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("rated_voltage", vec![w.rated_voltage]),
        ("rated_speed", vec![w.rated_speed]),
        ("rated_torque", vec![w.rated_torque]),
        ("rated_power", vec![w.rated_power]),
        ("rated_current", vec![w.rated_current]),
        ("line_to_line_resistance", vec![w.line_to_line_resistance]),
        ("line_to_line_inductance", vec![w.line_to_line_inductance]),
        ("torque_constant", vec![w.torque_constant]),
        ("back_emf_voltage", vec![w.back_emf_voltage]),
        ("rotor_inertia", vec![w.rotor_inertia]),
        ("gear_ratio", vec![w.gear_ratio]),
        ("rated_output_torque", vec![w.rated_output_torque]),
        ("max_output_torque", vec![w.max_output_torque]),
        ("rated_input_speed", vec![w.rated_input_speed]),
        ("stages", vec![w.stages]),
        ("max_backlash", vec![w.max_backlash]),
        ("max_input_current", vec![w.max_input_current]),
    ]
}

fn joint_fields(j: &JointDrive) -> Vec<(&'static str, Vec<f64>)> {
    let mut f = vec![
        ("motor_power", vec![j.motor_power]),
        ("nominal_torque", vec![j.nominal_torque]),
        ("peak_torque", vec![j.peak_torque]),
        ("max_angular_velocity", vec![j.max_angular_velocity]),
        ("max_angular_acceleration", vec![j.max_angular_acceleration]),
        ("gear_ratio", vec![j.gear_ratio]),
        ("nominal_power_current", vec![j.nominal_power_current]),
        ("max_current", vec![j.max_current]),
        ("coulomb_friction", vec![j.coulomb_friction]),
        ("viscous_friction", vec![j.viscous_friction]),
        ("position_ctrl_pd_gains", j.position_ctrl_pd_gains.to_vec()),
        ("speed_ctrl_pd_gains", j.speed_ctrl_pd_gains.to_vec()),
    ];
    if let Some(r) = j.reference_speed {
        f.push(("reference_speed", vec![r]));
    }
    f
}

/// The text of a cfg file; a missing file fails the test with its path.
fn read(path: &std::path::Path) -> String {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e} (the hardware cfg files)", path.display()))
}

/// Every key of the cfg file is a constant, with the same value(s), and vice versa.
fn check_drive(dir: &std::path::Path, model: &str, fields: Vec<(&'static str, Vec<f64>)>) {
    let path = dir.join(format!("{model}.cfg"));
    let cfg = parse_cfg(&read(&path));
    let ours: BTreeMap<&str, Vec<f64>> = fields.into_iter().collect();
    assert_eq!(
        cfg.keys().map(String::as_str).collect::<Vec<_>>(),
        ours.keys().copied().collect::<Vec<_>>(),
        "{}: keys",
        path.display()
    );
    for (key, value) in &cfg {
        let parsed: Vec<f64> = value
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(&parsed, &ours[key.as_str()], "{}: {key}", path.display());
    }
}

#[test]
fn hardware_constants_match_the_cfg_files() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/krang/hardware");
    check_drive(&dir, "bly343d", wheel_fields(&hardware::BLY343D));
    for j in [
        hardware::WAIST,
        hardware::PRL120,
        hardware::PRL100,
        hardware::PRL80,
        hardware::PRL60,
    ] {
        check_drive(&dir, j.model, joint_fields(&j));
    }
    // krang_motors.cfg: make and model of every actuator, and nothing else in the file.
    let motors = parse_cfg(&read(&dir.join("krang_motors.cfg")));
    assert_eq!(motors.len(), 2 * ACTUATOR_COUNT);
    for a in hardware::ACTUATORS {
        assert_eq!(motors[&format!("{}_make", a.joint)], a.make, "{}", a.joint);
        assert_eq!(
            motors[&format!("{}_model", a.joint)],
            a.drive.model(),
            "{}",
            a.joint
        );
        if let Drive::Wheel(w) = a.drive {
            assert_eq!(w, hardware::BLY343D);
        }
    }
}

#[test]
fn arm_ranges_name_the_same_joints_in_the_actuator_vector_and_in_u() {
    use krang_dynamics::forward;
    let b = Krang::default().actuator_matrix();
    for (arm, speeds) in [
        (actuator::LEFT_ARM, forward::LEFT_ARM),
        (actuator::RIGHT_ARM, forward::RIGHT_ARM),
    ] {
        assert_eq!(arm.len(), 7);
        for (j, i) in arm.zip(speeds) {
            assert_eq!(b[(i, j)], 1.0, "actuator {j} drives speed {i}");
            assert_eq!(
                ACTUATOR_NAMES[j].trim_start_matches("tau_"),
                SPEED_NAMES[i].trim_start_matches("qd")
            );
        }
    }
}

#[test]
fn index_names_speeds_as_well_as_coordinates() {
    assert_eq!((index::XD, index::PSID), (index::X, index::PSI));
    assert_eq!((index::QD_IMU, index::QD_W), (index::Q_IMU, index::Q_W));
    assert_eq!(index::QD7R, index::Q7R);
    for (i, name) in SPEED_NAMES.iter().enumerate() {
        assert_eq!(krang_dynamics::SPEED_NAMES[i], *name);
    }
    assert_eq!(SPEED_NAMES[index::QD_TORSO], "qd_torso");
    assert_eq!(SPEED_NAMES[index::PSID], "psid");
}
