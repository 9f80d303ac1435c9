//! Generates the optional dynamics modules from the robot descriptions next to this file: one
//! generator call per module, each behind its feature of the crate (Cargo compiles the script
//! with `--cfg feature="..."` and sets `CARGO_FEATURE_<NAME>`, `-` as `_`). Without features
//! this script does nothing and `kanegen` is not even a build dependency: the default module
//! (f64 Krang with M, c, g and inverse dynamics) is pre-generated in `src/generated/krang.rs`
//! (`tests/pregenerated.rs` checks it against the generator). With `coriolis-matrix` the Krang
//! module is generated here instead, with the Coriolis matrix.
fn main() {
    #[cfg(any(
        feature = "coriolis-matrix",
        feature = "baked",
        feature = "f32",
        feature = "fixed-wheels",
        feature = "two-link"
    ))]
    generate();
}

#[cfg(any(
    feature = "coriolis-matrix",
    feature = "baked",
    feature = "f32",
    feature = "fixed-wheels",
    feature = "two-link"
))]
fn generate() {
    let enabled = |feature: &str| std::env::var_os(format!("CARGO_FEATURE_{feature}")).is_some();
    let coriolis_matrix = enabled("CORIOLIS_MATRIX");
    let builder = |model: &str| kanegen::Builder::new(model).coriolis_matrix(coriolis_matrix);
    if coriolis_matrix {
        builder("krang.toml").run();
    }
    if enabled("BAKED") {
        builder("krang.toml").baked(true).run();
    }
    if enabled("F32") {
        builder("krang.toml")
            .precision(kanegen::Precision::F32)
            .run();
    }
    if enabled("FIXED_WHEELS") {
        builder("krang-fixed-wheels.toml").run();
    }
    if enabled("TWO_LINK") {
        builder("two-link.toml").run();
    }
}
