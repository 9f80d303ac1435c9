//! `RobotDynamics` and `CoriolisMatrix` can be implemented by hand (as generated code does) and
//! used generically: a computed-torque controller written once drives a 1-DOF pendulum and a
//! planar 2-link arm (in `f64` and `f32`), and the Coriolis-matrix conventions hold.

use kanegen_runtime::{CoriolisMatrix, RobotDynamics};
use nalgebra::{RealField, SMatrix, SVector};

/// Computed-torque control for any robot: the torque that gives `u̇ = kp (q_ref − q) − kd u`.
fn computed_torque<R: RobotDynamics<N>, const N: usize>(
    robot: &R,
    q: &SVector<R::Scalar, N>,
    u: &SVector<R::Scalar, N>,
    q_ref: &SVector<R::Scalar, N>,
    (kp, kd): (R::Scalar, R::Scalar),
) -> SVector<R::Scalar, N> {
    let ud = (q_ref - q) * kp - u * kd;
    robot.inverse_dynamics(q, u, &ud)
}

/// A point mass on a massless rod; `q` is the angle from straight down.
struct Pendulum {
    m: f64,
    l: f64,
    g: f64,
}

impl RobotDynamics<1> for Pendulum {
    type Scalar = f64;
    const SPEED_NAMES: [&'static str; 1] = ["qd"];
    const COORDINATE_NAMES: [&'static str; 1] = ["q"];

    fn mass_matrix(&self, _q: &SVector<f64, 1>) -> SMatrix<f64, 1, 1> {
        SMatrix::from_element(self.m * self.l * self.l)
    }
    fn coriolis(&self, _q: &SVector<f64, 1>, _u: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::zeros()
    }
    fn gravity(&self, q: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::from_element(self.m * self.g * self.l * q[0].sin())
    }
    fn inverse_dynamics(
        &self,
        q: &SVector<f64, 1>,
        u: &SVector<f64, 1>,
        ud: &SVector<f64, 1>,
    ) -> SVector<f64, 1> {
        self.mass_matrix(q) * ud + self.coriolis(q, u) + self.gravity(q)
    }
}

/// A planar arm of two point masses `m1`, `m2` at the ends of massless links `l1`, `l2`,
/// joint angles measured from the horizontal and relative to the first link; generic in the
/// scalar like a generated module's `f64` and `f32` variants.
struct TwoLinkArm<T> {
    m1: T,
    m2: T,
    l1: T,
    l2: T,
    g: T,
}

impl<T: RealField + Copy> TwoLinkArm<T> {
    /// `(m11, m12, m22, h)` with `h = m2 l1 l2 sin q2`.
    fn terms(&self, q: &SVector<T, 2>) -> (T, T, T, T) {
        let (s2, c2) = q[1].sin_cos();
        let a = self.m2 * self.l1 * self.l2;
        let m22 = self.m2 * self.l2 * self.l2;
        let m12 = m22 + a * c2;
        let m11 = (self.m1 + self.m2) * self.l1 * self.l1 + m22 + (a + a) * c2;
        (m11, m12, m22, a * s2)
    }
}

/// The arm every test uses: 1.5 and 0.8 kg on links of 0.6 and 0.4 m.
fn sample_arm<T: RealField + Copy>() -> TwoLinkArm<T> {
    TwoLinkArm {
        m1: nalgebra::convert(1.5),
        m2: nalgebra::convert(0.8),
        l1: nalgebra::convert(0.6),
        l2: nalgebra::convert(0.4),
        g: nalgebra::convert(9.81),
    }
}

impl<T: RealField + Copy> RobotDynamics<2> for TwoLinkArm<T> {
    type Scalar = T;
    const SPEED_NAMES: [&'static str; 2] = ["qd1", "qd2"];
    const COORDINATE_NAMES: [&'static str; 2] = ["q1", "q2"];

    fn mass_matrix(&self, q: &SVector<T, 2>) -> SMatrix<T, 2, 2> {
        let (m11, m12, m22, _) = self.terms(q);
        SMatrix::<T, 2, 2>::new(m11, m12, m12, m22)
    }
    fn coriolis(&self, q: &SVector<T, 2>, u: &SVector<T, 2>) -> SVector<T, 2> {
        self.coriolis_matrix(q, u) * u
    }
    fn gravity(&self, q: &SVector<T, 2>) -> SVector<T, 2> {
        let c1 = q[0].cos();
        let c12 = (q[0] + q[1]).cos();
        let g2 = self.m2 * self.g * self.l2 * c12;
        SVector::<T, 2>::new((self.m1 + self.m2) * self.g * self.l1 * c1 + g2, g2)
    }
    fn inverse_dynamics(
        &self,
        q: &SVector<T, 2>,
        u: &SVector<T, 2>,
        ud: &SVector<T, 2>,
    ) -> SVector<T, 2> {
        self.mass_matrix(q) * ud + self.coriolis(q, u) + self.gravity(q)
    }
}

impl<T: RealField + Copy> CoriolisMatrix<2> for TwoLinkArm<T> {
    fn coriolis_matrix(&self, q: &SVector<T, 2>, u: &SVector<T, 2>) -> SMatrix<T, 2, 2> {
        let (.., h) = self.terms(q);
        SMatrix::<T, 2, 2>::new(-h * u[1], -h * (u[0] + u[1]), h * u[0], T::zero())
    }
}

#[test]
fn computed_torque_on_a_pendulum() {
    let p = Pendulum {
        m: 2.0,
        l: 0.5,
        g: 9.81,
    };
    let q = SVector::from([0.3]);
    let at_rest = SVector::from([0.0]);
    assert_eq!(
        computed_torque(&p, &q, &at_rest, &q, (25.0, 10.0)),
        p.gravity(&q)
    );
    let tau = computed_torque(
        &p,
        &q,
        &SVector::from([1.0]),
        &SVector::from([0.5]),
        (25.0, 10.0),
    );
    let expected = 9.81 * 0.3_f64.sin() + 0.5 * (25.0 * (0.5 - 0.3) - 10.0);
    assert!((tau[0] - expected).abs() < 1e-12, "{tau} vs {expected}");
}

#[test]
fn forward_dynamics_inverts_inverse_dynamics_and_refuses_a_non_physical_robot() {
    let p = Pendulum {
        m: 2.0,
        l: 0.5,
        g: 9.81,
    };
    let (q, u, tau) = (
        SVector::from([0.3]),
        SVector::from([-1.2]),
        SVector::from([4.0]),
    );
    let ud = p.forward_dynamics(&q, &u, &tau).expect("positive mass");
    let expected = (4.0 - 2.0 * 9.81 * 0.5 * 0.3_f64.sin()) / (2.0 * 0.5 * 0.5);
    assert!((ud[0] - expected).abs() < 1e-12, "{ud} vs {expected}");
    assert!((p.inverse_dynamics(&q, &u, &ud) - tau).norm() < 1e-12);
    // The two-link arm: τ → u̇ → τ, in both precisions.
    let arm = sample_arm::<f64>();
    let (q, u, ud) = (
        SVector::from([0.2, 0.9]),
        SVector::from([-1.3, 0.7]),
        SVector::from([2.5, -0.4]),
    );
    let tau = arm.inverse_dynamics(&q, &u, &ud);
    let back = arm.forward_dynamics(&q, &u, &tau).unwrap();
    assert!((back - ud).norm() < 1e-12, "{back} vs {ud}");
    let arm32 = sample_arm::<f32>();
    let (q, u, ud) = (q.cast::<f32>(), u.cast::<f32>(), ud.cast::<f32>());
    let back = arm32
        .forward_dynamics(&q, &u, &arm32.inverse_dynamics(&q, &u, &ud))
        .unwrap();
    assert!((back - ud).norm() < 1e-4, "{back} vs {ud}");
    // A negative mass makes M negative definite, a NaN mass makes it NaN: no acceleration.
    let (q, u, tau) = (
        SVector::from([0.3]),
        SVector::from([0.0]),
        SVector::from([1.0]),
    );
    for m in [-2.0, 0.0, f64::NAN] {
        assert_eq!(
            Pendulum { m, ..p }.forward_dynamics(&q, &u, &tau),
            None,
            "m = {m}"
        );
    }
}

/// Integrates the closed loop `M u̇ + c + g = τ(q, u)` (semi-implicit Euler) with the
/// computed-torque law and returns the final `q`: with exact inverse dynamics the loop is the
/// linear `ë = −kp e − kd ė`, which settles on the reference.
fn settle<R: RobotDynamics<2>>(
    robot: &R,
    q_ref: &SVector<R::Scalar, 2>,
    steps: usize,
) -> SVector<R::Scalar, 2> {
    let dt = nalgebra::convert::<f64, R::Scalar>(1e-3);
    let gains = (nalgebra::convert(100.0), nalgebra::convert(20.0));
    let mut q = SVector::<R::Scalar, 2>::zeros();
    let mut u = SVector::<R::Scalar, 2>::zeros();
    for _ in 0..steps {
        let tau = computed_torque(robot, &q, &u, q_ref, gains);
        let ud = robot
            .forward_dynamics(&q, &u, &tau)
            .expect("M is positive definite");
        u += ud * dt;
        q += u * dt;
    }
    q
}

#[test]
fn computed_torque_settles_a_two_link_arm_in_both_precisions() {
    let arm = sample_arm::<f64>();
    let q_ref = SVector::from([0.7, -1.1]);
    let q = settle(&arm, &q_ref, 3000);
    assert!((q - q_ref).norm() < 1e-6, "{q}");
    let arm32 = sample_arm::<f32>();
    let q = settle(&arm32, &SVector::from([0.7_f32, -1.1]), 3000);
    assert!((q - SVector::from([0.7_f32, -1.1])).norm() < 1e-3, "{q}");
    assert_eq!(
        <TwoLinkArm<f32> as RobotDynamics<2>>::COORDINATE_NAMES,
        ["q1", "q2"]
    );
}

#[test]
fn coriolis_matrix_conventions() {
    let arm = sample_arm::<f64>();
    let (q, u) = (SVector::from([0.2, 0.9]), SVector::from([-1.3, 0.7]));
    // c = C u.
    let c = arm.coriolis(&q, &u);
    assert!((arm.coriolis_matrix(&q, &u) * u - c).norm() < 1e-12);
    // Ṁ − 2C skew-symmetric, Ṁ by central differences along q̇ = u.
    let h = 1e-6;
    let m_dot = (arm.mass_matrix(&(q + u * h)) - arm.mass_matrix(&(q - u * h))) / (2.0 * h);
    let n = m_dot - arm.coriolis_matrix(&q, &u) * 2.0;
    assert!((n + n.transpose()).norm() < 1e-8, "{n}");
}
