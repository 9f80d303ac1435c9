//! Criterion benchmarks of Krang's derivatives (19 speeds, `models/krang.toml`, the model
//! file's parameters), ids `krang/<what>/<variant>`:
//!
//! * `inverse_dynamics/generated`: one generated τ call, the unit of the issue's target;
//! * `id_derivatives/generated`: the generated `inverse_dynamics_derivatives` (both 19×19
//!   matrices ∂τ/∂q, ∂τ/∂u);
//! * `id_derivatives/into`, `id_derivatives/with`: the same into a matrix kept across calls
//!   (`inverse_dynamics_derivatives_into`, which zeroes it and a workspace every call) and into
//!   a `DerivativesWorkspace` kept across calls (`inverse_dynamics_derivatives_with`, which
//!   zeroes nothing);
//! * `id_derivatives/central_differences`: the same two matrices by central differences of the
//!   generated τ (2 × 2N = 76 calls; Richardson extrapolation would double that);
//! * `id_derivatives/rbd_dual`: the same by `kanegen-rbd`'s recursion in `num_dual::Dual64`
//!   (2N = 38 forward-mode passes of the numeric RNEA);
//! * `forward_dynamics/generated`: `Krang::forward_dynamics` (τ with u̇ = 0, M, block Cholesky);
//! * `forward_dynamics/fixed_wheels`: `KrangFixedWheels::forward_dynamics` (17 speeds,
//!   `BlockCholesky<3, 17>`), at the trunk and arm coordinates of the same states;
//! * `fd_derivatives/generated`: `Krang::forward_dynamics_derivatives` (u̇, ∂u̇/∂q, ∂u̇/∂u, M⁻¹);
//! * `fd_derivatives/with`: `Krang::forward_dynamics_derivatives_with`, the same into a
//!   `ForwardDynamicsDerivativesWorkspace` kept across calls;
//! * `forward_dynamics/fixed_wheels_trait`: the same through the runtime trait's provided
//!   `RobotDynamics::forward_dynamics` (a dense Cholesky), what every generated robot has;
//! * `fd_derivatives/fixed_wheels`: `KrangFixedWheels::try_forward_dynamics_derivatives` (17
//!   speeds), at the same states as `forward_dynamics/fixed_wheels`;
//! * `fd_derivatives/fixed_wheels_with`: `KrangFixedWheels::forward_dynamics_derivatives_with`,
//!   the same into a `fixed_wheels::ForwardDynamicsDerivativesWorkspace` kept across calls;
//! * `linearize/fixed_wheels`, `linearize/fixed_wheels_with`: `KrangFixedWheels::linearize`
//!   (A 34×34, B 34×17) and `linearize_with` (into a `fixed_wheels::LinearizationWorkspace`);
//! * `fd_derivatives/fixed_wheels_trait`: the same through the runtime trait's provided
//!   `InverseDynamicsDerivatives::forward_dynamics_derivatives` (a dense Cholesky), what every
//!   generated robot without a block factor of its own gets;
//! * `linearize/generated`: `Krang::linearize` (A 38×38, B 38×18);
//! * `linearize/with`: `Krang::linearize_with`, the same into a `LinearizationWorkspace` kept
//!   across calls.
//!
//! Every variant cycles through the same 8 random states, inputs behind `black_box`.
//!
//! ```sh
//! cargo bench --bench derivatives
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kanegen_reference::random::SplitMix64;
use krang_dynamics::Krang;
use nalgebra::{SMatrix, SVector};

type V = SVector<f64, 19>;

/// 8 random states `(q, u, u̇)`: q in [−π, π], u in [−2, 2], u̇ in [−5, 5].
fn states() -> Vec<(V, V, V)> {
    let mut r = SplitMix64::new(12);
    let mut v = |lo: f64, hi: f64| V::from_fn(|_, _| lo + (hi - lo) * r.next_f64());
    (0..8)
        .map(|_| {
            let pi = std::f64::consts::PI;
            (v(-pi, pi), v(-2.0, 2.0), v(-5.0, 5.0))
        })
        .collect()
}

/// ∂τ/∂q and ∂τ/∂u by central differences of the generated τ (step 1e-6).
fn central_differences(k: &Krang, q: &V, u: &V, ud: &V) -> SMatrix<f64, 19, 38> {
    let h = 1e-6;
    let mut d = SMatrix::<f64, 19, 38>::zeros();
    for j in 0..19 {
        let (mut qp, mut qm) = (*q, *q);
        qp[j] += h;
        qm[j] -= h;
        let col = (k.inverse_dynamics(&qp, u, ud) - k.inverse_dynamics(&qm, u, ud)) / (2.0 * h);
        d.set_column(j, &col);
        let (mut up, mut um) = (*u, *u);
        up[j] += h;
        um[j] -= h;
        let col = (k.inverse_dynamics(q, &up, ud) - k.inverse_dynamics(q, &um, ud)) / (2.0 * h);
        d.set_column(19 + j, &col);
    }
    d
}

/// The fixed-wheel tree's state from one of Krang's: the trunk and arm coordinates and speeds
/// (Krang's entries 2..19), and `τ = 10 u̇` as the Krang entries use.
fn fixed_wheel_state(
    q: &V,
    u: &V,
    ud: &V,
) -> (SVector<f64, 17>, SVector<f64, 17>, SVector<f64, 17>) {
    (
        q.fixed_rows::<17>(2).into_owned(),
        u.fixed_rows::<17>(2).into_owned(),
        ud.fixed_rows::<17>(2) * 10.0,
    )
}

fn bench(c: &mut Criterion) {
    let k = Krang::default();
    let s = states();
    // Checked before timing: the generated derivatives agree with the differences.
    for (q, u, ud) in &s {
        let (g, f) = (
            k.inverse_dynamics_derivatives(q, u, ud),
            central_differences(&k, q, u, ud),
        );
        assert!((g - f).abs().max() <= 1e-4 * f.abs().max().max(1.0));
    }
    let mut g = c.benchmark_group("krang");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .sample_size(50);
    macro_rules! cycle {
        ($id:expr, |$q:ident, $u:ident, $ud:ident| $body:expr) => {
            g.bench_function($id, |b| {
                let mut i = 0;
                b.iter(|| {
                    let ($q, $u, $ud) = &s[i % s.len()];
                    i += 1;
                    let ($q, $u, $ud) = (black_box($q), black_box($u), black_box($ud));
                    black_box($body)
                })
            });
        };
    }
    cycle!("inverse_dynamics/generated", |q, u, ud| k
        .inverse_dynamics(q, u, ud));
    cycle!("id_derivatives/generated", |q, u, ud| k
        .inverse_dynamics_derivatives(q, u, ud));
    let mut kept = SMatrix::<f64, 19, 38>::zeros();
    cycle!("id_derivatives/into", |q, u, ud| {
        k.inverse_dynamics_derivatives_into(q, u, ud, &mut kept);
        kept[(7, 20)]
    });
    let mut ws = krang_dynamics::DerivativesWorkspace::new();
    cycle!("id_derivatives/with", |q, u, ud| k
        .inverse_dynamics_derivatives_with(q, u, ud, &mut ws)[(7, 20)]);
    cycle!("id_partials/generated", |q, u, ud| k
        .inverse_dynamics_partials(q, u, ud));
    cycle!("id_derivatives/central_differences", |q, u, ud| {
        central_differences(&k, q, u, ud)
    });
    let model = kanegen_model::Model::from_toml_file(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/krang.toml"),
    )
    .expect("krang.toml loads");
    let dual = kanegen_rbd::DualDerivatives::<19>::new(&model, &model.param_values())
        .expect("the recursion builds");
    cycle!("id_derivatives/rbd_dual", |q, u, ud| {
        dual.inverse_dynamics_derivatives(q, u, ud)
    });
    cycle!("forward_dynamics/generated", |q, u, ud| k.forward_dynamics(
        q,
        u,
        &(ud * 10.0)
    ));
    cycle!("fd_derivatives/generated", |q, u, ud| k
        .forward_dynamics_derivatives(q, u, &(ud * 10.0)));
    let mut fd_ws = krang_dynamics::ForwardDynamicsDerivativesWorkspace::new();
    cycle!("fd_derivatives/with", |q, u, ud| k
        .forward_dynamics_derivatives_with(q, u, &(ud * 10.0), &mut fd_ws)
        .dud_dq[(7, 9)]);
    // The fixed-wheel tree (17 speeds): the block factor with a trunk of three speeds.
    let fixed = krang_dynamics::fixed_wheels::KrangFixedWheels::default();
    cycle!("forward_dynamics/fixed_wheels", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        fixed.forward_dynamics(&q, &u, &tau)
    });
    cycle!("forward_dynamics/fixed_wheels_trait", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        krang_dynamics::RobotDynamics::forward_dynamics(&fixed, &q, &u, &tau)
    });
    cycle!("fd_derivatives/fixed_wheels", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        fixed.try_forward_dynamics_derivatives(&q, &u, &tau)
    });
    let mut fixed_fd_ws = krang_dynamics::fixed_wheels::ForwardDynamicsDerivativesWorkspace::new();
    cycle!("fd_derivatives/fixed_wheels_with", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        fixed
            .forward_dynamics_derivatives_with(&q, &u, &tau, &mut fixed_fd_ws)
            .dud_dq[(7, 9)]
    });
    cycle!("linearize/fixed_wheels", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        fixed.linearize(&q, &u, &tau)
    });
    let mut fixed_lin_ws = krang_dynamics::fixed_wheels::LinearizationWorkspace::new();
    cycle!("linearize/fixed_wheels_with", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        fixed.linearize_with(&q, &u, &tau, &mut fixed_lin_ws).1[(25, 3)]
    });
    cycle!("fd_derivatives/fixed_wheels_trait", |q, u, ud| {
        let (q, u, tau) = fixed_wheel_state(q, u, ud);
        krang_dynamics::InverseDynamicsDerivatives::forward_dynamics_derivatives(
            &fixed, &q, &u, &tau,
        )
    });
    let a = SVector::<f64, 18>::from_element(1.0);
    cycle!("linearize/generated", |q, u, _ud| k.linearize(q, u, &a));
    let mut lin_ws = krang_dynamics::LinearizationWorkspace::new();
    cycle!("linearize/with", |q, u, _ud| k
        .linearize_with(q, u, &a, &mut lin_ws)
        .1[(25, 3)]);
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
