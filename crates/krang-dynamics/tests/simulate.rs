//! Runs the `simulate` example's code on a shorter horizon (a debug build takes seconds) and
//! checks what the example claims: energy conservation of the zero-torque fall, the upright
//! pitch by forward kinematics, computed-torque tracking, and the four PNG files.
//!
//! The full run is `cargo run --release -p krang-dynamics --features fixed-wheels,kinematics --example simulate -- DIR`.

#[allow(dead_code)]
#[path = "../examples/simulate/main.rs"]
mod simulate;

use std::path::Path;

#[test]
fn simulate_example_conserves_energy_tracks_and_writes_the_plots() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("simulate-plots");
    let cfg = simulate::Config {
        duration: 1.5,
        fall_step: 2.5e-4,
        control_step: 1e-3,
        tilt: 0.3,
    };
    let s = simulate::run(&dir, &cfg).unwrap();
    eprintln!("{s:#?}");
    // Upright: the centre of mass is above the axle (by forward kinematics, independent of
    // the generated gravity vector that `upright_pitch` uses).
    assert!(s.com_offset_at_upright.abs() < 1e-12);
    assert!(s.com_height_at_upright > 0.3);
    // The robot really falls, and energy is conserved.
    assert!(s.tilt_range.0 < -1.0);
    assert!(s.max_kinetic_energy > 500.0);
    assert!(
        s.energy_drift_relative < 1e-6,
        "{}",
        s.energy_drift_relative
    );
    assert!(s.power_balance_relative < 1e-6);
    // g is the gradient of the FK potential: V(q) − V(q0) = ∫ uᵀ g dt up to quadrature error.
    assert!(s.potential_vs_gravity_relative < 1e-8);
    // The generated potential energy is the FK potential of the example.
    assert!(s.potential_generated_vs_fk_relative < 1e-12);
    // Computed torque: the exact model tracks to what the 1 kHz hold leaves; an unmodelled
    // payload leaves far more.
    assert!(s.tracking_error_exact < 1e-2);
    assert!(s.tracking_error_payload > 10.0 * s.tracking_error_exact);
    assert!(s.peak_joint_torque_ratio < 1.0);
    assert_eq!(s.files.len(), 4);
    for name in ["pitch.png", "heading.png", "energy.png", "tracking.png"] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{name}");
        assert!(bytes.len() > 10_000, "{name}: {} bytes", bytes.len());
    }
}
