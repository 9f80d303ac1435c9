//! Random, physically valid parameter values and states for tests (of this and other crates).
//!
//! Nothing here depends on a random-number crate: every function draws from a caller-supplied
//! uniform source `&mut impl FnMut() -> f64` returning values in `[0, 1)`. [`SplitMix64`] is a
//! tiny deterministic such source (`let mut rng = SplitMix64::new(7); let mut u = || rng.next_f64();`);
//! a `rand` generator works as well (`|| rng.random::<f64>()`).

use kanegen_model::{Body, Model, ParamKind};
use nalgebra::{Matrix3, Vector3};

/// SplitMix64 (Steele, Lea & Flood 2014; the seeding generator of xoshiro): a small, fast,
/// deterministic 64-bit generator, good enough for test data. Not cryptographic.
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator starting from `seed` (any value, zero included).
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform value in `[0, 1)` (53 random bits).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// A uniform value in `[lo, hi)`.
pub fn uniform_in(uniform: &mut impl FnMut() -> f64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * uniform()
}

/// `n` values uniform in `[lo, hi)` (e.g. a random `q`, `u` or `u̇`).
pub fn uniform_vec(uniform: &mut impl FnMut() -> f64, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n).map(|_| uniform_in(uniform, lo, hi)).collect()
}

/// A uniformly distributed random rotation matrix (Shoemake's unit quaternion).
pub fn random_rotation(uniform: &mut impl FnMut() -> f64) -> Matrix3<f64> {
    let (u1, u2, u3) = (uniform(), uniform(), uniform());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (w, x, y, z) = (
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    );
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// Writes Khalil's standard parameters of `body` into `params` from a mass, a centre of mass
/// `com` (in the body frame) and an inertia `inertia_com` about the centre of mass:
/// `MS = m·S` and `J = I_G + m(|S|²·1 − S Sᵀ)` (about the frame origin).
pub fn set_body_params(
    body: &Body,
    params: &mut [f64],
    mass: f64,
    com: Vector3<f64>,
    inertia_com: Matrix3<f64>,
) {
    let j = inertia_com + (Matrix3::identity() * com.norm_squared() - com * com.transpose()) * mass;
    params[body.mass] = mass;
    for (r, &id) in body.first_moment.iter().enumerate() {
        params[id] = mass * com[r];
    }
    let [xx, xy, xz, yy, yz, zz] = body.inertia;
    params[xx] = j[(0, 0)];
    params[xy] = j[(0, 1)];
    params[xz] = j[(0, 2)];
    params[yy] = j[(1, 1)];
    params[yz] = j[(1, 2)];
    params[zz] = j[(2, 2)];
}

/// Random, physically valid parameter values for `model`, indexed by
/// [`kanegen_model::ParamId`]:
///
/// * bodies: mass in `[0.5, 10)` kg; centre of mass with each component in `[−0.3, 0.3)` m;
///   inertia about the centre of mass `R diag(λ) Rᵀ` with a random rotation `R` and principal
///   moments `λ = m(b+c, a+c, a+b)`, `a, b, c ∈ [0.002, 0.05)` m² (so the triangle inequality
///   holds strictly), converted to the frame origin by [`set_body_params`];
/// * lengths in `[0.05, 0.6)` m (the sign is in the joint translation, not the parameter);
/// * `g` in `[9.7, 9.9)` m/s²;
/// * wheels: `R ∈ [0.1, 0.4)`, `L ∈ [0.3, 0.9)`, `mw ∈ [0.5, 6)`, `YYw = mw R² k` with
///   `k ∈ [0.3, 0.5)` and `ZZw = YYw · [0.5, 0.8)` (axisymmetric and physical). Remove them with
///   [`zero_wheel_params`].
///
/// Any parameter not covered above keeps its default value.
pub fn random_physical_params(model: &Model, uniform: &mut impl FnMut() -> f64) -> Vec<f64> {
    let mut p = model.param_values();
    for (id, param) in model.params.iter().enumerate() {
        match param.kind {
            ParamKind::Length => p[id] = uniform_in(uniform, 0.05, 0.6),
            ParamKind::Gravity => p[id] = uniform_in(uniform, 9.7, 9.9),
            ParamKind::Inertial | ParamKind::Wheel => {}
        }
    }
    for link in &model.links {
        let Some(body) = &link.body else { continue };
        let mass = uniform_in(uniform, 0.5, 10.0);
        let com = Vector3::from_fn(|_, _| uniform_in(uniform, -0.3, 0.3));
        let (a, b, c) = (
            uniform_in(uniform, 0.002, 0.05),
            uniform_in(uniform, 0.002, 0.05),
            uniform_in(uniform, 0.002, 0.05),
        );
        let lambda = Matrix3::from_diagonal(&Vector3::new(b + c, a + c, a + b)) * mass;
        let r = random_rotation(uniform);
        let inertia_com = r * lambda * r.transpose();
        set_body_params(body, &mut p, mass, com, inertia_com);
    }
    if let Some(w) = model.wheeled_base() {
        let radius = uniform_in(uniform, 0.1, 0.4);
        let mw = uniform_in(uniform, 0.5, 6.0);
        let yy = mw * radius * radius * uniform_in(uniform, 0.3, 0.5);
        p[w.radius] = radius;
        p[w.track] = uniform_in(uniform, 0.3, 0.9);
        p[w.wheel_mass] = mw;
        p[w.wheel_axle_inertia] = yy;
        p[w.wheel_diametral_inertia] = yy * uniform_in(uniform, 0.5, 0.8);
    }
    p
}

/// Sets the wheel mass and inertias (`mw`, `YYw`, `ZZw`) to zero, keeping the geometry (`R`,
/// `L`). Does nothing for a model without a wheeled base.
pub fn zero_wheel_params(model: &Model, params: &mut [f64]) {
    if let Some(w) = model.wheeled_base() {
        params[w.wheel_mass] = 0.0;
        params[w.wheel_axle_inertia] = 0.0;
        params[w.wheel_diametral_inertia] = 0.0;
    }
}
