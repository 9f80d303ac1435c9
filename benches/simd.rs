//! The generated Krang functions with each instruction set of the run-time dispatch
//! (`baseline`, `x86-64-v3`: AVX2 + FMA, `x86-64-v4`: AVX-512, which only the batched functions
//! have a copy for) and batched at 4 and 8 states per call.
//!
//! ```sh
//! cargo bench --bench simd                 # ≈ 2 minutes
//! ```
//!
//! Ids: `simd/<function>/<isa>` (one state per call) and `simd/<function>/<isa>/batch<L>` (one
//! call of `<function>_batch_into` with `L` states: divide by `L` for the time per state;
//! `batch<L>_by_value`: `mass_matrix_batch`, which returns the results), `…/soa<L>` (the
//! structure-of-arrays form `<function>_batch_soa_into`) and `simd/<function>_into/<isa>` (M
//! and C written into a kept matrix). `simd/forward_dynamics/<isa>` and `…/soa<L>` time
//! `Krang::forward_dynamics` and its batched form `forward_dynamics_batch_soa_into`, and
//! `…/soa<L>_kept_m` `forward_dynamics_batch_soa_with_mass_matrix` (the lane mass matrix kept
//! across calls). These are not generated functions: they run M, c + g and the block Cholesky;
//! the single state's factorisation has no x86-64-v4 copy. The states cycle through the profile driver's 64
//! random ones (their accelerations taken as the torques of forward dynamics).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use krang_dynamics::Krang;
use krang_dynamics::isa::{self, Isa};
use krang_dynamics::lanes::{Lanes, soa};
use nalgebra::{SMatrix, SVector};

/// The 64 states the profile driver (`crates/krang-dynamics/benches/profile/functions.rs`)
/// cycles through, so that its figures and this bench's measure the same inputs.
#[path = "../crates/krang-dynamics/benches/profile/states.rs"]
mod profile_states;
use profile_states::{V, states};

/// `L` consecutive states from state `i`, as the batched functions take them.
fn batch<const L: usize>(s: &[(V, V, V)], i: usize) -> ([V; L], [V; L], [V; L]) {
    (
        std::array::from_fn(|l| s[(i + l) & 63].0),
        std::array::from_fn(|l| s[(i + l) & 63].1),
        std::array::from_fn(|l| s[(i + l) & 63].2),
    )
}

fn bench_batch<const L: usize>(c: &mut Criterion, k: &Krang, s: &[(V, V, V)], tag: &str) {
    let batches: Vec<_> = (0..64).step_by(L).map(|i| batch::<L>(s, i)).collect();
    let n = batches.len();
    let mut i = 0;
    // The `_into` forms, into arrays kept across calls (no zeroed array, no copy of the
    // results), and the by-value form of M for comparison.
    let mut m = [nalgebra::SMatrix::<f64, 19, 19>::zeros(); L];
    let mut v = [V::zeros(); L];
    c.bench_function(&format!("simd/mass_matrix/{tag}/batch{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            black_box(k).mass_matrix_batch_into(black_box(&batches[i].0), &mut m);
            black_box(&m);
        })
    });
    c.bench_function(&format!("simd/mass_matrix/{tag}/batch{L}_by_value"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            black_box(k).mass_matrix_batch(black_box(&batches[i].0))
        })
    });
    c.bench_function(&format!("simd/coriolis/{tag}/batch{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, _) = &batches[i];
            black_box(k).coriolis_batch_into(black_box(q), black_box(u), &mut v);
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/gravity/{tag}/batch{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            black_box(k).gravity_batch_into(black_box(&batches[i].0), &mut v);
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/inverse_dynamics/{tag}/batch{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, ud) = &batches[i];
            black_box(k).inverse_dynamics_batch_into(
                black_box(q),
                black_box(u),
                black_box(ud),
                &mut v,
            );
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/coriolis_matrix/{tag}/batch{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, _) = &batches[i];
            black_box(k).coriolis_matrix_batch_into(black_box(q), black_box(u), &mut m);
            black_box(&m);
        })
    });
}

/// The structure-of-arrays forms (`<function>_batch_soa_into`): the same `L` states as
/// [`bench_batch`], built once with `lanes::soa`, into results kept across calls. Ids
/// `simd/<function>/<isa>/soa<L>`.
fn bench_batch_soa<const L: usize>(c: &mut Criterion, k: &Krang, s: &[(V, V, V)], tag: &str) {
    let batches: Vec<_> = (0..64)
        .step_by(L)
        .map(|i| {
            let (q, u, ud) = batch::<L>(s, i);
            (soa(&q), soa(&u), soa(&ud))
        })
        .collect();
    let n = batches.len();
    let mut i = 0;
    let mut m = SMatrix::<Lanes<L>, 19, 19>::from_element(Lanes::splat(0.0));
    let mut v = SVector::<Lanes<L>, 19>::from_element(Lanes::splat(0.0));
    c.bench_function(&format!("simd/mass_matrix/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            black_box(k).mass_matrix_batch_soa_into(black_box(&batches[i].0), &mut m);
            black_box(&m);
        })
    });
    c.bench_function(&format!("simd/coriolis/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, _) = &batches[i];
            black_box(k).coriolis_batch_soa_into(black_box(q), black_box(u), &mut v);
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/gravity/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            black_box(k).gravity_batch_soa_into(black_box(&batches[i].0), &mut v);
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/inverse_dynamics/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, ud) = &batches[i];
            black_box(k).inverse_dynamics_batch_soa_into(
                black_box(q),
                black_box(u),
                black_box(ud),
                &mut v,
            );
            black_box(&v);
        })
    });
    c.bench_function(&format!("simd/coriolis_matrix/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, _) = &batches[i];
            black_box(k).coriolis_matrix_batch_soa_into(black_box(q), black_box(u), &mut m);
            black_box(&m);
        })
    });
    // Forward dynamics (not generated: batched M, batched c + g and the lane block Cholesky),
    // the accelerations of the states taken as torques.
    c.bench_function(&format!("simd/forward_dynamics/{tag}/soa{L}"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, tau) = &batches[i];
            black_box(k).forward_dynamics_batch_soa_into(
                black_box(q),
                black_box(u),
                black_box(tau),
                &mut v,
            );
            black_box(&v);
        })
    });
    // The same with the lane mass matrix kept across calls (not zeroed per call).
    c.bench_function(&format!("simd/forward_dynamics/{tag}/soa{L}_kept_m"), |b| {
        b.iter(|| {
            i = (i + 1) % n;
            let (q, u, tau) = &batches[i];
            black_box(k).forward_dynamics_batch_soa_with_mass_matrix(
                black_box(q),
                black_box(u),
                black_box(tau),
                &mut m,
                &mut v,
            );
            black_box(&v);
        })
    });
}

fn simd(c: &mut Criterion) {
    let k = Krang::default();
    let s = states();
    for isa in Isa::ALL.into_iter().filter(|&i| isa::available(i)) {
        isa::select(isa).unwrap();
        let tag = isa.name();
        let mut i = 0;
        c.bench_function(&format!("simd/mass_matrix/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).mass_matrix(black_box(&s[i].0))
            })
        });
        c.bench_function(&format!("simd/coriolis/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).coriolis(black_box(&s[i].0), black_box(&s[i].1))
            })
        });
        c.bench_function(&format!("simd/gravity/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).gravity(black_box(&s[i].0))
            })
        });
        c.bench_function(&format!("simd/inverse_dynamics/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                let (q, u, ud) = &s[i];
                black_box(&k).inverse_dynamics(black_box(q), black_box(u), black_box(ud))
            })
        });
        c.bench_function(&format!("simd/coriolis_matrix/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).coriolis_matrix(black_box(&s[i].0), black_box(&s[i].1))
            })
        });
        c.bench_function(&format!("simd/forward_dynamics/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                let (q, u, tau) = &s[i];
                black_box(&k).forward_dynamics(black_box(q), black_box(u), black_box(tau))
            })
        });
        let mut m = SMatrix::<f64, 19, 19>::zeros();
        c.bench_function(&format!("simd/mass_matrix_into/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).mass_matrix_into(black_box(&s[i].0), &mut m);
                black_box(&m);
            })
        });
        c.bench_function(&format!("simd/coriolis_matrix_into/{tag}"), |b| {
            b.iter(|| {
                i = (i + 1) & 63;
                black_box(&k).coriolis_matrix_into(black_box(&s[i].0), black_box(&s[i].1), &mut m);
                black_box(&m);
            })
        });
        bench_batch::<4>(c, &k, &s, tag);
        bench_batch::<8>(c, &k, &s, tag);
        bench_batch_soa::<4>(c, &k, &s, tag);
        bench_batch_soa::<8>(c, &k, &s, tag);
    }
    isa::select(isa::detected()).unwrap();
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(1))
        .sample_size(30)
}

criterion_group! {
    name = benches;
    config = config();
    targets = simd
}
criterion_main!(benches);
