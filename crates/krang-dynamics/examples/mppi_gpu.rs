//! MPPI balancing of the 19-speed Krang with thousands of rollouts per control step on the GPU.
//!
//! Krang starts at rest, tilted `tilt` past its balancing pitch (`Krang::upright_pitch`).
//! Waist, torso and arms are servoed to their initial pose by the plant's joint controllers
//! (gravity compensation and a PD); the rollouts hold them with the servo's torques at the
//! state of the control step. The
//! controller commands one wheel torque (both wheels) per control step. Each step, model
//! predictive path integral control (MPPI) perturbs its nominal torque sequence with Gaussian
//! noise into `rollouts` (default 4,096) candidate sequences, rolls every one out over the
//! horizon (semi-implicit Euler, `u += h u̇` then `q += h u`, on the device:
//! `kanegen_gpu::Dynamics::rollout` in f32), scores them (pitch error, pitch rate, wheel
//! speed, torque; the horizon's last step weighs as much as the others together), and averages the sequences with weights `exp(−(cost − min)/λ)`. The first
//! torque of the average drives the plant, simulated on the CPU in f64 with the generated
//! forward dynamics at a finer step; the sequence shifts by one step.
//!
//! Without a GPU adapter the rollouts run on the CPU's batched forward dynamics
//! (`Krang::forward_dynamics_batch_soa_with_mass_matrix`, 8 states per call) on every core.
//!
//! ```text
//! cargo run --release -p krang-dynamics --features gpu,batch --example mppi_gpu -- [DIR] [ROLLOUTS]
//! ```
//! writes `mppi_gpu.png` (pitch error and wheel torque over time) to DIR (default
//! `target/plots`) and prints the final pitch error and the time per control step (kernel,
//! transfers, total).

#[path = "simulate/plot.rs"]
#[allow(dead_code)]
mod plot;

use std::error::Error;
use std::path::PathBuf;
use std::time::Instant;

use krang_dynamics::kanegen_gpu::{Dynamics, Gpu, Rollout};
use krang_dynamics::lanes::{Lanes, soa, state};
use krang_dynamics::{ACTUATOR_COUNT, Krang, Params, actuator, gpu, hardware, index};
use nalgebra::{SMatrix, SVector};

type Res<T> = Result<T, Box<dyn Error>>;
const N: usize = 19;

/// Controller and plant settings.
#[derive(Clone, Copy, Debug)]
struct Config {
    tilt: f64,
    rollouts: usize,
    horizon: usize,
    step: f64,
    control_steps: usize,
    plant_substeps: usize,
    noise: f64,
    lambda: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            tilt: 0.05,
            rollouts: 4096,
            horizon: 40,
            step: 0.01,
            control_steps: 80,
            plant_substeps: 10,
            noise: 15.0,
            lambda: 1.0,
        }
    }
}

/// The rollouts, on the GPU or on the CPU's batched path.
enum Sampler {
    Gpu(Box<Dynamics<f32>>),
    Cpu,
}

/// Generalized forces: `hold + t · wheel` for wheel torque `t`.
struct Forces {
    hold: SVector<f64, N>,
    wheel: SVector<f64, N>,
}

/// The end-of-step states of every rollout: `(q, u)` per step, per rollout.
fn rollouts_cpu(
    k: &Krang,
    cfg: &Config,
    f: &Forces,
    q0: &SVector<f64, N>,
    u0: &SVector<f64, N>,
    torques: &[f64],
) -> Vec<[f64; 3]> {
    let (h, steps) = (cfg.step, cfg.horizon);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = cfg.rollouts.div_ceil(threads).div_ceil(8) * 8;
    let mut out = vec![[0.0; 3]; cfg.rollouts * steps];
    std::thread::scope(|s| {
        for (chunk, out) in out.chunks_mut(per * steps).enumerate() {
            s.spawn(move || {
                let first = chunk * per;
                for block in (0..out.len() / steps).step_by(8) {
                    let lanes = |l: usize| (first + block + l).min(cfg.rollouts - 1);
                    let (mut q, mut u) = (soa(&[*q0; 8]), soa(&[*u0; 8]));
                    let mut ud = SVector::<Lanes<8>, N>::from_element(Lanes::splat(0.0));
                    let mut m = SMatrix::<Lanes<8>, N, N>::from_element(Lanes::splat(0.0));
                    for t in 0..steps {
                        let tau: [SVector<f64, N>; 8] = core::array::from_fn(|l| {
                            f.hold + f.wheel * torques[lanes(l) * steps + t]
                        });
                        k.forward_dynamics_batch_soa_with_mass_matrix(
                            &q,
                            &u,
                            &soa(&tau),
                            &mut m,
                            &mut ud,
                        );
                        for i in 0..N {
                            u[i] = u[i] + ud[i] * h;
                            q[i] = q[i] + u[i] * h;
                        }
                        for l in 0..8 {
                            let r = block + l;
                            if r < out.len() / steps {
                                let (qs, us) = (state(&q, l), state(&u, l));
                                out[r * steps + t] =
                                    [qs[index::Q_IMU], us[index::QD_IMU], us[index::XD]];
                            }
                        }
                    }
                }
            });
        }
    });
    out
}

/// The same on the device: pitch, pitch rate and forward speed per step, per rollout.
fn rollouts_gpu(
    d: &mut Dynamics<f32>,
    cfg: &Config,
    f: &Forces,
    q0: &SVector<f64, N>,
    u0: &SVector<f64, N>,
    torques: &[f64],
) -> Res<Vec<[f64; 3]>> {
    let (r, steps) = (cfg.rollouts, cfg.horizon);
    let soa_of = |x: &SVector<f64, N>| -> Vec<f32> {
        (0..N)
            .flat_map(|j| std::iter::repeat_n(x[j] as f32, r))
            .collect()
    };
    let mut forces = vec![0.0f32; steps * N * r];
    for t in 0..steps {
        for j in 0..N {
            let row = &mut forces[(t * N + j) * r..(t * N + j + 1) * r];
            for (i, v) in row.iter_mut().enumerate() {
                *v = (f.hold[j] + f.wheel[j] * torques[i * steps + t]) as f32;
            }
        }
    }
    let (q0, u0) = (soa_of(q0), soa_of(u0));
    let out = d.rollout(
        r,
        &Rollout {
            q0: &q0,
            u0: &u0,
            forces: &forces,
            steps: steps as u32,
            dt: cfg.step,
            record: true,
        },
    )?;
    let at = |t: usize, j: usize, i: usize| f64::from(out[(t * 2 * N + j) * r + i]);
    let mut states = vec![[0.0; 3]; r * steps];
    for i in 0..r {
        for t in 0..steps {
            states[i * steps + t] = [
                at(t, index::Q_IMU, i),
                at(t, N + index::QD_IMU, i),
                at(t, N + index::XD, i),
            ];
        }
    }
    Ok(states)
}

/// Normal draws by Box–Muller from a xorshift generator.
struct Noise(u64);
impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

fn main() -> Res<()> {
    let mut args = std::env::args_os().skip(1);
    let dir = args
        .next()
        .map_or_else(|| PathBuf::from("target/plots"), PathBuf::from);
    let mut cfg = Config::default();
    if let Some(r) = args.next() {
        cfg.rollouts = r.to_string_lossy().parse()?;
    }
    let k = Krang::default();
    let mut sampler = match Gpu::new() {
        Ok(g) => {
            let d = Dynamics::<f32>::new(&g, &gpu::MODULE, &Params::default().to_array())?;
            println!("rollouts on {} ({})", g.adapter_name(), g.backend());
            Sampler::Gpu(Box::new(d))
        }
        Err(e) => {
            println!("rollouts on the CPU's batched path ({e})");
            Sampler::Cpu
        }
    };
    let mut q = SVector::<f64, N>::zeros();
    let upright = k.upright_pitch(&q);
    q[index::Q_IMU] = upright + cfg.tilt;
    let mut u = SVector::<f64, N>::zeros();
    // The joints above the base (waist, torso, arms) are servoed to their initial pose by the
    // plant's joint controllers: gravity compensation plus a PD scaled by M's diagonal. The
    // rollouts model them by their holding torques at the current state.
    let pose = q;
    let inertia = k.mass_matrix(&q).diagonal();
    let servo = |q: &SVector<f64, N>, u: &SVector<f64, N>| {
        let mut t = k.gravity(q);
        for j in 0..N {
            if j < index::Q_W {
                t[j] = 0.0;
            } else {
                t[j] -= inertia[j] * (100.0 * (q[j] - pose[j]) + 20.0 * u[j]);
            }
        }
        t
    };
    let mut unit = SVector::<f64, ACTUATOR_COUNT>::zeros();
    unit[actuator::WHEEL_L] = 1.0;
    unit[actuator::WHEEL_R] = 1.0;
    let mut f = Forces {
        hold: servo(&q, &u),
        wheel: k.generalized_forces(&unit),
    };
    let limit = hardware::TORQUE_LIMITS[actuator::WHEEL_L];
    let mut nominal = vec![0.0; cfg.horizon];
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let (mut pitch, mut torque) = (Vec::new(), Vec::new());
    let (mut kernel, mut transfer, mut total) = (0.0, 0.0, 0.0);
    for step in 0..cfg.control_steps {
        let t0 = Instant::now();
        f.hold = servo(&q, &u);
        let (r, h) = (cfg.rollouts, cfg.horizon);
        let eps: Vec<f64> = (0..r * h).map(|_| cfg.noise * noise.normal()).collect();
        let torques: Vec<f64> = (0..r * h)
            .map(|n| (nominal[n % h] + eps[n]).clamp(-limit, limit))
            .collect();
        let states = match &mut sampler {
            Sampler::Gpu(d) => {
                let s = rollouts_gpu(d, &cfg, &f, &q, &u, &torques)?;
                let t = d.last_timing();
                kernel += t.kernel.as_secs_f64();
                transfer += (t.upload + t.download).as_secs_f64();
                s
            }
            Sampler::Cpu => rollouts_cpu(&k, &cfg, &f, &q, &u, &torques),
        };
        let cost: Vec<f64> = (0..r)
            .map(|i| {
                (0..h)
                    .map(|t| {
                        let [p, pd, xd] = states[i * h + t];
                        let e = p - upright;
                        // The last step weighs as much as the rest of the horizon.
                        let w = if t + 1 == h { h as f64 } else { 1.0 };
                        let c = w * (100.0 * e * e + pd * pd + 0.01 * xd * xd)
                            + 1e-4 * torques[i * h + t].powi(2);
                        if c.is_finite() { c } else { 1e9 }
                    })
                    .sum()
            })
            .collect();
        let best = cost.iter().copied().fold(f64::INFINITY, f64::min);
        let w: Vec<f64> = cost
            .iter()
            .map(|c| (-(c - best) / cfg.lambda).exp())
            .collect();
        let sum: f64 = w.iter().sum();
        for (t, n) in nominal.iter_mut().enumerate() {
            *n = (0..r).map(|i| w[i] * torques[i * h + t]).sum::<f64>() / sum;
        }
        total += t0.elapsed().as_secs_f64();
        // The plant: the first torque for one control step, finer semi-implicit Euler in f64.
        let dt = cfg.step / cfg.plant_substeps as f64;
        for _ in 0..cfg.plant_substeps {
            let tau = servo(&q, &u) + f.wheel * nominal[0];
            let ud = k.forward_dynamics(&q, &u, &tau);
            u += ud * dt;
            q += u * dt;
        }
        let time = (step + 1) as f64 * cfg.step;
        pitch.push((time, q[index::Q_IMU] - upright));
        torque.push((time, nominal[0]));
        nominal.rotate_left(1);
        nominal[h - 1] = 0.0;
    }
    let steps = cfg.control_steps as f64;
    let last = pitch.last().map_or(0.0, |p| p.1);
    println!(
        "{} rollouts of {} steps ({} s) per control step, {} control steps",
        cfg.rollouts,
        cfg.horizon,
        cfg.horizon as f64 * cfg.step,
        cfg.control_steps
    );
    println!(
        "pitch error {:.4} rad -> {:.2e} rad; wheel torque peak {:.1} N·m",
        cfg.tilt,
        last,
        torque.iter().map(|t| t.1.abs()).fold(0.0, f64::max)
    );
    println!(
        "per control step: {:.1} ms in all, rollout kernel {:.1} ms, transfers {:.1} ms",
        1e3 * total / steps,
        1e3 * kernel / steps,
        1e3 * transfer / steps
    );
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("mppi_gpu.png");
    plot::figure(
        &path,
        (900, 600),
        &[
            plot::Panel {
                title: format!(
                    "MPPI balancing, {} rollouts per step: pitch error",
                    cfg.rollouts
                ),
                y_label: "rad",
                series: vec![plot::Series::line("q_imu - upright", plot::BLUE_, pitch)],
            },
            plot::Panel {
                title: "wheel torque (each wheel)".into(),
                y_label: "N m",
                series: vec![plot::Series::line("torque", plot::RED_, torque)],
            },
        ],
    )?;
    println!("wrote {}", path.display());
    Ok(())
}
