//! The floating base's dynamics as derived (through the derivation's evaluator, no code
//! generation), on a small TOML model with a prismatic joint and on Solo 12, with random
//! parameters and states:
//!
//! * M, c, g, τ and the nonlinear effects equal a spatial-vector recursion with a free-flyer root
//!   (`support/free_flyer.rs`, independent of the Kane derivation);
//! * M equals the kinetic-energy mass matrix of `kanegen-model`, is symmetric positive definite,
//!   and `½ uᵀ M u` is the bodies' kinetic energy;
//! * g is the gradient of the potential energy in the tangent space (`q ⊕ δ`, central
//!   differences);
//! * the base position never enters τ.

#[path = "support/free_flyer.rs"]
mod free_flyer;

use kanegen::kane::derive;
use kanegen::model::{Model, UrdfOptions, kinetic_energy_mass_matrix};
use kanegen::{FunctionId, FunctionSet, Options};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::{DMatrix, DVector};

fn model(name: &str) -> Model {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    if name.ends_with(".urdf") {
        let path = dir.join("tests/corpus").join(name);
        Model::from_urdf_file(&path, &UrdfOptions::floating()).expect("URDF imports")
    } else {
        Model::from_toml_file(dir.join("models").join(name)).expect("model loads")
    }
}

const DYNAMICS: [FunctionId; 5] = [
    FunctionId::MassMatrix,
    FunctionId::Coriolis,
    FunctionId::Gravity,
    FunctionId::InverseDynamics,
    FunctionId::NonlinearEffects,
];

fn rel_err(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

fn check_model(name: &str, seed: u64) {
    let model = model(name);
    assert!(model.is_floating());
    let n = model.dof();
    assert_eq!(model.nq(), n + 1);
    let options = Options {
        functions: DYNAMICS.into_iter().collect::<FunctionSet>(),
        ..Options::default()
    };
    let d = derive(&model, options);
    let mut r = SplitMix64::new(seed);
    let mut uniform = move || r.next_f64();
    for _ in 0..3 {
        let params = random_physical_params(&model, &mut uniform);
        let q = free_flyer::random_configuration(&model, &mut uniform);
        let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
        let ud = uniform_vec(&mut uniform, n, -5.0, 5.0);
        let zero = vec![0.0; n];
        let eval =
            |id, u: &[f64], ud: &[f64]| DVector::from_vec(d.evaluate(id, &params, &q, u, ud));
        let m = DMatrix::from_row_slice(
            n,
            n,
            &d.evaluate(FunctionId::MassMatrix, &params, &q, &zero, &zero),
        );
        let c = eval(FunctionId::Coriolis, &u, &zero);
        let g = eval(FunctionId::Gravity, &zero, &zero);
        let tau = eval(FunctionId::InverseDynamics, &u, &ud);
        let h = eval(FunctionId::NonlinearEffects, &u, &zero);

        // Against the spatial-vector recursion.
        let m_ref = free_flyer::mass_matrix(&model, &params, &q);
        let tau_ref = free_flyer::rnea(&model, &params, &q, &u, &ud, true);
        let c_ref = free_flyer::rnea(&model, &params, &q, &u, &zero, false);
        let g_ref = free_flyer::rnea(&model, &params, &q, &zero, &zero, true);
        let h_ref = free_flyer::rnea(&model, &params, &q, &u, &zero, true);
        assert!(
            (&m - &m_ref).amax() < 1e-10 * m_ref.amax(),
            "{name}: M\n{m}\n{m_ref}"
        );
        assert!(
            rel_err(&tau, &tau_ref) < 1e-10,
            "{name}: τ\n{tau}\n{tau_ref}"
        );
        assert!(rel_err(&c, &c_ref) < 1e-10, "{name}: c\n{c}\n{c_ref}");
        assert!(rel_err(&g, &g_ref) < 1e-10, "{name}: g\n{g}\n{g_ref}");
        assert!(rel_err(&h, &h_ref) < 1e-10, "{name}: nle\n{h}\n{h_ref}");
        assert!(rel_err(&h, &(&c + &g)) < 1e-12, "{name}: nle = c + g");
        let ud_v = DVector::from_vec(ud.clone());
        assert!(
            rel_err(&tau, &(&m * &ud_v + &h)) < 1e-10,
            "{name}: τ = M u̇ + h"
        );

        // M from the kinetic energy (coordinates indexed like the speeds), symmetric positive
        // definite, and ½ uᵀ M u the kinetic energy.
        let q_speeds: Vec<f64> = (0..n).map(|s| q[model.coordinate_index(s)]).collect();
        let m_ke = kinetic_energy_mass_matrix(&model, &q_speeds, &params);
        assert!(
            (&m - &m_ke).amax() < 1e-10 * m_ke.amax(),
            "{name}: M vs kinetic energy"
        );
        assert!((&m - m.transpose()).amax() == 0.0, "{name}: M symmetric");
        assert!(
            m.clone().cholesky().is_some(),
            "{name}: M positive definite"
        );
        let u_v = DVector::from_vec(u.clone());
        let t = 0.5 * u_v.dot(&(&m * &u_v));
        let t_ref = free_flyer::kinetic_energy(&model, &params, &q, &u);
        assert!(
            (t - t_ref).abs() < 1e-10 * t_ref.abs().max(1.0),
            "{name}: T {t} vs {t_ref}"
        );

        // g = ∂V/∂δ at q ⊕ δ (central differences).
        let eps = 1e-6;
        for k in 0..n {
            let mut dp = vec![0.0; n];
            dp[k] = eps;
            let dm: Vec<f64> = dp.iter().map(|x| -x).collect();
            let vp = free_flyer::potential_energy(
                &model,
                &params,
                &free_flyer::integrate(&model, &q, &dp),
            );
            let vm = free_flyer::potential_energy(
                &model,
                &params,
                &free_flyer::integrate(&model, &q, &dm),
            );
            let fd = (vp - vm) / (2.0 * eps);
            assert!(
                (fd - g[k]).abs() < 1e-6 * g.amax().max(1.0),
                "{name}: g[{k}] = {} vs ∂V = {fd}",
                g[k]
            );
        }

        // The base position does not enter τ.
        let mut moved = q.clone();
        moved[0] += 3.0;
        moved[2] -= 1.5;
        let tau_moved =
            DVector::from_vec(d.evaluate(FunctionId::InverseDynamics, &params, &moved, &u, &ud));
        assert_eq!(tau_moved, tau, "{name}: τ independent of the base position");
    }
}

#[test]
fn floating_toml_model_dynamics_match_the_free_flyer_recursion() {
    check_model("floating-hopper.toml", 11);
}

#[test]
fn floating_solo12_dynamics_match_the_free_flyer_recursion() {
    check_model("solo12.urdf", 12);
}
