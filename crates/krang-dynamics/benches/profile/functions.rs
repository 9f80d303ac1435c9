//! Profiling driver (example `profile`): instruction counts and quick timings of one generated
//! function of Krang (or a batched form, or the block-Cholesky forward dynamics) called N times,
//! for work on the generator (the published speed figures come from the criterion benchmarks,
//! `cargo bench`).
//!
//! ```sh
//! cargo build --release -p krang-dynamics --features batch --example profile
//! # instructions per call, repeatable on a loaded machine (callgrind counts, it does not time):
//! valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!     target/release/examples/profile mass_matrix 1000
//! # rough ns per call (the fastest of many batches of 1000 calls):
//! target/release/examples/profile all 200000
//! # instructions per call by execution port, and the floors in cycles they imply:
//! tools/port-bound/run.sh mass_matrix_into inverse_dynamics
//! ```
//!
//! Arguments: a function (`mass_matrix`, `coriolis`, `gravity`, `inverse_dynamics`, or `all`;
//! `mass_matrix_into` (into a matrix kept across calls), `forward_dynamics`, and `mass_matrix_cholesky` (M, its block factor and one solve);
//! a suffix `_b4` or `_b8` calls the batched form (`_batch_into`, into arrays kept across
//! calls) with 4 or 8 states, counted as one call, `_s8` the structure-of-arrays form
//! (`_batch_soa_into`) with 8 states (`forward_dynamics_s8` too, and
//! `forward_dynamics_kept_m_s8` with the lane mass matrix kept across calls; `solve_s8`: the
//! batched block solve alone, `forward_batch::block_solve_lanes`, on 8 fixed mass matrices;
//! `gravity_s8_then_gravity` and `inverse_dynamics_s8_then_inverse_dynamics`: an 8-state batch
//! and one single-state call in turn, what a caller mixing both pays); with
//! the feature `derivatives` also `inverse_dynamics_derivatives`, `…_into` (into a matrix kept
//! across calls), `…_with` (into a `DerivativesWorkspace` kept across calls),
//! `forward_dynamics_derivatives`, `forward_dynamics_derivatives_with` (into a
//! `ForwardDynamicsDerivativesWorkspace` kept across calls), `linearize` and `linearize_with`
//! (into a `LinearizationWorkspace` kept across calls); with the feature `coriolis-matrix` also
//! `coriolis_matrix`, `coriolis_matrix_s4`, `coriolis_matrix_s8` and `coriolis_matrix_s16`
//! (its 4-, 8- and 16-state structure-of-arrays forms), `coriolis_matrix_b4` and
//! `coriolis_matrix_b8` (arrays of 4 and 8 states); with the
//! feature `kinematics`
//! also `whole_body_terms`, `whole_body_separate` (the eleven calls it combines),
//! `hands_jacobians`, `hands_jacobians_separate` (the two `frame_jacobian` calls it combines),
//! `com_jacobian` and `sin_cos_17`), the
//! number of calls, and optionally the instruction set (`baseline` or `x86-64-v3`; default: the
//! best the CPU has, see `kanegen_runtime::isa`). States cycle through 64 fixed pseudo-random
//! states.

use std::hint::black_box;
use std::time::Instant;

use krang_dynamics::Krang;
use krang_dynamics::lanes::{Lanes, soa};
use nalgebra::{SMatrix, SVector};

mod states;
use states::{V, states};

/// The batched inputs: coordinates and speeds of 4 or 8 consecutive states from each state,
/// and the 8-state ones in structure-of-arrays form (`_s8`). Made once, before any timing.
struct Batches {
    b4: Vec<([V; 4], [V; 4])>,
    b8: Vec<([V; 8], [V; 8])>,
    s8: Vec<(SVector<Lanes<8>, 19>, SVector<Lanes<8>, 19>)>,
    /// 4 states in structure-of-arrays form (`coriolis_matrix_s4`).
    #[cfg(feature = "coriolis-matrix")]
    s4: Vec<(SVector<Lanes<4>, 19>, SVector<Lanes<4>, 19>)>,
    /// 16 states in structure-of-arrays form (`coriolis_matrix_s16`).
    #[cfg(feature = "coriolis-matrix")]
    s16: Vec<(SVector<Lanes<16>, 19>, SVector<Lanes<16>, 19>)>,
}

impl Batches {
    fn new(s: &[(V, V, V)]) -> Self {
        let b4: Vec<_> = (0..64)
            .map(|i| (batch::<4>(s, i), batch_u::<4>(s, i)))
            .collect();
        let b8: Vec<_> = (0..64)
            .map(|i| (batch::<8>(s, i), batch_u::<8>(s, i)))
            .collect();
        let s8 = b8.iter().map(|(q, u)| (soa(q), soa(u))).collect();
        #[cfg(feature = "coriolis-matrix")]
        let s4 = b4.iter().map(|(q, u)| (soa(q), soa(u))).collect();
        Batches {
            #[cfg(feature = "coriolis-matrix")]
            s4,
            b4,
            b8,
            s8,
            #[cfg(feature = "coriolis-matrix")]
            s16: (0..64)
                .map(|i| (soa(&batch::<16>(s, i)), soa(&batch_u::<16>(s, i))))
                .collect(),
        }
    }
}

fn run(k: &Krang, f: &str, s: &[(V, V, V)], batches: &Batches, calls: usize) -> f64 {
    let mut acc = 0.0;
    let Batches { b4, b8, s8, .. } = batches;
    // The batched forms write into these (`_into`: no zeroed array, no copy of the results).
    let mut m4 = [nalgebra::SMatrix::<f64, 19, 19>::zeros(); 4];
    let mut m8 = [nalgebra::SMatrix::<f64, 19, 19>::zeros(); 8];
    #[cfg(feature = "derivatives")]
    let mut d_out = SMatrix::<f64, 19, 38>::zeros();
    #[cfg(feature = "derivatives")]
    let mut d_ws = krang_dynamics::DerivativesWorkspace::new();
    #[cfg(feature = "derivatives")]
    let mut fd_ws = krang_dynamics::ForwardDynamicsDerivativesWorkspace::new();
    #[cfg(feature = "derivatives")]
    let mut lin_ws = krang_dynamics::LinearizationWorkspace::new();
    let mut m_into = nalgebra::SMatrix::<f64, 19, 19>::zeros();
    let mut v4 = [V::zeros(); 4];
    let mut v8 = [V::zeros(); 8];
    let mut ms8 = SMatrix::<Lanes<8>, 19, 19>::from_element(Lanes::splat(0.0));
    #[cfg(feature = "coriolis-matrix")]
    let mut ms4 = SMatrix::<Lanes<4>, 19, 19>::from_element(Lanes::splat(0.0));
    #[cfg(feature = "coriolis-matrix")]
    let mut ms16 = SMatrix::<Lanes<16>, 19, 19>::from_element(Lanes::splat(0.0));
    let mut vs8 = SVector::<Lanes<8>, 19>::from_element(Lanes::splat(0.0));
    let m_fixed = k.mass_matrix(&s[0].0);
    let chol_fixed = krang_dynamics::MassMatrixCholesky::new(&m_fixed).unwrap();
    let mut ms8_fixed = SMatrix::<Lanes<8>, 19, 19>::from_element(Lanes::splat(0.0));
    k.mass_matrix_batch_soa_into(&s8[0].0, &mut ms8_fixed);
    for i in 0..calls {
        let (q, u, ud) = &s[i & 63];
        acc += match f {
            "mass_matrix" => black_box(k).mass_matrix(black_box(q))[(5, 3)],
            "mass_matrix_into" => {
                black_box(k).mass_matrix_into(black_box(q), &mut m_into);
                black_box(&m_into)[(5, 3)]
            }
            "forward_dynamics" => {
                black_box(k).forward_dynamics(black_box(q), black_box(u), black_box(ud))[7]
            }
            "cholesky_only" => {
                let chol = krang_dynamics::MassMatrixCholesky::new(black_box(&m_fixed)).unwrap();
                black_box(&chol);
                0.0
            }
            "solve_only" => black_box(&chol_fixed).solve(black_box(ud))[7],
            "solve_57" => {
                let mut x = SMatrix::<f64, 19, 57>::from_element(ud[3]);
                black_box(&chol_fixed).solve_columns_mut(black_box(&mut x));
                x[(7, 40)]
            }
            "mass_matrix_cholesky" => {
                let m = black_box(k).mass_matrix(black_box(q));
                let chol = krang_dynamics::MassMatrixCholesky::new(black_box(&m)).unwrap();
                chol.solve(black_box(ud))[7]
            }
            "coriolis" => black_box(k).coriolis(black_box(q), black_box(u))[7],
            "gravity" => black_box(k).gravity(black_box(q))[7],
            "inverse_dynamics" => {
                black_box(k).inverse_dynamics(black_box(q), black_box(u), black_box(ud))[7]
            }
            "mass_matrix_b4" => {
                black_box(k).mass_matrix_batch_into(black_box(&b4[i & 63].0), &mut m4);
                black_box(&m4)[1][(5, 3)]
            }
            "mass_matrix_b8" => {
                black_box(k).mass_matrix_batch_into(black_box(&b8[i & 63].0), &mut m8);
                black_box(&m8)[1][(5, 3)]
            }
            "coriolis_b4" => {
                let (q, u) = &b4[i & 63];
                black_box(k).coriolis_batch_into(black_box(q), black_box(u), &mut v4);
                black_box(&v4)[1][7]
            }
            "coriolis_b8" => {
                let (q, u) = &b8[i & 63];
                black_box(k).coriolis_batch_into(black_box(q), black_box(u), &mut v8);
                black_box(&v8)[1][7]
            }
            "gravity_b4" => {
                black_box(k).gravity_batch_into(black_box(&b4[i & 63].0), &mut v4);
                black_box(&v4)[1][7]
            }
            "gravity_b8" => {
                black_box(k).gravity_batch_into(black_box(&b8[i & 63].0), &mut v8);
                black_box(&v8)[1][7]
            }
            "inverse_dynamics_b4" => {
                let (q, u) = &b4[i & 63];
                let (q, u) = (black_box(q), black_box(u));
                black_box(k).inverse_dynamics_batch_into(q, u, u, &mut v4);
                black_box(&v4)[1][7]
            }
            "inverse_dynamics_b8" => {
                let (q, u) = &b8[i & 63];
                let (q, u) = (black_box(q), black_box(u));
                black_box(k).inverse_dynamics_batch_into(q, u, u, &mut v8);
                black_box(&v8)[1][7]
            }
            "mass_matrix_s8" => {
                black_box(k).mass_matrix_batch_soa_into(black_box(&s8[i & 63].0), &mut ms8);
                black_box(&ms8)[(5, 3)].0[1]
            }
            "coriolis_s8" => {
                let (q, u) = &s8[i & 63];
                black_box(k).coriolis_batch_soa_into(black_box(q), black_box(u), &mut vs8);
                black_box(&vs8)[7].0[1]
            }
            "gravity_s8" => {
                black_box(k).gravity_batch_soa_into(black_box(&s8[i & 63].0), &mut vs8);
                black_box(&vs8)[7].0[1]
            }
            "inverse_dynamics_s8" => {
                let (q, u) = &s8[i & 63];
                let (q, u) = (black_box(q), black_box(u));
                black_box(k).inverse_dynamics_batch_soa_into(q, u, u, &mut vs8);
                black_box(&vs8)[7].0[1]
            }
            "gravity_s8_then_gravity" => {
                // One 8-state batch (x86-64-v4 copy where the CPU has it), then one single-state
                // call (x86-64-v3 copy): what a caller mixing both pays.
                black_box(k).gravity_batch_soa_into(black_box(&s8[i & 63].0), &mut vs8);
                black_box(&vs8)[7].0[1] + black_box(k).gravity(black_box(q))[7]
            }
            "inverse_dynamics_s8_then_inverse_dynamics" => {
                let (qs, us) = &s8[i & 63];
                let (qs, us) = (black_box(qs), black_box(us));
                black_box(k).inverse_dynamics_batch_soa_into(qs, us, us, &mut vs8);
                black_box(&vs8)[7].0[1]
                    + black_box(k).inverse_dynamics(black_box(q), black_box(u), black_box(ud))[7]
            }
            "forward_dynamics_s8" => {
                // The speeds as the torques too: any finite τ will do.
                let (q, u) = &s8[i & 63];
                let (q, u) = (black_box(q), black_box(u));
                black_box(k).forward_dynamics_batch_soa_into(q, u, u, &mut vs8);
                black_box(&vs8)[7].0[1]
            }
            "forward_dynamics_kept_m_s8" => {
                // The same with the lane mass matrix kept across calls (`ms8`, not zeroed).
                let (q, u) = &s8[i & 63];
                let (q, u) = (black_box(q), black_box(u));
                black_box(k)
                    .forward_dynamics_batch_soa_with_mass_matrix(q, u, u, &mut ms8, &mut vs8);
                black_box(&vs8)[7].0[1]
            }
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix" => black_box(k).coriolis_matrix(black_box(q), black_box(u))[(7, 9)],
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix_s8" => {
                let (q, u) = &s8[i & 63];
                black_box(k).coriolis_matrix_batch_soa_into(black_box(q), black_box(u), &mut ms8);
                black_box(&ms8)[(7, 9)].0[1]
            }
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix_s16" => {
                let (q, u) = &batches.s16[i & 63];
                black_box(k).coriolis_matrix_batch_soa_into(black_box(q), black_box(u), &mut ms16);
                black_box(&ms16)[(7, 9)].0[1]
            }
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix_s4" => {
                let (q, u) = &batches.s4[i & 63];
                black_box(k).coriolis_matrix_batch_soa_into(black_box(q), black_box(u), &mut ms4);
                black_box(&ms4)[(7, 9)].0[1]
            }
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix_b4" => {
                let (q, u) = &b4[i & 63];
                black_box(k).coriolis_matrix_batch_into(black_box(q), black_box(u), &mut m4);
                black_box(&m4)[1][(7, 9)]
            }
            #[cfg(feature = "coriolis-matrix")]
            "coriolis_matrix_b8" => {
                let (q, u) = &b8[i & 63];
                black_box(k).coriolis_matrix_batch_into(black_box(q), black_box(u), &mut m8);
                black_box(&m8)[1][(7, 9)]
            }
            "solve_s8" => {
                // The batched block solve alone, on M of the first 8 states (`ms8_fixed`).
                vs8 = s8[i & 63].1;
                krang_dynamics::forward_batch::block_solve_lanes::<5, 19, 8>(
                    black_box(&ms8_fixed),
                    &mut vs8,
                );
                black_box(&vs8)[7].0[1]
            }
            #[cfg(feature = "derivatives")]
            "inverse_dynamics_derivatives" => {
                black_box(k).inverse_dynamics_derivatives(black_box(q), black_box(u), black_box(ud))
                    [(7, 20)]
            }
            #[cfg(feature = "derivatives")]
            "forward_dynamics_derivatives_with" => {
                let ws = black_box(&mut fd_ws);
                black_box(k).forward_dynamics_derivatives_with(
                    black_box(q),
                    black_box(u),
                    black_box(ud),
                    ws,
                );
                black_box(&fd_ws).result().dud_dq[(7, 9)]
            }
            #[cfg(feature = "derivatives")]
            "forward_dynamics_derivatives" => {
                black_box(k)
                    .forward_dynamics_derivatives(black_box(q), black_box(u), black_box(ud))
                    .dud_dq[(7, 9)]
            }
            #[cfg(feature = "derivatives")]
            "linearize" => {
                // Any actuator torques: the state's accelerations, as numbers.
                let a = SVector::<f64, 18>::from_fn(|i, _| ud[i]);
                black_box(k)
                    .linearize(black_box(q), black_box(u), black_box(&a))
                    .1[(25, 3)]
            }
            #[cfg(feature = "derivatives")]
            "linearize_with" => {
                let a = SVector::<f64, 18>::from_fn(|i, _| ud[i]);
                let ws = black_box(&mut lin_ws);
                black_box(k)
                    .linearize_with(black_box(q), black_box(u), black_box(&a), ws)
                    .1[(25, 3)]
            }
            #[cfg(feature = "derivatives")]
            "inverse_dynamics_derivatives_into" => {
                let d = black_box(&mut d_out);
                black_box(k).inverse_dynamics_derivatives_into(
                    black_box(q),
                    black_box(u),
                    black_box(ud),
                    d,
                );
                d[(7, 20)]
            }
            #[cfg(feature = "derivatives")]
            "inverse_dynamics_derivatives_with" => {
                let ws = black_box(&mut d_ws);
                black_box(k).inverse_dynamics_derivatives_with(
                    black_box(q),
                    black_box(u),
                    black_box(ud),
                    ws,
                )[(7, 20)]
            }
            other => kinematics(k, other, q, u),
        };
    }
    acc
}

/// The combined `whole_body_terms` and `hands_jacobians` and the separate calls they replace
/// (feature `kinematics`), and the 17-angle `sin_cos_n` every call computes.
#[cfg(feature = "kinematics")]
fn kinematics(k: &Krang, f: &str, q: &V, u: &V) -> f64 {
    use krang_dynamics::Frame;
    let hands = [Frame::LeftHand, Frame::RightHand];
    match f {
        "whole_body_terms" => {
            let w = black_box(k).whole_body_terms(black_box(q), black_box(u));
            w.mass_matrix[(5, 3)] + w.frame_jacobian_right_hand[(2, 9)]
        }
        "whole_body_separate" => {
            let (k, q, u) = (black_box(k), black_box(q), black_box(u));
            let m = k.mass_matrix(q);
            let h = k.nonlinear_effects(q, u);
            let g = k.center_of_mass(q);
            let jg = k.com_jacobian(q);
            let bg = k.com_bias_acceleration(q, u);
            let hs = hands.map(|f| {
                (
                    k.frame_pose(q, f),
                    k.frame_jacobian(q, f),
                    k.frame_bias_acceleration(q, u, f),
                )
            });
            black_box((&m, &h, &g, &jg, &bg, &hs));
            m[(5, 3)] + hs[1].1[(2, 9)]
        }
        "hands_jacobians" => {
            let j = black_box(k).hands_jacobians(black_box(q));
            j.frame_jacobian_left_hand[(2, 9)] + j.frame_jacobian_right_hand[(2, 9)]
        }
        "hands_jacobians_separate" => {
            let (k, q) = (black_box(k), black_box(q));
            let j = hands.map(|f| k.frame_jacobian(q, f));
            black_box(&j);
            j[0][(2, 9)] + j[1][(2, 9)]
        }
        "com_jacobian" => black_box(k).com_jacobian(black_box(q))[(1, 7)],
        "sin_cos_17" => {
            let a: [f64; 17] = std::array::from_fn(|i| q[i + 2]);
            kanegen_runtime::trig::sin_cos_n(black_box(a)).0[3]
        }
        other => panic!("unknown function `{other}`"),
    }
}

#[cfg(not(feature = "kinematics"))]
fn kinematics(_: &Krang, other: &str, _: &V, _: &V) -> f64 {
    panic!("unknown function `{other}` (the kinematics need the feature `kinematics`)")
}

/// `L` consecutive states' coordinates, from state `i`.
fn batch<const L: usize>(s: &[(V, V, V)], i: usize) -> [V; L] {
    std::array::from_fn(|l| s[(i + l) & 63].0)
}

/// `L` consecutive states' speeds, from state `i`.
fn batch_u<const L: usize>(s: &[(V, V, V)], i: usize) -> [V; L] {
    std::array::from_fn(|l| s[(i + l) & 63].1)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let f = args.get(1).map_or("all", String::as_str);
    let calls: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    if let Some(isa) = args.get(3) {
        let isa = kanegen_runtime::isa::Isa::ALL
            .into_iter()
            .find(|i| i.name() == isa)
            .unwrap_or_else(|| panic!("unknown instruction set `{isa}`"));
        kanegen_runtime::isa::select(isa).unwrap();
    }
    eprintln!("instruction set: {}", kanegen_runtime::isa::active());
    let k = Krang::default();
    let s = states();
    let batches = Batches::new(&s);
    let names = ["mass_matrix", "coriolis", "gravity", "inverse_dynamics"];
    let list: Vec<&str> = if f == "all" { names.to_vec() } else { vec![f] };
    for name in list {
        let mut best = f64::INFINITY;
        let mut sink = 0.0;
        // Many short batches: the fastest one is the least disturbed by other work.
        let batch = 1000.min(calls.max(1));
        for _ in 0..calls.div_ceil(batch) {
            let t = Instant::now();
            sink += run(&k, name, &s, &batches, batch);
            best = best.min(t.elapsed().as_secs_f64() * 1e9 / batch as f64);
        }
        println!("{name:<17} {best:8.1} ns/call (fastest batch of {batch}) [{sink:.3e}]");
    }
}
