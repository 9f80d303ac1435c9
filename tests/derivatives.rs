//! The generated derivatives of inverse dynamics (compiled) and the runtime's forward-dynamics
//! derivatives and linearization.
//!
//! * `∂τ/∂q`, `∂τ/∂u` of `inverse_dynamics_derivatives` against Richardson-extrapolated central
//!   differences of the generated `inverse_dynamics`, on 200 random (parameter, state) draws for
//!   Krang (19 speeds, wheeled base), the fixed-wheel tree (17), the two-link model and the
//!   7-DOF URDF arm; the two-link model also against the derivatives of Appendix B's closed forms;
//! * `∂τ/∂u = ∂c/∂u` and, c being quadratic in u, `(∂c/∂u) u = 2c`; with the Coriolis matrix,
//!   `∂c/∂u = C + (∂C/∂u) u`, i.e. `(∂c/∂u) v = C(q, u) v + C(q, v) u`;
//! * Krang's structural zeros: the x and ψ columns of ∂τ/∂q are exactly zero;
//! * forward-dynamics derivatives against central differences of `forward_dynamics`, Krang's
//!   (block Cholesky) and, for every generated robot with derivatives, the runtime trait's;
//!   Krang's and the fixed-wheel tree's into a kept workspace bit for bit equal to their
//!   by-value results;
//! * `linearize_with` (a kept workspace) bit for bit equal to `linearize`, both models;
//! * `linearize`: A and B against central differences of `ẋ = f(x, a)`; the upright
//!   equilibrium of the default Krang has exactly one unstable (pitch) mode.

mod common;

use common::*;
use kanegen_model::{Model, UrdfOptions};
use kanegen_reference::random::random_physical_params;
use krang_dynamics as kd;
use nalgebra::{DMatrix, SMatrix, SVector};

/// The 7-DOF arm generated from `models/singlearm.urdf` with every registry function.
#[allow(dead_code, clippy::all)]
mod singlearm_all {
    include!(concat!(env!("OUT_DIR"), "/singlearm_all.rs"));
}

/// Draws per model.
const DRAWS: usize = 200;

/// Richardson extrapolation of central differences: `(4 D(h/2) − D(h)) / 3` with
/// `D(h) = (f(x + h) − f(x − h)) / 2h`, error O(h⁴).
fn richardson<const N: usize>(f: &dyn Fn(f64) -> SVector<f64, N>, h: f64) -> SVector<f64, N> {
    let d = |h: f64| (f(h) - f(-h)) / (2.0 * h);
    (d(h / 2.0) * 4.0 - d(h)) / 3.0
}

/// `max |a − b| / max(max |b|, 1)` over two matrices.
fn mat_err(a: &[f64], b: &[f64]) -> f64 {
    rel_err(a, b, 1.0)
}

/// Worst relative errors `[∂τ/∂q, ∂τ/∂u, (∂c/∂u) u − 2c, ∂τ/∂u − ∂c/∂u]` of one compiled
/// module over `DRAWS` random draws, and the largest entry seen.
macro_rules! check_id_derivatives {
    ($module:path, $ty:ident, $n:expr, $model:expr, $seed:expr) => {{
        use $module as gm;
        const N: usize = $n;
        let model: &Model = $model;
        let mut r = rng($seed);
        let mut worst = [0.0f64; 4];
        for draw in 0..DRAWS {
            let p = if draw == 0 {
                model.param_values()
            } else {
                random_physical_params(model, &mut r)
            };
            let dy = gm::$ty::new(gm::Params::from_array(p.try_into().unwrap()));
            let (q, u, ud) = random_state(&mut r, N);
            let (q, u, ud) = (sv::<N>(&q), sv::<N>(&u), sv::<N>(&ud));
            let d = dy.inverse_dynamics_derivatives(&q, &u, &ud);
            let (mut fq, mut fu) = (SMatrix::<f64, N, N>::zeros(), SMatrix::<f64, N, N>::zeros());
            for j in 0..N {
                let col = richardson(
                    &|h| {
                        let mut qh = q;
                        qh[j] += h;
                        dy.inverse_dynamics(&qh, &u, &ud)
                    },
                    1e-3,
                );
                fq.set_column(j, &col);
                let col = richardson(
                    &|h| {
                        let mut uh = u;
                        uh[j] += h;
                        dy.inverse_dynamics(&q, &uh, &ud)
                    },
                    1e-3,
                );
                fu.set_column(j, &col);
            }
            let dq = d.fixed_view::<N, N>(0, 0).into_owned();
            let du = d.fixed_view::<N, N>(0, N).into_owned();
            worst[0] = worst[0].max(mat_err(dq.as_slice(), fq.as_slice()));
            worst[1] = worst[1].max(mat_err(du.as_slice(), fu.as_slice()));
            // c is quadratic in u: (∂c/∂u) u = 2c, and ∂τ/∂u = ∂c/∂u (u̇ and g do not depend on u).
            let dc = dy.inverse_dynamics_derivatives(&q, &u, &SVector::zeros());
            let dcu = dc.fixed_view::<N, N>(0, N).into_owned();
            let c = dy.coriolis(&q, &u);
            worst[2] = worst[2].max(rel_err((dcu * u).as_slice(), (c * 2.0).as_slice(), 1.0));
            worst[3] = worst[3].max(mat_err(du.as_slice(), dcu.as_slice()));
        }
        worst
    }};
}

fn assert_worst(name: &str, worst: [f64; 4]) {
    eprintln!(
        "{name}: ∂τ/∂q {:.1e}, ∂τ/∂u {:.1e}, (∂c/∂u)u − 2c {:.1e}, ∂τ/∂u − ∂c/∂u {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst[0] <= 1e-7, "{name}: ∂τ/∂q off by {:e}", worst[0]);
    assert!(worst[1] <= 1e-7, "{name}: ∂τ/∂u off by {:e}", worst[1]);
    assert!(worst[2] <= 1e-12, "{name}: (∂c/∂u)u ≠ 2c by {:e}", worst[2]);
    assert!(worst[3] <= 1e-12, "{name}: ∂τ/∂u ≠ ∂c/∂u by {:e}", worst[3]);
}

#[test]
fn krang_id_derivatives_match_richardson_central_differences() {
    let w = check_id_derivatives!(kd, Krang, 19, &model("krang.toml"), 1201);
    assert_worst("krang", w);
}

#[test]
fn fixed_wheel_id_derivatives_match_richardson_central_differences() {
    let w = check_id_derivatives!(
        kd::fixed_wheels,
        KrangFixedWheels,
        17,
        &model("krang-fixed-wheels.toml"),
        1202
    );
    assert_worst("fixed wheels", w);
}

#[test]
fn two_link_id_derivatives_match_richardson_central_differences() {
    let w = check_id_derivatives!(kd::two_link, TwoLink, 2, &model("two-link.toml"), 1203);
    assert_worst("two-link", w);
}

#[test]
fn urdf_arm_id_derivatives_match_richardson_central_differences() {
    let arm = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .expect("URDF imports");
    let w = check_id_derivatives!(singlearm_all, SingleArm, 7, &arm, 1204);
    assert_worst("singlearm", w);
}

#[test]
fn krang_position_and_heading_columns_are_exactly_zero() {
    let k = kd::Krang::default();
    let mut r = rng(1205);
    for _ in 0..50 {
        let (q, u, ud) = random_state(&mut r, 19);
        let (dq, _) = k.inverse_dynamics_partials(&sv(&q), &sv(&u), &sv(&ud));
        assert!(dq.column(kd::index::X).iter().all(|&x| x == 0.0));
        assert!(dq.column(kd::index::PSI).iter().all(|&x| x == 0.0));
    }
}

#[test]
fn derivatives_into_a_kept_matrix_or_workspace_equal_the_by_value_result_bit_for_bit() {
    // `inverse_dynamics_derivatives_into` writes every entry (structural zeros included) of a
    // matrix that holds anything before; `inverse_dynamics_derivatives_with` reuses one
    // `DerivativesWorkspace` across calls without zeroing it. Both must give the by-value bits,
    // whatever the calls before left behind — other parameters, other states, a state of NaN
    // and huge angles (the sines' and cosines' slow path) in between. Krang (looped form), the
    // fixed-wheel tree and the two-link model (straight-line form).
    let mut r = rng(1211);
    let mut m = SMatrix::<f64, 19, 38>::from_element(f64::NAN);
    let mut ws = kd::DerivativesWorkspace::new();
    assert_eq!(*ws.result(), SMatrix::<f64, 19, 38>::zeros());
    for draw in 0..30 {
        let k = if draw == 0 {
            kd::Krang::default()
        } else {
            random_krang(&mut r)
        };
        let (q, u, ud) = random_state(&mut r, 19);
        let (mut q, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        if draw % 10 == 5 {
            q[7] = f64::NAN;
            q[9] = 1e22;
        }
        let by_value = k.inverse_dynamics_derivatives(&q, &u, &ud);
        k.inverse_dynamics_derivatives_into(&q, &u, &ud, &mut m);
        assert!(same_bits(m.as_slice(), by_value.as_slice()), "draw {draw}");
        m.fill(f64::NAN);
        let kept = k.inverse_dynamics_derivatives_with(&q, &u, &ud, &mut ws);
        assert!(
            same_bits(kept.as_slice(), by_value.as_slice()),
            "draw {draw}"
        );
        assert!(same_bits(ws.result().as_slice(), by_value.as_slice()));
    }
    let fixed = kd::fixed_wheels::KrangFixedWheels::default();
    let mut ws = kd::fixed_wheels::DerivativesWorkspace::default();
    for _ in 0..10 {
        let (q, u, ud) = random_state(&mut r, 17);
        let (q, u, ud) = (sv::<17>(&q), sv::<17>(&u), sv::<17>(&ud));
        let by_value = fixed.inverse_dynamics_derivatives(&q, &u, &ud);
        let kept = fixed.inverse_dynamics_derivatives_with(&q, &u, &ud, &mut ws);
        assert!(same_bits(kept.as_slice(), by_value.as_slice()));
    }
    let two = kd::two_link::TwoLink::default();
    let mut m = SMatrix::<f64, 2, 4>::from_element(f64::NAN);
    let mut ws = kd::two_link::DerivativesWorkspace::new();
    for _ in 0..20 {
        let (q, u, ud) = random_state(&mut r, 2);
        let (q, u, ud) = (sv::<2>(&q), sv::<2>(&u), sv::<2>(&ud));
        let by_value = two.inverse_dynamics_derivatives(&q, &u, &ud);
        two.inverse_dynamics_derivatives_into(&q, &u, &ud, &mut m);
        assert_eq!(m, by_value);
        assert_eq!(
            *two.inverse_dynamics_derivatives_with(&q, &u, &ud, &mut ws),
            by_value
        );
    }
}

#[test]
fn dual_number_baseline_equals_the_generated_derivatives() {
    // kanegen-rbd's recursion in num-dual's Dual64 (2N passes): an independent derivation of
    // the same two matrices, on random parameters and states.
    for (name, seed) in [("krang.toml", 1207), ("krang-fixed-wheels.toml", 1208)] {
        let m = model(name);
        let mut r = rng(seed);
        for draw in 0..20 {
            let p = if draw == 0 {
                m.param_values()
            } else {
                random_physical_params(&m, &mut r)
            };
            let (q, u, ud) = random_state(&mut r, m.dof());
            let (dq, du, gq, gu) = if name == "krang.toml" {
                let dual = kanegen_rbd::DualDerivatives::<19>::new(&m, &p).unwrap();
                let (dq, du) = dual.inverse_dynamics_derivatives(&sv(&q), &sv(&u), &sv(&ud));
                let k = kd::Krang::new(kd::Params::from_array(p.clone().try_into().unwrap()));
                let (gq, gu) = k.inverse_dynamics_partials(&sv(&q), &sv(&u), &sv(&ud));
                let f = |x: SMatrix<f64, 19, 19>| x.as_slice().to_vec();
                (f(dq), f(du), f(gq), f(gu))
            } else {
                use kd::fixed_wheels as fw;
                let dual = kanegen_rbd::DualDerivatives::<17>::new(&m, &p).unwrap();
                let (dq, du) = dual.inverse_dynamics_derivatives(&sv(&q), &sv(&u), &sv(&ud));
                let k = fw::KrangFixedWheels::new(fw::Params::from_array(p.try_into().unwrap()));
                let g = k.inverse_dynamics_derivatives(&sv(&q), &sv(&u), &sv(&ud));
                let f = |x: SMatrix<f64, 17, 17>| x.as_slice().to_vec();
                let (gq, gu) = (
                    g.fixed_columns::<17>(0).into_owned(),
                    g.fixed_columns::<17>(17).into_owned(),
                );
                (f(dq), f(du), f(gq), f(gu))
            };
            let (eq, eu) = (mat_err(&gq, &dq), mat_err(&gu, &du));
            assert!(
                eq <= 1e-11 && eu <= 1e-11,
                "{name} draw {draw}: ∂τ/∂q {eq:e}, ∂τ/∂u {eu:e}"
            );
        }
    }
}

#[test]
fn coriolis_derivative_is_c_plus_dc_du_u() {
    // c(q, u) = C(q, u) u with C linear in u, so (∂c/∂u) v = C(q, u) v + C(q, v) u.
    let k = kd::Krang::default();
    let mut r = rng(1206);
    for _ in 0..DRAWS {
        let (q, u, _) = random_state(&mut r, 19);
        let (_, v, _) = random_state(&mut r, 19);
        let (q, u, v) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&v));
        let (_, dcu) = k.inverse_dynamics_partials(&q, &u, &SVector::zeros());
        let lhs = dcu * v;
        let rhs = k.coriolis_matrix(&q, &u) * v + k.coriolis_matrix(&q, &v) * u;
        let e = rel_err(lhs.as_slice(), rhs.as_slice(), 1.0);
        assert!(e <= 1e-12, "(∂c/∂u) v vs C(u) v + C(v) u: {e:e}");
    }
}

#[test]
fn two_link_id_derivatives_match_appendix_b_closed_forms() {
    use kd::two_link::{Params, TwoLink};
    let model = model("two-link.toml");
    let mut r = rng(1207);
    for _ in 0..1000 {
        let pv = random_physical_params(&model, &mut r);
        let p = Params::from_array(pv.try_into().unwrap());
        let dy = TwoLink::new(p);
        let (q, qd, qdd) = random_state(&mut r, 2);
        let (si, ci) = q[0].sin_cos();
        let (sw, cw) = q[1].sin_cos();
        let (qdi, qdw, qddi, qddw) = (qd[0], qd[1], qdd[0], qdd[1]);
        let g = p.g;
        // Appendix B.1 (see tests/appendix_b.rs): 𝕄3, 𝕄4 depend on q_w only, 𝕄5 = cos(q_imu + q_w),
        // 𝕄6 = sin(q_imu + q_w).
        let m3 = -p.L2 * cw + p.L1 * sw;
        let m4 = p.L1 * cw + p.L2 * sw;
        let m5 = ci * cw - si * sw;
        let m6 = ci * sw + cw * si;
        let mm2 = p.MZ2 * m4 - p.MY2 * m3;
        // ∂𝕄3/∂q_w = 𝕄4, ∂𝕄4/∂q_w = −𝕄3, ∂𝕄5 = −𝕄6, ∂𝕄6 = 𝕄5 (both angles).
        let dmm2 = -p.MZ2 * m3 - p.MY2 * m4;
        // τ1 = A11 q̈i + 𝕄1 q̈w + 𝕄2 (2 q̇i q̇w + q̇w²) + Q1, τ2 = 𝕄1 q̈i + XX2 q̈w − 𝕄2 q̇i² + Q2,
        // ∂A11/∂q_w = 2𝕄2, ∂𝕄1/∂q_w = 𝕄2.
        let dq2 = g * (-p.MZ2 * m6 - p.MY2 * m5);
        let dq1_di = g
            * (-p.MZ1 * si
                - p.MY1 * ci
                - p.MZ2 * m6
                - p.MY2 * m5
                - p.m2 * (-p.L2 * si + p.L1 * ci));
        let vel1 = 2.0 * qdi * qdw + qdw * qdw;
        let dq_exact = nalgebra::Matrix2::new(
            dq1_di,
            2.0 * mm2 * qddi + mm2 * qddw + dmm2 * vel1 + dq2,
            dq2,
            mm2 * qddi - dmm2 * qdi * qdi + dq2,
        );
        let du_exact = nalgebra::Matrix2::new(
            2.0 * mm2 * qdw,
            2.0 * mm2 * (qdi + qdw),
            -2.0 * mm2 * qdi,
            0.0,
        );
        let d = dy.inverse_dynamics_derivatives(
            &nalgebra::Vector2::new(q[0], q[1]),
            &nalgebra::Vector2::new(qdi, qdw),
            &nalgebra::Vector2::new(qddi, qddw),
        );
        let dq = d.fixed_view::<2, 2>(0, 0).into_owned();
        let du = d.fixed_view::<2, 2>(0, 2).into_owned();
        let scale = dq_exact.abs().max().max(du_exact.abs().max()).max(1.0);
        assert!(
            (dq - dq_exact).abs().max() <= 1e-12 * scale,
            "{dq} vs {dq_exact}"
        );
        assert!(
            (du - du_exact).abs().max() <= 1e-12 * scale,
            "{du} vs {du_exact}"
        );
    }
}

/// Krang parameters: the defaults with each body's inertial parameters scaled together.
fn random_krang(r: &mut impl FnMut() -> f64) -> kd::Krang {
    let model = model("krang.toml");
    let p = random_physical_params(&model, r);
    kd::Krang::new(kd::Params::from_array(p.try_into().unwrap()))
}

/// Fixed-wheel tree parameters drawn as [`random_krang`]'s, from its model `fixed`.
fn random_fixed_wheels(
    fixed: &Model,
    r: &mut impl FnMut() -> f64,
) -> kd::fixed_wheels::KrangFixedWheels {
    let p = random_physical_params(fixed, r);
    kd::fixed_wheels::KrangFixedWheels::new(kd::fixed_wheels::Params::from_array(
        p.try_into().unwrap(),
    ))
}

/// Krang with the right hand's body scaled by −10 (a negative mass): M is not positive
/// definite.
fn non_physical_krang() -> kd::Krang {
    let mut values = kd::Params::default().to_array();
    scale_right_hand(&mut values, &kd::Params::NAMES, -10.0);
    kd::Krang::new(kd::Params::from_array(values))
}

/// The fixed-wheel tree with the right hand's body scaled by −10, as [`non_physical_krang`].
fn non_physical_fixed_wheels() -> kd::fixed_wheels::KrangFixedWheels {
    let mut values = kd::fixed_wheels::Params::default().to_array();
    scale_right_hand(&mut values, &kd::fixed_wheels::Params::NAMES, -10.0);
    kd::fixed_wheels::KrangFixedWheels::new(kd::fixed_wheels::Params::from_array(values))
}

/// Scales the inertial parameters of the right hand's body (link `7r`) by `k`.
fn scale_right_hand(values: &mut [f64], names: &[&str], k: f64) {
    for kind in ["m", "MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"] {
        let name = format!("{kind}7r");
        let i = names.iter().position(|n| *n == name).unwrap();
        values[i] *= k;
    }
}

#[test]
fn forward_dynamics_derivatives_match_central_differences() {
    let mut r = rng(1208);
    let mut worst = [0.0f64; 3];
    for draw in 0..100 {
        let k = if draw == 0 {
            kd::Krang::default()
        } else {
            random_krang(&mut r)
        };
        let (q, u, _) = random_state(&mut r, 19);
        let (_, _, t) = random_state(&mut r, 19);
        let (q, u, tau) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&t) * 10.0);
        let e = fd_derivative_errors(
            &k.forward_dynamics_derivatives(&q, &u, &tau),
            |q, u, tau| k.forward_dynamics(q, u, tau),
            (&q, &u, &tau),
        );
        for (w, e) in worst.iter_mut().zip(e) {
            *w = w.max(e);
        }
    }
    eprintln!(
        "FD derivatives: ∂u̇/∂q {:.1e}, ∂u̇/∂u {:.1e}, M⁻¹ {:.1e}",
        worst[0], worst[1], worst[2]
    );
    assert!(worst.iter().all(|&w| w <= 1e-6), "{worst:?}");
}

#[test]
fn forward_dynamics_derivatives_into_a_kept_workspace_equal_the_by_value_result_bit_for_bit() {
    // One `ForwardDynamicsDerivativesWorkspace` across draws of other parameters and states
    // (and of non-physical parameters, which NaN-fill it as they do the by-value result): each
    // call overwrites every entry it returns, and solves each block's columns alone, with the
    // bits the by-value form's one solve of all 57 columns gives them.
    let mut r = rng(1212);
    let mut ws = kd::ForwardDynamicsDerivativesWorkspace::new();
    assert!(ws.result().minv.iter().all(|x| x.is_nan()));
    for draw in 0..30 {
        let k = match draw {
            0 => kd::Krang::default(),
            13 => non_physical_krang(),
            _ => random_krang(&mut r),
        };
        let (q, u, _) = random_state(&mut r, 19);
        let (_, _, t) = random_state(&mut r, 19);
        let (q, u, tau) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&t) * 10.0);
        let by_value = k.forward_dynamics_derivatives(&q, &u, &tau);
        let kept = k.forward_dynamics_derivatives_with(&q, &u, &tau, &mut ws);
        assert!(
            same_bits(&fd_bits(kept), &fd_bits(&by_value)),
            "draw {draw}"
        );
        assert_eq!(draw == 13, by_value.minv.iter().all(|x| x.is_nan()));
        assert!(same_bits(&fd_bits(ws.result()), &fd_bits(&by_value)));
    }
}

/// `u̇`, `∂u̇/∂q`, `∂u̇/∂u` and `M⁻¹` as one run of values, to compare their bits.
fn fd_bits<const N: usize>(fd: &kd::ForwardDynamicsDerivatives<N>) -> Vec<f64> {
    [
        fd.ud.as_slice(),
        fd.dud_dq.as_slice(),
        fd.dud_du.as_slice(),
        fd.minv.as_slice(),
    ]
    .concat()
}

/// A kept workspace's `(A, B)` has the bits of the by-value linearization's.
fn assert_same_linearization(kept: (&[f64], &[f64]), by_value: (&[f64], &[f64]), draw: usize) {
    assert!(same_bits(kept.0, by_value.0), "A, draw {draw}");
    assert!(same_bits(kept.1, by_value.1), "B, draw {draw}");
}

#[test]
fn fixed_wheel_derivatives_and_linearization_into_kept_workspaces_equal_the_by_value_results() {
    // The fixed-wheel tree's `forward_dynamics_derivatives_with` and `linearize_with`, one
    // workspace each across draws of other parameters and states, and of non-physical
    // parameters (NaN, as the by-value `linearize`; `try_forward_dynamics_derivatives` errs).
    let model = model("krang-fixed-wheels.toml");
    let mut r = rng(1214);
    let mut fd_ws = kd::fixed_wheels::ForwardDynamicsDerivativesWorkspace::new();
    let mut lin_ws = kd::fixed_wheels::LinearizationWorkspace::new();
    assert!(fd_ws.result().minv.iter().all(|x| x.is_nan()));
    for draw in 0..24 {
        let k = if draw % 8 == 5 {
            non_physical_fixed_wheels()
        } else {
            random_fixed_wheels(&model, &mut r)
        };
        let (q, u, t) = random_state(&mut r, 17);
        let (q, u, tau) = (sv::<17>(&q), sv::<17>(&u), sv::<17>(&t) * 10.0);
        let kept = fd_bits(k.forward_dynamics_derivatives_with(&q, &u, &tau, &mut fd_ws));
        match k.try_forward_dynamics_derivatives(&q, &u, &tau) {
            Ok(fd) => assert!(same_bits(&kept, &fd_bits(&fd)), "draw {draw}"),
            Err(_) => {
                assert_eq!(draw % 8, 5);
                assert!(kept.iter().all(|x| x.is_nan()), "draw {draw}");
            }
        }
        let (a_mat, b_mat) = k.linearize(&q, &u, &tau);
        let (a_kept, b_kept) = k.linearize_with(&q, &u, &tau, &mut lin_ws);
        assert_same_linearization(
            (a_kept.as_slice(), b_kept.as_slice()),
            (a_mat.as_slice(), b_mat.as_slice()),
            draw,
        );
        assert_eq!(draw % 8 == 5, a_mat.iter().all(|x| x.is_nan()));
    }
}

#[test]
fn fixed_wheel_forward_dynamics_derivatives_match_central_differences() {
    let model = model("krang-fixed-wheels.toml");
    let mut r = rng(1209);
    for _ in 0..50 {
        let k = random_fixed_wheels(&model, &mut r);
        let (q, u, t) = random_state(&mut r, 17);
        let (q, u, tau) = (sv::<17>(&q), sv::<17>(&u), sv::<17>(&t));
        let (a, b) = k.linearize(&q, &u, &tau);
        let f = |x: &SVector<f64, 34>, tau: &SVector<f64, 17>| {
            let q = x.fixed_rows::<17>(0).into_owned();
            let u = x.fixed_rows::<17>(17).into_owned();
            let mut out = SVector::<f64, 34>::zeros();
            out.fixed_rows_mut::<17>(0).copy_from(&u);
            out.fixed_rows_mut::<17>(17)
                .copy_from(&k.forward_dynamics(&q, &u, tau));
            out
        };
        let mut x = SVector::<f64, 34>::zeros();
        x.fixed_rows_mut::<17>(0).copy_from(&q);
        x.fixed_rows_mut::<17>(17).copy_from(&u);
        let mut fa = SMatrix::<f64, 34, 34>::zeros();
        for j in 0..34 {
            fa.set_column(
                j,
                &richardson(
                    &|h| {
                        let mut xh = x;
                        xh[j] += h;
                        f(&xh, &tau)
                    },
                    1e-3,
                ),
            );
        }
        let mut fb = SMatrix::<f64, 34, 17>::zeros();
        for j in 0..17 {
            fb.set_column(
                j,
                &richardson(
                    &|h| {
                        let mut th = tau;
                        th[j] += h;
                        f(&x, &th)
                    },
                    1e-3,
                ),
            );
        }
        assert!(mat_err(a.as_slice(), fa.as_slice()) <= 1e-6);
        assert!(mat_err(b.as_slice(), fb.as_slice()) <= 1e-6);
    }
}

/// The forward-dynamics derivatives through a block Cholesky factor (`block`) equal those
/// through the dense one (`dense`) to 10⁻¹¹ relative.
fn block_equals_dense<const N: usize>(
    block: &kanegen_runtime::ForwardDynamicsDerivatives<f64, N>,
    dense: &kanegen_runtime::ForwardDynamicsDerivatives<f64, N>,
) {
    for (b, d) in [
        (block.dud_dq, dense.dud_dq),
        (block.dud_du, dense.dud_du),
        (block.minv, dense.minv),
    ] {
        assert!(mat_err(d.as_slice(), b.as_slice()) <= 1e-11, "{d} vs {b}");
    }
}

/// Relative errors `[∂u̇/∂q, ∂u̇/∂u, M⁻¹]` of the forward-dynamics derivatives `d` at
/// `(q, u, τ)` against Richardson central differences of the forward dynamics `fd`, after
/// checking that `d.ud` is `fd` at that state, bit for bit.
fn fd_derivative_errors<const N: usize>(
    d: &kanegen_runtime::ForwardDynamicsDerivatives<f64, N>,
    fd: impl Fn(&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>) -> SVector<f64, N>,
    (q, u, tau): (&SVector<f64, N>, &SVector<f64, N>, &SVector<f64, N>),
) -> [f64; 3] {
    assert_eq!(d.ud, fd(q, u, tau));
    let shift = |v: &SVector<f64, N>, j: usize, h: f64| {
        let mut w = *v;
        w[j] += h;
        w
    };
    let (mut fq, mut fu, mut ft) = (
        SMatrix::<f64, N, N>::zeros(),
        SMatrix::<f64, N, N>::zeros(),
        SMatrix::<f64, N, N>::zeros(),
    );
    for j in 0..N {
        fq.set_column(j, &richardson(&|h| fd(&shift(q, j, h), u, tau), 1e-3));
        fu.set_column(j, &richardson(&|h| fd(q, &shift(u, j, h), tau), 1e-3));
        ft.set_column(j, &richardson(&|h| fd(q, u, &shift(tau, j, h)), 1e-3));
    }
    [
        mat_err(d.dud_dq.as_slice(), fq.as_slice()),
        mat_err(d.dud_du.as_slice(), fu.as_slice()),
        mat_err(d.minv.as_slice(), ft.as_slice()),
    ]
}

/// The trait's forward-dynamics derivatives (`InverseDynamicsDerivatives`, which every module
/// generated with `inverse_dynamics_derivatives` implements) against central differences of
/// the trait's `forward_dynamics` ([`fd_derivative_errors`]), on `draws` random states: the
/// worst errors, written once for any robot.
fn trait_fd_derivatives_errors<R, const N: usize>(
    robot: &R,
    r: &mut impl FnMut() -> f64,
    draws: usize,
) -> [f64; 3]
where
    R: kanegen_runtime::InverseDynamicsDerivatives<N, Scalar = f64>,
{
    let mut worst = [0.0f64; 3];
    for _ in 0..draws {
        let (q, u, t) = random_state(r, N);
        let (q, u, tau) = (sv::<N>(&q), sv::<N>(&u), sv::<N>(&t) * 10.0);
        let d = robot
            .forward_dynamics_derivatives(&q, &u, &tau)
            .expect("physical parameters");
        let e = fd_derivative_errors(
            &d,
            |q, u, tau| kanegen_runtime::RobotDynamics::forward_dynamics(robot, q, u, tau).unwrap(),
            (&q, &u, &tau),
        );
        for (w, e) in worst.iter_mut().zip(e) {
            *w = w.max(e);
        }
    }
    worst
}

#[test]
fn every_generated_robot_has_forward_dynamics_derivatives_through_the_trait() {
    let mut r = rng(1210);
    let arm = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .expect("URDF imports");
    let fixed = model("krang-fixed-wheels.toml");
    for draw in 0..10 {
        let p = random_physical_params(&arm, &mut r);
        let a =
            singlearm_all::SingleArm::new(singlearm_all::Params::from_array(p.try_into().unwrap()));
        let f = random_fixed_wheels(&fixed, &mut r);
        let k = if draw == 0 {
            kd::Krang::default()
        } else {
            random_krang(&mut r)
        };
        for (name, worst) in [
            ("urdf arm", trait_fd_derivatives_errors(&a, &mut r, 5)),
            ("fixed wheels", trait_fd_derivatives_errors(&f, &mut r, 2)),
            (
                "two-link",
                trait_fd_derivatives_errors(&kd::two_link::TwoLink::default(), &mut r, 5),
            ),
            ("krang", trait_fd_derivatives_errors(&k, &mut r, 1)),
        ] {
            assert!(worst.iter().all(|&w| w <= 1e-6), "{name}: {worst:?}");
        }
        // Krang's and the fixed-wheel tree's inherent derivatives (block Cholesky) equal the
        // trait's (dense).
        let (q, u, t) = random_state(&mut r, 19);
        let (q, u, tau) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&t) * 10.0);
        block_equals_dense(
            &k.forward_dynamics_derivatives(&q, &u, &tau),
            &kanegen_runtime::InverseDynamicsDerivatives::forward_dynamics_derivatives(
                &k, &q, &u, &tau,
            )
            .unwrap(),
        );
        let (q, u, t) = random_state(&mut r, 17);
        let (q, u, tau) = (sv::<17>(&q), sv::<17>(&u), sv::<17>(&t) * 10.0);
        block_equals_dense(
            &f.try_forward_dynamics_derivatives(&q, &u, &tau).unwrap(),
            &kanegen_runtime::InverseDynamicsDerivatives::forward_dynamics_derivatives(
                &f, &q, &u, &tau,
            )
            .unwrap(),
        );
    }
    // Non-physical parameters: None, not NaNs.
    let bad = kd::Params {
        m4l: -1e3,
        ..kd::Params::default()
    };
    let z = SVector::<f64, 19>::zeros();
    assert!(
        kanegen_runtime::InverseDynamicsDerivatives::forward_dynamics_derivatives(
            &kd::Krang::new(bad),
            &z,
            &z,
            &z
        )
        .is_none()
    );
}

/// `ẋ = f(x, a)` of Krang for the state `x = [q; u]` and the actuator torques `a`.
fn krang_f(k: &kd::Krang, x: &SVector<f64, 38>, a: &SVector<f64, 18>) -> SVector<f64, 38> {
    let q = x.fixed_rows::<19>(0).into_owned();
    let u = x.fixed_rows::<19>(19).into_owned();
    let mut out = SVector::<f64, 38>::zeros();
    out.fixed_rows_mut::<19>(0).copy_from(&u);
    out.fixed_rows_mut::<19>(19)
        .copy_from(&k.forward_dynamics(&q, &u, &k.generalized_forces(a)));
    out
}

/// A draw of the linearization tests: the default parameters first, then random physical
/// ones, with a random state and random actuator torques.
fn linearization_draw(
    r: &mut impl FnMut() -> f64,
    draw: usize,
) -> (
    kd::Krang,
    SVector<f64, 19>,
    SVector<f64, 19>,
    SVector<f64, 18>,
) {
    let k = if draw == 0 {
        kd::Krang::default()
    } else {
        random_krang(r)
    };
    let (q, u, _) = random_state(r, 19);
    let a = SVector::from_fn(|_, _| 20.0 * (r() - 0.5));
    (k, sv(&q), sv(&u), a)
}

#[test]
fn krang_linearization_matches_central_differences() {
    let mut r = rng(1210);
    for draw in 0..50 {
        let (k, q, u, a) = linearization_draw(&mut r, draw);
        let mut x = SVector::<f64, 38>::zeros();
        x.fixed_rows_mut::<19>(0).copy_from(&q);
        x.fixed_rows_mut::<19>(19).copy_from(&u);
        let (am, bm) = k.linearize(&q, &u, &a);
        let mut fa = SMatrix::<f64, 38, 38>::zeros();
        for j in 0..38 {
            fa.set_column(
                j,
                &richardson(
                    &|h| {
                        let mut xh = x;
                        xh[j] += h;
                        krang_f(&k, &xh, &a)
                    },
                    1e-3,
                ),
            );
        }
        let mut fb = SMatrix::<f64, 38, 18>::zeros();
        for j in 0..18 {
            fb.set_column(
                j,
                &richardson(
                    &|h| {
                        let mut ah = a;
                        ah[j] += h;
                        krang_f(&k, &x, &ah)
                    },
                    1e-3,
                ),
            );
        }
        let (ea, eb) = (
            mat_err(am.as_slice(), fa.as_slice()),
            mat_err(bm.as_slice(), fb.as_slice()),
        );
        assert!(ea <= 1e-6 && eb <= 1e-6, "A {ea:e}, B {eb:e}");
    }
}

/// `linearize` forms `B`'s lower block `M⁻¹ B_act` from the columns of `M⁻¹` (a joint's column
/// or a wheel's sum of three) instead of solving with `B_act`: equal to the block factor's solve
/// of `B_act` to rounding; `B`'s upper block (`∂q̇/∂a`) stays exactly zero.
#[test]
fn linearization_into_a_kept_workspace_equals_the_by_value_result_bit_for_bit() {
    // One `LinearizationWorkspace` across draws of other parameters, states and inputs, and
    // of non-physical parameters (all NaN, as by value; the constant blocks come back after).
    let mut r = rng(1213);
    let mut ws = kd::LinearizationWorkspace::new();
    for draw in 0..24 {
        let k = if draw % 8 == 3 {
            non_physical_krang()
        } else {
            random_krang(&mut r)
        };
        let (q, u, _) = random_state(&mut r, 19);
        let (q, u) = (sv::<19>(&q), sv::<19>(&u));
        let a = SVector::<f64, 18>::from_fn(|_, _| 20.0 * r() - 10.0);
        let (a_mat, b_mat) = k.linearize(&q, &u, &a);
        let (a_kept, b_kept) = k.linearize_with(&q, &u, &a, &mut ws);
        assert_same_linearization(
            (a_kept.as_slice(), b_kept.as_slice()),
            (a_mat.as_slice(), b_mat.as_slice()),
            draw,
        );
        assert_eq!(draw % 8 == 3, a_mat.iter().all(|x| x.is_nan()));
    }
}

#[test]
fn krang_linearization_input_matrix_equals_the_factors_solve_of_the_actuator_matrix() {
    let mut r = rng(1211);
    for draw in 0..100 {
        let (k, q, u, a) = linearization_draw(&mut r, draw);
        let (_, bm) = k.linearize(&q, &u, &a);
        let mut solved = k.actuator_matrix();
        k.mass_matrix_cholesky(&q)
            .unwrap()
            .solve_columns_mut(&mut solved);
        let lower = bm.fixed_rows::<19>(19).into_owned();
        let e = mat_err(lower.as_slice(), solved.as_slice());
        assert!(e <= 1e-12, "draw {draw}: M⁻¹ B_act {e:e}");
        assert!(bm.fixed_rows::<19>(0).iter().all(|&x| x == 0.0));
    }
}

/// The upright pose with the joints held: `q` with the pitch that puts the centre of mass above
/// the axle, and the joint torques that cancel gravity there.
fn upright(k: &kd::Krang) -> (SVector<f64, 19>, SVector<f64, 18>) {
    let mut q = SVector::<f64, 19>::zeros();
    q[kd::index::Q_W] = 0.4;
    q[kd::index::Q_TORSO] = -0.2;
    q[kd::index::Q_IMU] = k.upright_pitch(&q);
    let g = k.gravity(&q);
    let mut a = SVector::<f64, 18>::zeros();
    for j in kd::actuator::WAIST..18 {
        a[j] = g[j + 1];
    }
    (q, a)
}

#[test]
fn upright_krang_with_locked_joints_has_exactly_one_unstable_mode() {
    // With every joint held by its servo (locked), Krang at the upright pose is a wheeled
    // inverted pendulum: the base speeds b = [ẋ, ψ̇, q̇_imu] obey M_bb u̇_b = τ_b − (c + g)_b, whose
    // linearization at rest is A = [[0, I], [−M_bb⁻¹ ∂τ_b/∂q_b, −M_bb⁻¹ ∂τ_b/∂u_b]] from the
    // generated derivatives. Position and heading are neutral (zero eigenvalues); the pitch
    // has one real unstable and one stable mode.
    let k = kd::Krang::default();
    let (q, a) = upright(&k);
    // An equilibrium: no acceleration at rest.
    let ud = k.forward_dynamics(&q, &SVector::zeros(), &k.generalized_forces(&a));
    assert!(ud.abs().max() < 1e-9, "{ud}");
    let (dq, du) = k.inverse_dynamics_partials(&q, &SVector::zeros(), &SVector::zeros());
    let m = k.mass_matrix(&q);
    let b = [kd::index::X, kd::index::PSI, kd::index::Q_IMU];
    let pick = |x: &SMatrix<f64, 19, 19>| nalgebra::Matrix3::from_fn(|i, j| x[(b[i], b[j])]);
    let mbb_inv = pick(&m).try_inverse().unwrap();
    let mut am = nalgebra::Matrix6::<f64>::zeros();
    am.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&nalgebra::Matrix3::identity());
    am.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-mbb_inv * pick(&dq)));
    am.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(-mbb_inv * pick(&du)));
    let eig = am.complex_eigenvalues();
    let unstable: Vec<_> = eig.iter().filter(|l| l.re > 1e-9).collect();
    eprintln!("locked-joint modes: {eig}");
    assert_eq!(unstable.len(), 1, "{eig}");
    assert!(unstable[0].im == 0.0 && unstable[0].re > 1.0);
    // With the joints free (constant torques, no servo) the arm links fall too: the full
    // 38-state linearization has more unstable modes (printed for the record).
    let (full, _) = k.linearize(&q, &SVector::zeros(), &a);
    let eig = DMatrix::from_column_slice(38, 38, full.as_slice()).complex_eigenvalues();
    let n = eig.iter().filter(|l| l.re > 1e-6).count();
    eprintln!("free joints: {n} unstable modes");
    assert!(n >= 1);
}
