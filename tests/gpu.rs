//! The GPU kernels on a device (Mesa's lavapipe in CI): every kernel of Krang and of the URDF
//! arm against the CPU functions in `f32` (≤ 1e-4 of the result's largest entry) and in `f64`
//! (≤ 1e-3), the `f64` kernels (where the device has `SHADER_F64`) against `f64` to near
//! rounding, including far-off angles that exercise the sine and cosine's reduction, forward
//! dynamics and rollouts against the CPU's, chunked batches, results kept on the device, and
//! the typed errors.
//!
//! Without a device the tests print why and pass, unless `KANEGEN_GPU_REQUIRED` is set (as CI
//! sets it where lavapipe is installed): then they fail.

use kanegen_gpu::{Dynamics, Gpu, GpuError, GpuFloat, Rollout};
use krang_dynamics::Krang;
use nalgebra::SVector;

#[allow(dead_code, clippy::all)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm_gpu.rs"));
}
#[allow(dead_code, clippy::all)]
mod arm_f32 {
    include!(concat!(env!("OUT_DIR"), "/singlearm_gpu_f32.rs"));
}

/// The device, or `None` (with a note) where none opens and none is required.
fn device() -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) if std::env::var_os("KANEGEN_GPU_REQUIRED").is_some() => {
            panic!("KANEGEN_GPU_REQUIRED is set but no device opens: {e}")
        }
        Err(e) => {
            eprintln!("no GPU device, GPU tests skipped: {e}");
            None
        }
    }
}

/// A small deterministic generator (xorshift64*), uniform in `[lo, hi)`.
struct Draw(u64);
impl Draw {
    fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * r
    }
}

/// `count` states of `n` values each, structure of arrays (`v[j * count + i]`), and the same
/// per state.
fn states(draw: &mut Draw, n: usize, count: usize, lo: f64, hi: f64) -> (Vec<f64>, Vec<Vec<f64>>) {
    let per: Vec<Vec<f64>> = (0..count)
        .map(|_| (0..n).map(|_| draw.next(lo, hi)).collect())
        .collect();
    let soa = (0..n).flat_map(|j| per.iter().map(move |s| s[j])).collect();
    (soa, per)
}

fn cast<T: GpuFloat>(v: &[f64]) -> Vec<T> {
    v.iter().map(|&x| T::from_f64(x)).collect()
}

/// The largest difference between `gpu` (structure of arrays) and `cpu` (per state, dense)
/// over the largest magnitude of `cpu`.
fn relative_error<T: GpuFloat>(gpu: &[T], cpu: &[Vec<f64>]) -> f64 {
    let count = cpu.len();
    let (mut err, mut scale) = (0.0f64, 0.0f64);
    for (i, s) in cpu.iter().enumerate() {
        for (k, &c) in s.iter().enumerate() {
            let g = gpu[k * count + i].to_f64();
            assert!(g.is_finite(), "entry {k} of state {i} is {g}");
            err = err.max((g - c).abs());
            scale = scale.max(c.abs());
        }
    }
    err / scale.max(f64::MIN_POSITIVE)
}

fn dense<const R: usize, const C: usize>(m: nalgebra::SMatrix<f64, R, C>) -> Vec<f64> {
    (0..R)
        .flat_map(|r| (0..C).map(move |c| m[(r, c)]))
        .collect()
}

fn dense32<const R: usize, const C: usize>(m: nalgebra::SMatrix<f32, R, C>) -> Vec<f64> {
    (0..R)
        .flat_map(|r| (0..C).map(move |c| f64::from(m[(r, c)])))
        .collect()
}

/// A CPU function at one state (`q`, `u`, `u̇`), as a dense row-major result.
type Cpu<'a> = Box<dyn Fn(&[f64], &[f64], &[f64]) -> Vec<f64> + 'a>;

/// Runs `kernel` on `count` random states in `T` and returns its error against `cpu`.
fn kernel_error<T: GpuFloat>(
    d: &mut Dynamics<T>,
    kernel: &str,
    cpu: &Cpu<'_>,
    count: usize,
    angle: f64,
    seed: u64,
) -> f64 {
    let n = d.module().dof;
    let mut draw = Draw(seed);
    let (q, qs) = states(&mut draw, n, count, -angle, angle);
    let (u, us) = states(&mut draw, n, count, -1.0, 1.0);
    let (a, as_) = states(&mut draw, n, count, -1.0, 1.0);
    let k = d.module().kernel(kernel).expect("kernel");
    let (uu, aa) = match k.inputs {
        kanegen_gpu::KernelInputs::Q => (vec![], vec![]),
        kanegen_gpu::KernelInputs::QU => (cast(&u), vec![]),
        kanegen_gpu::KernelInputs::QUUd => (cast(&u), cast(&a)),
    };
    let out = d
        .evaluate(kernel, count, &cast::<T>(&q), &uu, &aa)
        .expect("evaluates");
    let expected: Vec<Vec<f64>> = (0..count).map(|i| cpu(&qs[i], &us[i], &as_[i])).collect();
    relative_error(&out, &expected)
}

fn v<const N: usize>(x: &[f64]) -> SVector<f64, N> {
    SVector::from_column_slice(x)
}
fn v32<const N: usize>(x: &[f64]) -> SVector<f32, N> {
    SVector::from_iterator(x.iter().map(|&a| a as f32))
}

/// The entries M, c, g, τ and C of a `*_functions` list: the robot `$k`'s CPU functions in f64
/// and `$k32`'s in f32, `$n` speeds.
macro_rules! dynamics_functions {
    ($k:ident, $k32:ident, $n:ident) => {{
        let functions: [(&'static str, Cpu<'static>, Option<Cpu<'static>>); 5] = [
            (
                "mass_matrix",
                Box::new(move |q, _, _| dense($k.mass_matrix(&v::<$n>(q)))),
                Some(Box::new(move |q, _, _| {
                    dense32($k32.mass_matrix(&v32::<$n>(q)))
                })),
            ),
            (
                "coriolis",
                Box::new(move |q, u, _| dense($k.coriolis(&v::<$n>(q), &v(u)))),
                Some(Box::new(move |q, u, _| {
                    dense32($k32.coriolis(&v32::<$n>(q), &v32(u)))
                })),
            ),
            (
                "gravity",
                Box::new(move |q, _, _| dense($k.gravity(&v::<$n>(q)))),
                Some(Box::new(move |q, _, _| {
                    dense32($k32.gravity(&v32::<$n>(q)))
                })),
            ),
            (
                "inverse_dynamics",
                Box::new(move |q, u, a| dense($k.inverse_dynamics(&v::<$n>(q), &v(u), &v(a)))),
                Some(Box::new(move |q, u, a| {
                    dense32($k32.inverse_dynamics(&v32::<$n>(q), &v32(u), &v32(a)))
                })),
            ),
            (
                "coriolis_matrix",
                Box::new(move |q, u, _| dense($k.coriolis_matrix(&v::<$n>(q), &v(u)))),
                Some(Box::new(move |q, u, _| {
                    dense32($k32.coriolis_matrix(&v32::<$n>(q), &v32(u)))
                })),
            ),
        ];
        functions
    }};
}

/// Krang's kernels and its CPU functions in f64 and f32.
fn krang_functions() -> Vec<(&'static str, Cpu<'static>, Option<Cpu<'static>>)> {
    let k: &'static Krang = Box::leak(Box::new(Krang::default()));
    let k32: &'static krang_dynamics::f32::Krang =
        Box::leak(Box::new(krang_dynamics::f32::Krang::default()));
    const N: usize = 19;
    let mut functions = Vec::from(dynamics_functions!(k, k32, N));
    let rest: Vec<(&'static str, Cpu<'static>, Option<Cpu<'static>>)> = vec![(
        "nonlinear_effects",
        Box::new(move |q, u, _| dense(k.nonlinear_effects(&v::<N>(q), &v(u)))),
        None,
    )];
    functions.extend(rest);
    functions
}

/// The arm's kernels and its CPU functions in f64 and f32.
fn arm_functions() -> Vec<(&'static str, Cpu<'static>, Option<Cpu<'static>>)> {
    use arm::SingleArm;
    use arm_f32::SingleArm as SingleArm32;
    let k: &'static SingleArm = Box::leak(Box::new(SingleArm::default()));
    let k32: &'static SingleArm32 = Box::leak(Box::new(SingleArm32::default()));
    const N: usize = arm::DOF;
    let scalar = |x: f64| vec![x];
    let mut functions = Vec::from(dynamics_functions!(k, k32, N));
    let rest: Vec<(&'static str, Cpu<'static>, Option<Cpu<'static>>)> = vec![
        (
            "nonlinear_effects",
            Box::new(move |q, u, _| dense(k.nonlinear_effects(&v::<N>(q), &v(u)))),
            Some(Box::new(move |q, u, _| {
                dense32(k32.nonlinear_effects(&v32::<N>(q), &v32(u)))
            })),
        ),
        (
            "center_of_mass",
            Box::new(move |q, _, _| dense(k.center_of_mass(&v::<N>(q)))),
            Some(Box::new(move |q, _, _| {
                dense32(k32.center_of_mass(&v32::<N>(q)))
            })),
        ),
        (
            "com_jacobian",
            Box::new(move |q, _, _| dense(k.com_jacobian(&v::<N>(q)))),
            Some(Box::new(move |q, _, _| {
                dense32(k32.com_jacobian(&v32::<N>(q)))
            })),
        ),
        (
            "kinetic_energy",
            Box::new(move |q, u, _| scalar(k.kinetic_energy(&v::<N>(q), &v(u)))),
            Some(Box::new(move |q, u, _| {
                vec![f64::from(k32.kinetic_energy(&v32::<N>(q), &v32(u)))]
            })),
        ),
        (
            "potential_energy",
            Box::new(move |q, _, _| scalar(k.potential_energy(&v::<N>(q)))),
            Some(Box::new(move |q, _, _| {
                vec![f64::from(k32.potential_energy(&v32::<N>(q)))]
            })),
        ),
    ];
    functions.extend(rest);
    functions
}

/// Every kernel of a module is in `functions`; each within the tolerances in f32 (and in f64
/// where the device has it).
fn check_every_kernel(
    gpu: &Gpu,
    module: &kanegen_gpu::GpuModule,
    params: &[f64],
    functions: &[(&'static str, Cpu<'static>, Option<Cpu<'static>>)],
    f64_kernels: &[&str],
) {
    let names: Vec<&str> = functions.iter().map(|f| f.0).collect();
    for k in module.kernels {
        assert!(names.contains(&k.name), "kernel {} is not checked", k.name);
    }
    let mut d32 = Dynamics::<f32>::new(gpu, module, params).expect("f32 kernels");
    let count = 96; // a workgroup and a half
    for (i, (name, cpu64, cpu32)) in functions.iter().enumerate() {
        let seed = 17 + i as u64;
        let e64 = kernel_error(&mut d32, name, cpu64, count, 3.2, seed);
        assert!(
            e64 <= 1e-3,
            "{}: f32 kernel {name} vs f64 CPU: {e64:e}",
            module.model
        );
        if let Some(cpu32) = cpu32 {
            let e32 = kernel_error(&mut d32, name, cpu32, count, 3.2, seed);
            assert!(
                e32 <= 1e-4,
                "{}: f32 kernel {name} vs f32 CPU: {e32:e}",
                module.model
            );
        }
    }
    if gpu.has_f64() {
        let mut d64 = Dynamics::<f64>::new(gpu, module, params).expect("f64 kernels");
        let checked = functions.iter().filter(|f| f64_kernels.contains(&f.0));
        for (i, (name, cpu64, _)) in checked.enumerate() {
            // Angles up to ±60 rad: the reduction by π/2 of the kernels' own sine and cosine.
            let e = kernel_error(&mut d64, name, cpu64, count, 60.0, 31 + i as u64);
            assert!(
                e <= 1e-12,
                "{}: f64 kernel {name} vs f64 CPU: {e:e}",
                module.model
            );
        }
    }
}

#[test]
fn krang_kernels_match_the_cpu_functions_in_f32_and_f64() {
    let Some(gpu) = device() else { return };
    let params = krang_dynamics::Params::default().to_array();
    // In f64 (where the device has it) M and g: each kernel is a pipeline for the device's
    // compiler, and the arm's test runs every f64 kernel.
    let f64_kernels = ["mass_matrix", "gravity"];
    let functions = krang_functions();
    check_every_kernel(
        &gpu,
        &krang_dynamics::gpu::MODULE,
        &params,
        &functions,
        &f64_kernels,
    );
}

#[test]
fn urdf_arm_kernels_match_the_cpu_functions_in_f32_and_f64() {
    let Some(gpu) = device() else { return };
    let params = arm::Params::default().to_array();
    let functions = arm_functions();
    let every: Vec<&str> = functions.iter().map(|f| f.0).collect();
    check_every_kernel(&gpu, &arm::gpu::MODULE, &params, &functions, &every);
}

#[test]
fn f64_kernels_compute_sines_and_cosines_of_large_angles_to_rounding() {
    // The trap the kernels avoid: WGSL's f64 sin/cos lower to SPIR-V instructions defined for
    // 16- and 32-bit floats only, which lavapipe evaluates to ~1e-314 without an error. The
    // gravity of the arm is sums of products of sines and cosines: wrong trig shows at once.
    let Some(gpu) = device() else { return };
    if !gpu.has_f64() {
        eprintln!("{}: no SHADER_F64, f64 check skipped", gpu.adapter_name());
        return;
    }
    let k = arm::SingleArm::default();
    let cpu: Cpu<'_> = Box::new(move |q, _, _| dense(k.gravity(&v::<{ arm::DOF }>(q))));
    let mut d = Dynamics::<f64>::new(&gpu, &arm::gpu::MODULE, &arm::Params::default().to_array())
        .expect("f64 kernels");
    for (angle, seed) in [(1.0, 5), (100.0, 6), (1e4, 7)] {
        let e = kernel_error(&mut d, "gravity", &cpu, 64, angle, seed);
        assert!(e <= 1e-11, "gravity at |q| ≤ {angle}: {e:e}");
    }
}

/// Forward dynamics at `count` random states and rollouts of 25 steps of 2 ms from them
/// under constant forces, in `T` on the device, against the CPU's `fd` (f64) stepped the same
/// way; returns the two errors.
fn forward_and_rollout_errors<T: GpuFloat, const N: usize>(
    d: &mut Dynamics<T>,
    fd: impl Fn(&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>) -> SVector<f64, N>,
    count: usize,
) -> (f64, f64) {
    let mut draw = Draw(99);
    let (q, qs) = states(&mut draw, N, count, -0.6, 0.6);
    let (u, us) = states(&mut draw, N, count, -0.5, 0.5);
    let (tau, taus) = states(&mut draw, N, count, -5.0, 5.0);
    let cpu_ud: Vec<Vec<f64>> = (0..count)
        .map(|i| {
            fd(&v(&qs[i]), &v(&us[i]), &v(&taus[i]))
                .iter()
                .copied()
                .collect()
        })
        .collect();
    let (steps, dt) = (25u32, 2e-3);
    let cpu_final: Vec<Vec<f64>> = (0..count)
        .map(|i| {
            let (mut q, mut u, t) = (v::<N>(&qs[i]), v::<N>(&us[i]), v::<N>(&taus[i]));
            for _ in 0..steps {
                u += fd(&q, &u, &t) * dt;
                q += u * dt;
            }
            q.iter().chain(u.iter()).copied().collect()
        })
        .collect();
    let (q, u) = (cast::<T>(&q), cast::<T>(&u));
    let ud = d
        .forward_dynamics(count, &q, &u, &cast::<T>(&tau))
        .expect("forward dynamics");
    let forces: Vec<f64> = (0..steps).flat_map(|_| tau.iter().copied()).collect();
    let forces = cast::<T>(&forces);
    let r = Rollout {
        q0: &q,
        u0: &u,
        forces: &forces,
        steps,
        dt,
        record: false,
    };
    let last = d.rollout(count, &r).expect("rollout");
    // Every step recorded: the last recorded step is the final state.
    let every = d
        .rollout(count, &Rollout { record: true, ..r })
        .expect("rollout");
    let w = 2 * N * steps as usize;
    for i in 0..count {
        for j in 0..2 * N {
            assert_eq!(every[(w - 2 * N + j) * count + i], last[j * count + i]);
        }
    }
    (
        relative_error(&ud, &cpu_ud),
        relative_error(&last, &cpu_final),
    )
}

#[test]
fn forward_dynamics_and_rollouts_match_the_cpu() {
    let Some(gpu) = device() else { return };
    // Krang in f32 against the CPU's f64.
    let k = Krang::default();
    let params = krang_dynamics::Params::default().to_array();
    let mut d = Dynamics::<f32>::new(&gpu, &krang_dynamics::gpu::MODULE, &params).unwrap();
    let fd = |q: &_, u: &_, t: &_| {
        k.try_forward_dynamics(q, u, t)
            .expect("M is positive definite")
    };
    let (e_fd, e_roll) = forward_and_rollout_errors::<f32, 19>(&mut d, fd, 70);
    assert!(e_fd <= 1e-3, "Krang f32 forward dynamics: {e_fd:e}");
    assert!(e_roll <= 1e-3, "Krang f32 rollout: {e_roll:e}");
    // The arm in f64 (where the device has it) against the CPU's f64, through the runtime
    // trait's dense Cholesky.
    if gpu.has_f64() {
        let a = arm::SingleArm::default();
        let p = arm::Params::default().to_array();
        let mut d = Dynamics::<f64>::new(&gpu, &arm::gpu::MODULE, &p).unwrap();
        let fd = |q: &_, u: &_, t: &_| {
            kanegen_runtime::RobotDynamics::forward_dynamics(&a, q, u, t)
                .expect("M is positive definite")
        };
        let (e_fd, e_roll) = forward_and_rollout_errors::<f64, { arm::DOF }>(&mut d, fd, 70);
        assert!(e_fd <= 1e-10, "arm f64 forward dynamics: {e_fd:e}");
        assert!(e_roll <= 1e-10, "arm f64 rollout: {e_roll:e}");
    }
}

#[test]
fn chunked_batches_and_device_results_equal_one_dispatch() {
    let Some(gpu) = device() else { return };
    let params = arm::Params::default().to_array();
    let mut d = Dynamics::<f32>::new(&gpu, &arm::gpu::MODULE, &params).unwrap();
    let count = 300;
    let mut draw = Draw(3);
    let (q, _) = states(&mut draw, arm::DOF, count, -3.0, 3.0);
    let q = cast::<f32>(&q);
    let whole = d.evaluate("mass_matrix", count, &q, &[], &[]).unwrap();
    assert_eq!(d.last_timing().chunks, 1);
    d.set_max_chunk(64);
    let chunked = d.evaluate("mass_matrix", count, &q, &[], &[]).unwrap();
    assert_eq!(d.last_timing().chunks, 5);
    assert_eq!(whole, chunked);
    let kept = d
        .evaluate_on_device("mass_matrix", count, &q, &[], &[])
        .unwrap();
    assert_eq!(kept.chunks.len(), 5);
    assert_eq!(d.read(&kept).unwrap(), whole);
    let later = pollster::block_on(d.evaluate_async("mass_matrix", count, &q, &[], &[])).unwrap();
    assert_eq!(later, whole);
    // New parameters reach the kernels (through the precomputed values too).
    let mut p = arm::Params::default();
    p.set(arm::Params::NAMES[0], 2.0 * p.to_array()[0]).unwrap();
    d.set_params(&p.to_array()).unwrap();
    let changed = d.evaluate("mass_matrix", count, &q, &[], &[]).unwrap();
    let cpu = arm::SingleArm::new(p);
    let expected: Vec<Vec<f64>> = (0..count)
        .map(|i| {
            let qi: Vec<f64> = (0..arm::DOF).map(|j| f64::from(q[j * count + i])).collect();
            dense(cpu.mass_matrix(&v::<{ arm::DOF }>(&qi)))
        })
        .collect();
    assert!(relative_error(&changed, &expected) <= 1e-4);
}

#[test]
fn bad_requests_are_typed_errors() {
    let Some(gpu) = device() else { return };
    let params = arm::Params::default().to_array();
    let bad = Dynamics::<f32>::new(&gpu, &arm::gpu::MODULE, &params[1..]);
    assert!(matches!(
        bad,
        Err(GpuError::InputLength {
            input: "params",
            ..
        })
    ));
    let mut d = Dynamics::<f32>::new(&gpu, &arm::gpu::MODULE, &params).unwrap();
    let e = d
        .evaluate("mass_matrx", 1, &[0.0; 7], &[], &[])
        .unwrap_err();
    assert!(e.to_string().contains("mass_matrix"), "{e}");
    let e = d
        .evaluate("coriolis", 2, &[0.0; 14], &[0.0; 7], &[])
        .unwrap_err();
    assert!(
        matches!(
            e,
            GpuError::InputLength {
                input: "u",
                expected: 14,
                ..
            }
        ),
        "{e}"
    );
    // A rollout whose one state needs more than the largest binding.
    let steps = (gpu.max_binding_bytes() / (4 * 2 * arm::DOF as u64)) as u32 + 1;
    let q = [0.0f32; arm::DOF];
    let r = Rollout {
        q0: &q,
        u0: &q,
        forces: &[],
        steps,
        dt: 1e-3,
        record: true,
    };
    let e = d.rollout(1, &r).unwrap_err();
    assert!(
        matches!(
            e,
            GpuError::InputLength {
                input: "forces",
                ..
            }
        ),
        "{e}"
    );
    let forces = vec![0.0f32; steps as usize * arm::DOF];
    let e = d
        .rollout(
            1,
            &Rollout {
                forces: &forces,
                ..r
            },
        )
        .unwrap_err();
    assert!(matches!(e, GpuError::BatchTooLarge { .. }), "{e}");
    if !gpu.has_f64() {
        let e = Dynamics::<f64>::new(&gpu, &arm::gpu::MODULE, &params).unwrap_err();
        assert!(matches!(e, GpuError::NoF64(_)));
    }
}
