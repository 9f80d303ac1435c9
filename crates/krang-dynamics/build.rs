//! Generates the dynamics modules from the robot descriptions next to this file: one generator
//! call per module, the optional ones behind the crate's features (Cargo sets
//! `CARGO_FEATURE_<NAME>` for each enabled feature, `-` as `_`). Without features this is one
//! call: the f64 Krang module with M, c, g and inverse dynamics.
fn main() {
    let enabled = |feature: &str| std::env::var_os(format!("CARGO_FEATURE_{feature}")).is_some();
    let coriolis_matrix = enabled("CORIOLIS_MATRIX");
    let builder = |model: &str| kanegen::Builder::new(model).coriolis_matrix(coriolis_matrix);
    builder("krang.toml").run();
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
