//! The loop form of the inverse-dynamics regressor and its base regressor (README, "Regressors:
//! the loop form"): the straight-line part through the lowering's interpreter, the loop through
//! `kanegen_runtime::regressor` itself, against the straight-line function on random physical
//! parameters and states (Krang with its wheeled base, the two-link model, the URDF arm), and
//! the rule that chooses the form.

use kanegen::kane::KIN;
use kanegen::model::{Model, UrdfOptions};
use kanegen::{
    EmitOptions, FunctionId, FunctionSet, Generated, Options, RegressorForm, generate_with,
};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use kanegen_runtime::regressor::{
    LANES, Link, NO_COLUMN, Seed, inverse_dynamics_regressor_with as run_loop,
};

fn load(name: &str) -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("models")
        .join(name);
    if name.ends_with(".urdf") {
        Model::from_urdf_file(&path, &UrdfOptions::default()).expect("URDF imports")
    } else {
        Model::from_toml_file(&path).expect("model loads")
    }
}

/// Krang with the default rule, generated once per test binary (its debug generation takes
/// seconds).
fn krang() -> &'static Generated {
    static KRANG: std::sync::OnceLock<Generated> = std::sync::OnceLock::new();
    KRANG.get_or_init(|| generated(&load("krang.toml"), RegressorForm::Auto))
}

fn generated(model: &Model, form: RegressorForm) -> Generated {
    let options = Options {
        functions: FunctionSet::regressors().with(FunctionId::InverseDynamics),
        ..Options::default()
    };
    let emit = EmitOptions {
        regressor_form: form,
        ..EmitOptions::default()
    };
    generate_with(model.clone(), options, &emit).expect("generates")
}

/// Function `id` of `g` evaluated in its loop form: row-major `rows × cols`.
#[allow(clippy::too_many_arguments)]
fn loop_value(
    g: &Generated,
    id: FunctionId,
    rows: usize,
    cols: usize,
    params: &[f64],
    q: &[f64],
    u: &[f64],
    ud: &[f64],
) -> Vec<f64> {
    let f = g.lowered.functions.iter().find(|f| f.id == id).unwrap();
    let tables = &f.looped.as_ref().expect("loop form").tables;
    let (kin, extra) = g
        .lowered
        .evaluate_loop_inputs(id, params, q, u, ud)
        .expect("loop form");
    let kin: Vec<[f64; KIN]> = kin.chunks(KIN).map(|c| c.try_into().unwrap()).collect();
    let (chunks, slots) = tables.chunks();
    assert_eq!(kanegen::kane::LANES, LANES);
    let links: Vec<Link> = tables
        .links
        .iter()
        .zip(&chunks)
        .map(|(l, &(n, slot))| Link {
            parent: l.parent as u16,
            columns: l.columns.map(|c| c.map_or(NO_COLUMN, |c| c as u16)),
            chunks: n as u16,
            slot: slot as u16,
        })
        .collect();
    let seeds: Vec<Seed<f64>> = tables
        .seeds()
        .into_iter()
        .map(|(row, link, phi)| Seed {
            row: row as u16,
            link: link as u16,
            phi,
        })
        .collect();
    // As the generated `…_into` does with a result of unknown content: the columns that are not
    // a body's zeroed, then their entries stored; the loop must write every other entry (NaN
    // left anywhere fails the comparison).
    let mut out = vec![f64::NAN; rows * cols];
    let body: Vec<usize> = tables
        .links
        .iter()
        .flat_map(|l| l.columns.iter().flatten().copied())
        .collect();
    for c in (0..cols).filter(|c| !body.contains(c)) {
        out[c * rows..(c + 1) * rows].fill(0.0);
    }
    for (r, c, v) in extra {
        out[c * rows + r] = v;
    }
    let mut phi = vec![[[0.0; LANES]; 6]; slots];
    run_loop(&kin, &links, &seeds, rows, &mut out, &mut phi);
    // Column-major to row-major.
    (0..rows * cols)
        .map(|i| out[(i % cols) * rows + i / cols])
        .collect()
}

#[test]
fn loop_form_equals_the_straight_line_regressors_on_random_states() {
    let cases = [
        ("krang.toml", RegressorForm::Auto),
        ("two-link.toml", RegressorForm::Loop),
        ("singlearm.urdf", RegressorForm::Loop),
    ];
    for (i, (name, form)) in cases.into_iter().enumerate() {
        let model = load(name);
        let own;
        let g = if name == "krang.toml" {
            krang()
        } else {
            own = generated(&model, form);
            &own
        };
        let n = model.dof();
        let mut r = SplitMix64::new(31 + i as u64);
        let mut uniform = move || r.next_f64();
        let mut worst: f64 = 0.0;
        for _ in 0..40 {
            let params = random_physical_params(&model, &mut uniform);
            let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
            let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
            let ud = uniform_vec(&mut uniform, n, -2.0, 2.0);
            for (id, cols) in [
                (
                    FunctionId::InverseDynamicsRegressor,
                    g.lowered.sizes.inertial,
                ),
                (FunctionId::BaseRegressor, g.lowered.sizes.base),
            ] {
                let straight = g.lowered.evaluate(id, &params, &q, &u, &ud);
                let looped = loop_value(g, id, n, cols, &params, &q, &u, &ud);
                let scale = straight.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                assert!(
                    looped.iter().all(|v| v.is_finite()),
                    "{name} {id:?}: entry not written"
                );
                for (j, (a, b)) in looped.iter().zip(&straight).enumerate() {
                    if (a - b).abs() / scale > 1e-9 && std::env::var("DBG").is_ok() {
                        eprintln!(
                            "{name} {id:?} r{} c{}: loop {a} straight {b}",
                            j / cols,
                            j % cols
                        );
                    }
                    worst = worst.max((a - b).abs() / scale);
                }
            }
        }
        println!("{name}: loop form = straight line to {worst:.1e}");
        assert!(worst <= 1e-12, "{name}: {worst:e}");
    }
}

#[test]
fn the_loop_form_is_chosen_where_the_straight_line_outgrows_the_instruction_cache() {
    let looped = |g: &Generated| {
        g.lowered
            .functions
            .iter()
            .filter(|f| f.looped.is_some())
            .map(|f| f.id)
            .collect::<Vec<_>>()
    };
    let krang = krang();
    assert_eq!(
        looped(krang),
        [
            FunctionId::InverseDynamicsRegressor,
            FunctionId::BaseRegressor
        ]
    );
    let f = &krang.lowered.functions;
    let y = f
        .iter()
        .find(|f| f.id == FunctionId::InverseDynamicsRegressor)
        .unwrap();
    let lp = y.looped.as_ref().unwrap();
    // Krang: 19 speeds over 20 bodies, 138 (speed, body) pairs.
    assert_eq!(lp.tables.pairs(), 138);
    assert!(
        krang
            .source
            .contains("kanegen_runtime::regressor::inverse_dynamics_regressor::<")
    );
    assert!(kanegen::stats(krang).contains("runs in loop form"));
    let straight = generated(&load("krang.toml"), RegressorForm::StraightLine);
    assert!(looped(&straight).is_empty());
    assert!(!straight.source.contains("kanegen_runtime::regressor"));
    for small in ["two-link.toml", "singlearm.urdf"] {
        let g = generated(&load(small), RegressorForm::Auto);
        assert!(looped(&g).is_empty(), "{small}");
    }
}
