//! The two-link model of the fixed-wheels report (Zafar 2014), Appendix B (bodies 1 and 2, frame 0 fixed) against the
//! printed closed forms.
//!
//! Appendix B prints two versions of `A`: B.1 (Lagrange) with `XX1`, `XX2`, and B.2 (Kane) with
//! `XX_i` replaced by `XX_i + (MY_i² + MZ_i²)/m_i`. With Khalil's parameters (inertia about the
//! frame origin, which is what the model IR holds) the Lagrange `A` is the right one: the
//! inertia of body `i` about its joint axis `x_i` (through the frame origin) *is* `XX_i`. The
//! B.2 substitution is the parallel-axis shift from the centre of mass to the origin, i.e. the
//! Kane derivation there read `XX_i` as the moment about the centre of mass; applied to
//! origin-referred parameters it counts `(MY² + MZ²)/m` twice. The second test checks that the
//! reference differs from B.2 by exactly that amount. `C` and `Q` are the same in B.1 and B.2.
//! `𝕄3 … 𝕄6` are printed in B.1 (B.2 prints 𝕄5 twice and omits 𝕄6; B.1's 𝕄5 has a stray
//! parenthesis): `𝕄5 = cos(q_imu + q_w)`, `𝕄6 = sin(q_imu + q_w)`.
//!
//! The equation is `τ = A q̈ + C q̇ + Q`: `Q` is the gradient of the potential energy
//! (`Q1 = g(MZ1 cos q_imu − MY1 sin q_imu) + …`), the reference's `g(q)`.

mod common;

use kanegen_reference::Reference;
use kanegen_reference::random::{random_physical_params, uniform_vec};
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

/// The parameters of Appendix B, by name.
struct Params {
    g: f64,
    l1: f64,
    l2: f64,
    m1: f64,
    my1: f64,
    mz1: f64,
    xx1: f64,
    m2: f64,
    my2: f64,
    mz2: f64,
    xx2: f64,
}

impl Params {
    fn from(model: &kanegen_model::Model, p: &[f64]) -> Self {
        let v = |n: &str| p[model.param_index(n).unwrap_or_else(|| panic!("no {n}"))];
        Self {
            g: v("g"),
            l1: v("L1"),
            l2: v("L2"),
            m1: v("m1"),
            my1: v("MY1"),
            mz1: v("MZ1"),
            xx1: v("XX1"),
            m2: v("m2"),
            my2: v("MY2"),
            mz2: v("MZ2"),
            xx2: v("XX2"),
        }
    }
}

/// The auxiliary quantities 𝕄1 … 𝕄6 of Appendix B.1.
fn aux(p: &Params, q_imu: f64, q_w: f64) -> [f64; 6] {
    let m3 = -p.l2 * q_w.cos() + p.l1 * q_w.sin();
    let m4 = p.l1 * q_w.cos() + p.l2 * q_w.sin();
    let m1 = p.xx2 + p.my2 * m4 + p.mz2 * m3;
    let m2 = p.mz2 * m4 - p.my2 * m3;
    let m5 = q_imu.cos() * q_w.cos() - q_imu.sin() * q_w.sin();
    let m6 = q_imu.cos() * q_w.sin() + q_w.cos() * q_imu.sin();
    [m1, m2, m3, m4, m5, m6]
}

/// Appendix B's `A` with the given `XX1`, `XX2` (B.1: as they are; B.2: shifted).
fn a_matrix(p: &Params, xx1: f64, xx2: f64, q: &[f64]) -> Matrix2<f64> {
    let [_, _, m3, m4, _, _] = aux(p, q[0], q[1]);
    let m1 = xx2 + p.my2 * m4 + p.mz2 * m3;
    Matrix2::new(
        xx1 + xx2 + 2.0 * p.my2 * m4 + 2.0 * p.mz2 * m3 + p.m2 * m4 * m4 + p.m2 * m3 * m3,
        m1,
        m1,
        xx2,
    )
}

/// Appendix B's `C` (eq. 13).
fn c_matrix(p: &Params, q: &[f64], qd: &[f64]) -> Matrix2<f64> {
    let [_, m2, ..] = aux(p, q[0], q[1]);
    Matrix2::new(qd[1] * m2, (qd[1] + qd[0]) * m2, -qd[0] * m2, 0.0)
}

/// Appendix B's `Q` (eq. 14).
fn q_vector(p: &Params, q: &[f64]) -> Vector2<f64> {
    let [.., m5, m6] = aux(p, q[0], q[1]);
    let (s, c) = q[0].sin_cos();
    let q2 = p.mz2 * p.g * m5 - p.my2 * p.g * m6;
    Vector2::new(
        p.mz1 * p.g * c - p.my1 * p.g * s + q2 - p.g * p.m2 * (p.l2 * c + p.l1 * s),
        q2,
    )
}

fn to_dmat(m: Matrix2<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(2, 2, |i, j| m[(i, j)])
}

fn to_dvec(v: Vector2<f64>) -> DVector<f64> {
    DVector::from_column_slice(v.as_slice())
}

#[test]
fn two_link_matches_appendix_b_closed_forms() {
    let model = common::load_model("two-link");
    let mut rnd = common::uniform(0xB0B);
    for case in 0..200 {
        let params = random_physical_params(&model, &mut rnd);
        let p = Params::from(&model, &params);
        let r = Reference::with_params(&model, &params);
        let q = uniform_vec(&mut rnd, 2, -std::f64::consts::PI, std::f64::consts::PI);
        let qd = uniform_vec(&mut rnd, 2, -3.0, 3.0);

        let m = r.mass_matrix(&q);
        let a = to_dmat(a_matrix(&p, p.xx1, p.xx2, &q));
        let e = common::rel_err_mat(&m, &a, 1e-300);
        assert!(
            e < 1e-12,
            "case {case}: M vs Appendix B.1 A: rel err {e:e}\n{m}\n{a}"
        );

        let c = r.coriolis(&q, &qd);
        let cq = to_dvec(c_matrix(&p, &q, &qd) * Vector2::new(qd[0], qd[1]));
        // c = τ(q, q̇, 0) − τ(q, 0, 0) is a difference: its rounding error scales with the
        // larger of the two, not with c (which is near zero where 𝕄2 is).
        let scale = r.gravity(&q).amax().max((&c + r.gravity(&q)).amax());
        let e = common::rel_err_vec(&c, &cq, scale);
        assert!(e < 1e-12, "case {case}: c vs C q̇: rel err {e:e}\n{c}\n{cq}");

        let g = r.gravity(&q);
        let qv = to_dvec(q_vector(&p, &q));
        let e = common::rel_err_vec(&g, &qv, 1e-300);
        assert!(e < 1e-12, "case {case}: g vs Q: rel err {e:e}\n{g}\n{qv}");

        // The full equation τ = A q̈ + C q̇ + Q.
        let qdd = uniform_vec(&mut rnd, 2, -3.0, 3.0);
        let tau = r.inverse_dynamics(&q, &qd, &qdd);
        let expected = &a * DVector::from_column_slice(&qdd) + cq + qv;
        let e = common::rel_err_vec(&tau, &expected, 1e-300);
        assert!(e < 1e-12, "case {case}: τ: rel err {e:e}");
    }
}

#[test]
fn appendix_b_kane_a_double_counts_the_parallel_axis_shift() {
    let model = common::load_model("two-link");
    let mut rnd = common::uniform(0xB2);
    for case in 0..100 {
        let params = random_physical_params(&model, &mut rnd);
        let p = Params::from(&model, &params);
        let r = Reference::with_params(&model, &params);
        let q = uniform_vec(&mut rnd, 2, -3.0, 3.0);
        let shift1 = (p.my1 * p.my1 + p.mz1 * p.mz1) / p.m1;
        let shift2 = (p.my2 * p.my2 + p.mz2 * p.mz2) / p.m2;
        let kane = a_matrix(&p, p.xx1 + shift1, p.xx2 + shift2, &q);
        let m = r.mass_matrix(&q);
        let diff = to_dmat(kane) - &m;
        let expected = to_dmat(Matrix2::new(shift1 + shift2, shift2, shift2, shift2));
        let e = common::rel_err_mat(&diff, &expected, 1e-300);
        assert!(
            e < 1e-9,
            "case {case}: B.2 A − M = {diff}, expected {expected}"
        );
        assert!(
            diff.amax() > 1e-6 * m.amax(),
            "case {case}: B.2 should differ"
        );
    }
}
