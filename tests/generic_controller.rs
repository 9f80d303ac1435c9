//! One controller, written once against `kanegen_runtime::RobotDynamics`, runs on every
//! generated robot: Krang (19 speeds, wheeled base), its baked module, the f32 module, the
//! two-link model and the 7-DOF arm generated from URDF by this package's build script; a
//! simulator's forward dynamics is the trait's too.

use kanegen_runtime::{CoriolisMatrix, RobotDynamics};
use krang_dynamics as kd;
use nalgebra::{RealField, SVector};

/// The 7-DOF arm generated from `models/singlearm.urdf` by this package's `build.rs`.
#[allow(dead_code)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm.rs"));
}

/// A reference trajectory sample: position, speed and acceleration.
struct Reference<T: RealField + Copy, const N: usize> {
    q: SVector<T, N>,
    u: SVector<T, N>,
    ud: SVector<T, N>,
}

/// Computed torque: the generalized forces that give the acceleration
/// `u̇ = u̇_ref + kd (u_ref − u) + kp (q_ref − q)`, i.e. `τ = M u̇ + c + g` in one
/// inverse-dynamics call. Generic over the robot and its scalar.
fn computed_torque<R: RobotDynamics<N>, const N: usize>(
    robot: &R,
    q: &SVector<R::Scalar, N>,
    u: &SVector<R::Scalar, N>,
    reference: &Reference<R::Scalar, N>,
    (kp, kd): (R::Scalar, R::Scalar),
) -> SVector<R::Scalar, N> {
    let ud = reference.ud + (reference.u - u) * kd + (reference.q - q) * kp;
    robot.inverse_dynamics(q, u, &ud)
}

/// Runs the controller on `robot` at a deterministic state: the robot's acceleration under the
/// computed torque equals the commanded one, and `C u = c` where the module has C. Returns the
/// relative error of the acceleration.
fn check<R: CoriolisMatrix<N>, const N: usize>(robot: &R, tol: f64) -> f64
where
    R::Scalar: RealField + Copy + From<f32> + Into<f64>,
{
    let s = |x: f64| R::Scalar::from(x as f32);
    let q = SVector::<R::Scalar, N>::from_fn(|i, _| s(0.3 * (i as f64 * 0.7).sin()));
    let u = SVector::<R::Scalar, N>::from_fn(|i, _| s(0.2 * (i as f64 * 1.3).cos()));
    let reference = Reference {
        q: q.map(|x| x + s(0.05)),
        u: SVector::<R::Scalar, N>::zeros(),
        ud: SVector::<R::Scalar, N>::from_fn(|i, _| s(0.1 * i as f64 - 0.4)),
    };
    let (kp, kd) = (s(100.0), s(20.0));
    let tau = computed_torque(robot, &q, &u, &reference, (kp, kd));
    let commanded = reference.ud + (reference.u - u) * kd + (reference.q - q) * kp;
    let ud = robot
        .forward_dynamics(&q, &u, &tau)
        .expect("M is positive definite");
    let err: f64 = (ud - commanded).norm().into() / commanded.norm().into();
    assert!(err < tol, "acceleration error {err:e} (tolerance {tol:e})");
    let cu = robot.coriolis_matrix(&q, &u) * u;
    let c = robot.coriolis(&q, &u);
    let c_err: f64 = (cu - c).norm().into() / (c.norm().into() + 1.0);
    assert!(c_err < tol, "C u vs c: {c_err:e}");
    assert_eq!(R::SPEED_NAMES.len(), N);
    err
}

#[test]
fn one_generic_controller_runs_on_every_generated_robot() {
    let errors = [
        check(&kd::Krang::default(), 1e-9),
        check(&kd::baked::Krang, 1e-9),
        check(&kd::fixed_wheels::KrangFixedWheels::default(), 1e-9),
        check(&kd::two_link::TwoLink::default(), 1e-9),
        check(&arm::SingleArm::default(), 1e-9),
        check(&kd::f32::Krang::default(), 1e-2),
    ];
    eprintln!("relative acceleration errors: {errors:?}");
    // Krang's inherent forward dynamics (block Cholesky) and the trait's dense one agree.
    let k = kd::Krang::default();
    let q = SVector::<f64, 19>::from_fn(|i, _| 0.4 * (i as f64 * 0.9).sin());
    let u = SVector::<f64, 19>::from_fn(|i, _| 0.3 * (i as f64 * 1.7).cos());
    let tau = SVector::<f64, 19>::from_fn(|i, _| 5.0 * (i as f64 * 0.4).sin());
    let dense = RobotDynamics::forward_dynamics(&k, &q, &u, &tau).expect("M positive definite");
    let block = k.forward_dynamics(&q, &u, &tau);
    assert!(
        (dense - block).norm() <= 1e-12 * block.norm(),
        "{dense} vs {block}"
    );
    // A non-physical parameter set: the trait returns None instead of NaNs.
    // m4l = -1000 kg: M[ẋ, ẋ], the total mass and more, becomes negative.
    let bad = kd::Params {
        m4l: -1e3,
        ..kd::Params::default()
    };
    assert_eq!(
        RobotDynamics::forward_dynamics(&kd::Krang::new(bad), &q, &u, &tau),
        None
    );
    assert_eq!(
        <kd::Krang as RobotDynamics<19>>::SPEED_NAMES,
        kd::SPEED_NAMES
    );
    assert_eq!(
        <arm::SingleArm as RobotDynamics<7>>::COORDINATE_NAMES,
        arm::COORDINATE_NAMES
    );
}
