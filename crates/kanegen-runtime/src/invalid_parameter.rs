//! The checks of a generated `Params::validate`, and their error.

use crate::unknown_parameter::InlineName;

/// What is wrong with a parameter (see [`InvalidParameter`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Problem {
    /// The value is NaN or infinite.
    NotFinite,
    /// A mass, wheel radius or track width that is zero or negative.
    NotPositive,
    /// A wheel moment of inertia that is negative.
    Negative,
    /// The body's inertia about its centre of mass (the inertia about the frame origin `XX…ZZ`
    /// shifted by Huygens–Steiner with `m` and `MX…MZ`) is not that of a rigid body: a
    /// principal moment exceeds the sum of the other two (triangle inequality; this includes a
    /// negative principal moment).
    InertiaNotPhysical,
}

/// A parameter set that is not physical: the error of a generated `Params::validate`.
/// Allocation-free (`no_std`): the name is kept inline, truncated to 48 bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct InvalidParameter {
    name: InlineName,
    problem: Problem,
}

impl InvalidParameter {
    /// The error for parameter `name` (for [`Problem::InertiaNotPhysical`], the body's name).
    pub fn new(name: &str, problem: Problem) -> Self {
        Self {
            name: InlineName::new(name),
            problem,
        }
    }

    /// The parameter at fault; for [`Problem::InertiaNotPhysical`] the name of the body (`4l`).
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// What is wrong.
    pub fn problem(&self) -> Problem {
        self.problem
    }
}

impl core::fmt::Debug for InvalidParameter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("InvalidParameter")
            .field("name", &self.name())
            .field("problem", &self.problem)
            .finish()
    }
}

impl core::fmt::Display for InvalidParameter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let name = self.name();
        match self.problem {
            Problem::NotFinite => write!(f, "parameter `{name}` is not finite"),
            Problem::NotPositive => write!(f, "parameter `{name}` must be positive"),
            Problem::Negative => write!(f, "parameter `{name}` must not be negative"),
            Problem::InertiaNotPhysical => write!(
                f,
                "body `{name}`: the inertia about the centre of mass violates the triangle \
                 inequality (a principal moment exceeds the sum of the other two)"
            ),
        }
    }
}

impl core::error::Error for InvalidParameter {}

/// Every value finite; the error names the first one that is not.
pub fn check_finite<T: Copy + Into<f64>>(
    names: &[&str],
    values: &[T],
) -> Result<(), InvalidParameter> {
    match names
        .iter()
        .zip(values)
        .find(|(_, v)| !(**v).into().is_finite())
    {
        Some((name, _)) => Err(InvalidParameter::new(name, Problem::NotFinite)),
        None => Ok(()),
    }
}

/// `value > 0` (a mass, a wheel radius, a track width).
pub fn check_positive(name: &str, value: f64) -> Result<(), InvalidParameter> {
    if value > 0.0 {
        Ok(())
    } else {
        Err(InvalidParameter::new(name, Problem::NotPositive))
    }
}

/// `value ≥ 0` (a wheel's moment of inertia).
pub fn check_non_negative(name: &str, value: f64) -> Result<(), InvalidParameter> {
    if value >= 0.0 {
        Ok(())
    } else {
        Err(InvalidParameter::new(name, Problem::Negative))
    }
}

/// The inertial parameters of one body in Khalil's standard form: a positive mass `m` (named
/// `mass_name`), first moments `ms = m·S` and the inertia about the frame origin
/// `j = [XX, XY, XZ, YY, YZ, ZZ]` (tensor entries), whose inertia about the centre of mass
/// `I_G = J − (|ms|²·1 − ms msᵀ)/m` satisfies the triangle inequalities (each principal moment
/// at most the sum of the other two, hence all non-negative).
///
/// The triangle inequalities hold exactly when `Σ = tr(I_G)/2·1 − I_G` (the second moment of
/// the mass distribution about the centre of mass) is positive semi-definite, which is checked
/// by its principal minors, each with a tolerance of `rel_tol` times the matching power of
/// `tr(J)` (rounding of the shift; `1e-9` for `f64` parameters, `1e-5` for `f32`).
pub fn check_body(
    body: &str,
    mass_name: &str,
    m: f64,
    ms: [f64; 3],
    j: [f64; 6],
    rel_tol: f64,
) -> Result<(), InvalidParameter> {
    check_positive(mass_name, m)?;
    let [xx, xy, xz, yy, yz, zz] = j;
    let [mx, my, mz] = ms;
    let s2 = (mx * mx + my * my + mz * mz) / m;
    // I_G = J − (|ms|²·1 − ms msᵀ)/m.
    let g = [
        [xx - s2 + mx * mx / m, xy + mx * my / m, xz + mx * mz / m],
        [xy + mx * my / m, yy - s2 + my * my / m, yz + my * mz / m],
        [xz + mx * mz / m, yz + my * mz / m, zz - s2 + mz * mz / m],
    ];
    let half_trace = (g[0][0] + g[1][1] + g[2][2]) / 2.0;
    let sigma = |r: usize, c: usize| {
        if r == c {
            half_trace - g[r][c]
        } else {
            -g[r][c]
        }
    };
    let scale = (xx + yy + zz).abs().max(f64::MIN_POSITIVE);
    let tol = rel_tol * scale;
    let diagonal = (0..3).all(|i| sigma(i, i) >= -tol);
    let minor = |a: usize, b: usize| sigma(a, a) * sigma(b, b) - sigma(a, b) * sigma(a, b);
    let minors =
        minor(0, 1) >= -tol * scale && minor(0, 2) >= -tol * scale && minor(1, 2) >= -tol * scale;
    let det = sigma(0, 0) * (sigma(1, 1) * sigma(2, 2) - sigma(1, 2) * sigma(1, 2))
        - sigma(0, 1) * (sigma(0, 1) * sigma(2, 2) - sigma(1, 2) * sigma(0, 2))
        + sigma(0, 2) * (sigma(0, 1) * sigma(1, 2) - sigma(1, 1) * sigma(0, 2));
    if diagonal && minors && det >= -tol * scale * scale {
        Ok(())
    } else {
        Err(InvalidParameter::new(body, Problem::InertiaNotPhysical))
    }
}
