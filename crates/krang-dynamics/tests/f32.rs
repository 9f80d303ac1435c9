//! The single-precision module agrees with the double-precision one; `UnknownParameter` keeps
//! the name inline (no allocation, `no_std`).

use krang_dynamics::{Krang, Params, SetParameterError, UnknownParameter, f32 as k32};
use nalgebra::{SMatrix, SVector};

/// xorshift64*: deterministic uniform draws in [-1, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (v >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// A vector whose f64 and f32 versions are the same numbers.
    fn vector(&mut self, scale: f64) -> (SVector<f64, 19>, SVector<f32, 19>) {
        let v32 = SVector::<f32, 19>::from_fn(|_, _| (scale * self.next()) as f32);
        (v32.map(f64::from), v32)
    }
}

/// |a32 − a64| ≤ 1e-4 · max|a64| elementwise (relative to the result's scale).
fn close<const R: usize, const C: usize>(
    a32: &SMatrix<f32, R, C>,
    a64: &SMatrix<f64, R, C>,
    what: &str,
) {
    let scale = a64.amax().max(1e-12);
    let err = (a32.map(f64::from) - a64).amax();
    assert!(
        err <= 1e-4 * scale,
        "{what}: max error {err:e} vs scale {scale:e}"
    );
}

#[test]
fn f32_agrees_with_f64_on_random_states() {
    let k64 = Krang::default();
    let k32 = k32::Krang::default();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for _ in 0..200 {
        let (q, q32) = rng.vector(3.2);
        let (u, u32_) = rng.vector(2.0);
        let (ud, ud32) = rng.vector(5.0);
        close(&k32.mass_matrix(&q32), &k64.mass_matrix(&q), "mass_matrix");
        close(
            &k32.coriolis(&q32, &u32_),
            &k64.coriolis(&q, &u),
            "coriolis",
        );
        close(&k32.gravity(&q32), &k64.gravity(&q), "gravity");
        close(
            &k32.inverse_dynamics(&q32, &u32_, &ud32),
            &k64.inverse_dynamics(&q, &u, &ud),
            "inverse_dynamics",
        );
        close(
            &k32.coriolis_matrix(&q32, &u32_),
            &k64.coriolis_matrix(&q, &u),
            "coriolis_matrix",
        );
    }
}

#[test]
fn f32_params_are_the_f64_params_rounded() {
    let p64 = Params::default();
    let mut p32 = k32::Params::default();
    assert_eq!(k32::Params::NAMES, Params::NAMES);
    for (a, b) in p32.to_array().iter().zip(p64.to_array()) {
        assert_eq!(*a, b as f32);
    }
    p32.set("MX4l", 0.25).unwrap();
    assert_eq!(p32.get("MX4l"), Some(0.25_f32));
    let err = p32.set("MX4k", 0.25).unwrap_err();
    assert_eq!(err.name(), "MX4k");
    assert!(err.to_string().contains("`MX4k`"));
    // Changed parameters: both precisions still agree.
    let mut p64 = p64;
    p64.set("MX4l", 0.25).unwrap();
    let mut rng = Rng(7);
    let (q, q32) = rng.vector(1.0);
    close(
        &k32::Krang::new(p32).gravity(&q32),
        &Krang::new(p64).gravity(&q),
        "gravity with MX4l = 0.25",
    );
}

#[test]
fn unknown_parameter_keeps_the_name_inline() {
    let mut p = Params::default();
    let Err(SetParameterError::Unknown(err)) = p.set("no_such_parameter", 1.0) else {
        panic!("an unknown name must be SetParameterError::Unknown")
    };
    assert_eq!(err.name(), "no_such_parameter");
    assert!(err.to_string().contains("no_such_parameter"));
    assert!(format!("{err:?}").contains("no_such_parameter"));
    // Longer than the capacity: truncated at a character boundary.
    let long = "é".repeat(40); // 80 bytes
    let err = p.set(&long, 1.0).unwrap_err();
    assert_eq!(UnknownParameter::CAPACITY, 48);
    assert_eq!(err.name(), "é".repeat(24));
    assert_eq!(
        err,
        SetParameterError::Unknown(UnknownParameter::new(&long))
    );
    let err = UnknownParameter::new("abcdefghijklmnopqrstuvwxyzabcdefghijklmnopqrstuvwxyz");
    assert_eq!(err.name().len(), 48);
    let _: &dyn core::error::Error = &err;
}
