//! Criterion benchmarks of the generated dynamics against the optimised numeric recursions of
//! `kanegen-rbd` (CRBA, RNEA, gravity pass) and the naive reference recursion of
//! `kanegen-reference`, for `M(q)`, `c(q, u)`, `g(q)` and `τ(q, u, u̇)`.
//!
//! Benchmark ids are `<model>/<function>/<variant>`:
//!
//! * models: `krang` (19 speeds, `models/krang.toml`), `krang_fixed_wheels` (17, the fixed-wheel
//!   tree), `arm` (7, `models/singlearm.urdf`) and `krang_urdf` (19, `models/Krang.urdf` with its
//!   wheeled base);
//! * functions: `mass_matrix`, `coriolis`, `gravity`, `inverse_dynamics`;
//! * variants: `generated` (runtime `Params`), `baked` (parameters folded in; `krang` and `arm`),
//!   `rbd` (`kanegen_rbd::Rbd`), `naive` (`kanegen_reference::Reference`, heap-allocating);
//!
//! plus `overhead/sin_cos_x17/{batched,generated,std,rbd}`: the 17 `sin_cos` of Krang's joint
//! angles, with the batched routine the generator emits into every module
//! (`kanegen_runtime::trig::sin_cos_n`, one call for all angles, as in generated code), with its
//! scalar fallback that generated code called once per joint before (`fast_sin_cos`, inlined),
//! with the standard library, and with `kanegen-rbd`'s batched polynomial kernel
//! (`Scalar::sin_cos_batch`, what `Rbd` calls); each returns an xor of its results' bits.
//!
//! Every variant runs on the same fixed set of [`STATES`] random states (deterministic seed),
//! cycled through call by call, inputs behind `black_box`; all variants of a model use the same
//! parameter values (the model file's) and are checked against each other before timing.
//!
//! ```sh
//! cargo bench --bench dynamics                    # everything (about 4 minutes)
//! cargo bench --bench dynamics -- krang/mass_matrix
//! cargo run --release --example bench_report      # Markdown table from target/criterion
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen_rbd::{Rbd, Scalar};
use kanegen_reference::Reference;
use kanegen_reference::random::SplitMix64;
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

// The generated modules are linted where they are tested (krang-dynamics, the URDF example);
// here they only host the benchmarks.

/// The 7-DOF arm generated from `models/singlearm.urdf` (by the root package's `build.rs`).
#[allow(missing_docs, dead_code, clippy::all)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm.rs"));
}

/// The same arm with its parameters folded in.
#[allow(missing_docs, dead_code, clippy::all)]
mod arm_baked {
    include!(concat!(env!("OUT_DIR"), "/singlearm_baked.rs"));
}

/// Krang generated from `models/Krang.urdf` with the two-wheeled base declaration.
#[allow(missing_docs, dead_code, clippy::all)]
mod krang_urdf {
    include!(concat!(env!("OUT_DIR"), "/krang_urdf.rs"));
}

/// Number of random states cycled through (a power of two).
const STATES: usize = 8;

/// One state `(q, u, u̇)`.
struct State<const N: usize> {
    q: SVector<f64, N>,
    u: SVector<f64, N>,
    ud: SVector<f64, N>,
}

/// [`STATES`] random states: `q` uniform in [−π, π], `u` in [−2, 2], `u̇` in [−5, 5].
fn states<const N: usize>(seed: u64) -> Vec<State<N>> {
    let mut rng = SplitMix64::new(seed);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let pi = std::f64::consts::PI;
    (0..STATES)
        .map(|_| State {
            q: SVector::from_fn(|_, _| uniform(-pi, pi)),
            u: SVector::from_fn(|_, _| uniform(-2.0, 2.0)),
            ud: SVector::from_fn(|_, _| uniform(-5.0, 5.0)),
        })
        .collect()
}

/// Column-major entries of a result, to check the variants against each other.
trait Flat {
    fn flat(&self) -> Vec<f64>;
}

impl<const R: usize, const C: usize> Flat for SMatrix<f64, R, C> {
    fn flat(&self) -> Vec<f64> {
        self.as_slice().to_vec()
    }
}

impl Flat for DMatrix<f64> {
    fn flat(&self) -> Vec<f64> {
        self.as_slice().to_vec()
    }
}

impl Flat for DVector<f64> {
    fn flat(&self) -> Vec<f64> {
        self.as_slice().to_vec()
    }
}

/// One implementation of a model's dynamics.
trait Dynamics<const N: usize> {
    type Mat: Flat;
    type Vec: Flat;
    fn mass_matrix(&self, q: &SVector<f64, N>) -> Self::Mat;
    fn coriolis(&self, q: &SVector<f64, N>, u: &SVector<f64, N>) -> Self::Vec;
    fn gravity(&self, q: &SVector<f64, N>) -> Self::Vec;
    fn inverse_dynamics(
        &self,
        q: &SVector<f64, N>,
        u: &SVector<f64, N>,
        ud: &SVector<f64, N>,
    ) -> Self::Vec;
}

/// Implements [`Dynamics`] for a generated wrapper struct (its inherent methods).
macro_rules! dynamics {
    ($ty:ty, $n:literal) => {
        impl Dynamics<$n> for $ty {
            type Mat = SMatrix<f64, $n, $n>;
            type Vec = SVector<f64, $n>;
            fn mass_matrix(&self, q: &SVector<f64, $n>) -> Self::Mat {
                <$ty>::mass_matrix(self, q)
            }
            fn coriolis(&self, q: &SVector<f64, $n>, u: &SVector<f64, $n>) -> Self::Vec {
                <$ty>::coriolis(self, q, u)
            }
            fn gravity(&self, q: &SVector<f64, $n>) -> Self::Vec {
                <$ty>::gravity(self, q)
            }
            fn inverse_dynamics(
                &self,
                q: &SVector<f64, $n>,
                u: &SVector<f64, $n>,
                ud: &SVector<f64, $n>,
            ) -> Self::Vec {
                <$ty>::inverse_dynamics(self, q, u, ud)
            }
        }
    };
}

/// The baked free functions of a generated module, as a [`Dynamics`].
macro_rules! baked {
    ($name:ident, $module:path, $n:literal) => {
        struct $name;
        impl Dynamics<$n> for $name {
            type Mat = SMatrix<f64, $n, $n>;
            type Vec = SVector<f64, $n>;
            fn mass_matrix(&self, q: &SVector<f64, $n>) -> Self::Mat {
                use $module as m;
                m::mass_matrix(q)
            }
            fn coriolis(&self, q: &SVector<f64, $n>, u: &SVector<f64, $n>) -> Self::Vec {
                use $module as m;
                m::coriolis(q, u)
            }
            fn gravity(&self, q: &SVector<f64, $n>) -> Self::Vec {
                use $module as m;
                m::gravity(q)
            }
            fn inverse_dynamics(
                &self,
                q: &SVector<f64, $n>,
                u: &SVector<f64, $n>,
                ud: &SVector<f64, $n>,
            ) -> Self::Vec {
                use $module as m;
                m::inverse_dynamics(q, u, ud)
            }
        }
    };
}

dynamics!(krang_dynamics::Krang, 19);
dynamics!(krang_dynamics::fixed_wheels::KrangFixedWheels, 17);
dynamics!(arm::SingleArm, 7);
dynamics!(krang_urdf::Krang, 19);
baked!(KrangBaked, krang_dynamics::baked, 19);
baked!(ArmBaked, arm_baked, 7);

/// `kanegen_rbd::Rbd` (CRBA, RNEA, gravity pass).
struct RbdDyn<const N: usize>(Rbd<N>);

impl<const N: usize> Dynamics<N> for RbdDyn<N> {
    type Mat = SMatrix<f64, N, N>;
    type Vec = SVector<f64, N>;
    fn mass_matrix(&self, q: &SVector<f64, N>) -> Self::Mat {
        self.0.mass_matrix(q)
    }
    fn coriolis(&self, q: &SVector<f64, N>, u: &SVector<f64, N>) -> Self::Vec {
        self.0.coriolis(q, u)
    }
    fn gravity(&self, q: &SVector<f64, N>) -> Self::Vec {
        self.0.gravity(q)
    }
    fn inverse_dynamics(
        &self,
        q: &SVector<f64, N>,
        u: &SVector<f64, N>,
        ud: &SVector<f64, N>,
    ) -> Self::Vec {
        self.0.inverse_dynamics(q, u, ud)
    }
}

/// The naive reference recursion (`M` column by column from inverse dynamics; heap results).
struct Naive(Reference<f64>);

impl<const N: usize> Dynamics<N> for Naive {
    type Mat = DMatrix<f64>;
    type Vec = DVector<f64>;
    fn mass_matrix(&self, q: &SVector<f64, N>) -> Self::Mat {
        self.0.mass_matrix(q.as_slice())
    }
    fn coriolis(&self, q: &SVector<f64, N>, u: &SVector<f64, N>) -> Self::Vec {
        self.0.coriolis(q.as_slice(), u.as_slice())
    }
    fn gravity(&self, q: &SVector<f64, N>) -> Self::Vec {
        self.0.gravity(q.as_slice())
    }
    fn inverse_dynamics(
        &self,
        q: &SVector<f64, N>,
        u: &SVector<f64, N>,
        ud: &SVector<f64, N>,
    ) -> Self::Vec {
        self.0
            .inverse_dynamics(q.as_slice(), u.as_slice(), ud.as_slice())
    }
}

/// `M`, `c`, `g`, `τ` of `d` at `s`, flattened.
fn evaluate<const N: usize, D: Dynamics<N>>(d: &D, s: &State<N>) -> [Vec<f64>; 4] {
    [
        d.mass_matrix(&s.q).flat(),
        d.coriolis(&s.q, &s.u).flat(),
        d.gravity(&s.q).flat(),
        d.inverse_dynamics(&s.q, &s.u, &s.ud).flat(),
    ]
}

/// Panics unless `d` agrees with the naive recursion `reference` on every state (relative to the
/// largest entry, 1e-9): the benchmarks compare implementations of the same function.
fn check<const N: usize, D: Dynamics<N>>(
    label: &str,
    d: &D,
    reference: &Naive,
    states: &[State<N>],
) {
    for s in states {
        let ours = evaluate(d, s);
        let theirs = evaluate::<N, _>(reference, s);
        for (f, (a, b)) in ["M", "c", "g", "tau"].iter().zip(ours.iter().zip(&theirs)) {
            let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let err = a
                .iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
                / scale;
            assert!(
                err < 1e-9,
                "{label}: {f} differs from the reference by {err:e}"
            );
        }
    }
}

/// The benchmarked functions.
#[derive(Clone, Copy)]
enum Function {
    MassMatrix,
    Coriolis,
    Gravity,
    InverseDynamics,
}

impl Function {
    const ALL: [Self; 4] = [
        Self::MassMatrix,
        Self::Coriolis,
        Self::Gravity,
        Self::InverseDynamics,
    ];

    fn name(self) -> &'static str {
        match self {
            Self::MassMatrix => "mass_matrix",
            Self::Coriolis => "coriolis",
            Self::Gravity => "gravity",
            Self::InverseDynamics => "inverse_dynamics",
        }
    }
}

/// Function `f` of `d` at `<model>/<function>/<variant>`, cycling through `states`.
fn bench_one<const N: usize, D: Dynamics<N>>(
    c: &mut Criterion,
    model: &str,
    f: Function,
    variant: &str,
    d: &D,
    states: &[State<N>],
) {
    assert!(states.len().is_power_of_two());
    let mask = states.len() - 1;
    let id = format!("{model}/{}/{variant}", f.name());
    // One closure per function so that the timed loop has no dispatch on `f`.
    match f {
        Function::MassMatrix => c.bench_function(&id, |b| {
            let mut i = 0;
            b.iter(|| {
                let s = &states[i & mask];
                i += 1;
                black_box(d).mass_matrix(black_box(&s.q))
            })
        }),
        Function::Coriolis => c.bench_function(&id, |b| {
            let mut i = 0;
            b.iter(|| {
                let s = &states[i & mask];
                i += 1;
                black_box(d).coriolis(black_box(&s.q), black_box(&s.u))
            })
        }),
        Function::Gravity => c.bench_function(&id, |b| {
            let mut i = 0;
            b.iter(|| {
                let s = &states[i & mask];
                i += 1;
                black_box(d).gravity(black_box(&s.q))
            })
        }),
        Function::InverseDynamics => c.bench_function(&id, |b| {
            let mut i = 0;
            b.iter(|| {
                let s = &states[i & mask];
                i += 1;
                black_box(d).inverse_dynamics(black_box(&s.q), black_box(&s.u), black_box(&s.ud))
            })
        }),
    };
}

/// A model file of the repository.
fn path(rel: &str) -> String {
    format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"))
}

/// Benchmarks one model: `generated` and the optional `baked` against `rbd` and `naive`, all
/// with the parameter values of `model` (the model file's).
fn bench_model<const N: usize, G: Dynamics<N>, B: Dynamics<N>>(
    c: &mut Criterion,
    name: &str,
    model: &Model,
    generated: &G,
    baked: Option<&B>,
    seed: u64,
) {
    assert_eq!(model.dof(), N, "{name}");
    let states = states::<N>(seed);
    let naive = Naive(Reference::new(model));
    let rbd = RbdDyn(Rbd::<N>::with_default_params(model).expect("Rbd builds"));
    check(&format!("{name}/generated"), generated, &naive, &states);
    check(&format!("{name}/rbd"), &rbd, &naive, &states);
    if let Some(baked) = baked {
        check(&format!("{name}/baked"), baked, &naive, &states);
    }
    // The variants of one function back to back, so that the ratios between them see the same
    // machine (a shared machine's load drifts over minutes).
    for f in Function::ALL {
        bench_one(c, name, f, "generated", generated, &states);
        if let Some(baked) = baked {
            bench_one(c, name, f, "baked", baked, &states);
        }
        bench_one(c, name, f, "rbd", &rbd, &states);
        bench_one(c, name, f, "naive", &naive, &states);
    }
}

/// What the `sin_cos` benchmarks return: every result read where it was computed, as generated
/// code reads its sines and cosines, and folded cheaply (xor of the bits; vectorized). Returning
/// the 17 pairs by value instead costs array copies that generated code does not pay.
#[inline(always)]
fn fold_bits(sin: &[f64; 17], cos: &[f64; 17]) -> u64 {
    sin.iter()
        .zip(cos)
        .fold(0, |h, (s, c)| h ^ s.to_bits() ^ c.to_bits())
}

fn krang(c: &mut Criterion) {
    let model = Model::from_toml_file(path("models/krang.toml")).expect("krang.toml loads");
    let generated = krang_dynamics::Krang::default();
    bench_model::<19, _, _>(c, "krang", &model, &generated, Some(&KrangBaked), 1);

    // The sines and cosines alone: the 17 joint angles Krang's functions use (q[2..19]).
    let states = states::<19>(1);
    let mask = states.len() - 1;
    c.bench_function("overhead/sin_cos_x17/batched", |b| {
        let mut i = 0;
        b.iter(|| {
            let q = black_box(&states[i & mask].q);
            i += 1;
            let x: [f64; 17] = std::array::from_fn(|k| q[k + 2]);
            let (sin, cos) = kanegen_runtime::trig::sin_cos_n(x);
            fold_bits(&sin, &cos)
        })
    });
    c.bench_function("overhead/sin_cos_x17/generated", |b| {
        let mut i = 0;
        b.iter(|| {
            let q = black_box(&states[i & mask].q);
            i += 1;
            let (mut sin, mut cos) = ([0.0; 17], [0.0; 17]);
            for k in 0..17 {
                (sin[k], cos[k]) = kanegen_runtime::trig::sin_cos(q[k + 2]);
            }
            fold_bits(&sin, &cos)
        })
    });
    c.bench_function("overhead/sin_cos_x17/std", |b| {
        let mut i = 0;
        b.iter(|| {
            let q = black_box(&states[i & mask].q);
            i += 1;
            let (mut sin, mut cos) = ([0.0; 17], [0.0; 17]);
            for k in 0..17 {
                (sin[k], cos[k]) = q[k + 2].sin_cos();
            }
            fold_bits(&sin, &cos)
        })
    });
    c.bench_function("overhead/sin_cos_x17/rbd", |b| {
        let mut i = 0;
        b.iter(|| {
            let q = black_box(&states[i & mask].q);
            i += 1;
            let x: [f64; 17] = std::array::from_fn(|k| q[k + 2]);
            let (mut sin, mut cos) = ([0.0; 17], [0.0; 17]);
            f64::sin_cos_batch(&x, &mut sin, &mut cos);
            fold_bits(&sin, &cos)
        })
    });
}

fn krang_fixed_wheels(c: &mut Criterion) {
    let model = Model::from_toml_file(path("models/krang-fixed-wheels.toml"))
        .expect("krang-fixed-wheels.toml loads");
    let generated = krang_dynamics::fixed_wheels::KrangFixedWheels::default();
    bench_model::<17, _, Naive>(c, "krang_fixed_wheels", &model, &generated, None, 2);
}

fn arm(c: &mut Criterion) {
    let model = Model::from_urdf_file(path("models/singlearm.urdf"), &UrdfOptions::default())
        .expect("singlearm.urdf loads");
    let generated = arm::SingleArm::new(arm::Params::default());
    bench_model::<7, _, _>(c, "arm", &model, &generated, Some(&ArmBaked), 3);
}

fn krang_from_urdf(c: &mut Criterion) {
    // As in build.rs.
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.pitch_name = "imu".into();
    let options =
        UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]);
    let model =
        Model::from_urdf_file(path("models/Krang.urdf"), &options).expect("Krang.urdf loads");
    let generated = krang_urdf::Krang::new(krang_urdf::Params::default());
    bench_model::<19, _, Naive>(c, "krang_urdf", &model, &generated, None, 4);
}

/// 1 s warm-up and 2 s of measurement per benchmark (about 3.5 s each with the analysis; 56
/// benchmarks): the whole run stays near 4 minutes.
fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .sample_size(50)
}

criterion_group! {
    name = benches;
    config = config();
    targets = krang, krang_fixed_wheels, arm, krang_from_urdf
}
criterion_main!(benches);
