//! Krang's regressors (19 speeds, runtime parameters) against the dynamics functions they
//! replace: `inverse_dynamics_regressor` and `base_regressor` against `inverse_dynamics`,
//! `gravity_regressor` and `base_gravity_regressor` against `gravity`; the loop form's in-place
//! variants `…_into` and the cost of the by-value result alone. 64 random states cycled
//! through call by call, inputs behind `black_box`.
//!
//! ```text
//! cargo bench --bench regressors
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kanegen_reference::random::SplitMix64;
use krang_dynamics::Krang;
use nalgebra::SVector;

type State = (SVector<f64, 19>, SVector<f64, 19>, SVector<f64, 19>);

fn states() -> Vec<State> {
    let mut r = SplitMix64::new(1);
    let mut v = |a: f64| SVector::<f64, 19>::from_fn(|_, _| a * (2.0 * r.next_f64() - 1.0));
    (0..64).map(|_| (v(3.0), v(2.0), v(2.0))).collect()
}

fn bench(c: &mut Criterion) {
    let k = Krang::default();
    let xs = states();
    let mut g = c.benchmark_group("krang_regressors");
    g.measurement_time(Duration::from_secs(3));
    g.warm_up_time(Duration::from_secs(1));
    macro_rules! run {
        ($name:literal, |$x:ident| $call:expr) => {{
            let mut i = 0;
            g.bench_function($name, |b| {
                b.iter(|| {
                    let $x = &xs[i % xs.len()];
                    i += 1;
                    black_box($call)
                })
            });
        }};
    }
    run!("inverse_dynamics", |x| k.inverse_dynamics(
        black_box(&x.0),
        black_box(&x.1),
        black_box(&x.2)
    ));
    run!("inverse_dynamics_regressor", |x| k
        .inverse_dynamics_regressor(
            black_box(&x.0),
            black_box(&x.1),
            black_box(&x.2)
        ));
    run!("base_regressor", |x| k.base_regressor(
        black_box(&x.0),
        black_box(&x.1),
        black_box(&x.2)
    ));
    // The loop form's in-place variants (docs/regressors.md): the result
    // matrix kept by the caller, nothing zeroed or copied per call.
    let mut y = nalgebra::SMatrix::<f64, 19, 173>::zeros();
    run!("inverse_dynamics_regressor_into", |x| {
        k.inverse_dynamics_regressor_into(
            black_box(&x.0),
            black_box(&x.1),
            black_box(&x.2),
            &mut y,
        );
        y[(7, 60)]
    });
    let mut yb = nalgebra::SMatrix::<f64, 19, 122>::zeros();
    run!("base_regressor_into", |x| {
        k.base_regressor_into(black_box(&x.0), black_box(&x.1), black_box(&x.2), &mut yb);
        yb[(7, 40)]
    });
    // What the by-value functions' 26 KB result costs on its own: zeroed, returned, dropped.
    run!("result_only_19x173", |x| {
        let _ = black_box(x);
        nalgebra::SMatrix::<f64, 19, 173>::zeros()
    });
    run!("gravity", |x| k.gravity(black_box(&x.0)));
    run!("gravity_regressor", |x| k
        .gravity_regressor(black_box(&x.0)));
    run!("base_gravity_regressor", |x| k
        .base_gravity_regressor(black_box(&x.0)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
