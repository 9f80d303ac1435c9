//! The two-link model of the fixed-wheels report (Zafar 2014), Appendix B (bodies 1 and 2 on a fixed frame 0) against the
//! printed closed forms B.1 (with Khalil's origin-referred `XX_i`): `τ = A q̈ + C q̇ + Q`, at 250
//! random states with random physical parameters.

mod common;

use std::f64::consts::PI;

use common::{Rng, load_model, random_params, rel_err};
use kanegen_rbd::Rbd;
use nalgebra::{Matrix2, Vector2};

#[test]
fn two_link_matches_appendix_b_closed_forms() {
    let model = load_model("two-link");
    let mut rng = Rng::new(0xB0B);
    for case in 0..250 {
        let p = random_params(&model, &mut rng);
        let v = |n: &str| p[model.param_index(n).unwrap_or_else(|| panic!("no {n}"))];
        let (g, l1, l2) = (v("g"), v("L1"), v("L2"));
        let (my1, mz1, xx1) = (v("MY1"), v("MZ1"), v("XX1"));
        let (m2, my2, mz2, xx2) = (v("m2"), v("MY2"), v("MZ2"), v("XX2"));
        let rbd = Rbd::<2>::new(&model, &p).expect("builds");
        let q = rng.vec::<2>(-PI, PI);
        let qd = rng.vec::<2>(-3.0, 3.0);
        let qdd = rng.vec::<2>(-3.0, 3.0);
        let (qi, qw) = (q[0], q[1]);
        // 𝕄1 … 𝕄6 of Appendix B.1.
        let mm3 = -l2 * qw.cos() + l1 * qw.sin();
        let mm4 = l1 * qw.cos() + l2 * qw.sin();
        let mm1 = xx2 + my2 * mm4 + mz2 * mm3;
        let mm2 = mz2 * mm4 - my2 * mm3;
        let mm5 = (qi + qw).cos();
        let mm6 = (qi + qw).sin();
        let a = Matrix2::new(
            xx1 + xx2 + 2.0 * my2 * mm4 + 2.0 * mz2 * mm3 + m2 * (mm4 * mm4 + mm3 * mm3),
            mm1,
            mm1,
            xx2,
        );
        let c = Matrix2::new(qd[1] * mm2, (qd[0] + qd[1]) * mm2, -qd[0] * mm2, 0.0);
        let q2 = mz2 * g * mm5 - my2 * g * mm6;
        let qv = Vector2::new(
            mz1 * g * qi.cos() - my1 * g * qi.sin() + q2 - g * m2 * (l2 * qi.cos() + l1 * qi.sin()),
            q2,
        );
        let m = rbd.mass_matrix(&q);
        let e = rel_err(m.as_slice(), a.as_slice(), 1e-300);
        assert!(e < 1e-13, "case {case}: M vs A: {e:e}\n{m}\n{a}");
        let gq = rbd.gravity(&q);
        let e = rel_err(gq.as_slice(), qv.as_slice(), 1e-300);
        assert!(e < 1e-13, "case {case}: g vs Q: {e:e}");
        let cq = c * qd;
        let e = rel_err(
            rbd.coriolis(&q, &qd).as_slice(),
            cq.as_slice(),
            a.amax() * qd.amax().powi(2),
        );
        assert!(e < 1e-13, "case {case}: c vs C q̇: {e:e}");
        let tau = a * qdd + cq + qv;
        let e = rel_err(
            rbd.inverse_dynamics(&q, &qd, &qdd).as_slice(),
            tau.as_slice(),
            1e-300,
        );
        assert!(e < 1e-13, "case {case}: τ: {e:e}");
    }
}
