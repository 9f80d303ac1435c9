//! The pairing's tests: mirrored programs keep every value's bits, on Krang and on models
//! without mirrors.

use super::*;
use crate::kane::derive;
use crate::options::Options;
use kanegen_model::Model;

fn lowered(file: &str) -> (Derivation, Lowered, Lowered) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let model = Model::from_toml_file(root.join(file)).expect("model loads");
    let d = derive(&model, Options::default());
    let plain = crate::lower::build::lower(&d);
    let mut paired = plain.clone();
    apply(&mut paired, &d);
    (d, plain, paired)
}

/// A deterministic pseudo-random value in ±`scale` (the `k`-th of a sequence).
fn draw(k: usize, scale: f64) -> f64 {
    scale * ((k as f64 * 12.9898 + 78.233).sin() * 43_758.547).fract()
}

#[test]
fn krang_pairs_most_arm_statements_and_computes_the_same_values() {
    let (d, plain, paired) = lowered("models/krang.toml");
    // (function, at least this many lane pairs): Krang's figures are M 301, c 181, g 43,
    // τ 192, C 967.
    for (id, at_least) in [
        (FunctionId::MassMatrix, 250),
        (FunctionId::Coriolis, 150),
        (FunctionId::Gravity, 35),
        (FunctionId::InverseDynamics, 150),
        (FunctionId::CoriolisMatrix, 800),
    ] {
        let f = paired
            .functions
            .iter()
            .find(|f| f.id == id)
            .expect("function");
        let plan = f.lanes.as_ref().expect("Krang's arms pair");
        assert!(
            plan.lane_pairs() >= at_least,
            "{id:?}: {}",
            plan.lane_pairs()
        );
        // The same operations: the rewrite moves statements and signs, never adds work.
        let before = plain.function(id).expect("function").ops;
        assert_eq!(f.program.ops.muls, before.muls, "{id:?}");
        assert_eq!(f.program.ops.fmas, before.fmas, "{id:?}");
        for draw_at in 0..20 {
            let n = d.dof;
            let params: Vec<f64> = (0..paired
                .lane_leaves
                .as_ref()
                .expect("paired")
                .mirror
                .params
                .len())
                .map(|k| 1.0 + draw(draw_at * 1000 + k, 0.5))
                .collect();
            let q: Vec<f64> = (0..n).map(|k| draw(draw_at * 77 + k, 3.1)).collect();
            let u: Vec<f64> = (0..n).map(|k| draw(draw_at * 91 + k + 500, 2.0)).collect();
            let ud: Vec<f64> = (0..n).map(|k| draw(draw_at * 13 + k + 900, 5.0)).collect();
            let a = plain.evaluate(id, &params, &q, &u, &ud);
            let b = paired.evaluate(id, &params, &q, &u, &ud);
            let scale = a.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() <= 1e-12 * scale, "{id:?}: {x} against {y}");
            }
        }
    }
}

#[test]
fn every_lane_pair_is_its_left_statement_mirrored_term_for_term() {
    // What makes the two-lane statement compute both scalar statements' bits: the right
    // statement is the left one with mirrored leaves and partners, same terms, same order.
    let (_, _, paired) = lowered("models/krang.toml");
    let leaves = paired.lane_leaves.as_ref().expect("paired");
    for f in &paired.functions {
        let Some(plan) = &f.lanes else { continue };
        let p = &f.program;
        for (t, role) in plan.roles.iter().enumerate() {
            if *role != Role::Left {
                continue;
            }
            assert_eq!(plan.roles[t + 1], Role::Right);
            let image = |k: usize| Some(plan.partner[k].unwrap_or(k));
            let mirrored = map_expr(&p.stmts[t].expr, &|l| leaves.leaf(l), &image)
                .expect("a lane statement's leaves have mirrors");
            assert_eq!(
                mirrored,
                p.stmts[t + 1].expr,
                "{}: {}",
                p.name,
                p.stmts[t].name
            );
            // Every statement it reads comes before it.
            let mut reads = Vec::new();
            locals(&p.stmts[t + 1].expr, &mut reads);
            assert!(reads.iter().all(|&r| r < t), "{}", p.stmts[t].name);
        }
    }
}

#[test]
fn the_looped_derivatives_straight_line_part_pairs_and_fills_the_same_workspace() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let model = Model::from_toml_file(root.join("models/krang.toml")).expect("loads");
    let options = Options {
        functions: crate::registry::FunctionSet::default()
            .with(FunctionId::InverseDynamicsDerivatives),
        ..Options::default()
    };
    let d = derive(&model, options);
    let plain = crate::lower::build::lower(&d);
    let mut paired = plain.clone();
    apply(&mut paired, &d);
    let (a, b) = (
        plain
            .derivative_loop
            .as_ref()
            .expect("Krang's derivatives are looped"),
        paired.derivative_loop.as_ref().expect("looped"),
    );
    let plan = b.lanes.as_ref().expect("the straight-line part pairs");
    // Krang: 2,200 statements, 793 lane pairs, 54 packed pairs.
    assert!(plan.lane_pairs() >= 600, "{}", plan.lane_pairs());
    // Other parameter values than `apply`'s check used.
    let params: Vec<f64> = (0..model.params.len())
        .map(|k| 1.0 + draw(k, 0.5))
        .collect();
    let pre = plain.precompute_values(&params);
    assert!(same_values(&a.program, &b.program, d.dof, &params, &pre));
}

#[test]
fn combined_programs_pair_and_give_the_same_parts() {
    use crate::combined::{Combined, resolve};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let model = Model::from_toml_file(root.join("models/krang.toml")).expect("loads");
    let mut c = Combined::new("whole_body_terms")
        .with(FunctionId::MassMatrix)
        .with(FunctionId::NonlinearEffects)
        .with(FunctionId::ComJacobian);
    for hand in ["left_hand", "right_hand"] {
        c = c.with_frame(FunctionId::FrameBiasAcceleration, hand);
    }
    let combined = resolve(&model, &[c]).expect("resolves");
    let d = crate::kane::derive_with(&model, Options::default(), &combined);
    let plain = crate::lower::build::lower(&d);
    let mut paired = plain.clone();
    apply(&mut paired, &d);
    let plan = paired.combined[0]
        .lanes
        .as_ref()
        .expect("the combined program pairs");
    assert!(plan.lane_pairs() > 300, "{}", plan.lane_pairs());
    let n = d.dof;
    for k in 0..10 {
        let params: Vec<f64> = (0..model.params.len())
            .map(|i| 1.0 + draw(k * 1000 + i, 0.5))
            .collect();
        let q: Vec<f64> = (0..n).map(|i| draw(k * 77 + i, 3.1)).collect();
        let u: Vec<f64> = (0..n).map(|i| draw(k * 91 + i + 500, 2.0)).collect();
        let a = plain.evaluate_combined(0, &params, &q, &u, &[]);
        let b = paired.evaluate_combined(0, &params, &q, &u, &[]);
        for (x, y) in a.iter().flatten().zip(b.iter().flatten()) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{x} against {y}");
        }
    }
}

#[test]
fn a_model_without_mirrored_subtrees_is_left_as_it_is() {
    let (_, plain, paired) = lowered("models/two-link.toml");
    assert!(paired.lane_leaves.is_none());
    for (a, b) in plain.functions.iter().zip(&paired.functions) {
        assert!(b.lanes.is_none());
        assert_eq!(
            format!("{:?}", a.program.stmts),
            format!("{:?}", b.program.stmts)
        );
    }
}
