//! Runs the `rollouts` example's code on a shorter horizon and checks what it claims: every
//! lane of the batched rollouts (`forward_dynamics_batch_soa_with_mass_matrix`, states and
//! lane mass matrix kept across steps) ends in the state of the same rollout by
//! `forward_dynamics`, bit for bit; and the physics the choice rests on.
//!
//! The full run is `cargo run --release -p krang-dynamics --example rollouts`.

#[allow(dead_code)]
#[path = "../examples/rollouts.rs"]
mod rollouts;

#[test]
fn batched_rollouts_equal_single_state_rollouts_and_pick_a_recovering_torque() {
    let cfg = rollouts::Config {
        horizon: 0.15,
        ..rollouts::Config::default()
    };
    let o = rollouts::run(&cfg);
    eprintln!("{o:#?}");
    assert_eq!(o.steps, 150);
    assert!(o.lanes_equal_single_rollouts);
    // More wheel torque pushes the body back harder: the end pitch falls with the torque.
    assert!(
        o.pitch_errors.windows(2).all(|w| w[1] < w[0]),
        "{:?}",
        o.pitch_errors
    );
    // Without enough torque the tilt grows; the strongest candidate pulls it past upright.
    assert!(o.pitch_errors[0] > cfg.tilt);
    assert!(o.pitch_errors[rollouts::SAMPLES - 1] < 0.0);
    // The cheapest candidate is the one that ends nearest to upright and at rest, which
    // needs a torque between the extremes.
    assert!(o.costs.iter().all(|c| c.is_finite()));
    assert!(o.best > 0 && o.best < rollouts::SAMPLES - 1, "{}", o.best);
    assert!(o.torques[o.best] > 0.0);
}
