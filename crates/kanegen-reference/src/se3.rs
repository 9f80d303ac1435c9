//! The free-flyer configuration space `ℝ³ × S³ × ℝⁿ` of [`crate::FreeFlyer`], written
//! independently of the generated configuration helpers: `q = [x, y, z, qx, qy, qz, qw, joint
//! coordinates]` (base position in the world, unit quaternion base → world), tangent vectors
//! `v = [v, ω, joint speeds]` (the base origin's linear velocity and the base's angular
//! velocity, both in the base frame), as Pinocchio's `JointModelFreeFlyer`.
//!
//! * [`integrate`]`(q, v, dt)` is `q ⊕ v·dt`: the base pose times the exact SE(3) exponential of
//!   the body twist `v·dt` (`T₁ = T₀ · exp(v·dt)`, `pinocchio::integrate`), the joints `+ v·dt`;
//! * [`difference`]`(q0, q1)` is its inverse, `log(T₀⁻¹ T₁)` and `q1 − q0` on the joints
//!   (`pinocchio::difference`): `integrate(q0, difference(q0, q1), 1) = q1`.
//!
//! Small angles use Taylor series (no `0/0`), so that both are smooth at zero and can be
//! evaluated in dual numbers for tangent-space derivatives.

use nalgebra::{Matrix3, RealField, Vector3};

use crate::cst;

/// Below this squared angle the series of the exponential and logarithm are used.
const SMALL_ANGLE2: f64 = 1e-8;

/// The rotation matrix of the quaternion `(x, y, z, w)`, normalized first.
pub fn quaternion_to_rotation<T: RealField + Copy>(quat: [T; 4]) -> Matrix3<T> {
    let [x, y, z, w] = quat;
    let n = (x * x + y * y + z * z + w * w).sqrt();
    let (x, y, z, w) = (x / n, y / n, z / n, w / n);
    let (one, two) = (T::one(), cst::<T>(2.0));
    Matrix3::new(
        one - two * (y * y + z * z),
        two * (x * y - z * w),
        two * (x * z + y * w),
        two * (x * y + z * w),
        one - two * (x * x + z * z),
        two * (y * z - x * w),
        two * (x * z - y * w),
        two * (y * z + x * w),
        one - two * (x * x + y * y),
    )
}

/// The Hamilton product `a ⊗ b` of quaternions stored `(x, y, z, w)`.
pub fn quaternion_product<T: RealField + Copy>(a: [T; 4], b: [T; 4]) -> [T; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// The unit quaternion `exp(φ/2)` of the rotation vector `φ` (a rotation by `|φ|` about `φ`).
pub fn quaternion_exp<T: RealField + Copy>(phi: &Vector3<T>) -> [T; 4] {
    let t2 = phi.dot(phi);
    let (s, c) = if t2 < cst(SMALL_ANGLE2) {
        // sin(θ/2)/θ and cos(θ/2) to fourth order.
        (
            cst::<T>(0.5) - t2 / cst(48.0),
            T::one() - t2 / cst(8.0) + t2 * t2 / cst(384.0),
        )
    } else {
        let t = t2.sqrt();
        let half = t / cst(2.0);
        (half.sin() / t, half.cos())
    };
    [phi.x * s, phi.y * s, phi.z * s, c]
}

/// The rotation vector `φ` of a unit quaternion (the shorter way round: `|φ| ≤ π`).
pub fn quaternion_log<T: RealField + Copy>(quat: [T; 4]) -> Vector3<T> {
    let [mut x, mut y, mut z, mut w] = quat;
    if w < T::zero() {
        (x, y, z, w) = (-x, -y, -z, -w);
    }
    let v = Vector3::new(x, y, z);
    let n2 = v.dot(&v);
    let scale = if n2 < cst(SMALL_ANGLE2) {
        // 2 atan2(n, w)/n to second order in n/w.
        cst::<T>(2.0) / w * (T::one() - n2 / (cst::<T>(3.0) * w * w))
    } else {
        let n = n2.sqrt();
        cst::<T>(2.0) * n.atan2(w) / n
    };
    v * scale
}

/// `V(φ) = 1 + (1 − cos θ)/θ² [φ]× + (θ − sin θ)/θ³ [φ]×²`: the translation of `exp` of the
/// twist `(ρ, φ)` is `V(φ) ρ`.
pub fn left_jacobian<T: RealField + Copy>(phi: &Vector3<T>) -> Matrix3<T> {
    let t2 = phi.dot(phi);
    let (a, b) = if t2 < cst(SMALL_ANGLE2) {
        (
            cst::<T>(0.5) - t2 / cst(24.0),
            cst::<T>(1.0 / 6.0) - t2 / cst(120.0),
        )
    } else {
        let t = t2.sqrt();
        ((T::one() - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let k = phi.cross_matrix();
    Matrix3::identity() + k * a + k * k * b
}

/// `V(φ)⁻¹ = 1 − ½[φ]× + (1/θ²)(1 − θ sin θ / (2(1 − cos θ))) [φ]×²`.
pub fn left_jacobian_inverse<T: RealField + Copy>(phi: &Vector3<T>) -> Matrix3<T> {
    let t2 = phi.dot(phi);
    let b = if t2 < cst(SMALL_ANGLE2) {
        cst::<T>(1.0 / 12.0) + t2 / cst(720.0)
    } else {
        let t = t2.sqrt();
        (T::one() - t * t.sin() / (cst::<T>(2.0) * (T::one() - t.cos()))) / t2
    };
    let k = phi.cross_matrix();
    Matrix3::identity() - k * cst::<T>(0.5) + k * k * b
}

fn check(q: usize, v: usize) {
    assert!(
        q >= 7 && v + 1 == q,
        "a free-flyer configuration has 7 + n entries and its tangent 6 + n; got {q} and {v}"
    );
}

/// `q ⊕ v·dt`: the base moves by the SE(3) exponential of its body twist `v·dt`
/// (`p₁ = p₀ + R₀ V(ω dt) v dt`, `R₁ = R₀ exp(ω dt)`, the quaternion renormalized), the joints
/// by `v·dt`.
///
/// # Panics
/// If `q` does not have 7 + n entries and `v` 6 + n.
pub fn integrate<T: RealField + Copy>(q: &[T], v: &[T], dt: T) -> Vec<T> {
    check(q.len(), v.len());
    let quat = [q[3], q[4], q[5], q[6]];
    let r0 = quaternion_to_rotation(quat);
    let rho = Vector3::new(v[0], v[1], v[2]) * dt;
    let phi = Vector3::new(v[3], v[4], v[5]) * dt;
    let p = Vector3::new(q[0], q[1], q[2]) + r0 * (left_jacobian(&phi) * rho);
    let mut quat = quaternion_product(quat, quaternion_exp(&phi));
    let n = quat.iter().fold(T::zero(), |s, &x| s + x * x).sqrt();
    for x in &mut quat {
        *x /= n;
    }
    let mut out = Vec::with_capacity(q.len());
    out.extend_from_slice(&[p.x, p.y, p.z]);
    out.extend_from_slice(&quat);
    out.extend(q[7..].iter().zip(&v[6..]).map(|(&a, &b)| a + b * dt));
    out
}

/// `q1 ⊖ q0`: the body twist `log(T₀⁻¹ T₁)` of the base and `q1 − q0` on the joints, so that
/// `integrate(q0, difference(q0, q1), 1) = q1`.
///
/// # Panics
/// If `q0` and `q1` do not both have 7 + n entries.
pub fn difference<T: RealField + Copy>(q0: &[T], q1: &[T]) -> Vec<T> {
    assert_eq!(q0.len(), q1.len(), "two configurations of different sizes");
    check(q0.len(), q0.len() - 1);
    let a = [q0[3], q0[4], q0[5], q0[6]];
    let b = [q1[3], q1[4], q1[5], q1[6]];
    let na = a.iter().fold(T::zero(), |s, &x| s + x * x).sqrt();
    let nb = b.iter().fold(T::zero(), |s, &x| s + x * x).sqrt();
    let conj = [-a[0] / na, -a[1] / na, -a[2] / na, a[3] / na];
    let rel = quaternion_product(conj, b.map(|x| x / nb));
    let phi = quaternion_log(rel);
    let r0 = quaternion_to_rotation(a);
    let dp = Vector3::new(q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]);
    let rho = left_jacobian_inverse(&phi) * (r0.transpose() * dp);
    let mut out = Vec::with_capacity(q0.len() - 1);
    out.extend_from_slice(&[rho.x, rho.y, rho.z, phi.x, phi.y, phi.z]);
    out.extend(q0[7..].iter().zip(&q1[7..]).map(|(&a, &b)| b - a));
    out
}
