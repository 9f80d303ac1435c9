//! Runs the `whole_body` example's controller on a shorter horizon and checks what the example
//! claims: the right hand on its circle, the left hand held, the centre of mass above the axle,
//! the torques within `TORQUE_LIMITS` (no clamping) and the actuators' reach respected (the
//! underactuated direction), and the plot written.
//!
//! The full run is `cargo run --release -p krang-dynamics --features fixed-wheels,kinematics
//! --example whole_body -- DIR`.

#[allow(dead_code)]
#[path = "../examples/whole_body.rs"]
mod whole_body;

use std::path::Path;

#[test]
fn whole_body_control_balances_and_tracks_the_hands_within_the_torque_limits() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("whole-body-plots");
    let cfg = whole_body::Config {
        // 1.5 s at 500 Hz: a debug build takes about 15 s.
        duration: 1.5,
        step: 2e-3,
        ..whole_body::Config::default()
    };
    let s = whole_body::run(&dir, &cfg).unwrap();
    eprintln!("{s:#?}");
    assert!(
        s.right_hand_error < 5e-4,
        "right hand {}",
        s.right_hand_error
    );
    assert!(s.left_hand_error < 2e-4, "left hand {}", s.left_hand_error);
    assert!(s.orientation_error < 5e-3);
    assert!(s.com_offset < 2e-5, "CoM {}", s.com_offset);
    assert!(s.max_torque_ratio < 1.0 && s.saturated_steps == 0);
    assert!(s.underactuation_residual < 1e-6);
    assert!(std::fs::metadata(&s.file).unwrap().len() > 10_000);
}
