//! Criterion benchmark of one generated τ call and one `inverse_dynamics_derivatives` call in
//! the same binary (their ratio is the figure of issue 12), for comparing the two forms of the
//! derivatives: the module is built in the form the generator chooses (looped for Krang), or in
//! the form `KANEGEN_DERIVATIVES_FORM` (`looped`, `straight-line`) names at build time:
//!
//! ```sh
//! cargo bench -p krang-dynamics --features derivatives --bench derivatives_form
//! KANEGEN_DERIVATIVES_FORM=straight-line \
//!     cargo bench -p krang-dynamics --features derivatives --bench derivatives_form
//! ```
//!
//! Ids `form/inverse_dynamics` and `form/inverse_dynamics_derivatives`; both cycle through the
//! same 8 random states, inputs behind `black_box`. (The workspace's `benches/derivatives.rs`
//! compares the derivatives with central differences and the dual-number recursion.)

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use krang_dynamics::Krang;
use nalgebra::SVector;

type V = SVector<f64, 19>;

/// 8 states `(q, u, u̇)` from a fixed linear congruential sequence: q in [−π, π], u in
/// [−2, 2], u̇ in [−5, 5].
fn states() -> Vec<(V, V, V)> {
    let mut x: u64 = 12;
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut v = |lo: f64, hi: f64| V::from_fn(|_, _| lo + (hi - lo) * next());
    let pi = std::f64::consts::PI;
    (0..8)
        .map(|_| (v(-pi, pi), v(-2.0, 2.0), v(-5.0, 5.0)))
        .collect()
}

fn bench(c: &mut Criterion) {
    let k = Krang::default();
    let s = states();
    let mut g = c.benchmark_group("form");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(50);
    g.bench_function("inverse_dynamics", |b| {
        let mut i = 0;
        b.iter(|| {
            let (q, u, ud) = &s[i % s.len()];
            i += 1;
            black_box(k.inverse_dynamics(black_box(q), black_box(u), black_box(ud)))
        })
    });
    g.bench_function("inverse_dynamics_derivatives", |b| {
        let mut i = 0;
        b.iter(|| {
            let (q, u, ud) = &s[i % s.len()];
            i += 1;
            black_box(k.inverse_dynamics_derivatives(black_box(q), black_box(u), black_box(ud)))
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
