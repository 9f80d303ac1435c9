//! The function registry: a module gets exactly the functions asked for, through every stage
//! (derivation, lowering, free functions, wrapper methods, runtime traits, stats, CLI).

use std::path::PathBuf;
use std::process::Command;

use kanegen::model::{UrdfOptions, WheeledBaseSpec};
use kanegen::registry::FUNCTIONS;
use kanegen::{Builder, FunctionId, FunctionSet, Options};

fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models")
}

fn kanegen(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kanegen"))
        .args(args)
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the CLI runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_module_gets_only_the_functions_asked_for() {
    let set: FunctionSet = [FunctionId::MassMatrix, FunctionId::Gravity]
        .into_iter()
        .collect();
    let options = Options {
        functions: set,
        ..Options::default()
    };
    let g = Builder::new(models().join("two-link.toml"))
        .options(options)
        .generate()
        .unwrap();
    let ids: Vec<FunctionId> = g.derivation.functions.iter().map(|f| f.id).collect();
    assert_eq!(ids, [FunctionId::MassMatrix, FunctionId::Gravity]);
    let ids: Vec<FunctionId> = g.lowered.functions.iter().map(|f| f.id).collect();
    assert_eq!(ids, [FunctionId::MassMatrix, FunctionId::Gravity]);
    for spec in &FUNCTIONS {
        let free = format!("pub fn {}(", spec.name);
        let method = format!("pub fn {}(\n            &self", spec.name);
        let has = set.contains(spec.id);
        assert_eq!(g.source.contains(&free), has, "{}", spec.name);
        assert_eq!(
            g.source.contains(&method) || g.source.contains(&format!("pub fn {}(&self", spec.name)),
            has,
            "wrapper method {}",
            spec.name
        );
        assert_eq!(
            kanegen::stats(&g).contains(spec.name),
            has,
            "stats row {}",
            spec.name
        );
    }
    // M, c, g and τ together make `RobotDynamics`: without c and τ the wrapper does not claim it.
    assert!(!g.source.contains("RobotDynamics"));
    let full = Builder::new(models().join("two-link.toml"))
        .generate()
        .unwrap();
    assert!(
        full.source
            .contains("impl kanegen_runtime::RobotDynamics<DOF> for TwoLink")
    );
    assert!(
        full.source
            .contains("impl kanegen_runtime::CoriolisMatrix<DOF> for TwoLink")
    );
}

#[test]
fn functions_derived_without_the_mass_matrix_compute_the_same_values() {
    let set: FunctionSet = [FunctionId::Gravity, FunctionId::CoriolisMatrix]
        .into_iter()
        .collect();
    let part = Builder::new(models().join("krang.toml"))
        .options(Options {
            functions: set,
            ..Options::default()
        })
        .generate()
        .unwrap();
    let full = Builder::new(models().join("krang.toml"))
        .generate()
        .unwrap();
    let params = full.model.param_values();
    let q: Vec<f64> = (0..19).map(|i| 0.13 * i as f64 - 0.9).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.4 - 0.03 * i as f64).collect();
    let ud = vec![0.0; 19];
    for id in set.iter() {
        let a = part.lowered.evaluate(id, &params, &q, &u, &ud);
        let b = full.lowered.evaluate(id, &params, &q, &u, &ud);
        let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-13 * scale, "{id}: {x} vs {y}");
        }
    }
}

#[test]
fn coriolis_matrix_switch_is_the_registry_entry() {
    let dir = std::env::temp_dir().join(format!("kanegen-registry-{}", std::process::id()));
    let a = Builder::new(models().join("two-link.toml"))
        .coriolis_matrix(false)
        .out_dir(&dir)
        .output("a.rs")
        .build()
        .unwrap();
    let b = Builder::new(models().join("two-link.toml"))
        .functions(FunctionSet::default().without(FunctionId::CoriolisMatrix))
        .out_dir(&dir)
        .output("b.rs")
        .build()
        .unwrap();
    let (a, b) = (
        std::fs::read_to_string(a).unwrap(),
        std::fs::read_to_string(b).unwrap(),
    );
    assert_eq!(a, b);
    assert!(!a.contains("coriolis_matrix"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_reads_urdf_with_the_builders_import_options() {
    let (ok, stats, err) = kanegen(&["stats", "models/singlearm.urdf"]);
    assert!(ok, "{err}");
    assert!(
        stats.contains("7 speeds") && stats.contains("coriolis_matrix"),
        "{stats}"
    );

    let (ok, cli, err) = kanegen(&[
        "emit",
        "models/Krang.urdf",
        "--wheeled",
        "JLWheel,JRWheel,Base",
        "--up",
        "0,1,0",
        "--radius",
        "0.25",
        "--pitch-name",
        "imu",
        "--drop-links",
        "lgPlate1,lgPlate2,rgPlate1,rgPlate2",
        "--functions",
        "gravity",
    ]);
    assert!(ok, "{err}");
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.pitch_name = "imu".into();
    let options =
        UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]);
    let built = Builder::urdf(models().join("Krang.urdf"), options)
        .functions([FunctionId::Gravity].into_iter().collect())
        .generate()
        .unwrap();
    assert_eq!(cli, built.source);
    assert!(cli.contains("// URDF import notes:"));
    assert!(cli.contains("pub fn gravity(") && !cli.contains("pub fn mass_matrix("));
}

#[test]
fn cli_rejects_unknown_functions_and_urdf_options_on_toml() {
    let (ok, _, err) = kanegen(&["stats", "models/two-link.toml", "--functions", "jacobian"]);
    assert!(!ok);
    assert!(
        err.contains("unknown function `jacobian`") && err.contains("mass_matrix"),
        "{err}"
    );
    let (ok, _, err) = kanegen(&["stats", "models/two-link.toml", "--wheeled", "a,b,c"]);
    assert!(!ok);
    assert!(err.contains(".urdf"), "{err}");
    let (ok, _, err) = kanegen(&["stats", "models/singlearm.urdf", "--radius", "0.2"]);
    assert!(!ok);
    assert!(err.contains("--wheeled"), "{err}");
}

#[test]
fn kinematics_are_opt_in_listed_by_stats_and_the_same_without_the_dynamics() {
    let default = FunctionSet::default();
    for spec in &FUNCTIONS {
        assert_eq!(default.contains(spec.id), spec.default, "{}", spec.name);
        assert!(FunctionSet::all().contains(spec.id));
    }
    assert!(!default.contains(FunctionId::FrameJacobian));
    let (ok, out, err) = kanegen(&["stats", "models/krang.toml", "--functions", "all"]);
    assert!(ok, "{err}");
    for row in [
        "center_of_mass",
        "com_bias_acceleration",
        "kinetic_energy",
        "frame_pose[0]",
        "frame_jacobian[10l]",
        "frame_bias_acceleration[10r]",
    ] {
        assert!(out.contains(row), "{row} in\n{out}");
    }
    // Derived alone (no M composites, no motion pass of c to reuse), the same values.
    // (The opt-in kinematics; the derivatives, also opt-in, take u̇ and are tested elsewhere.)
    let kinematics = FunctionSet::kinematics();
    let with = |functions| {
        let options = Options {
            functions,
            ..Options::default()
        };
        Builder::new(models().join("krang.toml"))
            .options(options)
            .generate()
            .unwrap()
    };
    let (part, full) = (with(kinematics), with(FunctionSet::all()));
    let params = full.model.param_values();
    let q: Vec<f64> = (0..19).map(|i| 0.21 * i as f64 - 1.3).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.7 - 0.05 * i as f64).collect();
    let hand = full.model.link_index("10l");
    for id in kinematics.iter() {
        let frame = id.spec().per_frame.then_some(hand).flatten();
        let a = part.lowered.evaluate_at(id, frame, &params, &q, &u, &u);
        let b = full.lowered.evaluate_at(id, frame, &params, &q, &u, &u);
        let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-13 * scale, "{id}: {x} vs {y}");
        }
    }
}

/// Results are zeroed by assigning `zeros()` or filling a slice (one `memset`), never by
/// nalgebra's element-wise `Matrix::fill`: its strided iterator compiles to a dependent scalar
/// loop, which made `inverse_dynamics_derivatives_into` a third slower than the by-value form
/// (≈ 600 ns to zero the 19×38 matrix; `docs/performance.md`;
/// regression test).
#[test]
fn generated_code_zeroes_results_with_a_memset_not_nalgebras_element_wise_fill() {
    let options = Options {
        functions: FunctionSet::all(),
        ..Options::default()
    };
    let g = Builder::new(models().join("krang.toml"))
        .options(options)
        .generate()
        .unwrap();
    let s = &g.source;
    // Both looped forms, whose `_into` functions zero before storing the non-zero entries.
    assert!(s.contains("kanegen_runtime::derivatives_loop::run"));
    assert!(s.contains("kanegen_runtime::regressor::inverse_dynamics_regressor::<"));
    assert!(s.contains("*m = <SMatrix<f64, 19, 38>>::zeros();"));
    for (at, _) in s.match_indices(".fill(") {
        let line_start = s[..at].rfind('\n').map_or(0, |i| i + 1);
        assert!(
            s[..at].ends_with(".as_mut_slice()"),
            "element-wise fill in the generated code: {}",
            &s[line_start..at + 12]
        );
    }
}

#[test]
fn a_constant_that_is_no_finite_number_is_an_error_not_a_panic() {
    // The loaders refuse a model without speeds; one built in memory reached the emitter, whose
    // centre of mass divides by a total mass of zero: the folded constant is infinite, and
    // printing it as a literal panicked inside proc-macro2.
    let mut model = kanegen::model::Model::from_toml_file(models().join("two-link.toml")).unwrap();
    model.speeds.clear();
    for link in &mut model.links {
        if let Some(mount) = &mut link.mount {
            mount.joint.kind = kanegen::model::JointKind::Fixed;
        }
        link.body = None;
    }
    let options = Options {
        functions: FunctionSet::all(),
        ..Options::default()
    };
    match kanegen::Builder::from_model(model)
        .options(options)
        .generate()
    {
        Err(kanegen::Error::NonFiniteConstant {
            function, value, ..
        }) => {
            assert_eq!(function, "center_of_mass");
            assert!(!value.is_finite());
        }
        other => panic!("expected NonFiniteConstant, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn a_baked_constant_beyond_f32_range_is_an_error_in_an_f32_module() {
    // A finite f64 that an f32 literal cannot hold (the loaders bound parameters at 1e9; a
    // model built in memory is not bound): an error naming the precision, not a panic.
    let mut model = kanegen::model::Model::from_toml_file(models().join("two-link.toml")).unwrap();
    let xx2 = model.params.iter().position(|p| p.name == "XX2").unwrap();
    model.params[xx2].value = 1e40;
    let options = Options {
        params: kanegen::ParamMode::Baked,
        ..Options::default()
    };
    match kanegen::Builder::from_model(model.clone())
        .options(options)
        .precision(kanegen::Precision::F32)
        .generate()
    {
        Err(
            e @ kanegen::Error::NonFiniteConstant {
                precision: "f32", ..
            },
        ) => {
            assert!(e.to_string().contains("f32"), "{e}");
        }
        other => panic!("expected NonFiniteConstant, got {:?}", other.map(|_| ())),
    }
    // The same model in f64 is fine.
    assert!(
        kanegen::Builder::from_model(model)
            .options(options)
            .generate()
            .is_ok()
    );
}

#[test]
fn a_function_that_reads_only_sines_binds_no_unused_cosines() {
    // Baked, some functions of this arm (its mass matrix among them) read sines and no cosine:
    // the module bound `let (sin_q, cos_q) = sin_cos_n(…)`, and the user's build warned
    // "unused variable: cos_q".
    let inertial = r#"<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>"#;
    let urdf = format!(
        r#"<robot name="arm"><link name="base"/>
        <link name="l1">{inertial}</link><link name="l2">{inertial}</link><link name="l3">{inertial}</link>
        <joint name="a" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/></joint>
        <joint name="b" type="continuous"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/></joint>
        <joint name="c" type="continuous"><parent link="l2"/><child link="l3"/><axis xyz="1 0 0"/></joint>
        </robot>"#
    );
    let model =
        kanegen::model::Model::from_urdf_str(&urdf, "arm.urdf", &UrdfOptions::default()).unwrap();
    let options = Options {
        params: kanegen::ParamMode::Baked,
        functions: FunctionSet::all(),
    };
    let source = kanegen::Builder::from_model(model)
        .options(options)
        .generate()
        .unwrap()
        .source;
    let bindings: Vec<&str> = source.split("sin_cos_n(").collect();
    let mut sine_only = 0;
    // Between one binding and the next, the reads of the first.
    for pair in bindings.windows(2) {
        let (binding, reads) = (pair[0].rsplit("let (").next().unwrap(), pair[1]);
        for name in ["sin_q", "cos_q"] {
            if binding.starts_with(name) || binding.contains(&format!(", {name})")) {
                assert!(
                    reads.contains(&format!("{name}[")),
                    "`{name}` bound, never read"
                );
            }
        }
        // `binding` is the text after `let (`.
        sine_only += usize::from(binding.starts_with("sin_q, _)"));
    }
    assert!(
        sine_only > 0,
        "the model should have a function reading only sines"
    );
}
