//! The GPU kernels (`Builder::gpu`): every emitted WGSL module parses and validates with naga
//! (no device needed), the `f64` kernels call no transcendental built-in, the output is
//! deterministic and matches a golden file, and the Rust part of a module is unchanged.

use std::path::PathBuf;

use kanegen::emit::wgsl::{Kernels, kernels};
use kanegen::model::UrdfOptions;
use kanegen::{Builder, FunctionId as F, FunctionSet, Generated};
use naga::valid::{Capabilities, ValidationFlags, Validator};

fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models")
}

fn kernels_of(g: &Generated) -> Kernels {
    kernels(&g.model, &g.lowered, FunctionSet::all()).expect("kernels")
}

/// Parses and validates `source` as naga would for a device with `SHADER_F64`; returns the
/// module.
fn validate(what: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(source)));
    Validator::new(ValidationFlags::all(), Capabilities::FLOAT64)
        .validate(&module)
        .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(source)));
    module
}

/// The transcendental built-ins a module's functions call.
fn transcendentals(m: &naga::Module) -> Vec<naga::MathFunction> {
    use naga::MathFunction as M;
    let functions = m
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(m.entry_points.iter().map(|e| &e.function));
    let mut found = Vec::new();
    for f in functions {
        for (_, e) in f.expressions.iter() {
            if let naga::Expression::Math { fun, .. } = e
                && matches!(
                    fun,
                    M::Sin
                        | M::Cos
                        | M::Tan
                        | M::Exp
                        | M::Exp2
                        | M::Log
                        | M::Log2
                        | M::Pow
                        | M::Asin
                        | M::Acos
                        | M::Atan
                        | M::Atan2
                        | M::Sinh
                        | M::Cosh
                        | M::Tanh
                )
            {
                found.push(*fun);
            }
        }
    }
    found
}

fn check(what: &str, k: &Kernels) {
    validate(&format!("{what} f32"), &k.wgsl_f32);
    let m = validate(&format!("{what} f64"), &k.wgsl_f64);
    assert_eq!(
        transcendentals(&m),
        [],
        "{what}: f64 kernels must not call sin/cos/exp built-ins (SPIR-V defines them for 16/32-bit floats only)"
    );
    let names: Vec<&str> = m.entry_points.iter().map(|e| e.name.as_str()).collect();
    for (name, ..) in &k.entries {
        assert!(
            names.contains(&name.as_str()),
            "{what}: no entry point {name}"
        );
    }
    assert!(names.contains(&"precompute"));
    assert_eq!(
        k.forward_dynamics,
        names.contains(&"forward_dynamics") && names.contains(&"rollout")
    );
}

#[test]
fn krang_kernels_validate_in_both_precisions_without_f64_transcendentals() {
    let set = FunctionSet::default().with(F::NonlinearEffects);
    let g = Builder::new(models().join("krang.toml"))
        .functions(set)
        .generate()
        .unwrap();
    let k = kernels_of(&g);
    check("krang", &k);
    assert!(k.forward_dynamics);
    assert_eq!((k.dof, k.params), (19, 185));
}

#[test]
fn every_registry_function_of_the_urdf_arm_validates_as_a_kernel() {
    let g = Builder::urdf(models().join("singlearm.urdf"), UrdfOptions::default())
        .functions(FunctionSet::all())
        .generate()
        .unwrap();
    let k = kernels_of(&g);
    check("singlearm", &k);
    assert_eq!(k.entries.len(), g.lowered.functions.len());
    // One kernel per frame of a per-frame function.
    assert!(
        k.entries
            .iter()
            .filter(|e| e.0.starts_with("frame_pose_"))
            .count()
            > 1
    );
}

#[test]
fn baked_mimic_and_forward_dynamics_from_inverse_dynamics_validate() {
    // Baked parameters (no `params` reads), a mimic joint's angle from its master, and
    // forward dynamics from τ at zero acceleration (no c, no g in the set).
    let set: FunctionSet = [F::MassMatrix, F::InverseDynamics].into_iter().collect();
    let g = Builder::urdf(models().join("mimic_gripper.urdf"), UrdfOptions::default())
        .baked(true)
        .functions(set)
        .generate()
        .unwrap();
    let k = kernels_of(&g);
    check("mimic_gripper", &k);
    assert!(k.forward_dynamics);
    assert_eq!(k.params, 0);
}

#[test]
fn modules_without_mass_matrix_have_no_forward_dynamics_kernel() {
    let set: FunctionSet = [F::Gravity].into_iter().collect();
    let g = Builder::new(models().join("two-link.toml"))
        .functions(set)
        .generate()
        .unwrap();
    let k = kernels_of(&g);
    check("two-link gravity", &k);
    assert!(!k.forward_dynamics);
}

#[test]
fn gpu_output_is_deterministic_and_leaves_the_rust_part_unchanged() {
    let base = Builder::new(models().join("two-link.toml"));
    let plain = base.generate().unwrap().source;
    let run = || base.clone().gpu(true).generate().unwrap().source;
    let (a, b) = (run(), run());
    assert_eq!(a, b, "two generations differ");
    assert!(a.starts_with(&plain), "the Rust part changed");
    let tail = &a[plain.len()..];
    assert!(tail.contains("pub mod gpu {"));
    assert!(tail.contains("pub const MODULE: kanegen_runtime::gpu::GpuModule"));
    // The whole file still parses as Rust.
    syn::parse_file(&a).expect("parses");
    // Golden file of the two-link kernels (`KANEGEN_ACCEPT_GOLDEN=1` rewrites it).
    let golden = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden/two_link_gpu.rs.txt");
    if std::env::var_os("KANEGEN_ACCEPT_GOLDEN").is_some() {
        std::fs::write(&golden, tail).unwrap();
    }
    let expected = std::fs::read_to_string(&golden).expect("golden file");
    assert!(
        expected == tail,
        "the two-link GPU kernels differ from tests/golden/two_link_gpu.rs.txt"
    );
}
