//! Generates, for the benchmarks (`benches/dynamics.rs`), the dynamics of the URDF robots into
//! `$OUT_DIR`: the 7-DOF arm of `models/singlearm.urdf` (runtime parameters and baked) and Krang
//! imported from `models/Krang.urdf` with its two-wheeled base (runtime parameters); and, for
//! `tests/kinematics.rs`, the arm and the two-link model with every registry function; for
//! `tests/gpu.rs` and `benches/gpu.rs`, the arm with GPU kernels and batched forms, and in f32; for
//! `tests/mimic.rs`, a gripper with mimic joints; for `tests/big_tree.rs`, a 100-DOF tree; for
//! `tests/isa_batch.rs`, a cart on a rail (structurally zero c, g, C) with every registry
//! function and the batched forms; for `tests/unicode_names.rs`, two models with names in
//! Greek and Japanese; for `tests/floating_base.rs`, `tests/floating_reference.rs` and
//! `examples/pinocchio_free_flyer.rs`, the small floating-base model
//! `models/floating-hopper.toml`, Solo 12 (`tests/corpus/solo12.urdf`) and the humanoid
//! `tests/corpus/simple_humanoid.urdf` on a floating base (and, for the example, the last two
//! baked).
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
    // The arm's GPU kernels and, for the comparison in `tests/gpu.rs`, the same functions on
    // the CPU in f32 (the f64 ones are in the module with the kernels).
    let gpu_set = {
        use kanegen::FunctionId as F;
        kanegen::FunctionSet::default()
            .with(F::NonlinearEffects)
            .with(F::CenterOfMass)
            .with(F::ComJacobian)
            .with(F::KineticEnergy)
            .with(F::PotentialEnergy)
    };
    arm()
        .functions(gpu_set)
        .gpu(true)
        .batch(true)
        .output("singlearm_gpu.rs")
        .run();
    arm()
        .functions(gpu_set)
        .precision(kanegen::Precision::F32)
        .output("singlearm_gpu_f32.rs")
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
    // A gripper with <mimic> fingers (exact constraints), every registry function and the
    // batched forms, for `tests/mimic.rs`.
    kanegen::Builder::urdf("models/mimic_gripper.urdf", UrdfOptions::default())
        .functions(kanegen::FunctionSet::all())
        .batch(true)
        .output("mimic_gripper_all.rs")
        .run();
    // A cart on a horizontal rail, every registry function and the batched forms: c, g and C
    // are structurally zero (their batched forms have no loop) and the gravity regressor has no
    // base parameter (`tests/isa_batch.rs` compiles the module with warnings denied).
    let slider = out_dir().join("slider.urdf");
    std::fs::write(&slider, SLIDER_URDF).expect("OUT_DIR is writable");
    kanegen::Builder::urdf(&slider, UrdfOptions::default())
        .functions(kanegen::FunctionSet::all())
        .batch(true)
        .output("slider.rs")
        .run();
    // Names in Greek and Japanese (links, joints, a speed `qd_ψ`), for `tests/unicode_names.rs`.
    kanegen::Builder::urdf("tests/data/unicode_arm.urdf", UrdfOptions::default())
        .output("unicode_arm.rs")
        .run();
    kanegen::Builder::new("tests/data/unicode_two_link.toml")
        .output("unicode_two_link.rs")
        .run();
    // Floating bases, for `tests/floating_base.rs` and `tests/floating_reference.rs`: the hopper
    // with every function a floating base has and the batched forms, Solo 12 with the default
    // functions, the nonlinear effects, the kinematics, the centroidal terms and the derivatives.
    kanegen::Builder::new("models/floating-hopper.toml")
        .functions(kanegen::floating::SUPPORTED.into_iter().collect())
        .batch(true)
        .output("floating_hopper.rs")
        .run();
    let floating = kanegen::FunctionSet::default()
        .iter()
        .chain([
            kanegen::FunctionId::NonlinearEffects,
            kanegen::FunctionId::CenterOfMass,
            kanegen::FunctionId::FramePose,
            kanegen::FunctionId::FrameJacobian,
            kanegen::FunctionId::FrameBiasAcceleration,
            kanegen::FunctionId::CentroidalMomentumMatrix,
            kanegen::FunctionId::CentroidalMomentumBias,
            kanegen::FunctionId::InverseDynamicsDerivatives,
        ])
        .collect::<kanegen::FunctionSet>();
    kanegen::Builder::urdf("tests/corpus/solo12.urdf", UrdfOptions::floating())
        .functions(floating)
        .output("solo12_floating.rs")
        .run();
    // The 35-speed humanoid with the same functions, for `tests/floating_reference.rs` and the
    // Pinocchio comparison (`examples/pinocchio_free_flyer.rs`).
    kanegen::Builder::urdf("tests/corpus/simple_humanoid.urdf", UrdfOptions::floating())
        .functions(floating)
        .output("simple_humanoid_floating.rs")
        .run();
    // Both with the URDF's parameter values folded in (baked), M, c, g, τ, h and the derivatives:
    // the form to set beside Pinocchio's generated code, which folds them in too.
    let baked = kanegen::FunctionSet::default()
        .without(kanegen::FunctionId::CoriolisMatrix)
        .with(kanegen::FunctionId::NonlinearEffects)
        .with(kanegen::FunctionId::InverseDynamicsDerivatives);
    for (urdf, output) in [
        ("tests/corpus/solo12.urdf", "solo12_floating_baked.rs"),
        (
            "tests/corpus/simple_humanoid.urdf",
            "simple_humanoid_floating_baked.rs",
        ),
    ] {
        kanegen::Builder::urdf(urdf, UrdfOptions::floating())
            .functions(baked)
            .baked(true)
            .output(output)
            .run();
    }
    kanegen::Builder::urdf("models/Krang.urdf", krang_urdf_options())
        .output("krang_urdf.rs")
        .run();
    // A 100-DOF tree (ten branches of ten links), for `tests/big_tree.rs`: its functions are
    // long enough to be split into blocks, and this debug build (with debug info) compiles it.
    let tree = out_dir().join("tree10x10.urdf");
    std::fs::write(&tree, tree_urdf(10, 10)).expect("OUT_DIR is writable");
    kanegen::Builder::urdf(&tree, UrdfOptions::default())
        .output("tree10x10.rs")
        .run();
}

/// Cargo's output directory of this build script.
fn out_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"))
}

/// One prismatic joint along x on a fixed base (gravity along −z): M = [m], c = g = C = 0.
const SLIDER_URDF: &str = r#"<?xml version="1.0"?>
<robot name="slider">
  <link name="base"/>
  <link name="cart">
    <inertial>
      <origin xyz="0 0 0.1"/>
      <mass value="2.5"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.04"/>
    </inertial>
  </link>
  <joint name="rail" type="prismatic">
    <parent link="base"/>
    <child link="cart"/>
    <axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="100" velocity="1"/>
  </joint>
</robot>
"#;

/// A tree of `branches` serial branches of `depth` revolute links each on a fixed base: joint
/// axes cycle through z, y, x, every link has an offset origin, a distinct mass and a full
/// inertia, and the branches leave the base at different yaw angles.
fn tree_urdf(branches: usize, depth: usize) -> String {
    let axes = ["0 0 1", "0 1 0", "1 0 0"];
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"tree{branches}x{depth}\">\n<link name=\"base\"/>\n"
    );
    let mut k = 0;
    for b in 0..branches {
        let mut parent = "base".to_owned();
        for d in 0..depth {
            k += 1;
            let link = format!("b{b}l{d}");
            let mass = 1.0 + 0.01 * k as f64;
            let yaw = if d == 0 { 0.3 * b as f64 } else { 0.0 };
            let axis = axes[(b + d) % 3];
            s += &format!(
                "<link name=\"{link}\"><inertial><origin xyz=\"0.01 0.02 0.1\" rpy=\"0 0 0\"/>\
                 <mass value=\"{mass}\"/><inertia ixx=\"0.02\" ixy=\"0.001\" ixz=\"0\" \
                 iyy=\"0.03\" iyz=\"0.002\" izz=\"0.015\"/></inertial></link>\n\
                 <joint name=\"j{b}_{d}\" type=\"revolute\"><parent link=\"{parent}\"/>\
                 <child link=\"{link}\"/><origin xyz=\"0.01 0.02 0.2\" rpy=\"0 0 {yaw}\"/>\
                 <axis xyz=\"{axis}\"/><limit lower=\"-3\" upper=\"3\" effort=\"10\" \
                 velocity=\"1\"/></joint>\n"
            );
            parent = link;
        }
    }
    s + "</robot>\n"
}

/// A combined function of every part shape (symmetric matrix, vectors, Jacobians, isometry,
/// scalars) on the arm's end link and a link merged by a fixed joint.
fn arm_terms() -> kanegen::Combined {
    use kanegen::FunctionId as F;
    let mut c = kanegen::Combined::new("arm_terms")
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

/// The declaration of Krang's wheeled base (as in docs/urdf.md and
/// `tests/urdf_generated_vs_reference.rs`); the 0.1 g gripper plates are dropped.
fn krang_urdf_options() -> UrdfOptions {
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.pitch_name = "imu".into();
    UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"])
}
