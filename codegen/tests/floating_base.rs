//! The floating base's dynamics as derived (through the derivation's evaluator, no code
//! generation), on a small TOML model with a prismatic joint and on Solo 12, with random
//! parameters and states:
//!
//! * M, c, g, τ and the nonlinear effects equal the free-flyer reference recursion
//!   `kanegen_reference::FreeFlyer` (independent of the Kane derivation; `support/free_flyer.rs`
//!   adapts its calls);
//! * M equals the kinetic-energy mass matrix of `kanegen-model`, is symmetric positive definite,
//!   and `½ uᵀ M u` is the bodies' kinetic energy;
//! * g is the gradient of the potential energy in the tangent space (`q ⊕ δ`, central
//!   differences);
//! * the base position never enters τ;
//! * kinematics and energies: every frame's world pose and the centre of mass equal the
//!   recursion's; along trajectories integrated on SE(3) (`q ⊕ δ`), `J u` is the derivative of
//!   the frame's world pose and of the centre of mass and `J u̇ + bias` the second derivative
//!   (in the base frame's axes); `T = ½ uᵀ M u` and `V` equal the recursion's;
//! * centroidal functions: `A_G u` is the momentum summed over the bodies (linear, angular about
//!   the centre of mass, world axes), `A_G u̇ + Ȧ_G u` its derivative along the motion, and
//!   `I_G` gives the angular momentum of the robot turning rigidly; on fixed bases `A_G` and
//!   `Ȧ_G u` equal the joint columns of the same tree on a floating base at rest; on Krang's
//!   wheeled base the linear rows are `m J_G` and `m` times the CoM bias, and `A_G u̇ + Ȧ_G u` the
//!   rate of `A_G u` in the turning heading frame.

#[path = "support/free_flyer.rs"]
mod free_flyer;

use kanegen::kane::derive;
use kanegen::model::{
    Base, JointKind, Model, UrdfOptions, floating_base_speeds, kinetic_energy_mass_matrix,
};
use kanegen::{FunctionId, FunctionSet, Options};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

fn model(name: &str) -> Model {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    if name.ends_with(".urdf") {
        let path = dir.join("tests/corpus").join(name);
        Model::from_urdf_file(&path, &UrdfOptions::floating()).expect("URDF imports")
    } else {
        Model::from_toml_file(dir.join("models").join(name)).expect("model loads")
    }
}

const DYNAMICS: [FunctionId; 11] = [
    FunctionId::BaseRegressor,
    FunctionId::BaseGravityRegressor,
    FunctionId::InverseDynamicsRegressor,
    FunctionId::GravityRegressor,
    FunctionId::InverseDynamicsDerivatives,
    FunctionId::MassMatrix,
    FunctionId::CoriolisMatrix,
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

        // The Coriolis matrix: C u = c, and Ṁ − 2C skew-symmetric (Ṁ by central differences
        // along q ⊕ u t).
        let cm = DMatrix::from_row_slice(
            n,
            n,
            &d.evaluate(FunctionId::CoriolisMatrix, &params, &q, &u, &zero),
        );
        assert!(rel_err(&(&cm * &u_v), &c) < 1e-10, "{name}: C u = c");
        let m_at = |t: f64| {
            let step: Vec<f64> = u.iter().map(|x| x * t).collect();
            let x = free_flyer::integrate(&model, &q, &step);
            DMatrix::from_row_slice(
                n,
                n,
                &d.evaluate(FunctionId::MassMatrix, &params, &x, &zero, &zero),
            )
        };
        let hs = 1e-5;
        let mdot = (m_at(hs) - m_at(-hs)) / (2.0 * hs);
        let skew = &mdot - &cm * 2.0;
        assert!(
            (&skew + skew.transpose()).amax() < 1e-6 * mdot.amax().max(1.0),
            "{name}: Ṁ − 2C skew"
        );

        // ∂τ/∂q in the tangent space and ∂τ/∂u against central differences of τ along
        // q ⊕ ε eₖ and u + ε eₖ.
        let dd = DMatrix::from_row_slice(
            n,
            2 * n,
            &d.evaluate(FunctionId::InverseDynamicsDerivatives, &params, &q, &u, &ud),
        );
        let eps = 1e-6;
        for k in 0..n {
            let mut dp = vec![0.0; n];
            dp[k] = eps;
            let dm: Vec<f64> = dp.iter().map(|x| -x).collect();
            let at = |x: &[f64], v: &[f64]| {
                DVector::from_vec(d.evaluate(FunctionId::InverseDynamics, &params, x, v, &ud))
            };
            let fq = (at(&free_flyer::integrate(&model, &q, &dp), &u)
                - at(&free_flyer::integrate(&model, &q, &dm), &u))
                / (2.0 * eps);
            let up: Vec<f64> = u.iter().zip(&dp).map(|(a, b)| a + b).collect();
            let um: Vec<f64> = u.iter().zip(&dm).map(|(a, b)| a + b).collect();
            let fu = (at(&q, &up) - at(&q, &um)) / (2.0 * eps);
            let scale = tau.amax().max(1.0);
            assert!(
                (dd.column(k) - &fq).amax() < 1e-6 * scale,
                "{name}: ∂τ/∂q[{k}]"
            );
            assert!(
                (dd.column(n + k) - &fu).amax() < 1e-6 * scale,
                "{name}: ∂τ/∂u[{k}]"
            );
        }

        // The regressors: τ = Y π, g = Y_g β.
        let pi: Vec<f64> = d.regressors.inertial.iter().map(|&k| params[k]).collect();
        let beta: Vec<f64> = d.regressors.beta.iter().map(|&k| params[k]).collect();
        let y = DMatrix::from_row_slice(
            n,
            pi.len(),
            &d.evaluate(FunctionId::InverseDynamicsRegressor, &params, &q, &u, &ud),
        );
        let yg = DMatrix::from_row_slice(
            n,
            beta.len(),
            &d.evaluate(FunctionId::GravityRegressor, &params, &q, &zero, &zero),
        );
        assert!(
            rel_err(&(&y * DVector::from_vec(pi)), &tau) < 1e-10,
            "{name}: Y π = τ"
        );
        assert!(
            rel_err(&(&yg * DVector::from_vec(beta)), &g) < 1e-10,
            "{name}: Y_g β = g"
        );

        // The base position does not enter τ.
        let mut moved = q.clone();
        moved[0] += 3.0;
        moved[2] -= 1.5;
        let tau_moved =
            DVector::from_vec(d.evaluate(FunctionId::InverseDynamics, &params, &moved, &u, &ud));
        assert_eq!(tau_moved, tau, "{name}: τ independent of the base position");
    }
}

const KINEMATICS: [FunctionId; 11] = [
    FunctionId::CentroidalMomentumMatrix,
    FunctionId::CentroidalMomentumBias,
    FunctionId::CentroidalInertia,
    FunctionId::CenterOfMass,
    FunctionId::ComJacobian,
    FunctionId::ComBiasAcceleration,
    FunctionId::KineticEnergy,
    FunctionId::PotentialEnergy,
    FunctionId::FramePose,
    FunctionId::FrameJacobian,
    FunctionId::FrameBiasAcceleration,
];

/// The world pose of link `l` from the recursion: `(R, p)`.
fn world_pose(model: &Model, params: &[f64], q: &[f64], l: usize) -> (Matrix3<f64>, Vector3<f64>) {
    let (r, o) = free_flyer::link_poses(model, q, params)[l];
    let r0 = free_flyer::base_rotation(q);
    (r0 * r, Vector3::new(q[0], q[1], q[2]) + r0 * o)
}

fn check_kinematics(name: &str, seed: u64) {
    let model = model(name);
    let n = model.dof();
    let options = Options {
        functions: DYNAMICS
            .into_iter()
            .chain(KINEMATICS)
            .collect::<FunctionSet>(),
        ..Options::default()
    };
    let d = derive(&model, options);
    let mut r = SplitMix64::new(seed);
    let mut uniform = move || r.next_f64();
    let params = random_physical_params(&model, &mut uniform);
    let q = free_flyer::random_configuration(&model, &mut uniform);
    let u = uniform_vec(&mut uniform, n, -1.5, 1.5);
    let ud = uniform_vec(&mut uniform, n, -3.0, 3.0);
    let zero = vec![0.0; n];
    // The motion q(t) with u(t) = u + u̇ t, integrated on SE(3) in midpoint steps.
    let state = |t: f64| {
        let steps = 40;
        let dt = t / steps as f64;
        let mut x = q.clone();
        for k in 0..steps {
            let mid: Vec<f64> = (0..n)
                .map(|i| (u[i] + ud[i] * dt * (k as f64 + 0.5)) * dt)
                .collect();
            x = free_flyer::integrate(&model, &x, &mid);
        }
        let ut: Vec<f64> = (0..n).map(|i| u[i] + ud[i] * t).collect();
        (x, ut)
    };
    let h = 2e-4;
    let samples = [-h, 0.0, h].map(state);
    let r0 = free_flyer::base_rotation(&q);
    let eval_at =
        |id, frame, q: &[f64], u: &[f64], ud: &[f64]| d.evaluate_at(id, frame, &params, q, u, ud);
    let close = |a: Vector3<f64>, b: Vector3<f64>, tol: f64, what: &str| {
        assert!(
            (a - b).norm() <= tol * b.norm().max(1.0),
            "{name}: {what}: {a} vs {b}"
        );
    };
    for l in 0..model.links.len() {
        let pose = eval_at(FunctionId::FramePose, Some(l), &q, &zero, &zero);
        let (rw, pw) = world_pose(&model, &params, &q, l);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (pose[i * 4 + j] - rw[(i, j)]).abs() < 1e-12,
                    "{name}: frame {l} rotation"
                );
            }
            assert!(
                (pose[i * 4 + 3] - pw[i]).abs() < 1e-12,
                "{name}: frame {l} origin"
            );
        }
        // J u against the derivative of the world pose (base axes), J u̇ + bias against the
        // second derivative.
        let jac = DMatrix::from_row_slice(
            6,
            n,
            &eval_at(FunctionId::FrameJacobian, Some(l), &q, &zero, &zero),
        );
        let bias = eval_at(FunctionId::FrameBiasAcceleration, Some(l), &q, &u, &zero);
        let poses = samples
            .clone()
            .map(|(x, _)| world_pose(&model, &params, &x, l));
        let vel = &jac * DVector::from_vec(u.clone());
        let acc = &jac * DVector::from_vec(ud.clone()) + DVector::from_vec(bias);
        let v_fd = (poses[2].1 - poses[0].1) / (2.0 * h);
        let a_fd = (poses[2].1 - 2.0 * poses[1].1 + poses[0].1) / (h * h);
        close(
            Vector3::new(vel[0], vel[1], vel[2]),
            r0.transpose() * v_fd,
            1e-6,
            "frame velocity",
        );
        close(
            Vector3::new(acc[0], acc[1], acc[2]),
            r0.transpose() * a_fd,
            1e-5,
            "frame acceleration",
        );
        let w_of = |(rm, _): &(Matrix3<f64>, Vector3<f64>),
                    (rp, _): &(Matrix3<f64>, Vector3<f64>),
                    dt: f64| {
            let s = (rp - rm) / dt * rp.transpose();
            Vector3::new(
                s[(2, 1)] - s[(1, 2)],
                s[(0, 2)] - s[(2, 0)],
                s[(1, 0)] - s[(0, 1)],
            ) / 2.0
        };
        let w_fd = w_of(&poses[0], &poses[2], 2.0 * h);
        close(
            Vector3::new(vel[3], vel[4], vel[5]),
            r0.transpose() * w_fd,
            1e-5,
            "frame angular velocity",
        );
        // Angular acceleration: the derivative of the world angular velocity (J u at q(t), u(t)).
        let w_world = |(x, ut): &(Vec<f64>, Vec<f64>)| {
            let j = DMatrix::from_row_slice(
                6,
                n,
                &eval_at(FunctionId::FrameJacobian, Some(l), x, &zero, &zero),
            );
            let w = &j * DVector::from_vec(ut.clone());
            free_flyer::base_rotation(x) * Vector3::new(w[3], w[4], w[5])
        };
        let alpha_fd = (w_world(&samples[2]) - w_world(&samples[0])) / (2.0 * h);
        close(
            Vector3::new(acc[3], acc[4], acc[5]),
            r0.transpose() * alpha_fd,
            1e-5,
            "frame angular acceleration",
        );
    }
    // Centre of mass: position, J u, J u̇ + bias.
    let com = |x: &[f64]| free_flyer::center_of_mass(&model, &params, x);
    let c = eval_at(FunctionId::CenterOfMass, None, &q, &zero, &zero);
    close(
        Vector3::new(c[0], c[1], c[2]),
        com(&q),
        1e-12,
        "centre of mass",
    );
    let jg = DMatrix::from_row_slice(
        3,
        n,
        &eval_at(FunctionId::ComJacobian, None, &q, &zero, &zero),
    );
    let bg = eval_at(FunctionId::ComBiasAcceleration, None, &q, &u, &zero);
    let cs = samples.clone().map(|(x, _)| com(&x));
    let vg = &jg * DVector::from_vec(u.clone());
    let ag = &jg * DVector::from_vec(ud.clone()) + DVector::from_vec(bg);
    close(
        Vector3::new(vg[0], vg[1], vg[2]),
        r0.transpose() * (cs[2] - cs[0]) / (2.0 * h),
        1e-6,
        "CoM velocity",
    );
    close(
        Vector3::new(ag[0], ag[1], ag[2]),
        r0.transpose() * (cs[2] - 2.0 * cs[1] + cs[0]) / (h * h),
        1e-5,
        "CoM acceleration",
    );
    // Centroidal momentum: A_G u against the bodies' momentum, A_G u̇ + Ȧ_G u against the
    // derivative of A_G u along the motion, I_G against a rigid rotation.
    let ag_at = |x: &[f64]| {
        DMatrix::from_row_slice(
            6,
            n,
            &eval_at(FunctionId::CentroidalMomentumMatrix, None, x, &zero, &zero),
        )
    };
    let ag = ag_at(&q);
    let hg = &ag * DVector::from_vec(u.clone());
    let (lin, ang) = free_flyer::centroidal_momentum(&model, &params, &q, &u);
    close(
        Vector3::new(hg[0], hg[1], hg[2]),
        lin,
        1e-12,
        "linear momentum",
    );
    close(
        Vector3::new(hg[3], hg[4], hg[5]),
        ang,
        1e-12,
        "angular momentum about the CoM",
    );
    let bias = DVector::from_vec(eval_at(
        FunctionId::CentroidalMomentumBias,
        None,
        &q,
        &u,
        &zero,
    ));
    let rate = &ag * DVector::from_vec(ud.clone()) + bias;
    let hs = samples
        .clone()
        .map(|(x, ut)| ag_at(&x) * DVector::from_vec(ut));
    let fd = (&hs[2] - &hs[0]) / (2.0 * h);
    assert!(
        (&rate - &fd).amax() < 1e-6 * fd.amax().max(1.0),
        "{name}: Ȧ_G u\n{rate}\n{fd}"
    );
    let ig = DMatrix::from_row_slice(
        6,
        6,
        &eval_at(FunctionId::CentroidalInertia, None, &q, &zero, &zero),
    );
    let mut rigid = vec![0.0; n];
    rigid[3..6].copy_from_slice(&u[3..6]);
    let (_, ang) = free_flyer::centroidal_momentum(&model, &params, &q, &rigid);
    let w_world = r0 * Vector3::new(u[3], u[4], u[5]);
    let jg = ig.fixed_view::<3, 3>(3, 3).into_owned();
    close(jg * w_world, ang, 1e-12, "I_G ω = L_G");
    let total: f64 = model
        .links
        .iter()
        .filter_map(|l| l.body.as_ref())
        .map(|b| params[b.mass])
        .sum();
    assert!(
        (ig[(0, 0)] - total).abs() < 1e-12 * total,
        "{name}: I_G mass"
    );

    // Energies.
    let m = DMatrix::from_row_slice(
        n,
        n,
        &d.evaluate(FunctionId::MassMatrix, &params, &q, &zero, &zero),
    );
    let t = d.evaluate(FunctionId::KineticEnergy, &params, &q, &u, &zero)[0];
    let uv = DVector::from_vec(u.clone());
    assert!(
        (t - 0.5 * uv.dot(&(&m * &uv))).abs() < 1e-10 * t.abs().max(1.0),
        "{name}: T = ½ uᵀMu"
    );
    let t_ref = free_flyer::kinetic_energy(&model, &params, &q, &u);
    assert!(
        (t - t_ref).abs() < 1e-10 * t_ref.abs().max(1.0),
        "{name}: T"
    );
    let v = d.evaluate(FunctionId::PotentialEnergy, &params, &q, &zero, &zero)[0];
    let v_ref = free_flyer::potential_energy(&model, &params, &q);
    assert!(
        (v - v_ref).abs() < 1e-10 * v_ref.abs().max(1.0),
        "{name}: V {v} vs {v_ref}"
    );
}

#[test]
fn floating_kinematics_and_energies_match_the_recursion_and_finite_differences() {
    check_kinematics("floating-hopper.toml", 13);
    check_kinematics("solo12.urdf", 14);
}

#[test]
fn floating_toml_model_dynamics_match_the_free_flyer_recursion() {
    check_model("floating-hopper.toml", 11);
}

#[test]
fn floating_solo12_dynamics_match_the_free_flyer_recursion() {
    check_model("solo12.urdf", 12);
}

/// The tree of `fixed` on a floating base (its speeds after the base's six).
fn on_floating_base(fixed: &Model) -> Model {
    let mut m = fixed.clone();
    m.base = Base::Floating;
    let mut speeds = floating_base_speeds();
    speeds.append(&mut m.speeds);
    m.speeds = speeds;
    for link in &mut m.links {
        if let Some(mount) = &mut link.mount {
            mount.joint.kind = match mount.joint.kind {
                JointKind::Revolute { speed } => JointKind::Revolute { speed: speed + 6 },
                JointKind::Prismatic { speed } => JointKind::Prismatic { speed: speed + 6 },
                JointKind::Fixed => JointKind::Fixed,
            };
        }
    }
    m
}

#[test]
fn fixed_base_centroidal_functions_equal_the_floating_tree_at_rest() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let arm = Model::from_urdf_file(dir.join("models/singlearm.urdf"), &UrdfOptions::default())
        .expect("imports");
    let two_link = Model::from_toml_file(dir.join("models/two-link.toml")).expect("loads");
    let functions: FunctionSet = FunctionSet::centroidal()
        .iter()
        .chain([
            FunctionId::CenterOfMass,
            FunctionId::ComJacobian,
            FunctionId::ComBiasAcceleration,
        ])
        .collect();
    for (k, fixed) in [arm, two_link].into_iter().enumerate() {
        let floating = on_floating_base(&fixed);
        let options = Options {
            functions,
            ..Options::default()
        };
        let (df, dl) = (derive(&fixed, options), derive(&floating, options));
        let n = fixed.dof();
        let mut r = SplitMix64::new(40 + k as u64);
        let mut uniform = move || r.next_f64();
        let params = random_physical_params(&fixed, &mut uniform);
        let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
        let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
        let mut qf = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        qf.extend(&q);
        let mut uf = vec![0.0; 6];
        uf.extend(&u);
        let zero = vec![0.0; n];
        let zf = vec![0.0; n + 6];
        let ag = df.evaluate(
            FunctionId::CentroidalMomentumMatrix,
            &params,
            &q,
            &zero,
            &zero,
        );
        let agf = dl.evaluate(FunctionId::CentroidalMomentumMatrix, &params, &qf, &zf, &zf);
        for row in 0..6 {
            for col in 0..n {
                let (a, b) = (ag[row * n + col], agf[row * (n + 6) + 6 + col]);
                assert!(
                    (a - b).abs() < 1e-12 * b.abs().max(1.0),
                    "{}: A_G[{row},{col}] {a} vs {b}",
                    fixed.name
                );
            }
        }
        let bias = DVector::from_vec(df.evaluate(
            FunctionId::CentroidalMomentumBias,
            &params,
            &q,
            &u,
            &zero,
        ));
        let biasf = DVector::from_vec(dl.evaluate(
            FunctionId::CentroidalMomentumBias,
            &params,
            &qf,
            &uf,
            &zf,
        ));
        assert!(rel_err(&bias, &biasf) < 1e-12, "{}: Ȧ_G u", fixed.name);
        let ig = DVector::from_vec(df.evaluate(
            FunctionId::CentroidalInertia,
            &params,
            &q,
            &zero,
            &zero,
        ));
        let igf =
            DVector::from_vec(dl.evaluate(FunctionId::CentroidalInertia, &params, &qf, &zf, &zf));
        assert!(rel_err(&ig, &igf) < 1e-12, "{}: I_G", fixed.name);
        // Linear rows: m J_G and m times the CoM bias.
        let jg = df.evaluate(FunctionId::ComJacobian, &params, &q, &zero, &zero);
        let m = ig[0];
        for row in 0..3 {
            for col in 0..n {
                assert!((ag[row * n + col] - m * jg[row * n + col]).abs() < 1e-12 * m.max(1.0));
            }
        }
        let ab = df.evaluate(FunctionId::ComBiasAcceleration, &params, &q, &u, &zero);
        for row in 0..3 {
            assert!(
                (bias[row] - m * ab[row]).abs() < 1e-10 * m.max(1.0),
                "{}: linear bias",
                fixed.name
            );
        }
    }
}

/// A small URDF whose root is a bare `world` link with one `floating` joint.
const WORLD_FLOATING: &str = r#"<robot name="hopper">
  <link name="world"/>
  <link name="torso"><inertial><origin xyz="0.01 0 0.05"/><mass value="3"/>
    <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.06" iyz="0" izz="0.04"/></inertial></link>
  <link name="leg"><inertial><origin xyz="0 0 -0.2"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial></link>
  <joint name="root" type="floating"><parent link="world"/><child link="torso"/></joint>
  <joint name="hip" type="revolute"><parent link="torso"/><child link="leg"/>
    <origin xyz="0 0 -0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
</robot>"#;

#[test]
fn a_urdf_hanging_from_a_world_floating_joint_gets_a_floating_base_by_default() {
    let import =
        kanegen::model::UrdfImport::parse(WORLD_FLOATING, "hopper.urdf", &UrdfOptions::default())
            .expect("imports");
    let m = &import.model;
    assert!(m.is_floating());
    assert_eq!(m.links[0].name, "torso");
    assert!(m.links[0].body.is_some(), "the base frame's inertia counts");
    assert_eq!(m.dof(), 7);
    assert_eq!(m.nq(), 8);
    assert_eq!(
        m.coordinate_names(),
        [
            "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw", "q_hip"
        ]
    );
    assert!(
        import
            .notes
            .iter()
            .any(|n| n.contains("floating joint `root`")),
        "{:?}",
        import.notes
    );
    // The same file with the root declared floating explicitly.
    let declared = Model::from_urdf_str(WORLD_FLOATING, "hopper.urdf", &UrdfOptions::floating())
        .expect("imports");
    assert_eq!(&declared, m);
}

/// `model` with its arm joint an exact mimic of its hip.
fn with_mimic(model: &Model) -> Model {
    let mut m = model.clone();
    let (arm, hip) = (
        m.speed_index("qd_arm").unwrap(),
        m.speed_index("qd_hip").unwrap(),
    );
    m.mimics.push(kanegen::model::Mimic {
        speed: arm,
        master: hip,
        multiplier: 1.0,
        offset: 0.0,
    });
    m
}

#[test]
fn what_a_floating_base_does_not_generate_is_a_typed_error() {
    let model = model("floating-hopper.toml");
    for (what, builder) in [
        (
            "coriolis_matrix of a mimic model",
            kanegen::Builder::from_model(with_mimic(&model)).coriolis_matrix(false),
        ),
        ("mimic", kanegen::Builder::from_model(with_mimic(&model))),
        (
            "GPU kernels",
            kanegen::Builder::from_model(model.clone()).gpu(true),
        ),
        (
            "GPU kernels of one function",
            kanegen::Builder::from_model(model.clone())
                .gpu_functions([FunctionId::MassMatrix].into_iter().collect()),
        ),
    ] {
        let err = builder
            .generate()
            .expect_err("not generated for a floating base");
        let text = err.to_string();
        assert!(
            matches!(err, kanegen::Error::FloatingBase { .. }),
            "{what}: {text}"
        );
        assert!(
            text.contains("floating-hopper") && text.contains("floating base"),
            "{what}: {text}"
        );
    }
}

#[test]
fn floating_modules_have_nq_coordinates_and_combined_functions() {
    let model = model("floating-hopper.toml");
    let combined = kanegen::Combined::new("whole_body")
        .with(FunctionId::MassMatrix)
        .with(FunctionId::NonlinearEffects)
        .with_frame(FunctionId::FrameJacobian, "foot");
    let g = kanegen::Builder::from_model(model.clone())
        .functions(FunctionSet::default().with(FunctionId::CentroidalMomentumMatrix))
        .combined(combined)
        .generate()
        .expect("generates");
    assert!(g.source.contains("pub const NQ: usize = 10;"));
    assert!(g.source.contains("pub const COORDINATE_NAMES: [&str; 10]"));
    assert!(
        g.source
            .contains("impl kanegen_runtime::Multibody<DOF> for FloatingHopper")
    );
    assert!(g.source.contains("q: &SVector<f64, 10>"));
    let mut r = SplitMix64::new(50);
    let mut uniform = move || r.next_f64();
    let params = random_physical_params(&model, &mut uniform);
    let q = free_flyer::random_configuration(&model, &mut uniform);
    let u = uniform_vec(&mut uniform, 9, -1.0, 1.0);
    let zero = vec![0.0; 9];
    let parts = g.lowered.evaluate_combined(0, &params, &q, &u, &zero);
    assert_eq!(
        parts[0],
        g.lowered
            .evaluate(FunctionId::MassMatrix, &params, &q, &zero, &zero)
    );
    let h = free_flyer::rnea(&model, &params, &q, &u, &zero, true);
    assert!(rel_err(&DVector::from_vec(parts[1].clone()), &h) < 1e-10);
}

#[test]
fn wheeled_centroidal_momentum_is_consistent_with_the_centre_of_mass_and_its_rate() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let krang = Model::from_toml_file(dir.join("models/krang.toml")).expect("loads");
    let functions: FunctionSet = [
        FunctionId::CentroidalMomentumMatrix,
        FunctionId::CentroidalMomentumBias,
        FunctionId::CentroidalInertia,
        FunctionId::ComJacobian,
        FunctionId::ComBiasAcceleration,
    ]
    .into_iter()
    .collect();
    let d = derive(
        &krang,
        Options {
            functions,
            ..Options::default()
        },
    );
    let n = krang.dof();
    let mut r = SplitMix64::new(60);
    let mut uniform = move || r.next_f64();
    let params = random_physical_params(&krang, &mut uniform);
    let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
    let u = uniform_vec(&mut uniform, n, -1.5, 1.5);
    let ud = uniform_vec(&mut uniform, n, -3.0, 3.0);
    let zero = vec![0.0; n];
    let ag_at = |x: &[f64]| {
        DMatrix::from_row_slice(
            6,
            n,
            &d.evaluate(
                FunctionId::CentroidalMomentumMatrix,
                &params,
                x,
                &zero,
                &zero,
            ),
        )
    };
    let ag = ag_at(&q);
    let ig = d.evaluate(FunctionId::CentroidalInertia, &params, &q, &zero, &zero);
    let m = ig[0];
    // Linear rows: m J_G (wheels included) and m times the CoM bias.
    let jg = DMatrix::from_row_slice(
        3,
        n,
        &d.evaluate(FunctionId::ComJacobian, &params, &q, &zero, &zero),
    );
    assert!(
        (ag.rows(0, 3) - &jg * m).amax() < 1e-12 * m,
        "A_G linear rows"
    );
    let bias = d.evaluate(FunctionId::CentroidalMomentumBias, &params, &q, &u, &zero);
    let ab = d.evaluate(FunctionId::ComBiasAcceleration, &params, &q, &u, &zero);
    for k in 0..3 {
        assert!((bias[k] - m * ab[k]).abs() < 1e-10 * m, "linear bias");
    }
    // A_G u̇ + Ȧ_G u is the rate of A_G u in frame 0's axes, which turn at ψ̇ about z:
    // d/dt (R_ψ h) = R_ψ (ḣ + ψ̇ ẑ × h), with h(t) = A_G(q(t)) u(t), q(t) = q + u t + ½ u̇ t².
    let psi = krang.speed_index("psid").expect("ψ̇");
    let at = |t: f64| {
        let x: Vec<f64> = (0..n)
            .map(|i| q[i] + u[i] * t + 0.5 * ud[i] * t * t)
            .collect();
        let v: Vec<f64> = (0..n).map(|i| u[i] + ud[i] * t).collect();
        ag_at(&x) * DVector::from_vec(v)
    };
    let h = 1e-5;
    let hdot = (at(h) - at(-h)) / (2.0 * h);
    let h0 = &ag * DVector::from_vec(u.clone());
    let rate = &ag * DVector::from_vec(ud.clone()) + DVector::from_vec(bias);
    let w = Vector3::new(0.0, 0.0, u[psi]);
    for part in [0, 3] {
        let hv = Vector3::new(h0[part], h0[part + 1], h0[part + 2]);
        let expected = Vector3::new(hdot[part], hdot[part + 1], hdot[part + 2]) + w.cross(&hv);
        let got = Vector3::new(rate[part], rate[part + 1], rate[part + 2]);
        assert!(
            (got - expected).norm() < 1e-6 * expected.norm().max(1.0),
            "rows {part}..: {got} vs {expected}"
        );
    }
}
