//! Forward dynamics along the tree (`SPEED_PARENTS`, `kanegen_runtime::tree_factor`) of
//! generated robots: the parent arrays the generator emits, and the forward dynamics, free and
//! under contacts, against the dense factorisation and the free-flyer reference recursion
//! (`kanegen_reference::FreeFlyer`, independent of the generator).

#[path = "../codegen/tests/support/free_flyer.rs"]
mod free_flyer;

use kanegen::model::{Model, UrdfOptions};
use kanegen_reference::FreeFlyer;
use kanegen_runtime::Multibody;
use kanegen_runtime::contact::{
    Contact, ContactJacobian, ContactSettings, constrained_forward_dynamics,
    constrained_forward_dynamics_factored, contact_impulse, contact_impulse_factored,
};
use kanegen_runtime::tree_factor::{TreeFactor, chain_parents};
use nalgebra::{DVector, SMatrix, SVector};

#[allow(dead_code)]
mod solo {
    include!(concat!(env!("OUT_DIR"), "/solo12_floating.rs"));
}

#[allow(dead_code)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm.rs"));
}

#[allow(dead_code)]
mod two_link_f32 {
    include!(concat!(env!("OUT_DIR"), "/two_link_all_baked_f32.rs"));
}

#[allow(dead_code)]
mod gripper {
    include!(concat!(env!("OUT_DIR"), "/mimic_gripper_all.rs"));
}

fn solo_model() -> Model {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    Model::from_urdf_file(
        root.join("tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports")
}

/// A deterministic pseudo-random stream in [0, 1).
fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut r = kanegen_reference::random::SplitMix64::new(seed);
    move || r.next_f64()
}

fn random<const N: usize>(uniform: &mut dyn FnMut() -> f64, a: f64) -> SVector<f64, N> {
    SVector::from_fn(|_, _| a * (2.0 * uniform() - 1.0))
}

/// `M⁻¹ (τ − c − g)` by nalgebra's dense Cholesky factorisation.
fn dense_forward_dynamics<R: Multibody<N, Scalar = f64>, const N: usize>(
    robot: &R,
    q: &R::Configuration,
    u: &SVector<f64, N>,
    tau: &SVector<f64, N>,
) -> SVector<f64, N> {
    let bias = robot.inverse_dynamics(q, u, &SVector::zeros());
    robot
        .mass_matrix(q)
        .cholesky()
        .unwrap()
        .solve(&(tau - bias))
}

fn close<const N: usize>(a: &SVector<f64, N>, b: &SVector<f64, N>, tol: f64) -> bool {
    (a - b).amax() <= tol * b.amax().max(1.0)
}

#[test]
fn generated_speed_parents_follow_the_tree() {
    // Solo 12: the base's chain, then four legs of three joints hanging from the base.
    let mut expected = chain_parents::<18>();
    for leg in 0..4 {
        expected[6 + 3 * leg] = Some(5);
    }
    assert_eq!(solo::SPEED_PARENTS, expected);
    assert_eq!(
        <solo::Solo as Multibody<18>>::SPEED_PARENTS,
        Some(solo::SPEED_PARENTS)
    );
    // An arm is a chain; so is its parent array.
    assert_eq!(arm::SPEED_PARENTS, chain_parents());
    assert_eq!(
        <arm::SingleArm as Multibody<7>>::SPEED_PARENTS,
        Some(chain_parents())
    );
    // Krang: the wheeled base's two speeds at the root, then the torso, from which the two arms
    // branch (the first joint of the second arm does not hang from the joint before it).
    let krang = krang_dynamics::SPEED_PARENTS;
    assert_eq!(&krang[..2], &[None, Some(0)]);
    assert!(
        krang
            .iter()
            .enumerate()
            .any(|(i, p)| i > 0 && *p != Some(i - 1))
    );
    // Mimic joints couple a master's ancestors with the dependent joint's: no parent array.
    assert_eq!(
        <gripper::MimicGripper as Multibody<{ gripper::DOF }>>::SPEED_PARENTS,
        None
    );
}

#[test]
fn floating_solo12_forward_dynamics_along_the_tree_matches_the_dense_one_and_the_reference() {
    let model = solo_model();
    let robot = solo::Solo::default();
    let ff = FreeFlyer::new(&model).unwrap();
    let mut uniform = stream(7);
    for _ in 0..20 {
        let q = SVector::<f64, 19>::from_column_slice(&free_flyer::random_configuration(
            &model,
            &mut uniform,
        ));
        let u: SVector<f64, 18> = random(&mut uniform, 2.0);
        let tau: SVector<f64, 18> = random(&mut uniform, 5.0);
        let ud = robot.forward_dynamics(&q, &u, &tau).unwrap();
        assert!(close(
            &ud,
            &dense_forward_dynamics(&robot, &q, &u, &tau),
            1e-10
        ));
        // The reference's inverse dynamics of the result give back τ.
        let back = ff.inverse_dynamics(q.as_slice(), u.as_slice(), ud.as_slice());
        let tau_ref = DVector::from_column_slice(tau.as_slice());
        assert!((back - &tau_ref).amax() <= 1e-9 * tau_ref.amax().max(1.0));
    }
}

#[test]
fn generated_straight_line_kernels_give_the_runtime_loops_factor() {
    let model = solo_model();
    let robot = solo::Solo::default();
    let mut uniform = stream(17);
    for _ in 0..10 {
        let q = SVector::<f64, 19>::from_column_slice(&free_flyer::random_configuration(
            &model,
            &mut uniform,
        ));
        let m = robot.mass_matrix(&q);
        let kernels = robot.mass_matrix_factor(&q).unwrap();
        let loops = TreeFactor::new(&m, &solo::SPEED_PARENTS).unwrap();
        let direct =
            TreeFactor::with_kernels(&m, &solo::SPEED_PARENTS, solo::TREE_KERNELS).unwrap();
        let (dk, dl) = (kernels.pivots(), loops.pivots());
        assert!(close(&dk, &dl, 1e-12));
        assert_eq!(dk, direct.pivots());
        let b: SVector<f64, 18> = random(&mut uniform, 3.0);
        assert!(close(&kernels.solve(&b), &loops.solve(&b), 1e-11));
        let mut cols = SMatrix::<f64, 18, 3>::from_fn(|_, _| uniform());
        let expected = m.cholesky().unwrap().solve(&cols);
        kernels.solve_columns(&mut cols);
        assert!((cols - expected).amax() <= 1e-10 * expected.amax());
        // Not positive definite: the kernels refuse it as the loops do.
        assert!(
            TreeFactor::with_kernels(&(-m), &solo::SPEED_PARENTS, solo::TREE_KERNELS).is_none()
        );
    }
    // An f32 module with its parameters baked in has the kernels in f32.
    let two = two_link_f32::TwoLink;
    let q = SVector::<f32, 2>::from([0.3, -0.7]);
    let m = kanegen_runtime::RobotDynamics::mass_matrix(&two, &q);
    let b = SVector::<f32, 2>::from([1.0, 2.0]);
    let x = kanegen_runtime::RobotDynamics::mass_matrix_factor(&two, &q)
        .unwrap()
        .solve(&b);
    assert!((m * x - b).amax() < 1e-5);
}

#[test]
fn fixed_and_wheeled_forward_dynamics_along_the_tree_match_the_dense_one() {
    let arm = arm::SingleArm::default();
    let krang = krang_dynamics::Krang::default();
    let mut uniform = stream(11);
    for _ in 0..20 {
        let (q, u, tau) = (
            random::<7>(&mut uniform, 3.0),
            random::<7>(&mut uniform, 2.0),
            random::<7>(&mut uniform, 5.0),
        );
        let ud = Multibody::forward_dynamics(&arm, &q, &u, &tau).unwrap();
        assert!(close(
            &ud,
            &dense_forward_dynamics(&arm, &q, &u, &tau),
            1e-10
        ));
        let (q, u, tau) = (
            random::<19>(&mut uniform, 3.0),
            random::<19>(&mut uniform, 2.0),
            random::<19>(&mut uniform, 5.0),
        );
        let ud = Multibody::forward_dynamics(&krang, &q, &u, &tau).unwrap();
        assert!(close(
            &ud,
            &dense_forward_dynamics(&krang, &q, &u, &tau),
            1e-10
        ));
        // Krang's own block Cholesky (its inherent method) agrees.
        assert!(close(&ud, &krang.forward_dynamics(&q, &u, &tau), 1e-10));
    }
}

const FEET: [solo::Frame; 4] = [
    solo::Frame::FLFOOT,
    solo::Frame::FRFOOT,
    solo::Frame::HLFOOT,
    solo::Frame::HRFOOT,
];

#[test]
fn solo12_contact_dynamics_through_the_tree_factor_match_the_dense_forms() {
    let model = solo_model();
    let robot = solo::Solo::default();
    let contacts = FEET.map(Contact::point);
    let mut uniform = stream(13);
    let settings = [
        ContactSettings::default(),
        ContactSettings {
            damping: 1e-6,
            baumgarte_position: 50.0,
            baumgarte_velocity: 10.0,
        },
    ];
    for _ in 0..10 {
        let q = SVector::<f64, 19>::from_column_slice(&free_flyer::random_configuration(
            &model,
            &mut uniform,
        ));
        let u: SVector<f64, 18> = random(&mut uniform, 1.0);
        let mut f: SVector<f64, 18> = random(&mut uniform, 5.0);
        f.fixed_rows_mut::<6>(0).fill(0.0);
        let jc = ContactJacobian::<f64, 18, 12>::stack(&contacts, &u, |frame| {
            (
                robot.frame_jacobian(&q, frame),
                robot.frame_bias_acceleration(&q, &u, frame),
            )
        })
        .unwrap();
        let m = robot.mass_matrix(&q);
        let h = Multibody::inverse_dynamics(&robot, &q, &u, &SVector::zeros());
        let factor: TreeFactor<f64, 18> = robot.mass_matrix_factor(&q).unwrap();
        assert_eq!(factor.parents(), &solo::SPEED_PARENTS);
        for s in &settings {
            let dense = constrained_forward_dynamics(m, &h, &f, &jc, s).unwrap();
            let tree = constrained_forward_dynamics_factored(&factor, &h, &f, &jc, s).unwrap();
            assert!(close(&tree.ud, &dense.ud, 1e-9));
            assert!(close(&tree.lambda, &dense.lambda, 1e-9));
            // Both equations, to rounding.
            let residual: SVector<f64, 18> =
                m * tree.ud + h - f - jc.jacobian.transpose() * tree.lambda;
            assert!(
                residual.amax() <= 1e-9 * (f - h).amax().max(1.0),
                "{residual}"
            );
            if s.damping == 0.0 {
                let constraint = jc.jacobian * tree.ud + jc.bias;
                assert!(constraint.amax() <= 1e-9 * jc.bias.amax().max(1.0));
            }
            let dense = contact_impulse(m, &u, &jc, 0.2, s).unwrap();
            let tree = contact_impulse_factored(&factor, &u, &jc, 0.2, s).unwrap();
            assert!(close(&tree.u_plus, &dense.u_plus, 1e-9));
            assert!(close(&tree.impulse, &dense.impulse, 1e-9));
        }
    }
}

#[test]
fn a_dense_robot_factor_is_the_chains() {
    // A hand-written robot with no parent array factors its mass matrix densely.
    struct Dense;
    impl kanegen_runtime::RobotDynamics<3> for Dense {
        type Scalar = f64;
        const SPEED_NAMES: [&'static str; 3] = ["a", "b", "c"];
        const COORDINATE_NAMES: [&'static str; 3] = ["a", "b", "c"];
        fn mass_matrix(&self, _: &SVector<f64, 3>) -> SMatrix<f64, 3, 3> {
            SMatrix::<f64, 3, 3>::new(4.0, 1.0, 2.0, 1.0, 3.0, 1.0, 2.0, 1.0, 5.0)
        }
        fn coriolis(&self, _: &SVector<f64, 3>, _: &SVector<f64, 3>) -> SVector<f64, 3> {
            SVector::zeros()
        }
        fn gravity(&self, _: &SVector<f64, 3>) -> SVector<f64, 3> {
            SVector::zeros()
        }
        fn inverse_dynamics(
            &self,
            q: &SVector<f64, 3>,
            _: &SVector<f64, 3>,
            ud: &SVector<f64, 3>,
        ) -> SVector<f64, 3> {
            kanegen_runtime::RobotDynamics::mass_matrix(self, q) * ud
        }
    }
    let q = SVector::zeros();
    let factor = Multibody::mass_matrix_factor(&Dense, &q).unwrap();
    assert_eq!(factor.parents(), &chain_parents());
    let b = SVector::from([1.0, -2.0, 0.5]);
    let m = Multibody::mass_matrix(&Dense, &q);
    assert!((m * factor.solve(&b) - b).amax() < 1e-14);
}
