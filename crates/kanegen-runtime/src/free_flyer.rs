//! The configuration space of a floating (free-flyer) base, as Pinocchio lays it out: the
//! coordinates `q = [x, y, z, qx, qy, qz, qw, joints…]` (`NQ` entries: the base origin in the
//! world and the unit quaternion that rotates base vectors into the world) and the speeds
//! `u = [v, ω, joint speeds…]` (`NV = NQ − 1` entries: the base origin's linear velocity and the
//! base's angular velocity, both in the base frame).
//!
//! [`integrate`] is `pinocchio::integrate` (the exact SE(3) exponential of the base twist, in the
//! base frame), [`difference`] is `pinocchio::difference` (its logarithm), [`neutral`] and
//! [`normalize`] are `pinocchio::neutral` and `pinocchio::normalize`. The joints' coordinates are
//! a vector space. Generated floating-base modules call these from their wrapper's methods of the
//! same names and from their [`Multibody`](crate::Multibody) implementation.
//!
//! ```
//! use kanegen_runtime::free_flyer;
//! use nalgebra::SVector;
//!
//! // A free flyer with one joint: NQ = 8 coordinates, NV = 7 speeds.
//! let q0: SVector<f64, 8> = free_flyer::neutral();
//! let u = SVector::<f64, 7>::from_column_slice(&[0.3, -0.1, 0.2, 0.5, 1.0, -0.7, 2.0]);
//! let q1 = free_flyer::integrate(&q0, &u, 0.1);
//! assert!((q1.fixed_rows::<4>(3).norm() - 1.0).abs() < 1e-15);
//! let back = free_flyer::difference(&q0, &q1);
//! assert!((back - u * 0.1).norm() < 1e-14);
//! ```

use nalgebra::{Matrix3, Quaternion, RealField, SVector, Unit, UnitQuaternion, Vector3};

fn c<T: RealField + Copy>(x: f64) -> T {
    nalgebra::convert(x)
}

/// The neutral configuration: base at the world origin, identity quaternion, joints at zero.
pub fn neutral<T: RealField + Copy, const NQ: usize>() -> SVector<T, NQ> {
    const { assert!(NQ >= 7, "a floating base has at least seven coordinates") };
    let mut q = SVector::zeros();
    q[6] = T::one();
    q
}

/// `q` with its quaternion scaled to unit norm (the identity if it is zero).
pub fn normalize<T: RealField + Copy, const NQ: usize>(q: &SVector<T, NQ>) -> SVector<T, NQ> {
    const { assert!(NQ >= 7, "a floating base has at least seven coordinates") };
    let mut out = *q;
    let n = q.fixed_rows::<4>(3).norm();
    if n > T::zero() {
        for k in 3..7 {
            out[k] /= n;
        }
    } else {
        out.fixed_rows_mut::<4>(3).fill(T::zero());
        out[6] = T::one();
    }
    out
}

/// The base's rotation (base → world) as a unit quaternion, from `q[3..7]` (normalised).
pub fn base_orientation<T: RealField + Copy, const NQ: usize>(
    q: &SVector<T, NQ>,
) -> UnitQuaternion<T> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[6], q[3], q[4], q[5]))
}

/// The base origin in the world, `q[0..3]`.
pub fn base_position<T: RealField + Copy, const NQ: usize>(q: &SVector<T, NQ>) -> Vector3<T> {
    Vector3::new(q[0], q[1], q[2])
}

/// `V(ω) = 1 + (1 − cos θ)/θ² [ω]× + (θ − sin θ)/θ³ [ω]×²`: the translation part of the SE(3)
/// exponential (series below θ = 1e-4).
fn left_jacobian<T: RealField + Copy>(w: &Vector3<T>) -> Matrix3<T> {
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < c(1e-4) {
        (
            c::<T>(0.5) - t2 / c(24.0),
            c::<T>(1.0 / 6.0) - t2 / c(120.0),
        )
    } else {
        ((T::one() - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let wx = w.cross_matrix();
    Matrix3::identity() + wx * a + wx * wx * b
}

/// `V(ω)⁻¹ = 1 − ½ [ω]× + (1/θ²)(1 − θ sin θ / (2 (1 − cos θ))) [ω]×²` (series below θ = 1e-4).
fn left_jacobian_inverse<T: RealField + Copy>(w: &Vector3<T>) -> Matrix3<T> {
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let b = if t < c(1e-4) {
        c::<T>(1.0 / 12.0) + t2 / c(720.0)
    } else {
        (T::one() - t * t.sin() / (c::<T>(2.0) * (T::one() - t.cos()))) / t2
    };
    let wx = w.cross_matrix();
    Matrix3::identity() - wx * c::<T>(0.5) + wx * wx * b
}

/// `q ⊕ u·dt`: the base moves by the SE(3) exponential of the twist `(v, ω)·dt` expressed in the
/// base frame (position `p + R V(ω dt) v dt`, quaternion `quat ⊗ exp(ω dt)`, normalised), the
/// joints by `u dt`. `NQ` must be `NV + 1`.
pub fn integrate<T: RealField + Copy, const NQ: usize, const NV: usize>(
    q: &SVector<T, NQ>,
    u: &SVector<T, NV>,
    dt: T,
) -> SVector<T, NQ> {
    const {
        assert!(
            NQ == NV + 1 && NV >= 6,
            "a floating base has NQ = NV + 1 ≥ 7"
        )
    };
    let r = base_orientation(q);
    let v = Vector3::new(u[0], u[1], u[2]) * dt;
    let w = Vector3::new(u[3], u[4], u[5]) * dt;
    let p = base_position(q) + r * (left_jacobian(&w) * v);
    let quat = r * UnitQuaternion::from_scaled_axis(w);
    let mut out = *q;
    out[0] = p.x;
    out[1] = p.y;
    out[2] = p.z;
    out[3] = quat.i;
    out[4] = quat.j;
    out[5] = quat.k;
    out[6] = quat.w;
    for s in 6..NV {
        out[s + 1] = q[s + 1] + u[s] * dt;
    }
    out
}

/// The tangent vector `δ` with `integrate(q0, δ, 1) = q1`: the SE(3) logarithm of the relative
/// base pose `M0⁻¹ M1` (linear part first, in the frame of `q0`'s base; the rotation taken the
/// short way, angle ≤ π) and the joints' differences.
pub fn difference<T: RealField + Copy, const NQ: usize, const NV: usize>(
    q0: &SVector<T, NQ>,
    q1: &SVector<T, NQ>,
) -> SVector<T, NV> {
    const {
        assert!(
            NQ == NV + 1 && NV >= 6,
            "a floating base has NQ = NV + 1 ≥ 7"
        )
    };
    let r0 = base_orientation(q0);
    let r1 = base_orientation(q1);
    let rel = r0.inverse() * r1;
    // The short way: a quaternion and its negative are the same rotation.
    let rel = if rel.w < T::zero() {
        Unit::new_unchecked(-rel.into_inner())
    } else {
        rel
    };
    let w = rel.scaled_axis();
    let p = r0.inverse() * (base_position(q1) - base_position(q0));
    let v = left_jacobian_inverse(&w) * p;
    let mut out = SVector::zeros();
    for k in 0..3 {
        out[k] = v[k];
        out[3 + k] = w[k];
    }
    for s in 6..NV {
        out[s] = q1[s + 1] - q0[s + 1];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (SVector<f64, 9>, SVector<f64, 8>) {
        let mut q = SVector::<f64, 9>::from_column_slice(&[
            0.3, -1.2, 0.8, 0.1, -0.4, 0.7, 0.5, 0.25, -1.0,
        ]);
        q = normalize(&q);
        let u = SVector::<f64, 8>::from_column_slice(&[0.4, -0.2, 1.1, 2.0, -1.5, 0.9, 0.3, -0.7]);
        (q, u)
    }

    #[test]
    fn integrate_keeps_the_quaternion_unit() {
        let (mut q, u) = sample();
        for _ in 0..1000 {
            q = integrate(&q, &u, 0.37);
        }
        assert!((q.fixed_rows::<4>(3).norm() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn difference_inverts_integrate() {
        let (q0, u) = sample();
        // |ω| dt < π: the logarithm returns the rotation the short way.
        for dt in [1e-9, 1e-5, 0.1, 1.0, 1.15] {
            let q1 = integrate(&q0, &u, dt);
            let d = difference(&q0, &q1);
            assert!(
                (d - u * dt).norm() < 1e-12 * (1.0 + dt),
                "dt {dt}: {d} vs {}",
                u * dt
            );
            let back = integrate(&q0, &d, 1.0);
            assert!((back - q1).norm() < 1e-13, "dt {dt}");
        }
    }

    #[test]
    fn the_base_moves_with_its_body_twist() {
        // Along q(t) = integrate(q0, u, t) the base's world velocity is R(t) v and its angular
        // velocity in the base frame ω: constant body twist.
        let (q0, u) = sample();
        let h = 1e-6;
        let t = 0.8;
        let (qm, qp) = (integrate(&q0, &u, t - h), integrate(&q0, &u, t + h));
        let q = integrate(&q0, &u, t);
        let pdot = (base_position(&qp) - base_position(&qm)) / (2.0 * h);
        let r = base_orientation(&q);
        let v = Vector3::new(u[0], u[1], u[2]);
        assert!((pdot - r * v).norm() < 1e-8);
        let dr =
            (base_orientation(&qm).inverse() * base_orientation(&qp)).scaled_axis() / (2.0 * h);
        assert!((dr - Vector3::new(u[3], u[4], u[5])).norm() < 1e-8);
    }

    #[test]
    fn neutral_and_normalize() {
        let q: SVector<f64, 7> = neutral();
        assert_eq!(
            q,
            SVector::<f64, 7>::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
        );
        let mut z = q;
        z[6] = 0.0;
        assert_eq!(normalize(&z), q);
        let mut s = q;
        s[3] = 3.0;
        s[6] = 4.0;
        let n = normalize(&s);
        assert!((n[3] - 0.6).abs() < 1e-15 && (n[6] - 0.8).abs() < 1e-15);
    }
}
