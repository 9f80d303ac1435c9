//! Generates the dynamics modules from the robot descriptions next to this file.
fn main() {
    // The opt-in kinematics and energies (centre of mass, frames, T, V) on the main module.
    kanegen::Builder::new("krang.toml")
        .functions(kanegen::FunctionSet::all())
        .run();
    kanegen::Builder::new("krang.toml").baked(true).run();
    kanegen::Builder::new("krang.toml")
        .precision(kanegen::Precision::F32)
        .run();
    kanegen::Builder::new("krang-fixed-wheels.toml").run();
    kanegen::Builder::new("two-link.toml").run();
}
