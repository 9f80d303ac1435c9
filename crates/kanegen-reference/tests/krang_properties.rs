//! Structural properties of the Krang models (19-speed wheeled and 17-DOF fixed-wheel tree):
//! symmetric positive definite M, c(q, 0) = 0, T = ½uᵀMu, g = ∂V/∂q, energy conservation along
//! simulated trajectories, and the wheel terms.

mod common;

use kanegen_model::Model;
use kanegen_reference::Reference;
use kanegen_reference::random::{random_physical_params, uniform_vec, zero_wheel_params};
use nalgebra::{DMatrix, DVector};

const MODELS: [&str; 2] = ["krang", "krang-fixed-wheels"];

/// Default parameters first, then random physical ones.
fn param_sets(model: &Model, rnd: &mut impl FnMut() -> f64, random: usize) -> Vec<Vec<f64>> {
    let mut sets = vec![model.param_values()];
    sets.extend((0..random).map(|_| random_physical_params(model, rnd)));
    sets
}

fn set_param(model: &Model, params: &mut [f64], name: &str, value: f64) {
    params[model
        .param_index(name)
        .unwrap_or_else(|| panic!("no {name}"))] = value;
}

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    let mut rnd = common::uniform(1);
    for name in MODELS {
        let model = common::load_model(name);
        for params in param_sets(&model, &mut rnd, 5) {
            let r = Reference::with_params(&model, &params);
            for _ in 0..10 {
                let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
                let m = r.mass_matrix(&q);
                let asym = (&m - m.transpose()).amax() / m.amax();
                assert!(asym < 1e-12, "{name}: M not symmetric: {asym:e}");
                assert!(
                    m.clone().cholesky().is_some(),
                    "{name}: M not positive definite\n{m}"
                );
            }
        }
    }
}

#[test]
fn coriolis_vanishes_at_zero_speed_and_is_quadratic() {
    let mut rnd = common::uniform(2);
    for name in MODELS {
        let model = common::load_model(name);
        for params in param_sets(&model, &mut rnd, 3) {
            let r = Reference::with_params(&model, &params);
            for _ in 0..10 {
                let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
                let u = uniform_vec(&mut rnd, r.dof(), -2.0, 2.0);
                let scale = r.gravity(&q).amax() + r.mass_matrix(&q).amax();
                let c0 = r.coriolis(&q, &vec![0.0; r.dof()]);
                assert!(c0.amax() <= 1e-13 * scale, "{name}: c(q, 0) = {c0}");
                // c(q, 2u) = 4 c(q, u).
                let c1 = r.coriolis(&q, &u);
                let u2: Vec<f64> = u.iter().map(|x| 2.0 * x).collect();
                let c2 = r.coriolis(&q, &u2);
                let e = common::rel_err_vec(&c2, &(c1 * 4.0), scale);
                assert!(e < 1e-12, "{name}: c not quadratic in u: {e:e}");
            }
        }
    }
}

#[test]
fn inverse_dynamics_is_m_ud_plus_c_plus_g() {
    let mut rnd = common::uniform(3);
    for name in MODELS {
        let model = common::load_model(name);
        for params in param_sets(&model, &mut rnd, 3) {
            let r = Reference::with_params(&model, &params);
            for _ in 0..5 {
                let n = r.dof();
                let q = uniform_vec(&mut rnd, n, -3.2, 3.2);
                let u = uniform_vec(&mut rnd, n, -2.0, 2.0);
                let ud = uniform_vec(&mut rnd, n, -2.0, 2.0);
                let tau = r.inverse_dynamics(&q, &u, &ud);
                let expected = r.mass_matrix(&q) * DVector::from_column_slice(&ud)
                    + r.coriolis(&q, &u)
                    + r.gravity(&q);
                let e = common::rel_err_vec(&tau, &expected, 1e-300);
                assert!(e < 1e-12, "{name}: τ ≠ M u̇ + c + g: {e:e}");
            }
        }
    }
}

#[test]
fn kinetic_energy_is_half_u_m_u() {
    let mut rnd = common::uniform(4);
    for name in MODELS {
        let model = common::load_model(name);
        for params in param_sets(&model, &mut rnd, 5) {
            let r = Reference::with_params(&model, &params);
            for _ in 0..10 {
                let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
                let u = DVector::from_vec(uniform_vec(&mut rnd, r.dof(), -2.0, 2.0));
                let t = r.kinetic_energy(&q, u.as_slice());
                let quad = 0.5 * u.dot(&(r.mass_matrix(&q) * &u));
                assert!(
                    (t - quad).abs() <= 1e-10 * quad.abs(),
                    "{name}: T = {t}, ½uᵀMu = {quad}"
                );
            }
        }
    }
}

#[test]
fn gravity_is_the_gradient_of_potential_energy() {
    let mut rnd = common::uniform(5);
    for name in MODELS {
        let model = common::load_model(name);
        let wheel_rows = model
            .wheeled_base()
            .map(|w| vec![w.x_speed, w.psi_speed])
            .unwrap_or_default();
        for params in param_sets(&model, &mut rnd, 3) {
            let r = Reference::with_params(&model, &params);
            for _ in 0..5 {
                let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
                let g = r.gravity(&q);
                let h = 1e-5;
                let grad = DVector::from_fn(r.dof(), |i, _| {
                    let (mut qp, mut qm) = (q.clone(), q.clone());
                    qp[i] += h;
                    qm[i] -= h;
                    (r.potential_energy(&qp) - r.potential_energy(&qm)) / (2.0 * h)
                });
                let e = common::rel_err_vec(&g, &grad, 1e-300);
                assert!(e < 1e-7, "{name}: g vs ∂V/∂q: {e:e}\n{g}\n{grad}");
                for &i in &wheel_rows {
                    assert!(g[i].abs() < 1e-12 * g.amax(), "{name}: g[{i}] = {}", g[i]);
                }
            }
        }
    }
}

/// Forward dynamics `u̇ = M⁻¹(−c − g)` (zero applied forces).
fn acceleration(r: &Reference<f64>, q: &[f64], u: &[f64]) -> DVector<f64> {
    let m = r.mass_matrix(q);
    // c + g = τ(q, u, 0).
    let rhs = -r.inverse_dynamics(q, u, &vec![0.0; r.dof()]);
    m.cholesky().expect("M positive definite").solve(&rhs)
}

/// One RK4 step of `q̇ = u` (the wheeled base's x, ψ included: they enter nothing), `u̇` above.
fn rk4_step(r: &Reference<f64>, q: &DVector<f64>, u: &DVector<f64>, dt: f64) -> [DVector<f64>; 2] {
    let f = |q: &DVector<f64>, u: &DVector<f64>| {
        (u.clone(), acceleration(r, q.as_slice(), u.as_slice()))
    };
    let (k1q, k1u) = f(q, u);
    let (k2q, k2u) = f(&(q + &k1q * (dt / 2.0)), &(u + &k1u * (dt / 2.0)));
    let (k3q, k3u) = f(&(q + &k2q * (dt / 2.0)), &(u + &k2u * (dt / 2.0)));
    let (k4q, k4u) = f(&(q + &k3q * dt), &(u + &k3u * dt));
    [
        q + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (dt / 6.0),
        u + (k1u + k2u * 2.0 + k3u * 2.0 + k4u) * (dt / 6.0),
    ]
}

/// Integrates 0.5 s with dt = 1 ms and returns the largest relative drift of T + V.
fn energy_drift(r: &Reference<f64>, q0: Vec<f64>, u0: Vec<f64>) -> f64 {
    let energy = |q: &DVector<f64>, u: &DVector<f64>| {
        r.kinetic_energy(q.as_slice(), u.as_slice()) + r.potential_energy(q.as_slice())
    };
    let (mut q, mut u) = (DVector::from_vec(q0), DVector::from_vec(u0));
    let e0 = energy(&q, &u);
    let t0 = r.kinetic_energy(q.as_slice(), u.as_slice());
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        [q, u] = rk4_step(r, &q, &u, 1e-3);
        worst = worst.max((energy(&q, &u) - e0).abs());
    }
    // Relative to the kinetic energy (V has an arbitrary zero).
    worst / t0
}

#[test]
fn kinetic_energy_is_conserved_without_gravity() {
    let mut rnd = common::uniform(6);
    for name in MODELS {
        let model = common::load_model(name);
        for (k, mut params) in param_sets(&model, &mut rnd, 1).into_iter().enumerate() {
            set_param(&model, &mut params, "g", 0.0);
            let r = Reference::with_params(&model, &params);
            let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
            let u = uniform_vec(&mut rnd, r.dof(), -1.0, 1.0);
            let drift = energy_drift(&r, q, u);
            eprintln!("{name} (set {k}): relative energy drift {drift:.2e}");
            assert!(
                drift < 1e-6,
                "{name} (set {k}): relative drift of T {drift:e}"
            );
        }
    }
}

#[test]
fn total_energy_is_conserved_with_gravity() {
    let mut rnd = common::uniform(7);
    for name in MODELS {
        let model = common::load_model(name);
        for (k, params) in param_sets(&model, &mut rnd, 1).into_iter().enumerate() {
            let r = Reference::with_params(&model, &params);
            let q = uniform_vec(&mut rnd, r.dof(), -3.2, 3.2);
            let u = uniform_vec(&mut rnd, r.dof(), -1.0, 1.0);
            let drift = energy_drift(&r, q, u);
            eprintln!("{name} (set {k}): relative energy drift {drift:.2e}");
            assert!(
                drift < 1e-6,
                "{name} (set {k}): relative drift of T + V {drift:e}"
            );
        }
    }
}

#[test]
fn wheels_add_exactly_their_terms_to_x_and_psi_diagonal() {
    let model = common::load_model("krang");
    let w = model
        .wheeled_base()
        .expect("krang has a wheeled base")
        .clone();
    let mut rnd = common::uniform(8);
    for params in param_sets(&model, &mut rnd, 5) {
        let mut bare = params.clone();
        zero_wheel_params(&model, &mut bare);
        let with = Reference::with_params(&model, &params);
        let without = Reference::with_params(&model, &bare);
        let (r, l, mw, yy, zz) = (
            params[w.radius],
            params[w.track],
            params[w.wheel_mass],
            params[w.wheel_axle_inertia],
            params[w.wheel_diametral_inertia],
        );
        let mut expected = DMatrix::zeros(model.dof(), model.dof());
        expected[(w.x_speed, w.x_speed)] = 2.0 * mw + 2.0 * yy / (r * r);
        expected[(w.psi_speed, w.psi_speed)] =
            mw * l * l / 2.0 + yy * l * l / (2.0 * r * r) + 2.0 * zz;
        for _ in 0..5 {
            let q = uniform_vec(&mut rnd, model.dof(), -3.2, 3.2);
            let u = uniform_vec(&mut rnd, model.dof(), -2.0, 2.0);
            let m_with = with.mass_matrix(&q);
            let diff = &m_with - without.mass_matrix(&q);
            let e = (&diff - &expected).amax() / m_with.amax();
            assert!(
                e < 1e-13,
                "M(wheels) − M(no wheels) ≠ wheel terms: {e:e}\n{diff}"
            );
            // No velocity-product or gravity terms from the wheels.
            let scale = with.gravity(&q).amax() + m_with.amax();
            let dc = (with.coriolis(&q, &u) - without.coriolis(&q, &u)).amax();
            let dg = (with.gravity(&q) - without.gravity(&q)).amax();
            assert!(
                dc < 1e-13 * scale && dg < 1e-13 * scale,
                "dc {dc:e}, dg {dg:e}"
            );
            // Kinetic energy: the wheels' ½(…)ẋ² + ½(…)ψ̇².
            let dt = with.kinetic_energy(&q, &u) - without.kinetic_energy(&q, &u);
            let u = DVector::from_vec(u.clone());
            let quad = 0.5 * u.dot(&(&expected * &u));
            assert!((dt - quad).abs() < 1e-12 * quad.abs().max(1.0));
        }
    }
}

#[test]
fn fixed_wheel_model_is_the_wheeled_model_without_base_motion() {
    let wheeled = common::load_model("krang");
    let fixed = common::load_model("krang-fixed-wheels");
    let w = wheeled.wheeled_base().unwrap().clone();
    // Speed i of the fixed model is speed map[i] of the wheeled one (matched by name).
    let map: Vec<usize> = fixed
        .speeds
        .iter()
        .map(|s| wheeled.speed_index(&s.name).unwrap())
        .collect();
    let mut rnd = common::uniform(9);
    for _ in 0..5 {
        let pw = random_physical_params(&wheeled, &mut rnd);
        let pf: Vec<f64> = fixed
            .params
            .iter()
            .map(|p| pw[wheeled.param_index(&p.name).unwrap()])
            .collect();
        let (rw, rf) = (
            Reference::with_params(&wheeled, &pw),
            Reference::with_params(&fixed, &pf),
        );
        let qf = uniform_vec(&mut rnd, fixed.dof(), -3.2, 3.2);
        let uf = uniform_vec(&mut rnd, fixed.dof(), -2.0, 2.0);
        let udf = uniform_vec(&mut rnd, fixed.dof(), -2.0, 2.0);
        let mut qw = uniform_vec(&mut rnd, wheeled.dof(), -3.2, 3.2); // x, ψ arbitrary
        let (mut uw, mut udw) = (vec![0.0; wheeled.dof()], vec![0.0; wheeled.dof()]);
        for (i, &j) in map.iter().enumerate() {
            (qw[j], uw[j], udw[j]) = (qf[i], uf[i], udf[i]);
        }
        assert_eq!(uw[w.x_speed], 0.0);
        let tw = rw.inverse_dynamics(&qw, &uw, &udw);
        let tw = DVector::from_fn(fixed.dof(), |i, _| tw[map[i]]);
        let tf = rf.inverse_dynamics(&qf, &uf, &udf);
        let e = common::rel_err_vec(&tw, &tf, 1e-300);
        assert!(e < 1e-12, "τ differs: {e:e}");
        let mw = rw.mass_matrix(&qw);
        let mw = DMatrix::from_fn(fixed.dof(), fixed.dof(), |i, j| mw[(map[i], map[j])]);
        let e = common::rel_err_mat(&mw, &rf.mass_matrix(&qf), 1e-300);
        assert!(e < 1e-12, "M differs: {e:e}");
    }
}
