//! Helpers shared by the workspace-level tests.
#![allow(dead_code)]

use std::path::PathBuf;

use kanegen_model::Model;
use kanegen_reference::random::{SplitMix64, uniform_vec};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// Bitwise equality (`==` would accept `0.0 == -0.0` and reject equal NaNs).
pub fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Load `models/<name>`.
pub fn model(name: &str) -> Model {
    Model::from_toml_file(root().join("models").join(name)).expect("model loads")
}

/// The text of `models/krang/<rel>` (the Krang data, `models/krang/README.md`); a missing file
/// fails the test with its path.
pub fn krang_data(rel: &str) -> String {
    let path = root().join("models/krang").join(rel);
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (the Krang data files)", path.display()))
}

/// `max |a − b| / max(max |b|, floor)`: relative to the largest entry, absolute below `floor`
/// (vectors such as c can be small by cancellation of large terms).
pub fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(floor, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// A deterministic uniform source.
pub fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut r = SplitMix64::new(seed);
    move || r.next_f64()
}

/// A random state `(q, u, u̇)`.
pub fn random_state(uniform: &mut impl FnMut() -> f64, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    (
        uniform_vec(uniform, n, -std::f64::consts::PI, std::f64::consts::PI),
        uniform_vec(uniform, n, -2.0, 2.0),
        uniform_vec(uniform, n, -5.0, 5.0),
    )
}

/// Fixed-size vector from a slice.
pub fn sv<const N: usize>(v: &[f64]) -> SVector<f64, N> {
    SVector::<f64, N>::from_column_slice(v)
}

/// Column-major data of a fixed-size matrix as a row-major Vec (to compare with DMatrix).
pub fn rows<const N: usize>(m: &SMatrix<f64, N, N>) -> Vec<f64> {
    (0..N)
        .flat_map(|r| (0..N).map(move |c| m[(r, c)]))
        .collect()
}

/// Row-major data of a dynamic matrix.
pub fn drows(m: &DMatrix<f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|r| (0..m.ncols()).map(move |c| m[(r, c)]))
        .collect()
}

/// Data of a dynamic vector.
pub fn dvec(v: &DVector<f64>) -> Vec<f64> {
    v.iter().copied().collect()
}

/// The hardware-fitted masses and first moments of Krang (`models/krang/params`), applied to the
/// model's bodies (inertias keep their defaults). The 23 entries of the hardware-trained beta
/// vector are, in order: Base, LWheel, RWheel, Spine, Bracket, L1..L6, lGripper, lgPlate1,
/// lgPlate2, R1..R6, rGripper, rgPlate1, rgPlate2 (the ideal vector has a 24th, the Kinect, after
/// Bracket), each `[m, m·cx, m·cy, m·cz]` in the link frame (which coincides with the report's
/// frame, see MODEL-NOTES). The fitted plates have negative masses; they are not bodies of the
/// 19-speed model and are left out.
pub fn hardware_fitted_params(model: &Model) -> Vec<f64> {
    let text = krang_data("params/convergedBetaVector104PosesHardwareTrained.txt");
    let beta: Vec<f64> = text
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(beta.len(), 92, "23 bodies × [m, MX, MY, MZ]");
    let bodies = [
        Some("1"),
        None,
        None,
        Some("2"),
        Some("3"),
        Some("4l"),
        Some("5l"),
        Some("6l"),
        Some("7l"),
        Some("8l"),
        Some("9l"),
        Some("10l"),
        None,
        None,
        Some("4r"),
        Some("5r"),
        Some("6r"),
        Some("7r"),
        Some("8r"),
        Some("9r"),
        Some("10r"),
        None,
        None,
    ];
    let mut p = model.param_values();
    for (k, b) in bodies.iter().enumerate() {
        let Some(b) = b else { continue };
        for (j, prefix) in ["m", "MX", "MY", "MZ"].iter().enumerate() {
            if let Some(i) = model.param_index(&format!("{prefix}{b}")) {
                p[i] = beta[4 * k + j];
            }
        }
    }
    p
}

/// `Ṁ = dM(q(t))/dt` along `q̇` by central differences with one Richardson step (error O(h⁴)):
/// `(4 D(h/2) − D(h)) / 3`, `D(h) = (M(q + h q̇) − M(q − h q̇)) / 2h`. `m` returns a row-major
/// matrix.
pub fn mdot_central(m: &dyn Fn(&[f64]) -> Vec<f64>, q: &[f64], qdot: &[f64], h: f64) -> Vec<f64> {
    let at = |t: f64| -> Vec<f64> {
        let qt: Vec<f64> = q.iter().zip(qdot).map(|(a, b)| a + t * b).collect();
        m(&qt)
    };
    let d = |h: f64| -> Vec<f64> {
        at(h)
            .iter()
            .zip(at(-h))
            .map(|(p, n)| (p - n) / (2.0 * h))
            .collect()
    };
    let (coarse, fine) = (d(h), d(h / 2.0));
    fine.iter()
        .zip(coarse)
        .map(|(f, c)| (4.0 * f - c) / 3.0)
        .collect()
}

/// `max |Ṁ − (C + Cᵀ)|` of row-major n × n matrices, i.e. the departure of `Ṁ − 2C` from
/// skew-symmetry (`Ṁ − 2C + (Ṁ − 2C)ᵀ = 2 (Ṁ − C − Cᵀ)`), divided by `max(max |Ṁ|, max |C|,
/// floor)`.
pub fn skew_defect(mdot: &[f64], c: &[f64], n: usize, floor: f64) -> f64 {
    let scale = mdot.iter().chain(c).fold(floor, |s, x| s.max(x.abs()));
    let mut worst = 0.0f64;
    for r in 0..n {
        for k in 0..n {
            let e = mdot[r * n + k] - c[r * n + k] - c[k * n + r];
            worst = worst.max(e.abs());
        }
    }
    worst / scale
}

/// Generalized coordinate rates `q̇` for speeds `u`: the joint coordinates' rates are their
/// speeds; the wheeled base's x and ψ (quasi-velocities ẋ, ψ̇; they do not enter M) get 0.
pub fn coordinate_rates(model: &Model, u: &[f64]) -> Vec<f64> {
    let mut qd = u.to_vec();
    if let Some(w) = model.wheeled_base() {
        qd[w.x_speed] = 0.0;
        qd[w.psi_speed] = 0.0;
    }
    qd
}
