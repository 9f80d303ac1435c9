//! The loop form of the inverse-dynamics regressor and its base regressor (docs/regressors.md): the straight-line part through the lowering's interpreter, the loop through
//! `kanegen_runtime::regressor` itself, against the straight-line function on random physical
//! parameters and states (Krang with its wheeled base, the two-link model, the URDF arm), and
//! the rule that chooses the form. Two kernels: the plain one the plan was derived from
//! (`inverse_dynamics_regressor_with`: every chunk from row 0, dense carries) and the plan kernel
//! the generated code calls (`inverse_dynamics_regressor_plan`: the tables as the emitter writes
//! them — chunks some ancestor speed moves, axis-specialised carries, seed and zero chunks, the
//! links' coefficients in `kin` — with both multiply-adds, `Plain` and `Fused`), each on a result
//! pre-filled with NaN.

use kanegen::kane::{CarryFrom, KIN, RegressorLoop};
use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options, RegressorForm};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use kanegen_runtime::isa::{Arith, Fused, Plain};
use kanegen_runtime::regressor::{
    DENSE_ROTATION, LANES, Link, NO_COLUMN, NO_SEED, NO_SLOT, PREVIOUS, Plan, Seed, Step,
    ZeroChunk, inverse_dynamics_regressor_plan, inverse_dynamics_regressor_with as run_loop,
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
    Builder::from_model(model.clone())
        .options(options)
        .regressor_form(form)
        .generate()
        .expect("generates")
}

/// What both kernels start from: function `id`'s loop tables, its `kin` table evaluated from the
/// generator's expressions, and a column-major `rows × cols` result as the generated `…_into`
/// prepares one of unknown content: NaN everywhere, the columns that are not a body's zeroed,
/// then their entries stored; the kernel must write every other entry (NaN left anywhere fails
/// the comparison).
#[allow(clippy::too_many_arguments)]
fn loop_inputs<'g>(
    g: &'g Generated,
    id: FunctionId,
    rows: usize,
    cols: usize,
    params: &[f64],
    q: &[f64],
    u: &[f64],
    ud: &[f64],
) -> (&'g RegressorLoop, Vec<[f64; KIN]>, Vec<f64>) {
    let f = g.lowered.functions.iter().find(|f| f.id == id).unwrap();
    let tables = &f.looped.as_ref().expect("loop form").tables;
    let (kin, extra) = g
        .lowered
        .evaluate_loop_inputs(id, params, q, u, ud)
        .expect("loop form");
    let kin = kin.chunks(KIN).map(|c| c.try_into().unwrap()).collect();
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
    (tables, kin, out)
}

/// A column-major `rows × cols` result as row-major entries.
fn row_major(out: &[f64], rows: usize, cols: usize) -> Vec<f64> {
    (0..rows * cols)
        .map(|i| out[(i % cols) * rows + i / cols])
        .collect()
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
    let (tables, kin, mut out) = loop_inputs(g, id, rows, cols, params, q, u, ud);
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
    let mut phi = vec![[[0.0; LANES]; 6]; slots];
    run_loop(&kin, &links, &seeds, rows, &mut out, &mut phi);
    row_major(&out, rows, cols)
}

/// The runtime tables of `tables` for a result of `rows` rows (as the emitter writes them).
struct Tables {
    columns: Vec<[u16; 10]>,
    steps: Vec<Step>,
    seeds: Vec<[[f64; LANES]; 6]>,
    zeros: Vec<ZeroChunk>,
    slots: usize,
}

fn first(columns: &[Option<usize>; 10]) -> u16 {
    match columns[0] {
        Some(c0) if (0..10).all(|t| columns[t] == Some(c0 + t)) => c0 as u16,
        _ => NO_COLUMN,
    }
}

fn tables(t: &RegressorLoop, rows: usize) -> Tables {
    let plan = t.plan(rows);
    Tables {
        columns: t
            .links
            .iter()
            .map(|l| l.columns.map(|c| c.map_or(NO_COLUMN, |c| c as u16)))
            .collect(),
        steps: plan
            .steps
            .iter()
            .map(|s| Step {
                link: s.link as u16,
                chunk: s.chunk as u16,
                slot: s.slot.map_or(NO_SLOT, |d| d as u16),
                from: match s.from {
                    Some(CarryFrom::Slot(f)) => f as u16,
                    Some(CarryFrom::Previous) => PREVIOUS,
                    None => NO_SLOT,
                },
                seed: s.seed.map_or(NO_SEED, |f| f as u16),
                rotation: t.joints[s.link]
                    .axis
                    .map_or(DENSE_ROTATION, |(r, c)| (3 * r + c) as u8),
                offset: t.joints[s.link].offset,
                body: s.body,
                first: first(&t.links[s.link].columns),
            })
            .collect(),
        seeds: plan.seeds.clone(),
        zeros: plan
            .zeros
            .iter()
            .map(|&(l, c)| ZeroChunk {
                link: l as u16,
                chunk: c as u16,
                first: first(&t.links[l].columns),
            })
            .collect(),
        slots: plan.slots,
    }
}

/// Function `id` of `g` in its loop form through the plan kernel with multiply-add `A`:
/// row-major `rows × cols`.
#[allow(clippy::too_many_arguments)]
fn plan_value<A: Arith<f64>>(
    g: &Generated,
    id: FunctionId,
    rows: usize,
    cols: usize,
    params: &[f64],
    q: &[f64],
    u: &[f64],
    ud: &[f64],
) -> Vec<f64> {
    let (t, kin, mut out) = loop_inputs(g, id, rows, cols, params, q, u, ud);
    let tb = tables(t, rows);
    let plan = Plan {
        columns: &tb.columns,
        steps: &tb.steps,
        seeds: &tb.seeds,
        zeros: &tb.zeros,
    };
    let mut phi = vec![[[f64::NAN; LANES]; 6]; tb.slots];
    inverse_dynamics_regressor_plan::<A, f64>(&kin, &plan, rows, &mut out, &mut phi);
    row_major(&out, rows, cols)
}

#[test]
fn loop_kernels_equal_the_straight_line_regressors_on_random_states() {
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
                let scale = straight.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                for (kernel, looped) in [
                    ("plain", loop_value(g, id, n, cols, &params, &q, &u, &ud)),
                    (
                        "plan, Plain",
                        plan_value::<Plain>(g, id, n, cols, &params, &q, &u, &ud),
                    ),
                    (
                        "plan, Fused",
                        plan_value::<Fused>(g, id, n, cols, &params, &q, &u, &ud),
                    ),
                ] {
                    assert!(
                        looped.iter().all(|v| v.is_finite()),
                        "{name} {id:?} ({kernel} kernel): entry not written"
                    );
                    for (j, (a, b)) in looped.iter().zip(&straight).enumerate() {
                        let e = (a - b).abs() / scale;
                        assert!(
                            e <= 1e-12,
                            "{name} {id:?} ({kernel} kernel), row {} column {}: loop {a}, straight line {b}",
                            j / cols,
                            j % cols
                        );
                        worst = worst.max(e);
                    }
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

#[test]
fn krang_plan_skips_the_chunks_no_ancestor_speed_moves_and_specialises_its_joints() {
    let g = krang();
    let f = g
        .lowered
        .functions
        .iter()
        .find(|f| f.id == FunctionId::InverseDynamicsRegressor)
        .unwrap();
    let t = &f.looped.as_ref().unwrap().tables;
    let plan = t.plan(19);
    // Every (link, chunk) of a body is computed or stored as zeros, never both.
    let bodies = t.links.iter().filter(|l| l.writes()).count();
    let computed = plan.steps.iter().filter(|s| s.body).count();
    assert_eq!(
        computed + plan.zeros.len(),
        bodies * 19usize.div_ceil(LANES)
    );
    // Fewer lane flops than the plain kernel's chunks from row 0 (which carry every chunk
    // densely and compute the 71-flop entries in all of them).
    assert!(
        plan.flops < t.plain_flops(),
        "{} {}",
        plan.flops,
        t.plain_flops()
    );
    // Krang's joints are rotations about a coordinate axis after a signed permutation.
    let mounted = t.links.iter().enumerate().filter(|(l, k)| k.parent != *l);
    for (l, _) in mounted {
        assert!(t.joints[l].axis.is_some(), "link {l}");
    }
    assert!(g.source.contains("kanegen_runtime::regressor::Step {"));
    assert!(g.source.contains("kanegen_runtime::isa::dispatch_fused("));
}
