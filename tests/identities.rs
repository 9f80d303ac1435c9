//! Identities the generated Krang dynamics must satisfy, independent of any other code.

mod common;

use common::*;
use kanegen_reference::random::random_physical_params;
use krang_dynamics::{Krang, Params};
use nalgebra::SVector;

type V = SVector<f64, 19>;

fn krang(seed: u64) -> (Krang, impl FnMut() -> f64) {
    let model = model("krang.toml");
    let mut r = rng(seed);
    let p = random_physical_params(&model, &mut r);
    (Krang::new(Params::from_array(p.try_into().unwrap())), r)
}

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    let (k, mut r) = krang(11);
    for _ in 0..200 {
        let (q, _, _) = random_state(&mut r, 19);
        let m = k.mass_matrix(&sv(&q));
        assert!(
            (m - m.transpose()).abs().max() == 0.0,
            "M is exactly symmetric"
        );
        assert!(m.cholesky().is_some(), "M is positive definite");
    }
}

#[test]
fn mass_matrix_columns_are_inverse_dynamics_differences() {
    let (k, mut r) = krang(12);
    for _ in 0..50 {
        let (q, _, _) = random_state(&mut r, 19);
        let q = sv::<19>(&q);
        let m = k.mass_matrix(&q);
        let t0 = k.inverse_dynamics(&q, &V::zeros(), &V::zeros());
        for i in 0..19 {
            let col = k.inverse_dynamics(&q, &V::zeros(), &V::ith(i, 1.0)) - t0;
            let err = (col - m.column(i)).abs().max() / m.abs().max();
            assert!(err < 1e-12, "column {i}: {err}");
        }
    }
}

#[test]
fn gravity_is_inverse_dynamics_at_rest() {
    let (k, mut r) = krang(13);
    for _ in 0..200 {
        let (q, _, _) = random_state(&mut r, 19);
        let q = sv::<19>(&q);
        let g = k.gravity(&q);
        let t = k.inverse_dynamics(&q, &V::zeros(), &V::zeros());
        assert!((g - t).abs().max() <= 1e-12 * g.abs().max().max(1.0));
    }
}

#[test]
fn coriolis_vanishes_at_zero_speed_and_completes_inverse_dynamics() {
    let (k, mut r) = krang(14);
    for _ in 0..200 {
        let (q, u, ud) = random_state(&mut r, 19);
        let (q, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        assert_eq!(k.coriolis(&q, &V::zeros()), V::zeros());
        let lhs = k.inverse_dynamics(&q, &u, &ud);
        let rhs = k.mass_matrix(&q) * ud + k.coriolis(&q, &u) + k.gravity(&q);
        assert!((lhs - rhs).abs().max() <= 1e-11 * rhs.abs().max());
    }
}

#[test]
fn x_and_psi_do_not_enter_the_dynamics() {
    let k = Krang::default();
    let mut r = rng(15);
    let (q, u, ud) = random_state(&mut r, 19);
    let (mut q2, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
    let t1 = k.inverse_dynamics(&q2, &u, &ud);
    q2[0] += 3.0;
    q2[1] -= 1.0;
    assert_eq!(t1, k.inverse_dynamics(&q2, &u, &ud));
}

#[test]
fn params_set_and_get_use_the_reports_symbols() {
    let mut p = Params::default();
    assert_eq!(Params::NAMES.len(), 185);
    assert_eq!(p.get("L1"), Some(0.499));
    p.set("MX4l", 0.12).unwrap();
    assert_eq!(p.MX4l, 0.12);
    let err = p.set("MX4k", 1.0).unwrap_err();
    assert!(err.to_string().contains("MX4k"));
    assert_eq!(p.get("nope"), None);
    assert_eq!(Params::from_array(p.to_array()), p);
    assert_eq!(
        krang_dynamics::SPEED_NAMES[krang_dynamics::index::Q_IMU],
        "qd_imu"
    );
}
