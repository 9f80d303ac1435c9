//! The compiled generated code (crate `krang-dynamics`) against the independent numeric reference
//! recursion (crate `kanegen-reference`) on many random parameter sets and states.

mod common;

use common::*;
use kanegen_model::Model;
use kanegen_reference::Reference;
use kanegen_reference::random::{random_physical_params, zero_wheel_params};
use krang_dynamics as kd;

const TOL: f64 = 1e-10;
/// Errors are relative to the largest reference entry, or absolute below 1 (N, N·m, kg·m²).
const FLOOR: f64 = 1.0;

/// Compare the four generated functions with the reference at one (params, state) draw.
macro_rules! compare {
    ($module:path, $ty:ident, $n:expr, $model:expr, $params:expr, $q:expr, $u:expr, $ud:expr) => {{
        use $module as gm;
        let params: Vec<f64> = $params;
        let dynamics = gm::$ty::new(gm::Params::from_array(params.clone().try_into().unwrap()));
        let reference = Reference::<f64>::with_params($model, &params);
        let (q, u, ud) = (sv::<$n>($q), sv::<$n>($u), sv::<$n>($ud));
        let em = rel_err(
            &rows(&dynamics.mass_matrix(&q)),
            &drows(&reference.mass_matrix($q)),
            FLOOR,
        );
        let ec = rel_err(
            &dynamics.coriolis(&q, &u).as_slice(),
            &dvec(&reference.coriolis($q, $u)),
            FLOOR,
        );
        let eg = rel_err(
            &dynamics.gravity(&q).as_slice(),
            &dvec(&reference.gravity($q)),
            FLOOR,
        );
        let et = rel_err(
            &dynamics.inverse_dynamics(&q, &u, &ud).as_slice(),
            &dvec(&reference.inverse_dynamics($q, $u, $ud)),
            FLOOR,
        );
        [em, ec, eg, et]
    }};
}

fn worst(acc: &mut [f64; 4], e: [f64; 4]) {
    for i in 0..4 {
        acc[i] = acc[i].max(e[i]);
    }
}

fn check(label: &str, w: [f64; 4]) {
    eprintln!(
        "{label}: worst relative error M {:.1e} c {:.1e} g {:.1e} tau {:.1e}",
        w[0], w[1], w[2], w[3]
    );
    assert!(w.iter().all(|e| *e < TOL), "{label}: {w:?} exceeds {TOL}");
}

#[test]
fn krang_generated_matches_reference_on_random_parameters_and_states() {
    let model = model("krang.toml");
    let mut r = rng(1);
    let mut w = [0.0; 4];
    for _ in 0..1000 {
        let p = random_physical_params(&model, &mut r);
        let (q, u, ud) = random_state(&mut r, 19);
        worst(&mut w, compare!(kd, Krang, 19, &model, p, &q, &u, &ud));
    }
    check("krang, 1000 random draws", w);
}

#[test]
fn krang_generated_matches_reference_with_wheels_zeroed() {
    let model = model("krang.toml");
    let mut r = rng(2);
    let mut w = [0.0; 4];
    for _ in 0..300 {
        let mut p = random_physical_params(&model, &mut r);
        zero_wheel_params(&model, &mut p);
        let (q, u, ud) = random_state(&mut r, 19);
        worst(&mut w, compare!(kd, Krang, 19, &model, p, &q, &u, &ud));
    }
    check("krang, wheels zeroed", w);
}

#[test]
fn krang_generated_matches_reference_with_hardware_fitted_masses() {
    let model = model("krang.toml");
    let p = hardware_fitted_params(&model);
    let mut r = rng(3);
    let mut w = [0.0; 4];
    for _ in 0..300 {
        let (q, u, ud) = random_state(&mut r, 19);
        worst(
            &mut w,
            compare!(kd, Krang, 19, &model, p.clone(), &q, &u, &ud),
        );
    }
    check("krang, hardware-fitted masses", w);
}

#[test]
fn krang_default_parameters_match_reference() {
    let model = model("krang.toml");
    let mut r = rng(4);
    let mut w = [0.0; 4];
    for _ in 0..200 {
        let (q, u, ud) = random_state(&mut r, 19);
        worst(
            &mut w,
            compare!(kd, Krang, 19, &model, model.param_values(), &q, &u, &ud),
        );
    }
    check("krang, default parameters", w);
}

#[test]
fn fixed_wheel_generated_matches_reference_on_random_parameters_and_states() {
    let model = model("krang-fixed-wheels.toml");
    let mut r = rng(5);
    let mut w = [0.0; 4];
    for _ in 0..1000 {
        let p = random_physical_params(&model, &mut r);
        let (q, u, ud) = random_state(&mut r, 17);
        worst(
            &mut w,
            compare!(
                kd::fixed_wheels,
                KrangFixedWheels,
                17,
                &model,
                p,
                &q,
                &u,
                &ud
            ),
        );
    }
    check("krang-fixed-wheels, 1000 random draws", w);
}

#[test]
fn two_link_generated_matches_reference_on_random_parameters_and_states() {
    let model = model("two-link.toml");
    let mut r = rng(6);
    let mut w = [0.0; 4];
    for _ in 0..1000 {
        let p = random_physical_params(&model, &mut r);
        let (q, u, ud) = random_state(&mut r, 2);
        worst(
            &mut w,
            compare!(kd::two_link, TwoLink, 2, &model, p, &q, &u, &ud),
        );
    }
    check("two-link, 1000 random draws", w);
}

#[test]
fn baked_krang_matches_reference_at_default_parameters() {
    let model: Model = model("krang.toml");
    let reference = Reference::<f64>::new(&model);
    let mut r = rng(7);
    let mut w = [0.0; 4];
    for _ in 0..200 {
        let (q, u, ud) = random_state(&mut r, 19);
        let (qs, us, uds) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        worst(
            &mut w,
            [
                rel_err(
                    &rows(&kd::baked::mass_matrix(&qs)),
                    &drows(&reference.mass_matrix(&q)),
                    FLOOR,
                ),
                rel_err(
                    kd::baked::coriolis(&qs, &us).as_slice(),
                    &dvec(&reference.coriolis(&q, &u)),
                    FLOOR,
                ),
                rel_err(
                    kd::baked::gravity(&qs).as_slice(),
                    &dvec(&reference.gravity(&q)),
                    FLOOR,
                ),
                rel_err(
                    kd::baked::inverse_dynamics(&qs, &us, &uds).as_slice(),
                    &dvec(&reference.inverse_dynamics(&q, &u, &ud)),
                    FLOOR,
                ),
            ],
        );
    }
    check("krang baked, default parameters", w);
}
