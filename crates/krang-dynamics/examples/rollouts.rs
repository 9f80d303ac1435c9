//! Sampling-based control with batched forward dynamics: one decision of a random-shooting
//! MPC (the sampling step of MPPI and its relatives) on the 19-speed Krang.
//!
//! Krang starts at rest, tilted `tilt` past its balancing pitch (`Krang::upright_pitch`).
//! Each of 8 candidates holds one wheel torque on both wheels for the horizon, spread evenly
//! over `±torque` (never beyond the wheels' peak torque, `hardware::TORQUE_LIMITS`). All
//! candidates are rolled out together, one state per lane, stepping semi-implicit Euler
//! (`u += h u̇`, then `q += h u`) with one call of
//! `Krang::forward_dynamics_batch_soa_with_mass_matrix` for all 8 states per step. The lane
//! mass matrix and the state lanes are kept across steps, so the loop allocates and zeroes
//! nothing. The candidate whose rollout ends nearest to upright and at rest wins (cost: pitch
//! error² + 0.1 · pitch rate² at the end of the horizon).
//!
//! The example also rolls every candidate out alone with `Krang::forward_dynamics`. It checks
//! that each lane of the batched rollout ended in that state **bit for bit**, and prints both
//! wall-clock times. Those times are informative only; criterion measures the calls
//! (`cargo bench --bench simd -- forward_dynamics`).
//!
//! ```text
//! cargo run --release -p krang-dynamics --example rollouts
//! ```

use std::time::Instant;

use krang_dynamics::lanes::{Lanes, soa, state};
use krang_dynamics::{ACTUATOR_COUNT, Krang, actuator, hardware, index};
use nalgebra::{SMatrix, SVector};

/// The number of candidates, one per lane (8: one AVX-512 register of `f64`).
pub const SAMPLES: usize = 8;

/// Rollout settings.
#[derive(Debug, Clone, Copy)]
pub struct Config {
    /// Initial tilt past the balancing pitch (rad; positive: forward).
    pub tilt: f64,
    /// Horizon (s).
    pub horizon: f64,
    /// Step (s).
    pub step: f64,
    /// The candidates' wheel torques spread over `±torque` (N·m per wheel).
    pub torque: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            tilt: 0.05,
            horizon: 0.4,
            step: 1e-3,
            torque: 40.0,
        }
    }
}

/// What the rollouts gave.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Each candidate's wheel torque (N·m per wheel).
    pub torques: [f64; SAMPLES],
    /// Each candidate's pitch error at the end of the horizon (rad; end pitch − balancing pitch).
    pub pitch_errors: [f64; SAMPLES],
    /// Each candidate's cost.
    pub costs: [f64; SAMPLES],
    /// The index of the cheapest candidate.
    pub best: usize,
    /// Whether every lane of the batched rollout ended in the state of its single-state
    /// rollout, bit for bit (coordinates and speeds).
    pub lanes_equal_single_rollouts: bool,
    /// The number of steps per rollout.
    pub steps: usize,
    /// Wall-clock time of the batched rollouts, all candidates (s).
    pub batched_seconds: f64,
    /// Wall-clock time of the single-state rollouts, all candidates (s).
    pub single_seconds: f64,
}

/// The generalized forces of a wheel torque `t` on both wheels (the other actuators idle).
fn wheel_forces(k: &Krang, t: f64) -> SVector<f64, 19> {
    let mut a = SVector::<f64, ACTUATOR_COUNT>::zeros();
    a[actuator::WHEEL_L] = t;
    a[actuator::WHEEL_R] = t;
    k.generalized_forces(&a)
}

/// Rolls the candidates out, batched and one by one (see the module docs).
pub fn run(cfg: &Config) -> Outcome {
    let k = Krang::default();
    let mut q0 = SVector::<f64, 19>::zeros();
    let upright = k.upright_pitch(&q0);
    q0[index::Q_IMU] = upright + cfg.tilt;
    let limit = cfg.torque.min(hardware::TORQUE_LIMITS[actuator::WHEEL_L]);
    let torques: [f64; SAMPLES] =
        core::array::from_fn(|l| -limit + 2.0 * limit * l as f64 / (SAMPLES - 1) as f64);
    let tau: [SVector<f64, 19>; SAMPLES] = torques.map(|t| wheel_forces(&k, t));
    let steps = (cfg.horizon / cfg.step).round() as usize;
    let h = cfg.step;

    // Batched: the states in lanes, kept across steps with the lane mass matrix.
    let start = Instant::now();
    let tau_lanes = soa(&tau);
    let (mut q, mut u) = (soa(&[q0; SAMPLES]), soa(&[SVector::zeros(); SAMPLES]));
    let mut ud = SVector::<Lanes<SAMPLES>, 19>::from_element(Lanes::splat(0.0));
    let mut m = SMatrix::<Lanes<SAMPLES>, 19, 19>::from_element(Lanes::splat(0.0));
    for _ in 0..steps {
        k.forward_dynamics_batch_soa_with_mass_matrix(&q, &u, &tau_lanes, &mut m, &mut ud);
        for i in 0..19 {
            u[i] = u[i] + ud[i] * h;
            q[i] = q[i] + u[i] * h;
        }
    }
    let batched_seconds = start.elapsed().as_secs_f64();

    // One by one, with the same operations per state.
    let start = Instant::now();
    let single: [(SVector<f64, 19>, SVector<f64, 19>); SAMPLES] = core::array::from_fn(|l| {
        let (mut q, mut u) = (q0, SVector::<f64, 19>::zeros());
        for _ in 0..steps {
            let ud = k.forward_dynamics(&q, &u, &tau[l]);
            for i in 0..19 {
                u[i] += ud[i] * h;
                q[i] += u[i] * h;
            }
        }
        (q, u)
    });
    let single_seconds = start.elapsed().as_secs_f64();

    let bits = |a: &SVector<f64, 19>, b: &SVector<f64, 19>| {
        a.iter()
            .zip(b.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    };
    let lanes_equal_single_rollouts = (0..SAMPLES)
        .all(|l| bits(&state(&q, l), &single[l].0) && bits(&state(&u, l), &single[l].1));
    let pitch_errors: [f64; SAMPLES] = core::array::from_fn(|l| q[index::Q_IMU].0[l] - upright);
    let costs: [f64; SAMPLES] = core::array::from_fn(|l| {
        let rate = u[index::QD_IMU].0[l];
        pitch_errors[l] * pitch_errors[l] + 0.1 * rate * rate
    });
    let best = (0..SAMPLES)
        .min_by(|&a, &b| costs[a].total_cmp(&costs[b]))
        .unwrap_or(0);
    Outcome {
        torques,
        pitch_errors,
        costs,
        best,
        lanes_equal_single_rollouts,
        steps,
        batched_seconds,
        single_seconds,
    }
}

fn main() {
    let cfg = Config::default();
    let o = run(&cfg);
    println!(
        "Krang {:.3} rad past upright, {SAMPLES} candidates × {} steps of {} s:",
        cfg.tilt, o.steps, cfg.step
    );
    println!("  wheel torque (N·m)   end pitch error (rad)   cost");
    for l in 0..SAMPLES {
        let mark = if l == o.best { "  ← best" } else { "" };
        println!(
            "  {:>10.2}           {:>12.5}          {:.3e}{mark}",
            o.torques[l], o.pitch_errors[l], o.costs[l]
        );
    }
    println!(
        "batched rollouts equal the single-state ones bit for bit: {}",
        o.lanes_equal_single_rollouts
    );
    println!(
        "wall clock: batched {:.2} ms, one by one {:.2} ms ({} forward-dynamics evaluations each)",
        o.batched_seconds * 1e3,
        o.single_seconds * 1e3,
        o.steps * SAMPLES
    );
    assert!(o.lanes_equal_single_rollouts);
}
