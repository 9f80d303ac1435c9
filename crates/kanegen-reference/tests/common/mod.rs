//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use kanegen_model::Model;
use kanegen_reference::random::SplitMix64;
use nalgebra::{DMatrix, DVector};

/// Loads `models/<name>.toml` from the workspace.
pub fn load_model(name: &str) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(format!("{name}.toml"));
    Model::from_toml_file(&path).unwrap_or_else(|e| panic!("loading {}: {e}", path.display()))
}

/// A deterministic uniform(0, 1) source.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut rng = SplitMix64::new(seed);
    move || rng.next_f64()
}

/// `max |a − b| / max(max |b|, floor)`.
pub fn rel_err_mat(a: &DMatrix<f64>, b: &DMatrix<f64>, floor: f64) -> f64 {
    assert_eq!(a.shape(), b.shape());
    (a - b).amax() / b.amax().max(floor)
}

/// `max |a − b| / max(max |b|, floor)`.
pub fn rel_err_vec(a: &DVector<f64>, b: &DVector<f64>, floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    (a - b).amax() / b.amax().max(floor)
}
