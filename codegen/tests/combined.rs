//! Combined functions (`kanegen::Combined`, `Builder::combined`): one straight-line program for
//! several registry functions and frames.
//!
//! * every part equals its separate function **bit for bit** (the lowering's interpreter, random
//!   parameters and states; Krang with its hands, the URDF arm with its end link, the mimic
//!   gripper), baked too;
//! * sharing: the combined program computes each joint's sine and cosine once and costs fewer
//!   operations than the separate functions together (Krang's whole-body terms);
//! * `nonlinear_effects` equals `coriolis + gravity` and `inverse_dynamics` at `u̇ = 0`;
//! * the emitted module has the struct, the free function and the wrapper method, and parses;
//! * a bad request (unknown frame, a frame for a function without one, none for a per-frame
//!   function, a taken or malformed name, a part twice, no part, a regressor) is a typed error
//!   naming the model file, the combined function and the fix.

use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, Error, FunctionId as F, FunctionSet, Generated, Options, ParamMode};
use kanegen::{Combined, CombinedError};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};

fn models_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models")
}

fn load(name: &str) -> Model {
    let path = models_dir().join(name);
    if name.ends_with(".urdf") {
        Model::from_urdf_file(&path, &UrdfOptions::default()).expect("URDF imports")
    } else {
        Model::from_toml_file(&path).expect("model loads")
    }
}

/// A controller's terms: M, h, the CoM's position, Jacobian and bias, and per frame its pose,
/// Jacobian and bias acceleration.
fn whole_body(name: &str, frames: &[&str]) -> Combined {
    let mut c = Combined::new(name)
        .with(F::MassMatrix)
        .with(F::NonlinearEffects)
        .with(F::CenterOfMass)
        .with(F::ComJacobian)
        .with(F::ComBiasAcceleration);
    for f in frames {
        c = c
            .with_frame(F::FramePose, *f)
            .with_frame(F::FrameJacobian, *f)
            .with_frame(F::FrameBiasAcceleration, *f);
    }
    c
}

/// The separate functions of the module: the dynamics, the kinematics and `nonlinear_effects`.
fn functions() -> FunctionSet {
    FunctionSet::default()
        .without(F::CoriolisMatrix)
        .union(FunctionSet::kinematics())
        .with(F::NonlinearEffects)
}

fn generate(model: &Model, params: ParamMode, combined: &[Combined]) -> Generated {
    let options = Options {
        params,
        functions: functions(),
    };
    let mut builder = Builder::from_model(model.clone()).options(options);
    for c in combined {
        builder = builder.combined(c.clone());
    }
    builder.generate().expect("generates")
}

/// Every part of combined function 0 equals its separate function, bit for bit, on `states`
/// random states and one random parameter set.
fn parts_equal_separate_functions(model: &Model, params: ParamMode, frames: &[&str], seed: u64) {
    let g = generate(model, params, &[whole_body("whole_body_terms", frames)]);
    let mut r = SplitMix64::new(seed);
    let mut uniform = move || r.next_f64();
    let p = match params {
        ParamMode::Runtime => random_physical_params(model, &mut uniform),
        ParamMode::Baked => model.param_values(),
    };
    let n = model.independent_dof();
    let c = &g.lowered.combined[0];
    for _ in 0..5 {
        let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
        let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
        let parts = g.lowered.evaluate_combined(0, &p, &q, &u, &[]);
        assert_eq!(parts.len(), c.spec.parts.len());
        for (part, value) in c.spec.parts.iter().zip(&parts) {
            let separate =
                g.lowered
                    .evaluate_at(part.function, part.frame, &p, &q, &u, &vec![0.0; n]);
            assert_eq!(
                value, &separate,
                "{}: {}: the combined part differs from the separate function",
                model.name, part.field
            );
        }
    }
}

#[test]
fn combined_parts_equal_the_separate_functions_bit_for_bit() {
    parts_equal_separate_functions(
        &load("krang.toml"),
        ParamMode::Runtime,
        &["left_hand", "right_hand"],
        1,
    );
    parts_equal_separate_functions(&load("krang.toml"), ParamMode::Baked, &["right_hand"], 2);
    parts_equal_separate_functions(&load("singlearm.urdf"), ParamMode::Runtime, &["L7_EFF"], 3);
    parts_equal_separate_functions(
        &load("krang-fixed-wheels.toml"),
        ParamMode::Runtime,
        &["10l", "10r"],
        4,
    );
}

#[test]
fn combined_function_on_a_mimic_model_equals_the_separate_functions() {
    let model = load("mimic_gripper.urdf");
    let frame = model.links.last().expect("links").name.clone();
    parts_equal_separate_functions(&model, ParamMode::Runtime, &[frame.as_str()], 5);
}

#[test]
fn combined_program_shares_trigonometry_and_variables() {
    let model = load("krang.toml");
    let hands = ["left_hand", "right_hand"];
    let g = generate(
        &model,
        ParamMode::Runtime,
        &[whole_body("whole_body_terms", &hands)],
    );
    let c = &g.lowered.combined[0];
    let separate: Vec<&kanegen::lower::Program> = c
        .spec
        .parts
        .iter()
        .map(|p| {
            g.lowered
                .function_at(p.function, p.frame)
                .expect("separate function")
        })
        .collect();
    let flops: usize = separate.iter().map(|p| p.ops.flops()).sum();
    let sincos: usize = separate.iter().map(|p| p.ops.sincos).sum();
    let union: std::collections::BTreeSet<usize> =
        separate.iter().flat_map(|p| p.sincos.clone()).collect();
    let ops = c.program.ops;
    println!(
        "whole_body_terms: {} flops, {} sin/cos; separate: {flops} flops, {sincos} sin/cos",
        ops.flops(),
        ops.sincos
    );
    // One sine and cosine per joint angle any part reads.
    assert_eq!(ops.sincos, union.len());
    assert!(sincos > 5 * ops.sincos);
    // Shared rotations, positions, motion and composites: fewer operations than the parts.
    assert!(
        ops.flops() < flops * 9 / 10,
        "{} flops combined, {flops} separate",
        ops.flops()
    );
}

#[test]
fn nonlinear_effects_is_coriolis_plus_gravity() {
    for (name, seed) in [("krang.toml", 11), ("singlearm.urdf", 12)] {
        let model = load(name);
        let g = generate(&model, ParamMode::Runtime, &[]);
        let mut r = SplitMix64::new(seed);
        let mut uniform = move || r.next_f64();
        let p = random_physical_params(&model, &mut uniform);
        let n = model.independent_dof();
        for _ in 0..5 {
            let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
            let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
            let zero = vec![0.0; n];
            let eval = |id| g.lowered.evaluate(id, &p, &q, &u, &zero);
            let h = eval(F::NonlinearEffects);
            let c = eval(F::Coriolis);
            let gr = eval(F::Gravity);
            let tau = eval(F::InverseDynamics);
            let scale = h.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for i in 0..n {
                assert!(
                    (h[i] - (c[i] + gr[i])).abs() < 1e-12 * scale,
                    "{name} h[{i}]"
                );
                assert!((h[i] - tau[i]).abs() < 1e-12 * scale, "{name} h[{i}] vs τ");
            }
        }
    }
}

#[test]
fn emitted_module_has_the_struct_function_and_method() {
    let model = load("singlearm.urdf");
    let g = generate(
        &model,
        ParamMode::Runtime,
        &[
            whole_body("arm_terms", &["L7_EFF"]),
            Combined::new("arm_pose").with_frame(F::FramePose, "L7_EFF"),
        ],
    );
    let src = &g.source;
    for needle in [
        "pub struct ArmTerms {",
        "pub mass_matrix: SMatrix<f64, 7, 7>,",
        "pub nonlinear_effects: SVector<f64, 7>,",
        "pub frame_jacobian_l7_eff: SMatrix<f64, 6, 7>,",
        "pub frame_pose_l7_eff: nalgebra::Isometry3<f64>,",
        "pub fn arm_terms(\n",
        "pub struct ArmPose {",
        "pub fn arm_pose(&self, q: &SVector<f64, 7>) -> ArmPose {",
    ] {
        assert!(src.contains(needle), "missing `{needle}`");
    }
    // The header lists it with its op counts; `stats` prints its row.
    assert!(src.contains("(combined: mass_matrix, nonlinear_effects"));
    assert!(kanegen::stats(&g).contains("arm_terms"));
    syn::parse_file(src).expect("the module parses");
}

fn error(c: Combined) -> CombinedError {
    let model = load("two-link.toml");
    match Builder::from_model(model).combined(c).generate() {
        Err(Error::Combined(e)) => e,
        other => panic!(
            "expected a combined-function error, got {:?}",
            other.map(|_| ())
        ),
    }
}

#[test]
fn bad_combined_functions_are_typed_errors_naming_the_fix() {
    let cases = [
        (
            Combined::new("terms").with_frame(F::FrameJacobian, "hand"),
            "no frame `hand`",
        ),
        (
            Combined::new("terms").with_frame(F::MassMatrix, "1"),
            "takes no frame",
        ),
        (Combined::new("terms").with(F::FramePose), "takes a frame"),
        (Combined::new("mass_matrix").with(F::Gravity), "taken"),
        (Combined::new("frame_pose_x").with(F::Gravity), "taken"),
        (Combined::new("new").with(F::Gravity), "taken"),
        (Combined::new("Terms").with(F::Gravity), "snake-case"),
        (Combined::new("fn").with(F::Gravity), "snake-case"),
        (
            Combined::new("terms").with(F::Gravity).with(F::Gravity),
            "twice",
        ),
        (Combined::new("terms"), "no parts"),
        (
            Combined::new("terms").with(F::GravityRegressor),
            "cannot be a part",
        ),
    ];
    for (c, problem) in cases {
        let name = c.name().to_owned();
        let e = error(c);
        let text = e.to_string();
        assert_eq!(e.function, name);
        assert!(text.contains(problem), "{text}");
        assert!(text.contains("two-link.toml"), "{text}");
        assert!(text.contains("fix: "), "{text}");
    }
    // Two combined functions with one name.
    let model = load("two-link.toml");
    let twice = [
        Combined::new("terms").with(F::Gravity),
        Combined::new("terms").with(F::MassMatrix),
    ];
    let e = twice
        .into_iter()
        .fold(Builder::from_model(model), Builder::combined)
        .generate();
    assert!(matches!(e, Err(Error::Combined(e)) if e.problem.contains("two combined functions")));
}
