//! The regressors as compiled generated code (modules of the root build script with every
//! registry function: the URDF arm and the two-link model): `Y π = τ`, `Y_g β = g`,
//! `Y_b π_b = τ` and `Y_gb β_b = g` with the compiled τ and g, the same values as the
//! generator's interpreter, and the `Params` ⇄ π, β conversions. (The values themselves are
//! checked against τ, g, derivatives and ranks in `codegen/tests/regressors.rs`.)

mod common;

use common::*;
use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Options};
use kanegen_reference::random::random_physical_params;

#[allow(dead_code)] // a module uses only the functions under test
mod singlearm_all {
    include!(concat!(env!("OUT_DIR"), "/singlearm_all.rs"));
}

#[allow(dead_code)] // a module uses only the functions under test
mod two_link_all {
    include!(concat!(env!("OUT_DIR"), "/two_link_all.rs"));
}

/// Row-major data of a fixed-size matrix.
fn row_major<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> Vec<f64> {
    (0..R)
        .flat_map(|r| (0..C).map(move |c| m[(r, c)]))
        .collect()
}

macro_rules! compiled_regressors {
    ($m:ident, $ty:ident, $model:expr, $seed:expr) => {{
        use $m::{BASE_BETA_NAMES, BASE_PARAMETER_NAMES, BETA_NAMES, DOF, INERTIAL_NAMES, Params};
        let model: Model = $model;
        let options = Options {
            functions: FunctionSet::all(),
            ..Options::default()
        };
        let g = Builder::from_model(model.clone())
            .options(options)
            .generate()
            .expect("generates");
        let reg = &g.derivation.regressors;
        let names = |ids: &[usize]| -> Vec<String> {
            ids.iter().map(|&p| model.params[p].name.clone()).collect()
        };
        assert_eq!(INERTIAL_NAMES.to_vec(), names(&reg.inertial));
        assert_eq!(BETA_NAMES.to_vec(), names(&reg.beta));
        assert_eq!(
            BASE_PARAMETER_NAMES.to_vec(),
            reg.base.as_ref().unwrap().names
        );
        assert_eq!(
            BASE_BETA_NAMES.to_vec(),
            reg.base_beta.as_ref().unwrap().names
        );
        let mut r = rng($seed);
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            let params = random_physical_params(&model, &mut r);
            let p = Params::from_array(params.clone().try_into().unwrap());
            let k = $m::$ty::new(p);
            let (q, u, ud) = random_state(&mut r, DOF);
            let (q, u, ud) = (sv::<DOF>(&q), sv::<DOF>(&u), sv::<DOF>(&ud));
            let pi = p.inertial_vector();
            let beta = p.beta_vector();
            let mut back = Params::default();
            back.set_inertial_vector(&pi);
            assert_eq!(back.inertial_vector(), pi);
            back.set_beta_vector(&beta);
            assert_eq!(back.beta_vector(), beta);
            let tau = k.inverse_dynamics(&q, &u, &ud);
            let grav = k.gravity(&q);
            let y = k.inverse_dynamics_regressor(&q, &u, &ud);
            let yg = k.gravity_regressor(&q);
            worst = worst.max(rel_err((y * pi).as_slice(), tau.as_slice(), 1.0));
            worst = worst.max(rel_err((yg * beta).as_slice(), grav.as_slice(), 1.0));
            // The interpreter's Y.
            let low = g.lowered.evaluate(
                FunctionId::InverseDynamicsRegressor,
                &params,
                q.as_slice(),
                u.as_slice(),
                ud.as_slice(),
            );
            worst = worst.max(rel_err(&row_major(&y), &low, 1.0));
            // The base regressors with the base parameters of the model file's geometry.
            let mut pm = Params::default();
            pm.set_inertial_vector(&pi);
            let km = $m::$ty::new(pm);
            let tau_m = km.inverse_dynamics(&q, &u, &ud);
            let yb = km.base_regressor(&q, &u, &ud);
            worst = worst.max(rel_err(
                (yb * $m::base_parameters(&pm)).as_slice(),
                tau_m.as_slice(),
                1.0,
            ));
            // With the random geometry too: `base_parameters(&Params)` uses the grouping
            // coefficients as expressions of the lengths.
            worst = worst.max(rel_err(
                (k.base_regressor(&q, &u, &ud) * $m::base_parameters(&p)).as_slice(),
                tau.as_slice(),
                1.0,
            ));
            worst = worst.max(rel_err(
                (k.base_gravity_regressor(&q) * $m::base_beta(&p)).as_slice(),
                grav.as_slice(),
                1.0,
            ));
            let ygb = km.base_gravity_regressor(&q);
            worst = worst.max(rel_err(
                (ygb * $m::base_beta(&pm)).as_slice(),
                km.gravity(&q).as_slice(),
                1.0,
            ));
        }
        worst
    }};
}

#[test]
fn compiled_regressors_reproduce_tau_and_g() {
    let arm = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .unwrap();
    let worst = compiled_regressors!(singlearm_all, SingleArm, arm, 31);
    assert!(worst <= 1e-12, "arm: {worst:e}");
    let worst = compiled_regressors!(two_link_all, TwoLink, model("two-link.toml"), 32);
    assert!(worst <= 1e-12, "two-link: {worst:e}");
}

#[test]
fn krang_compiled_regressors_reproduce_tau_and_g() {
    use krang_dynamics::{BASE_PARAMETER_NAMES, INERTIAL_NAMES, Krang, Params};
    assert_eq!(INERTIAL_NAMES.len(), 173);
    assert_eq!(BASE_PARAMETER_NAMES.len(), 122);
    let model = model("krang.toml");
    let geometry = Params::default();
    let mut r = rng(33);
    let mut worst: f64 = 0.0;
    for _ in 0..50 {
        let random = random_physical_params(&model, &mut r);
        let random = Params::from_array(random.try_into().unwrap());
        let mut p = geometry;
        p.set_inertial_vector(&random.inertial_vector());
        let k = Krang::new(p);
        let (q, u, ud) = random_state(&mut r, 19);
        let (q, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        let tau = k.inverse_dynamics(&q, &u, &ud);
        let y = k.inverse_dynamics_regressor(&q, &u, &ud);
        worst = worst.max(rel_err(
            (y * p.inertial_vector()).as_slice(),
            tau.as_slice(),
            1.0,
        ));
        let yb = k.base_regressor(&q, &u, &ud);
        let pb = krang_dynamics::base_parameters(&p);
        worst = worst.max(rel_err((yb * pb).as_slice(), tau.as_slice(), 1.0));
        let grav = k.gravity(&q);
        let yg = k.gravity_regressor(&q);
        worst = worst.max(rel_err(
            (yg * p.beta_vector()).as_slice(),
            grav.as_slice(),
            1.0,
        ));
        let ygb = k.base_gravity_regressor(&q);
        worst = worst.max(rel_err(
            (ygb * krang_dynamics::base_beta(&p)).as_slice(),
            grav.as_slice(),
            1.0,
        ));
    }
    assert!(worst <= 1e-12, "{worst:e}");
}

/// Krang's regressors are in loop form (docs/regressors.md): the in-place
/// variants write every entry of a matrix of any content (here NaN and a previous state's
/// result) and equal the by-value functions bit for bit; the fixed-wheel tree's too.
#[test]
fn krang_in_place_regressors_write_every_entry_and_equal_the_by_value_ones() {
    use krang_dynamics::Krang;
    use krang_dynamics::fixed_wheels::KrangFixedWheels;
    let k = Krang::default();
    let kf = KrangFixedWheels::default();
    let mut r = rng(34);
    let mut y = nalgebra::SMatrix::<f64, 19, 173>::from_element(f64::NAN);
    let mut yb = nalgebra::SMatrix::<f64, 19, 122>::from_element(f64::NAN);
    for _ in 0..20 {
        let (q, u, ud) = random_state(&mut r, 19);
        let (q, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        k.inverse_dynamics_regressor_into(&q, &u, &ud, &mut y);
        assert_eq!(y, k.inverse_dynamics_regressor(&q, &u, &ud));
        k.base_regressor_into(&q, &u, &ud, &mut yb);
        assert_eq!(yb, k.base_regressor(&q, &u, &ud));
        let (q, u, ud) = random_state(&mut r, 17);
        let (q, u, ud) = (sv::<17>(&q), sv::<17>(&u), sv::<17>(&ud));
        let mut yf = kf.inverse_dynamics_regressor(&q, &u, &ud);
        yf.fill(f64::NAN);
        kf.inverse_dynamics_regressor_into(&q, &u, &ud, &mut yf);
        assert_eq!(yf, kf.inverse_dynamics_regressor(&q, &u, &ud));
    }
}

#[test]
fn krang_base_parameters_follow_the_geometry_of_the_parameter_set() {
    // Random lengths, wheel radius and track as well as inertial parameters: the grouping
    // coefficients of `base_parameters(&Params)` are expressions of the geometry.
    let model = model("krang.toml");
    let mut r = rng(34);
    let mut worst: f64 = 0.0;
    for _ in 0..50 {
        let p = random_physical_params(&model, &mut r);
        let p = krang_dynamics::Params::from_array(p.try_into().unwrap());
        assert_ne!(p.L1, krang_dynamics::Params::default().L1);
        let k = krang_dynamics::Krang::new(p);
        let (q, u, ud) = random_state(&mut r, 19);
        let (q, u, ud) = (sv::<19>(&q), sv::<19>(&u), sv::<19>(&ud));
        let tau = k.inverse_dynamics(&q, &u, &ud);
        let yb = k.base_regressor(&q, &u, &ud);
        worst = worst.max(rel_err(
            (yb * krang_dynamics::base_parameters(&p)).as_slice(),
            tau.as_slice(),
            1.0,
        ));
        let ygb = k.base_gravity_regressor(&q);
        worst = worst.max(rel_err(
            (ygb * krang_dynamics::base_beta(&p)).as_slice(),
            k.gravity(&q).as_slice(),
            1.0,
        ));
    }
    assert!(worst <= 1e-12, "{worst:e}");
}
