//! Runs the `lqr` example's code on a shorter horizon and checks what the example claims: the
//! Riccati solver (residual, a known scalar case), both closed loops stable by their
//! eigenvalues, the nonlinear simulation of the full LQR returns to upright within the torque
//! limits, and the four PNG files.
//!
//! The full run is `cargo run --release -p krang-dynamics --features derivatives --example lqr -- DIR`.

#[allow(dead_code)]
#[path = "../examples/lqr/main.rs"]
mod lqr;

use std::path::Path;

use nalgebra::DMatrix;

#[test]
fn riccati_solver_matches_the_scalar_closed_form() {
    // x⁺ = a x + b u, cost q x² + r u²: X = a²X − a²b²X²/(r + b²X) + q, i.e.
    // b²X² + (r(1 − a²) − q b²) X − q r = 0.
    for (a, b, q, r) in [
        (1.2, 0.5, 2.0, 3.0),
        (0.9, 1.0, 1.0, 0.1),
        (2.0, 0.1, 5.0, 1.0),
    ] {
        let m = |v: f64| DMatrix::from_element(1, 1, v);
        let (x, k) = lqr::dlqr(&m(a), &m(b), &m(q), &m(r)).unwrap();
        let (qa, qb, qc) = (b * b, r * (1.0 - a * a) - q * b * b, -q * r);
        let exact = (-qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
        assert!((x[0] - exact).abs() <= 1e-10 * exact, "{} vs {exact}", x[0]);
        assert!((a - b * k[0]).abs() < 1.0, "closed loop stable");
    }
}

#[test]
fn lqr_example_balances_krang_and_writes_the_plots() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("lqr-plots");
    let cfg = lqr::Config {
        duration: 3.0,
        ..lqr::Config::default()
    };
    let s = lqr::run(&dir, &cfg).unwrap();
    eprintln!("{s:#?}");
    assert!(s.full_riccati_residual < 1e-8);
    assert!(s.full_closed_loop_radius < 1.0);
    assert!(s.wip_closed_loop_radius < 1.0);
    // The full LQR brings the robot back to upright.
    assert!(s.full.max_pitch_error >= cfg.tilt * 0.99);
    // Over the last of 3 s the pitch is within 0.02 rad (3.3e-3 at 5 s in the full run),
    // the joints within 0.1 rad of the pose, and no torque was clamped.
    assert!(
        s.full.final_pitch_error < 0.02,
        "{}",
        s.full.final_pitch_error
    );
    assert!(
        s.full.final_joint_error < 0.1,
        "{}",
        s.full.final_joint_error
    );
    assert_eq!(s.full.saturated_steps, 0);
    assert!(
        s.wip.final_pitch_error < 0.02,
        "{}",
        s.wip.final_pitch_error
    );
    for f in &s.files {
        let bytes = std::fs::read(f).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{}", f.display());
    }
    assert_eq!(s.files.len(), 4);
}
