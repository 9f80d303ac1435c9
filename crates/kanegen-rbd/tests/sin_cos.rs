//! The fast `f64` sine/cosine used for the joint angles (the routine of generated code,
//! `kanegen_runtime::trig`) against the standard library: within 2⁻⁵² absolute everywhere tested
//! (joint-sized angles, points next to multiples of π/2, huge arguments reduced by Payne–Hanek,
//! non-finite values), and every lane of the batch bit for bit a one-lane batch (the batch of
//! generated code: the scalar routine's bits in the baseline copy, its kernels fused in the
//! x86-64-v3 copy, within 2 ulp of the scalar routine).

mod common;

use kanegen_rbd::{Scalar, sin_cos_f64};

fn check(x: f64) {
    let (s, c) = sin_cos_f64(x);
    let (s0, c0) = x.sin_cos();
    if !x.is_finite() {
        assert!(s.is_nan() && c.is_nan(), "x = {x}: ({s}, {c})");
        return;
    }
    let tol = f64::EPSILON;
    assert!((s - s0).abs() <= tol, "sin({x:e}) = {s:e}, std {s0:e}");
    assert!((c - c0).abs() <= tol, "cos({x:e}) = {c:e}, std {c0:e}");
}

#[test]
fn sin_cos_f64_matches_std() {
    let mut rng = common::Rng::new(99);
    for _ in 0..1_000_000 {
        check(rng.range(-20.0, 20.0));
    }
    for _ in 0..100_000 {
        check(rng.range(-1e6, 1e6));
    }
    for k in -2000..=2000 {
        let x = k as f64 * std::f64::consts::FRAC_PI_2;
        for d in [-1e-9, -1e-15, 0.0, 1e-15, 1e-9] {
            check(x + d);
            check(f64::from_bits(x.to_bits() + 1) + d);
        }
    }
    for x in [
        0.0,
        -0.0,
        1e-300,
        -1e-300,
        524_287.9,
        524_288.0,
        823_548.9,
        823_549.0,
        1e300,
        f64::MAX,
        f64::MIN_POSITIVE,
    ] {
        check(x);
        check(-x);
    }
    for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        check(x);
    }
    assert_eq!(sin_cos_f64(0.0), (0.0, 1.0));
}

#[test]
fn batched_sin_cos_matches_scalar() {
    let mut rng = common::Rng::new(7);
    for round in 0..10_000 {
        let mut x: [f64; 19] = std::array::from_fn(|_| rng.range(-10.0, 10.0));
        if round % 10 == 0 {
            x[3] = 1e7;
            x[11] = f64::NAN;
        }
        let mut s = [0.0; 19];
        let mut c = [0.0; 19];
        f64::sin_cos_batch(&x, &mut s, &mut c);
        for k in 0..19 {
            let (mut s1, mut c1) = ([0.0], [0.0]);
            f64::sin_cos_batch(&[x[k]], &mut s1, &mut c1);
            let (s1, c1) = (s1[0], c1[0]);
            assert!(
                s[k].to_bits() == s1.to_bits() || (s[k].is_nan() && s1.is_nan()),
                "sin {}",
                x[k]
            );
            assert!(
                c[k].to_bits() == c1.to_bits() || (c[k].is_nan() && c1.is_nan()),
                "cos {}",
                x[k]
            );
            let (s0, c0) = sin_cos_f64(x[k]);
            if x[k].is_finite() {
                let ulp2 = |v: f64| 2.0 * f64::EPSILON * v.abs().max(f64::MIN_POSITIVE);
                assert!(
                    (s[k] - s0).abs() <= ulp2(s0),
                    "sin {}: {:e} vs {s0:e}",
                    x[k],
                    s[k]
                );
                assert!(
                    (c[k] - c0).abs() <= ulp2(c0),
                    "cos {}: {:e} vs {c0:e}",
                    x[k],
                    c[k]
                );
            } else {
                assert!(s[k].is_nan() && c[k].is_nan());
            }
        }
    }
}
