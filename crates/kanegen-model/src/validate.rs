//! Numeric validation: rotations, axes, masses and inertias.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::error::ModelErrorKind as K;
use crate::ir::{Body, Model};
use crate::limits::check_magnitude;

/// Tolerance on orthonormality, determinant and unit norms.
pub const TOLERANCE: f64 = 1e-9;

/// The norm of `v` if `v` is not a unit vector within [`TOLERANCE`] (a non-finite entry gives a
/// non-finite norm); `None` if it is one.
fn norm_unless_unit(v: [f64; 3]) -> Option<f64> {
    let norm = Vector3::from(v).norm();
    (!norm.is_finite() || (norm - 1.0).abs() > TOLERANCE).then_some(norm)
}

/// Checks that a joint axis is a unit vector.
pub(crate) fn check_axis(joint: &str, axis: [f64; 3]) -> Result<(), K> {
    match norm_unless_unit(axis) {
        Some(norm) => Err(K::AxisNotUnit {
            joint: joint.to_owned(),
            axis,
            norm,
        }),
        None => Ok(()),
    }
}

/// Checks that the direction of gravity is a unit vector (the same rule for TOML and URDF
/// models). The error is the detail for the caller's typed error, which names the item:
/// `direction [0.0, 0.0, -2.0] is not a unit vector (norm 2); normalise it`.
pub(crate) fn check_gravity_direction(direction: [f64; 3]) -> Result<(), String> {
    match norm_unless_unit(direction) {
        Some(norm) => Err(format!(
            "direction {direction:?} is not a unit vector (norm {norm}); normalise it"
        )),
        None => Ok(()),
    }
}

/// Checks that `rows` is a proper rotation (orthonormal, determinant +1).
pub(crate) fn check_rotation(joint: &str, rows: &[[f64; 3]; 3]) -> Result<(), K> {
    let r = Matrix3::from_fn(|i, j| rows[i][j]);
    let err = (r * r.transpose() - Matrix3::identity()).abs().max();
    if !err.is_finite() || err > TOLERANCE {
        return Err(K::BadRotation {
            joint: joint.to_owned(),
            detail: format!("|R Rᵀ − I| = {err:.3e}"),
        });
    }
    let det = r.determinant();
    if (det - 1.0).abs() > TOLERANCE {
        return Err(K::BadRotation {
            joint: joint.to_owned(),
            detail: format!("det R = {det}"),
        });
    }
    Ok(())
}

/// Principal moments of inertia about the centre of mass of `body` for parameter values `p`,
/// ascending (for a body without mass: of its inertia `J`).
pub fn principal_moments_about_com(body: &Body, p: &[f64]) -> [f64; 3] {
    let m = p[body.mass];
    let ms = Vector3::new(
        p[body.first_moment[0]],
        p[body.first_moment[1]],
        p[body.first_moment[2]],
    );
    let [xx, xy, xz, yy, yz, zz] = body.inertia.map(|i| p[i]);
    let j = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
    // J = I_G + m(|S|² 1 − S Sᵀ) with S = MS/m.
    let ig = if m == 0.0 {
        j
    } else {
        j - (Matrix3::identity() * ms.norm_squared() - ms * ms.transpose()) / m
    };
    principal_moments(&ig)
}

/// The eigenvalues of a symmetric 3×3 inertia, ascending.
pub(crate) fn principal_moments(i: &Matrix3<f64>) -> [f64; 3] {
    let e = SymmetricEigen::new(*i).eigenvalues;
    let mut v = [e[0], e[1], e[2]];
    v.sort_by(f64::total_cmp);
    v
}

/// How far principal moments `[a, b, c]` (ascending) are from a physical inertia about a centre
/// of mass (positive semi-definite, `c ≤ a + b`), relative to the largest: 0 for a physical one
/// (point masses and rods included), NaN for NaN moments; with the condition that fails.
pub(crate) fn inertia_violation([a, b, c]: [f64; 3]) -> (f64, &'static str) {
    let scale = c.abs().max(f64::MIN_POSITIVE);
    let negative = (-a).max(0.0) / scale;
    let triangle = (c - a - b).max(0.0) / scale;
    if a.is_nan() || c.is_nan() {
        (f64::NAN, "not a number")
    } else if negative > TOLERANCE {
        // A principal moment of −1e−22 (rounding of a semi-definite inertia such as
        // 1e−6 · [1 1 1; 1 1 1; 1 1 1]) is no semi-definiteness violation: the condition named
        // is then the triangle inequality.
        (negative.max(triangle), "not positive semi-definite")
    } else {
        (
            triangle,
            "triangle inequality: the largest exceeds the sum of the other two",
        )
    }
}

/// Checks the parameter values: every one finite; every one, and every constant of a joint's
/// translation, no larger in magnitude than [`crate::MAX_PARAMETER_MAGNITUDE`]; and the wheel
/// constants of a wheeled base physical (radius `R` and track `L` positive; wheel mass `mw` and
/// moments `YYw`, `ZZw` not negative).
fn check_parameters(model: &Model) -> Result<(), K> {
    if let Some(p) = model.params.iter().find(|p| !p.value.is_finite()) {
        return Err(K::NonFiniteParameter {
            name: p.name.clone(),
            value: p.value,
        });
    }
    for p in &model.params {
        check_magnitude(|| format!("parameter `{}`", p.name), &[p.value])?;
    }
    for joint in model.links.iter().filter_map(|l| l.joint()) {
        for (axis, length) in ["x", "y", "z"].iter().zip(&joint.translation) {
            if length.symbol.is_none() {
                let item = || format!("joint `{}` translation ({axis})", joint.name);
                check_magnitude(item, &[length.coef])?;
            }
        }
    }
    let Some(w) = model.wheeled_base() else {
        return Ok(());
    };
    for (id, what, positive) in [
        (w.radius, "the wheel radius", true),
        (w.track, "the track width", true),
        (w.wheel_mass, "the mass of one wheel", false),
        (
            w.wheel_axle_inertia,
            "a wheel's moment about its axle",
            false,
        ),
        (
            w.wheel_diametral_inertia,
            "a wheel's moment about a diameter",
            false,
        ),
    ] {
        let p = &model.params[id];
        if (positive && p.value <= 0.0) || p.value < 0.0 {
            return Err(K::NonPhysicalWheel {
                symbol: p.name.clone(),
                value: p.value,
                what,
                bound: if positive { "positive" } else { "≥ 0" },
            });
        }
    }
    Ok(())
}

/// Checks that the model moves ([`K::NoSpeeds`] if it has no speed), the parameters
/// ([`check_parameters`]), every body, and the mass matrix.
///
/// A body's mass is positive, or zero with no first moment (a rotor-like body that only adds
/// rotational inertia); its inertia about the centre of mass is positive semi-definite and
/// satisfies the triangle inequality (point masses and rods are physical), both up to
/// `inertia_tolerance` of its largest principal moment ([`TOLERANCE`] for TOML models; the
/// URDF importer passes [`UrdfOptions::inertia_tolerance`](crate::UrdfOptions::inertia_tolerance),
/// having noted each link it let through). Since single bodies may then carry no inertia in
/// some direction, the mass matrix as a whole is checked to be positive definite
/// ([`crate::mass_matrix::check_positive_definite`]).
pub(crate) fn check_physics(model: &Model, inertia_tolerance: f64) -> Result<(), K> {
    if model.dof() == 0 {
        return Err(K::NoSpeeds);
    }
    check_parameters(model)?;
    let p = model.param_values();
    for link in &model.links {
        let Some(b) = &link.body else { continue };
        let m = p[b.mass];
        let ms = b.first_moment.map(|i| p[i]);
        let scale = ms.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        if m.is_nan() || m < 0.0 || (m == 0.0 && scale > 0.0) {
            return Err(K::NonPositiveMass {
                body: b.name.clone(),
                symbol: model.params[b.mass].name.clone(),
                value: m,
            });
        }
        let moments = principal_moments_about_com(b, &p);
        let (violation, what) = inertia_violation(moments);
        if violation.is_nan() || violation > inertia_tolerance.max(TOLERANCE) {
            let [a, bb, c] = moments;
            return Err(K::NonPhysicalInertia {
                body: b.name.clone(),
                detail: format!("principal moments {a:.6e}, {bb:.6e}, {c:.6e}: {what}"),
            });
        }
    }
    crate::mass_matrix::check_positive_definite(model)
}
