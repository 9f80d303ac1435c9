//! Profiling driver (example `profile_regressors`): instruction counts and rough timings of
//! Krang's generated regressors, one function called N times, for work on the generator (next
//! to `functions.rs`, the example `profile`, which covers the other functions). Measures the
//! cost of one call of `inverse_dynamics_regressor`, `base_regressor`, the gravity regressors
//! and their in-place forms, against τ and g.
//!
//! ```sh
//! cargo build --release -p krang-dynamics --features regressors --example profile_regressors
//! valgrind --tool=callgrind --callgrind-out-file=cg.out \
//!     target/release/examples/profile_regressors inverse_dynamics_regressor 1000
//! callgrind_annotate cg.out | head -30
//! ```
//!
//! Arguments: a function (`inverse_dynamics`, `inverse_dynamics_regressor`, `base_regressor`,
//! their in-place loop forms `inverse_dynamics_regressor_into`, `base_regressor_into`,
//! `fill_19x173` (the 26 KB result written once, nothing computed: the floor of `_into`),
//! `gravity`, `gravity_regressor`, `base_gravity_regressor`) and the number of calls. States
//! cycle through 64 fixed pseudo-random states. Prints the fastest ns per call of batches of
//! 1000 calls as a rough figure (the published figures come from `cargo bench --bench
//! regressors`).

use std::hint::black_box;
use std::time::Instant;

use krang_dynamics::Krang;

mod states;
use states::{V, states};

fn run(k: &Krang, f: &str, s: &[(V, V, V)], calls: usize) -> Result<f64, String> {
    let mut acc = 0.0;
    let mut y = nalgebra::SMatrix::<f64, 19, 173>::zeros();
    let mut yb = nalgebra::SMatrix::<f64, 19, 122>::zeros();
    for i in 0..calls {
        let (q, u, ud) = &s[i & 63];
        let (q, u, ud) = (black_box(q), black_box(u), black_box(ud));
        acc += match f {
            "inverse_dynamics" => black_box(k).inverse_dynamics(q, u, ud)[7],
            "inverse_dynamics_regressor" => {
                black_box(k).inverse_dynamics_regressor(q, u, ud)[(7, 60)]
            }
            "base_regressor" => black_box(k).base_regressor(q, u, ud)[(7, 40)],
            "inverse_dynamics_regressor_into" => {
                black_box(k).inverse_dynamics_regressor_into(q, u, ud, &mut y);
                y[(7, 60)]
            }
            "base_regressor_into" => {
                black_box(k).base_regressor_into(q, u, ud, &mut yb);
                yb[(7, 40)]
            }
            // The floor of any `_into`: writing the 26 KB result once.
            "fill_19x173" => {
                black_box(&mut y).as_mut_slice().fill(black_box(q[0]));
                y[(7, 60)]
            }
            "gravity" => black_box(k).gravity(q)[7],
            "gravity_regressor" => black_box(k).gravity_regressor(q)[(7, 30)],
            "base_gravity_regressor" => black_box(k).base_gravity_regressor(q)[(7, 20)],
            _ => return Err(format!("unknown function `{f}`")),
        };
    }
    Ok(acc)
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let f = args
        .next()
        .unwrap_or_else(|| "inverse_dynamics_regressor".into());
    let calls: usize = args
        .next()
        .map(|c| c.parse().map_err(|e| format!("calls: {e}")))
        .transpose()?
        .unwrap_or(1000);
    let k = Krang::default();
    let s = states();
    let mut best = f64::INFINITY;
    let mut acc = 0.0;
    for _ in 0..(calls / 1000).max(1) {
        let t = Instant::now();
        acc += run(&k, &f, &s, calls.min(1000))?;
        best = best.min(t.elapsed().as_secs_f64() / calls.min(1000) as f64);
    }
    println!(
        "{f}: {:.0} ns per call (fastest batch; checksum {acc:.3e})",
        best * 1e9
    );
    Ok(())
}
