//! Runs the `identify` example's code and checks what it claims: without noise the
//! identifiable combinations come back exactly (to 1e-9), with noise to the noise level (every
//! estimate within 5 of its standard deviations, the residual RMS near the noise), the lab's
//! ideal vector maps onto the model's β, the balance pitches balance, and the four PNG files.
//!
//! The full run is `cargo run --release -p krang-dynamics --features regressors,fixed-wheels,kinematics --example identify -- DIR`.

#[allow(dead_code)]
#[path = "../examples/identify.rs"]
mod identify;

use std::path::{Path, PathBuf};

use krang_dynamics::{Krang, Params, index};
use nalgebra::SVector;

/// The lab's beta vectors (`models/krang/params`).
fn lab() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/krang/params")
}

/// Sized for CI: 104 poses as on hardware, a shorter trajectory.
fn config() -> identify::Config {
    identify::Config {
        samples: 150,
        ..identify::Config::default()
    }
}

#[test]
fn beta_and_base_parameters_are_recovered_exactly_without_noise() {
    let cfg = identify::Config {
        torque_noise: 0.0,
        pitch_noise: 0.0,
        trajectory_noise: 0.0,
        ..config()
    };
    let beta = identify::identify_beta(&cfg, &lab()).unwrap();
    assert!(
        beta.estimate.worst_relative <= 1e-9,
        "β_b: {:e}",
        beta.estimate.worst_relative
    );
    let arm = identify::identify_trajectory(&cfg).unwrap();
    assert!(
        arm.estimate.worst_relative <= 1e-9,
        "π_b: {:e}",
        arm.estimate.worst_relative
    );
    // 7 bodies × 10 standard parameters, 3 of each (m, the axial first moment, one in-plane
    // inertia) grouped into the parent body.
    assert_eq!(arm.arm.len(), 49, "the left arm's base parameters");
}

#[test]
fn identification_with_noise_is_accurate_to_the_noise_level_and_writes_the_plots() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("identify-plots");
    let cfg = config();
    let s = identify::run(&dir, &lab(), &cfg).unwrap();
    let (a, b) = (&s.beta.estimate, &s.trajectory.estimate);
    println!(
        "(a) RMS {:.3}, worst {:.2} σ; (b) RMS {:.3}, worst {:.2} σ",
        a.residual_rms, a.worst_sigma, b.residual_rms, b.worst_sigma
    );
    assert!(a.worst_sigma <= 5.0, "(a) {} σ", a.worst_sigma);
    assert!(b.worst_sigma <= 5.0, "(b) {} σ", b.worst_sigma);
    // The residuals are the noise: the torque noise, and in (a) also the pitch noise seen
    // through the gravity stiffness (≈ 0.6 N·m at the balance row for 2 mrad).
    assert!((0.8 * cfg.torque_noise..1.5 * cfg.torque_noise).contains(&a.residual_rms));
    assert!((0.8 * cfg.trajectory_noise..1.1 * cfg.trajectory_noise).contains(&b.residual_rms));
    for f in &s.files {
        let len = std::fs::metadata(f).unwrap().len();
        assert!(len > 10_000, "{}: {len} bytes", f.display());
    }
    assert_eq!(s.files.len(), 4);
}

#[test]
fn the_lab_ideal_vector_maps_onto_the_model_beta() {
    // Only the motor plates' 0.1 g (and their 0.1 g·m first moments) differ.
    let beta = identify::identify_beta(&config(), &lab()).unwrap();
    assert!(beta.ideal_vs_model <= 2.5e-4, "{}", beta.ideal_vs_model);
    for (i, t) in beta.ideal.iter().zip(&beta.estimate.truth) {
        assert!((i - t).abs() <= 1e-3, "{i} vs {t}");
    }
    // The hardware-trained vector is another robot (and a fit): it differs, but it is finite.
    assert!(beta.hardware.iter().all(|v| v.is_finite()));
    assert_eq!(beta.hardware.len(), beta.ideal.len());
}

#[test]
fn balance_pitch_puts_the_centre_of_mass_above_the_axle() {
    let k = Krang::new(Params::default());
    let mut q = SVector::<f64, 19>::zeros();
    for (i, v) in q.iter_mut().enumerate().skip(index::Q_W) {
        *v = 0.1 * i as f64 - 0.8;
    }
    let pitch = identify::balance_pitch(&k, &q);
    q[index::Q_IMU] = pitch;
    assert!(k.gravity(&q)[index::QD_IMU].abs() <= 1e-9);
    // Inverted: a small tilt makes gravity push further (negative slope of g_imu).
    let mut tilted = q;
    tilted[index::Q_IMU] += 1e-4;
    assert!(k.gravity(&tilted)[index::QD_IMU] < 0.0);
    // The lab's vector with 23 bodies is read; a wrong count is an error, not a panic.
    assert!(identify::lab_beta_to_model(&[[1.0; 4]; 7]).is_err());
}
