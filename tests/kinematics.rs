//! The opt-in kinematics and energies as compiled generated code (modules of the root build
//! script with every registry function: the URDF arm, the two-link model, and the two-link model
//! baked in `f32`): the same values as the generator's interpreter of its straight-line programs
//! (whose values `codegen/tests/kinematics.rs` checks against the reference recursion and the
//! derivative identities), and the `Frame` API.

mod common;

use common::*;
use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options};
use kanegen_reference::random::random_physical_params;

#[allow(dead_code)] // a module uses only the functions under test
mod singlearm_all {
    include!(concat!(env!("OUT_DIR"), "/singlearm_all.rs"));
}

#[allow(dead_code)] // a module uses only the functions under test
mod two_link_all {
    include!(concat!(env!("OUT_DIR"), "/two_link_all.rs"));
}

#[allow(dead_code)] // a module uses only the functions under test
mod two_link_all_baked_f32 {
    include!(concat!(env!("OUT_DIR"), "/two_link_all_baked_f32.rs"));
}

fn generated(model: &Model) -> Generated {
    let options = Options {
        functions: FunctionSet::all(),
        ..Options::default()
    };
    Builder::from_model(model.clone())
        .options(options)
        .generate()
        .expect("generates")
}

/// Row-major data of a fixed-size matrix.
fn row_major<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> Vec<f64> {
    (0..R)
        .flat_map(|r| (0..C).map(move |c| m[(r, c)]))
        .collect()
}

/// Every kinematic function of a compiled module (`$m`, `DOF` speeds, wrapper `$ty`) against the
/// interpreter, for random parameters and states of `$model`, and its `Frame` API.
macro_rules! compiled_matches_interpreter {
    ($m:ident, $ty:ident, $model:expr, $seed:expr) => {{
        use $m::{DOF, Frame, Params};
        let model: Model = $model;
        let g = generated(&model);
        let mut r = rng($seed);
        let params = random_physical_params(&model, &mut r);
        let k = $m::$ty::new(Params::from_array(params.clone().try_into().unwrap()));
        let low = |id: FunctionId, frame: Option<usize>, q: &[f64], u: &[f64]| {
            g.lowered.evaluate_at(id, frame, &params, q, u, &[])
        };
        assert_eq!(Frame::ALL.len(), model.links.len());
        for (l, f) in Frame::ALL.into_iter().enumerate() {
            assert_eq!(f.index(), l);
            assert_eq!(f.name(), model.links[l].name);
            assert_eq!(Frame::from_name(f.name()), Some(f));
        }
        assert_eq!(Frame::from_name("no such frame"), None);
        for _ in 0..10 {
            let (q, u, _) = random_state(&mut r, DOF);
            let (qv, uv) = (sv::<DOF>(&q), sv::<DOF>(&u));
            let check = |what: &str, compiled: Vec<f64>, expected: Vec<f64>| {
                let err = rel_err(&compiled, &expected, 1.0);
                assert!(err < 1e-12, "{}: {what}: {err:e}", stringify!($m));
            };
            check(
                "center_of_mass",
                k.center_of_mass(&qv).as_slice().to_vec(),
                low(FunctionId::CenterOfMass, None, &q, &u),
            );
            check(
                "com_jacobian",
                row_major(&k.com_jacobian(&qv)),
                low(FunctionId::ComJacobian, None, &q, &u),
            );
            check(
                "com_bias_acceleration",
                k.com_bias_acceleration(&qv, &uv).as_slice().to_vec(),
                low(FunctionId::ComBiasAcceleration, None, &q, &u),
            );
            check(
                "kinetic_energy",
                vec![k.kinetic_energy(&qv, &uv)],
                low(FunctionId::KineticEnergy, None, &q, &u),
            );
            check(
                "potential_energy",
                vec![k.potential_energy(&qv)],
                low(FunctionId::PotentialEnergy, None, &q, &u),
            );
            for f in Frame::ALL {
                let l = Some(f.index());
                let pose = k.frame_pose(&qv, f).to_homogeneous();
                let pose: Vec<f64> = (0..3)
                    .flat_map(|r| (0..4).map(move |c| pose[(r, c)]))
                    .collect();
                let expected = low(FunctionId::FramePose, l, &q, &u);
                // The rotation goes through a unit quaternion: a few ulps.
                assert!(rel_err(&pose, &expected, 1.0) < 1e-12, "{}: pose", f.name());
                check(
                    "frame_jacobian",
                    row_major(&k.frame_jacobian(&qv, f)),
                    low(FunctionId::FrameJacobian, l, &q, &u),
                );
                check(
                    "frame_bias_acceleration",
                    k.frame_bias_acceleration(&qv, &uv, f).as_slice().to_vec(),
                    low(FunctionId::FrameBiasAcceleration, l, &q, &u),
                );
            }
        }
    }};
}

#[test]
fn urdf_arm_kinematics_compiled_match_the_interpreter() {
    let model = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .expect("URDF imports");
    compiled_matches_interpreter!(singlearm_all, SingleArm, model, 71);
}

#[test]
fn two_link_kinematics_compiled_match_the_interpreter() {
    compiled_matches_interpreter!(two_link_all, TwoLink, model("two-link.toml"), 72);
}

#[test]
fn baked_f32_kinematics_agree_with_f64() {
    use two_link_all_baked_f32 as b;
    let k64 = two_link_all::TwoLink::default();
    let k32 = b::TwoLink;
    let mut r = rng(73);
    for _ in 0..20 {
        let (q, u, _) = random_state(&mut r, 2);
        let (q64, u64) = (sv::<2>(&q), sv::<2>(&u));
        let (q32, u32) = (q64.cast::<f32>(), u64.cast::<f32>());
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() < 1e-4 * b.abs().max(1.0);
        assert!(close(
            k32.kinetic_energy(&q32, &u32),
            k64.kinetic_energy(&q64, &u64)
        ));
        assert!(close(
            k32.potential_energy(&q32),
            k64.potential_energy(&q64)
        ));
        for (f32_, f64_) in b::Frame::ALL.into_iter().zip(two_link_all::Frame::ALL) {
            let j32 = k32.frame_jacobian(&q32, f32_);
            let j64 = k64.frame_jacobian(&q64, f64_);
            assert!(
                (j32.cast::<f64>() - j64).abs().max() < 1e-4,
                "{}",
                f64_.name()
            );
            let p32 = k32.frame_pose(&q32, f32_).translation.vector.cast::<f64>();
            let p64 = k64.frame_pose(&q64, f64_).translation.vector;
            assert!((p32 - p64).abs().max() < 1e-4, "{}", f64_.name());
        }
    }
}

/// Bit for bit in the baseline copy. The x86-64-v3 copies fuse multiply-adds, and where a
/// product is a shared statement of the combined program but inline in the separate one (or the
/// reverse), one is fused and the other is not: there they agree to rounding (checked below).
#[test]
fn urdf_arm_combined_function_equals_the_separate_functions_bit_for_bit() {
    use krang_dynamics::isa::{self, Isa};
    // The only test of this binary that selects an instruction set.
    isa::select(Isa::Baseline).unwrap();
    combined_arm_equals_separate();
    isa::select(isa::detected()).unwrap();
    if isa::detected() != Isa::Baseline {
        combined_arm_agrees_with_separate_to_rounding();
    }
}

/// The combined function's fields against the separate functions, relative to each result's
/// largest entry, with the active instruction set.
fn combined_arm_agrees_with_separate_to_rounding() {
    use singlearm_all::{DOF, Frame, Params, SingleArm};
    let model = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .expect("URDF imports");
    let mut r = rng(75);
    let end = Frame::from_name("L7_EFF").expect("frame");
    let near = |a: &[f64], b: &[f64], what: &str| {
        let scale = a.iter().fold(1.0f64, |s, x| s.max(x.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-12 * scale, "{what}: {x:e} vs {y:e}");
        }
    };
    for _ in 0..20 {
        let params = random_physical_params(&model, &mut r);
        let k = SingleArm::new(Params::from_array(params.try_into().unwrap()));
        let (q, u, _) = random_state(&mut r, DOF);
        let (q, u) = (sv::<DOF>(&q), sv::<DOF>(&u));
        let w = k.arm_terms(&q, &u);
        near(w.mass_matrix.as_slice(), k.mass_matrix(&q).as_slice(), "M");
        let h = k.nonlinear_effects(&q, &u);
        near(w.nonlinear_effects.as_slice(), h.as_slice(), "h");
        let com = k.center_of_mass(&q);
        near(w.center_of_mass.as_slice(), com.as_slice(), "CoM");
        let j = k.com_jacobian(&q);
        near(w.com_jacobian.as_slice(), j.as_slice(), "CoM Jacobian");
        let jf = k.frame_jacobian(&q, end);
        near(
            w.frame_jacobian_l7_eff.as_slice(),
            jf.as_slice(),
            "frame Jacobian",
        );
        let e = [w.kinetic_energy, w.potential_energy];
        near(
            &e,
            &[k.kinetic_energy(&q, &u), k.potential_energy(&q)],
            "energies",
        );
    }
}

fn combined_arm_equals_separate() {
    use singlearm_all::{DOF, Frame, Params, SingleArm};
    let model = Model::from_urdf_file(
        root().join("models/singlearm.urdf"),
        &UrdfOptions::default(),
    )
    .expect("URDF imports");
    let mut r = rng(74);
    let frames = ["L7_EFF", "Bracket"].map(|n| Frame::from_name(n).expect("frame"));
    for _ in 0..5 {
        let params = random_physical_params(&model, &mut r);
        let k = SingleArm::new(Params::from_array(params.try_into().unwrap()));
        for _ in 0..4 {
            let (q, u, _) = random_state(&mut r, DOF);
            let (q, u) = (sv::<DOF>(&q), sv::<DOF>(&u));
            let w = k.arm_terms(&q, &u);
            assert_eq!(w.mass_matrix, k.mass_matrix(&q));
            assert_eq!(w.nonlinear_effects, k.nonlinear_effects(&q, &u));
            assert_eq!(w.center_of_mass, k.center_of_mass(&q));
            assert_eq!(w.com_jacobian, k.com_jacobian(&q));
            assert_eq!(w.com_bias_acceleration, k.com_bias_acceleration(&q, &u));
            assert_eq!(w.kinetic_energy, k.kinetic_energy(&q, &u));
            assert_eq!(w.potential_energy, k.potential_energy(&q));
            let [end, bracket] = frames;
            assert_eq!(w.frame_pose_l7_eff, k.frame_pose(&q, end));
            assert_eq!(w.frame_jacobian_l7_eff, k.frame_jacobian(&q, end));
            assert_eq!(
                w.frame_bias_acceleration_l7_eff,
                k.frame_bias_acceleration(&q, &u, end)
            );
            assert_eq!(w.frame_pose_bracket, k.frame_pose(&q, bracket));
            assert_eq!(w.frame_jacobian_bracket, k.frame_jacobian(&q, bracket));
            assert_eq!(
                w.frame_bias_acceleration_bracket,
                k.frame_bias_acceleration(&q, &u, bracket)
            );
        }
    }
}
