//! Generates, for the benchmarks (`benches/dynamics.rs`), the dynamics of the URDF robots into
//! `$OUT_DIR`: the 7-DOF arm of `models/singlearm.urdf` (runtime parameters and baked) and Krang
//! imported from `models/Krang.urdf` with its two-wheeled base (runtime parameters); and, for
//! `tests/kinematics.rs`, the arm and the two-link model with every registry function; for
//! `tests/mimic.rs`, a gripper with mimic joints.
//! The TOML Krang models come from `krang-dynamics`.
use kanegen::model::{UrdfOptions, WheeledBaseSpec};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let arm = || kanegen::Builder::urdf("models/singlearm.urdf", UrdfOptions::default());
    arm().output("singlearm.rs").run();
    arm().baked(true).output("singlearm_baked.rs").run();
    // Every registry function (the opt-in kinematics and energies included), for
    // `tests/kinematics.rs`.
    // With a combined function (`tests/kinematics.rs` checks it against the separate ones).
    arm()
        .functions(kanegen::FunctionSet::all())
        .combined(arm_terms())
        .output("singlearm_all.rs")
        .run();
    kanegen::Builder::new("models/two-link.toml")
        .functions(kanegen::FunctionSet::all())
        .output("two_link_all.rs")
        .run();
    kanegen::Builder::new("models/two-link.toml")
        .functions(kanegen::FunctionSet::all())
        .baked(true)
        .precision(kanegen::Precision::F32)
        .output("two_link_all_baked_f32.rs")
        .run();
    // A gripper with <mimic> fingers (exact constraints), every registry function, for
    // `tests/mimic.rs`.
    kanegen::Builder::urdf("models/mimic_gripper.urdf", UrdfOptions::default())
        .functions(kanegen::FunctionSet::all())
        .output("mimic_gripper_all.rs")
        .run();
    kanegen::Builder::urdf("models/Krang.urdf", krang_urdf_options())
        .output("krang_urdf.rs")
        .run();
}

/// A combined function of every part shape (symmetric matrix, vectors, Jacobians, isometry,
/// scalars) on the arm's end link and a link merged by a fixed joint.
fn arm_terms() -> kanegen::combined::Combined {
    use kanegen::FunctionId as F;
    let mut c = kanegen::combined::Combined::new("arm_terms")
        .with(F::MassMatrix)
        .with(F::NonlinearEffects)
        .with(F::CenterOfMass)
        .with(F::ComJacobian)
        .with(F::ComBiasAcceleration)
        .with(F::KineticEnergy)
        .with(F::PotentialEnergy);
    for frame in ["L7_EFF", "Bracket"] {
        c = c
            .with_frame(F::FramePose, frame)
            .with_frame(F::FrameJacobian, frame)
            .with_frame(F::FrameBiasAcceleration, frame);
    }
    c
}

/// The declaration of Krang's wheeled base (as in README "Any robot from URDF" and
/// `tests/urdf_generated_vs_reference.rs`); the 0.1 g gripper plates are dropped.
fn krang_urdf_options() -> UrdfOptions {
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.pitch_name = "imu".into();
    UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"])
}
