//! Generated floating-base modules (`models/floating-hopper.toml` and Solo 12, from this
//! package's build script), compiled:
//!
//! * M, c, g, τ and the nonlinear effects equal the free-flyer reference recursion
//!   (`kanegen_reference::FreeFlyer`, through the adapters of
//!   `codegen/tests/support/free_flyer.rs`), at random states;
//! * the wrapper's `integrate` keeps the quaternion unit, `integrate(q0, difference(q0, q1), 1)
//!   = q1`, and `integrate` is the recursion's `q ⊕ δ`;
//! * free fall: with τ = 0 the forward dynamics (the `Multibody` trait's) accelerate the centre of
//!   mass at g, measured by second differences along the motion integrated with `integrate`;
//! * one generic controller, written against `kanegen_runtime::Multibody`, runs on a fixed-base
//!   arm and on both floating robots;
//! * the hopper's batched functions equal its single-state ones.

#[path = "../codegen/tests/support/free_flyer.rs"]
mod free_flyer;

use kanegen::model::{Model, UrdfOptions};
use kanegen_runtime::Multibody;
use nalgebra::{DVector, SVector};

#[allow(dead_code)]
mod hopper {
    include!(concat!(env!("OUT_DIR"), "/floating_hopper.rs"));
}

#[allow(dead_code)]
mod solo {
    include!(concat!(env!("OUT_DIR"), "/solo12_floating.rs"));
}

#[allow(dead_code)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm.rs"));
}

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn hopper_model() -> Model {
    Model::from_toml_file(root().join("models/floating-hopper.toml")).expect("loads")
}

fn solo_model() -> Model {
    Model::from_urdf_file(
        root().join("tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports")
}

/// A deterministic pseudo-random stream in [0, 1).
fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut r = kanegen_reference::random::SplitMix64::new(seed);
    move || r.next_f64()
}

fn random_speeds<const N: usize>(uniform: &mut dyn FnMut() -> f64, a: f64) -> SVector<f64, N> {
    SVector::from_fn(|_, _| a * (2.0 * uniform() - 1.0))
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

/// A robot's nonlinear effects `h(q, u)` (an inherent method of the generated wrapper).
type Nle<'a, const N: usize, const NQ: usize> =
    &'a dyn Fn(&SVector<f64, NQ>, &SVector<f64, N>) -> SVector<f64, N>;

/// The generated functions against the recursion, the configuration helpers and free fall, for
/// one floating robot `R` with `N` speeds and `NQ` coordinates.
fn check<
    R: Multibody<N, Scalar = f64, Configuration = SVector<f64, NQ>>,
    const N: usize,
    const NQ: usize,
>(
    robot: &R,
    model: &Model,
    nle: Nle<'_, N, NQ>,
    seed: u64,
) {
    assert_eq!(R::COORDINATE_NAMES.len(), NQ);
    assert_eq!(R::COORDINATE_NAMES, model.coordinate_names().as_slice());
    let params = model.param_values();
    let mut uniform = stream(seed);
    for _ in 0..3 {
        let q = SVector::<f64, NQ>::from_column_slice(&free_flyer::random_configuration(
            model,
            &mut uniform,
        ));
        let u: SVector<f64, N> = random_speeds(&mut uniform, 2.0);
        let ud: SVector<f64, N> = random_speeds(&mut uniform, 5.0);
        let dv = |v: SVector<f64, N>| DVector::from_column_slice(v.as_slice());
        let zero = [0.0; N];
        let tau_ref = free_flyer::rnea(
            model,
            &params,
            q.as_slice(),
            u.as_slice(),
            ud.as_slice(),
            true,
        );
        let c_ref = free_flyer::rnea(model, &params, q.as_slice(), u.as_slice(), &zero, false);
        let g_ref = free_flyer::rnea(model, &params, q.as_slice(), &zero, &zero, true);
        let m_ref = free_flyer::mass_matrix(model, &params, q.as_slice());
        assert!(
            rel(&dv(robot.inverse_dynamics(&q, &u, &ud)), &tau_ref) < 1e-10,
            "τ"
        );
        assert!(rel(&dv(robot.coriolis(&q, &u)), &c_ref) < 1e-10, "c");
        assert!(rel(&dv(robot.gravity(&q)), &g_ref) < 1e-10, "g");
        assert!(
            rel(&dv(nle(&q, &u)), &(&c_ref + &g_ref)) < 1e-10,
            "nonlinear effects"
        );
        let m = robot.mass_matrix(&q);
        let m_d = nalgebra::DMatrix::from_column_slice(N, N, m.as_slice());
        assert!((m_d - &m_ref).amax() < 1e-10 * m_ref.amax(), "M");

        // The configuration helpers.
        let q1 = robot.integrate(&q, &u, 0.7);
        assert!(
            (q1.fixed_rows::<4>(3).norm() - 1.0).abs() < 1e-14,
            "unit quaternion"
        );
        let back = robot.integrate(&q, &robot.difference(&q, &q1), 1.0);
        assert!(
            (back - q1).amax() < 1e-13,
            "integrate(q0, difference(q0, q1), 1) = q1"
        );
        let ours = free_flyer::integrate(model, q.as_slice(), (u * 0.7).as_slice());
        assert!(
            (q1 - SVector::<f64, NQ>::from_column_slice(&ours)).amax() < 1e-13,
            "q ⊕ δ"
        );

        // Free fall: τ = 0, the centre of mass accelerates at g. Its second difference along the
        // motion (u(t) = u + u̇ t, integrated in small midpoint steps on SE(3)).
        let fall = robot
            .forward_dynamics(&q, &u, &SVector::zeros())
            .expect("M positive definite");
        let at = |t: f64| {
            let steps = 20;
            let dt = t / steps as f64;
            let mut x = q;
            for k in 0..steps {
                let mid = u + fall * (dt * (k as f64 + 0.5));
                x = robot.integrate(&x, &mid, dt);
            }
            free_flyer::center_of_mass(model, &params, x.as_slice())
        };
        let h = 1e-3;
        let acc = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
        let g = params[model.gravity.symbol] * nalgebra::Vector3::from(model.gravity.direction);
        assert!(
            (acc - g).norm() < 1e-4 * g.norm(),
            "free fall: {acc} vs {g}"
        );
    }
}

#[test]
fn floating_hopper_generated_dynamics_helpers_and_free_fall() {
    let robot = hopper::FloatingHopper::default();
    check(
        &robot,
        &hopper_model(),
        &|q, u| robot.nonlinear_effects(q, u),
        21,
    );
}

#[test]
fn floating_solo12_generated_dynamics_helpers_and_free_fall() {
    let robot = solo::Solo::default();
    check(
        &robot,
        &solo_model(),
        &|q, u| robot.nonlinear_effects(q, u),
        22,
    );
}

/// A PD law in the tangent space, written once: the torque that gives
/// `u̇ = kp · difference(q, q_ref) − kd · u` (the base rows are what the base would need).
fn pd<R: Multibody<N, Scalar = f64>, const N: usize>(
    robot: &R,
    q: &R::Configuration,
    u: &SVector<f64, N>,
    q_ref: &R::Configuration,
) -> (SVector<f64, N>, SVector<f64, N>) {
    let ud = robot.difference(q, q_ref) * 25.0 - u * 10.0;
    (robot.inverse_dynamics(q, u, &ud), ud)
}

/// Runs the generic law on `robot` from `q0` toward a configuration a step away: the forward
/// dynamics of its torque give back the commanded acceleration.
fn run_generic<R: Multibody<N, Scalar = f64>, const N: usize>(robot: &R, seed: u64) {
    let mut uniform = stream(seed);
    let q =
        robot.normalize(&robot.integrate(&robot.neutral(), &random_speeds(&mut uniform, 0.5), 1.0));
    let q_ref = robot.integrate(&q, &random_speeds(&mut uniform, 0.3), 1.0);
    let u: SVector<f64, N> = random_speeds(&mut uniform, 1.0);
    let (tau, ud) = pd(robot, &q, &u, &q_ref);
    let back = robot
        .forward_dynamics(&q, &u, &tau)
        .expect("M positive definite");
    assert!((back - ud).amax() < 1e-8 * ud.amax().max(1.0));
}

#[test]
fn one_generic_controller_runs_on_fixed_and_floating_robots() {
    run_generic(&arm::SingleArm::default(), 31);
    run_generic(&hopper::FloatingHopper::default(), 32);
    run_generic(&solo::Solo::default(), 33);
}

#[test]
fn floating_batched_functions_equal_the_single_state_ones() {
    let robot = hopper::FloatingHopper::default();
    let model = hopper_model();
    let mut uniform = stream(41);
    let qs: [SVector<f64, 10>; 4] = core::array::from_fn(|_| {
        SVector::from_column_slice(&free_flyer::random_configuration(&model, &mut uniform))
    });
    let us: [SVector<f64, 9>; 4] = core::array::from_fn(|_| random_speeds(&mut uniform, 2.0));
    let uds: [SVector<f64, 9>; 4] = core::array::from_fn(|_| random_speeds(&mut uniform, 5.0));
    let m = robot.mass_matrix_batch(&qs);
    let tau = robot.inverse_dynamics_batch(&qs, &us, &uds);
    let dd = robot.inverse_dynamics_derivatives_batch(&qs, &us, &uds);
    for l in 0..4 {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        let m1 = robot.mass_matrix(&qs[l]);
        assert!(
            m[l].iter().zip(m1.iter()).all(|(a, b)| close(*a, *b)),
            "M, state {l}"
        );
        let t1 = robot.inverse_dynamics(&qs[l], &us[l], &uds[l]);
        assert!(
            tau[l].iter().zip(t1.iter()).all(|(a, b)| close(*a, *b)),
            "τ, state {l}"
        );
        let d1 = robot.inverse_dynamics_derivatives(&qs[l], &us[l], &uds[l]);
        assert!(
            dd[l].iter().zip(d1.iter()).all(|(a, b)| close(*a, *b)),
            "∂τ, state {l}"
        );
    }
}
