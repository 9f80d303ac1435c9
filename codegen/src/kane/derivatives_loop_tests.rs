//! The looped form (the workspace evaluated from the generator's expressions, then the
//! runtime's loop) against the straight-line form, on random parameters and states, for
//! every kind of joint and base the models have (mimic joints keep the straight-line form).

use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use kanegen_runtime::derivatives_loop::{Column, NO_ENTRY, NO_TRANSFORM, Plan, Step};

use crate::expr::Values;
use crate::options::{Options, ParamMode};
use crate::registry::{FunctionId, FunctionSet};

fn models_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models")
}

/// Worst `max |looped − straight| / max(max |straight|, 1)` over `draws` random draws.
fn compare(label: &str, model: &Model, params: ParamMode, draws: usize, seed: u64) {
    let options = Options {
        params,
        functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
    };
    let d = super::derive(model, options);
    let looped = d
        .derivative_loop
        .as_ref()
        .expect("no mimic joints: looped form derived");
    let plan = &looped.plan;
    let u16_of = |x: usize| u16::try_from(x).expect("fits");
    let u32_of = |x: usize| u32::try_from(x).expect("fits");
    let (flat_columns, flat_steps) = plan.flatten();
    let steps: Vec<Step> = flat_steps
        .iter()
        .map(|s| {
            let speed = plan.speeds[s.speed];
            let root = plan.floating_root.filter(|_| s.root);
            Step {
                transform: s.transform.map_or(NO_TRANSFORM, u16_of),
                motion: u16_of(root.unwrap_or(speed.motion)),
                axis: match root {
                    Some(_) => kanegen_runtime::derivatives_loop::FLOATING_ROOT,
                    None => speed
                        .axis
                        .unwrap_or(kanegen_runtime::derivatives_loop::DENSE),
                },
                joint: speed.joint && root.is_none(),
                entries: s.entries.map(|e| e.map_or(NO_ENTRY, u32_of)),
            }
        })
        .collect();
    let columns: Vec<Column> = flat_columns
        .iter()
        .map(|c| Column {
            forces: u16_of(c.forces),
            first: u32_of(c.first),
            own: u32_of(c.own),
            end: u32_of(c.end),
        })
        .collect();
    let tables = Plan {
        dof: plan.dof,
        columns: &columns,
        steps: &steps,
    };
    let n = model.independent_dof();
    let mut rng = SplitMix64::new(seed);
    let mut uni = move || rng.next_f64();
    let mut worst = 0.0f64;
    for draw in 0..draws {
        let p = if draw == 0 || params == ParamMode::Baked {
            model.param_values()
        } else {
            random_physical_params(model, &mut uni)
        };
        let q = super::rnea_derivatives_tests::random_coordinates(model, &mut uni);
        let u = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
        let ud = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
        // Row-major N × 2N.
        let straight = d.evaluate(FunctionId::InverseDynamicsDerivatives, &p, &q, &u, &ud);
        let x = Values {
            params: &p,
            q: &q,
            u: &u,
            ud: &ud,
        };
        let v = d.arena.eval(&x);
        let mut w = vec![0.0; plan.workspace];
        for &(k, _, e) in &looped.entries {
            w[k] = v[e.index()];
        }
        // Column-major N × 2N: the dispatched kernel (the AVX2 copy on x86-64-v3 CPUs)
        // and the portable one.
        let mut out = vec![0.0; n * 2 * n];
        kanegen_runtime::derivatives_loop::run(&tables, &w, &mut out);
        let mut portable = vec![0.0; n * 2 * n];
        kanegen_runtime::derivatives_loop::run_generic(&tables, &w, &mut portable);
        let scale = straight.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        for r in 0..n {
            for c in 0..2 * n {
                let b = straight[r * 2 * n + c];
                for (kernel, a) in [("run", out[r + n * c]), ("portable", portable[r + n * c])] {
                    let e = (a - b).abs() / scale;
                    assert!(
                        e < 1e-12,
                        "{label}: draw {draw}, entry [{r}, {c}]: looped ({kernel}) {a} vs straight-line {b}"
                    );
                    worst = worst.max(e);
                }
            }
        }
    }
    eprintln!("{label}: {draws} draws, worst relative difference {worst:.1e}");
}

#[test]
fn looped_derivatives_equal_the_straight_line_form_on_trees_and_wheeled_bases() {
    let toml = |name: &str| Model::from_toml_file(models_dir().join(name)).expect("loads");
    compare("krang", &toml("krang.toml"), ParamMode::Runtime, 20, 11);
    compare("krang, baked", &toml("krang.toml"), ParamMode::Baked, 2, 12);
    compare(
        "fixed wheels",
        &toml("krang-fixed-wheels.toml"),
        ParamMode::Runtime,
        20,
        13,
    );
    compare(
        "two-link",
        &toml("two-link.toml"),
        ParamMode::Runtime,
        50,
        14,
    );
    let arm = Model::from_urdf_file(models_dir().join("singlearm.urdf"), &UrdfOptions::default())
        .expect("imports");
    compare("arm", &arm, ParamMode::Runtime, 20, 15);
    let spec = WheeledBaseSpec::new(
        "left_wheel_joint",
        "right_wheel_joint",
        "chassis",
        [0.0, 0.0, 1.0],
        0.2,
    );
    let lift = Model::from_urdf_str(
        include_str!("../../tests/data/lift.urdf"),
        "lift.urdf",
        &UrdfOptions::wheeled(spec),
    )
    .expect("imports");
    compare("lift on a wheeled base", &lift, ParamMode::Runtime, 50, 16);
}

#[test]
fn looped_derivatives_equal_the_straight_line_form_on_floating_bases() {
    let hopper = Model::from_toml_file(models_dir().join("floating-hopper.toml")).expect("loads");
    compare("floating hopper", &hopper, ParamMode::Runtime, 20, 17);
    compare("floating hopper, baked", &hopper, ParamMode::Baked, 2, 18);
    let solo = Model::from_urdf_file(
        models_dir().join("../tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports");
    compare("solo 12, floating", &solo, ParamMode::Runtime, 10, 19);
}

#[test]
fn flat_tables_write_every_entry_once_and_move_once_per_ancestor_link() {
    let krang = Model::from_toml_file(models_dir().join("krang.toml")).expect("loads");
    let hopper = Model::from_toml_file(models_dir().join("floating-hopper.toml")).expect("loads");
    for model in [krang, hopper] {
        check_tables(&model);
    }
}

fn check_tables(model: &Model) {
    let options = Options {
        params: ParamMode::Runtime,
        functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
    };
    let d = super::derive(model, options);
    let plan = &d
        .derivative_loop
        .as_ref()
        .expect("looped form derived")
        .plan;
    let (columns, steps) = plan.flatten();
    assert!(plan.fits_tables());
    // Each result entry has one writer, so the loop may run the columns in any order.
    let n = plan.dof;
    let mut writers = vec![0usize; 2 * n * n];
    for s in &steps {
        for e in s.writes(n) {
            writers[e] += 1;
        }
    }
    assert!(writers.iter().all(|&w| w <= 1), "an entry written twice");
    if model.is_floating() {
        assert!(steps.iter().any(|s| s.root), "a floating base's root step");
    }
    // The columns' runs tile the steps; a run moves the forces once per ancestor link.
    assert_eq!(columns.last().map(|c| c.end), Some(steps.len()));
    let mut moves = 0;
    for (k, c) in columns.iter().enumerate() {
        assert_eq!(c.first, k.checked_sub(1).map_or(0, |j| columns[j].end));
        assert!(c.first <= c.own && c.own <= c.end);
        assert!(steps[c.first..c.own].iter().all(|s| s.transform.is_none()));
        moves += steps[c.own..c.end]
            .iter()
            .filter(|s| s.transform.is_some())
            .count();
    }
    assert_eq!(moves, plan.steps(), "one transform per step up");
}

#[test]
fn models_with_mimic_joints_keep_the_straight_line_form() {
    let gripper = Model::from_urdf_file(
        models_dir().join("mimic_gripper.urdf"),
        &UrdfOptions::default(),
    )
    .expect("imports");
    let options = Options {
        params: ParamMode::Runtime,
        functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
    };
    assert!(super::derive(&gripper, options).derivative_loop.is_none());
}
