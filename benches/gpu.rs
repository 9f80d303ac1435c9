//! Throughput of the GPU kernels against batch size, beside the CPU's batched path on every
//! core: states per second of M, τ, forward dynamics and a 100-step rollout, for Krang (19
//! speeds) and the 7-DOF URDF arm, in `f32` on the default adapter (Mesa's lavapipe where
//! there is no GPU).
//!
//! ```sh
//! cargo bench --bench gpu -- --measurement-time 2
//! KANEGEN_GPU_BENCH_MAX=1048576 cargo bench --bench gpu   # batches up to 2^20 states
//! ```
//!
//! Ids: `gpu/<model>/<function>/<count>/with_transfers` (the whole call: upload, kernel,
//! read-back), `…/kernel` (the kernel's time alone, from timestamps where the device has them,
//! else the wall clock around the dispatch) and `cpu/<model>/<function>/<count>` (the f64
//! batched structure-of-arrays functions, 8 states per call, the batch split over every core).
//! Throughput is in states (elements) per second; a rollout counts one element per state
//! and step.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput};
use kanegen_gpu::{Dynamics, Gpu, Rollout};
use krang_dynamics::lanes::Lanes;
use nalgebra::{SMatrix, SVector};

#[allow(dead_code, clippy::all)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm_gpu.rs"));
}

const ROLLOUT_STEPS: u32 = 100;

/// Batch sizes: powers of 8 from 1 up to `KANEGEN_GPU_BENCH_MAX` (default 32,768).
fn counts() -> Vec<usize> {
    let max: usize = std::env::var("KANEGEN_GPU_BENCH_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1 << 15);
    let mut v = vec![1];
    while v.last().unwrap() * 8 <= max {
        v.push(v.last().unwrap() * 8);
    }
    v
}

/// Deterministic values in (−1, 1).
fn values(n: usize, seed: u32) -> Vec<f32> {
    (0..n)
        .map(|i| ((i as u32).wrapping_mul(2_654_435_761).wrapping_add(seed) >> 8) as f32)
        .map(|x| x / (1u32 << 23) as f32 - 1.0)
        .collect()
}

fn bench_gpu(
    c: &mut Criterion,
    gpu: &Gpu,
    name: &str,
    module: &kanegen_gpu::GpuModule,
    params: &[f64],
) {
    let mut d = Dynamics::<f32>::new(gpu, module, params).expect("kernels");
    let n = module.dof;
    let mut g = c.benchmark_group(format!("gpu/{name}"));
    g.sample_size(10);
    for count in counts() {
        let (q, u, a) = (
            values(n * count, 1),
            values(n * count, 2),
            values(n * count, 3),
        );
        for function in ["mass_matrix", "inverse_dynamics", "forward_dynamics"] {
            g.throughput(Throughput::Elements(count as u64));
            let call = |d: &mut Dynamics<f32>| match function {
                "mass_matrix" => d.evaluate(function, count, &q, &[], &[]).map(drop),
                "inverse_dynamics" => d.evaluate(function, count, &q, &u, &a).map(drop),
                _ => d.forward_dynamics(count, &q, &u, &a).map(drop),
            };
            g.bench_function(format!("{function}/{count}/with_transfers"), |b| {
                b.iter(|| call(&mut d).expect("runs"))
            });
            g.bench_function(format!("{function}/{count}/kernel"), |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|_| {
                            call(&mut d).expect("runs");
                            d.last_timing().kernel
                        })
                        .sum()
                })
            });
        }
        // Rollouts: one element per state and step; only the final states come back.
        let forces = values(n * count * ROLLOUT_STEPS as usize, 4);
        let r = Rollout {
            q0: &q,
            u0: &u,
            forces: &forces,
            steps: ROLLOUT_STEPS,
            dt: 1e-3,
            record: false,
        };
        g.throughput(Throughput::Elements(
            count as u64 * u64::from(ROLLOUT_STEPS),
        ));
        g.bench_function(
            format!("rollout{ROLLOUT_STEPS}/{count}/with_transfers"),
            |b| b.iter(|| d.rollout(count, &r).expect("runs")),
        );
        g.bench_function(format!("rollout{ROLLOUT_STEPS}/{count}/kernel"), |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| {
                        d.rollout(count, &r).expect("runs");
                        d.last_timing().kernel
                    })
                    .sum()
            })
        });
    }
    g.finish();
}

/// Runs `f(block)` for `blocks` blocks of 8 states, split over every core.
fn on_every_core(blocks: usize, f: &(impl Fn(usize) + Sync)) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = blocks.div_ceil(threads).max(1);
    std::thread::scope(|s| {
        for t in 0..threads {
            let range = (t * per).min(blocks)..((t + 1) * per).min(blocks);
            if !range.is_empty() {
                s.spawn(move || range.for_each(f));
            }
        }
    });
}

/// The CPU's batched path of one model: 8 states per call, 64 distinct blocks cycled.
macro_rules! bench_cpu {
    ($c:expr, $name:expr, $robot:expr, $n:expr) => {{
        const N: usize = $n;
        let robot = $robot;
        type V = SVector<Lanes<8>, N>;
        let lanes = |seed: u32, b: usize| -> V {
            let v = values(N * 8, seed + b as u32);
            V::from_fn(|j, _| Lanes(core::array::from_fn(|l| f64::from(v[j * 8 + l]))))
        };
        let blocks: Vec<(V, V, V)> = (0..64)
            .map(|b| (lanes(1, b), lanes(2, b), lanes(3, b)))
            .collect();
        let mut g = $c.benchmark_group(format!("cpu/{}", $name));
        g.sample_size(10);
        for count in counts().into_iter().filter(|&c| c >= 8) {
            let n_blocks = count / 8;
            g.throughput(Throughput::Elements(count as u64));
            g.bench_function(format!("mass_matrix/{count}"), |b| {
                b.iter(|| {
                    on_every_core(n_blocks, &|i| {
                        let mut m = SMatrix::<Lanes<8>, N, N>::from_element(Lanes::splat(0.0));
                        robot.mass_matrix_batch_soa_into(&blocks[i & 63].0, &mut m);
                        black_box(&m);
                    })
                })
            });
            g.bench_function(format!("inverse_dynamics/{count}"), |b| {
                b.iter(|| {
                    on_every_core(n_blocks, &|i| {
                        let s = &blocks[i & 63];
                        let mut t = V::from_element(Lanes::splat(0.0));
                        robot.inverse_dynamics_batch_soa_into(&s.0, &s.1, &s.2, &mut t);
                        black_box(&t);
                    })
                })
            });
        }
        g.finish();
    }};
}

fn main() {
    let mut c = Criterion::default()
        .configure_from_args()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    match Gpu::new() {
        Ok(gpu) => {
            eprintln!(
                "adapter: {} ({}), kernel times from {}",
                gpu.adapter_name(),
                gpu.backend(),
                if gpu.has_timestamps() {
                    "timestamps"
                } else {
                    "the wall clock"
                }
            );
            let krang = krang_dynamics::Params::default().to_array();
            bench_gpu(&mut c, &gpu, "krang", &krang_dynamics::gpu::MODULE, &krang);
            let p = arm::Params::default().to_array();
            bench_gpu(&mut c, &gpu, "arm7", &arm::gpu::MODULE, &p);
        }
        Err(e) => eprintln!("no GPU adapter, GPU benchmarks skipped: {e}"),
    }
    bench_cpu!(c, "krang", krang_dynamics::Krang::default(), 19);
    bench_cpu!(c, "arm7", arm::SingleArm::default(), arm::DOF);
    c.final_summary();
}
