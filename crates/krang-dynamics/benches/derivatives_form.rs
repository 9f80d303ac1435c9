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
//! profiling examples' 64 fixed pseudo-random states (`examples/profile_states`), inputs behind
//! `black_box`. (The workspace's `benches/derivatives.rs`
//! compares the derivatives with central differences and the dual-number recursion.)

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use krang_dynamics::Krang;

#[path = "../examples/profile_states/mod.rs"]
mod profile_states;
use profile_states::states;

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
