//! The generated two-link code (the fixed-wheels report (Zafar 2014), Appendix B) reproduces the printed closed forms
//! A (B.1, Lagrange), C and Q exactly: τ = A q̈ + C q̇ + Q.
//!
//! B.2 (Kane) prints A with XXᵢ + (MYᵢ² + MZᵢ²)/mᵢ in place of XXᵢ, which double-counts the
//! parallel-axis shift for inertias about the frame origin; B.1 is the correct form (see the
//! reference crate's `appendix_b_kane_a_double_counts_the_parallel_axis_shift`). The appendix
//! prints 𝕄5 twice and omits 𝕄6; from B.1, 𝕄5 = cos(q_imu + q_w), 𝕄6 = sin(q_imu + q_w).

mod common;

use common::*;
use kanegen_reference::random::random_physical_params;
use krang_dynamics::two_link::{Params, TwoLink};
use nalgebra::{Matrix2, Vector2};

#[test]
fn generated_two_link_reproduces_appendix_b_printed_a_c_q() {
    let model = model("two-link.toml");
    let mut r = rng(21);
    for _ in 0..1000 {
        let pv = random_physical_params(&model, &mut r);
        let p = Params::from_array(pv.try_into().unwrap());
        let dynamics = TwoLink::new(p);
        let (q, qd, _) = random_state(&mut r, 2);
        let (si, ci) = q[0].sin_cos();
        let (sw, cw) = q[1].sin_cos();
        let (qdi, qdw) = (qd[0], qd[1]);
        let m3 = -p.L2 * cw + p.L1 * sw;
        let m4 = p.L1 * cw + p.L2 * sw;
        let m5 = ci * cw - si * sw;
        let m6 = ci * sw + cw * si;
        let m1 = p.XX2 + p.MY2 * m4 + p.MZ2 * m3;
        let m2 = p.MZ2 * m4 - p.MY2 * m3;
        let a = Matrix2::new(
            p.XX1 + p.XX2 + 2.0 * p.MY2 * m4 + 2.0 * p.MZ2 * m3 + p.m2 * m4 * m4 + p.m2 * m3 * m3,
            m1,
            m1,
            p.XX2,
        );
        let c = Matrix2::new(qdw * m2, (qdw + qdi) * m2, -qdi * m2, 0.0);
        let g = p.g;
        let qq = Vector2::new(
            p.MZ1 * g * ci - p.MY1 * g * si + p.MZ2 * g * m5
                - p.MY2 * g * m6
                - g * p.m2 * (p.L2 * ci + p.L1 * si),
            p.MZ2 * g * m5 - p.MY2 * g * m6,
        );
        let (qv, qdv) = (Vector2::new(q[0], q[1]), Vector2::new(qdi, qdw));
        let scale = a.abs().max().max(1.0);
        assert!((dynamics.mass_matrix(&qv) - a).abs().max() <= 1e-12 * scale);
        let cv = c * qdv;
        let cscale = (a.abs().max() * qdv.norm_squared()).max(1.0);
        assert!((dynamics.coriolis(&qv, &qdv) - cv).abs().max() <= 1e-12 * cscale);
        assert!((dynamics.gravity(&qv) - qq).abs().max() <= 1e-12 * qq.abs().max().max(1.0));
    }
}
