//! The loop form's plan (README, "Regressors: the loop form"): the tables the generated code
//! passes to `kanegen_runtime::regressor::inverse_dynamics_regressor` (chunks some ancestor
//! speed moves, axis-specialised carries, seed chunks, zero chunks, the links' coefficients in
//! the `kin` table), run through the runtime's kernel with both multiply-adds (`Plain`, `Fused`)
//! on a result pre-filled with NaN, against the straight-line function on random physical
//! parameters and states: Krang (wheeled base), the two-link model and the URDF arm.

use kanegen::kane::{CarryFrom, KIN, RegressorLoop};
use kanegen::model::{Model, UrdfOptions};
use kanegen::{
    EmitOptions, FunctionId, FunctionSet, Generated, Options, RegressorForm, generate_with,
};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use kanegen_runtime::isa::{Arith, Fused, Plain};
use kanegen_runtime::regressor::{
    DENSE_ROTATION, LANES, NO_COLUMN, NO_SEED, NO_SLOT, PREVIOUS, Plan, Step, ZeroChunk,
    inverse_dynamics_regressor_plan,
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

/// Krang in loop form, generated once per test binary (its debug generation takes seconds).
fn krang() -> &'static Generated {
    static KRANG: std::sync::OnceLock<Generated> = std::sync::OnceLock::new();
    KRANG.get_or_init(|| generated(&load("krang.toml"), RegressorForm::Loop))
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
    let f = g.lowered.functions.iter().find(|f| f.id == id).unwrap();
    let t = &f.looped.as_ref().expect("loop form").tables;
    let (kin, extra) = g
        .lowered
        .evaluate_loop_inputs(id, params, q, u, ud)
        .expect("loop form");
    let kin: Vec<[f64; KIN]> = kin.chunks(KIN).map(|c| c.try_into().unwrap()).collect();
    let tb = tables(t, rows);
    let plan = Plan {
        columns: &tb.columns,
        steps: &tb.steps,
        seeds: &tb.seeds,
        zeros: &tb.zeros,
    };
    let mut out = vec![f64::NAN; rows * cols];
    let body: Vec<usize> = t
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
    let mut phi = vec![[[f64::NAN; LANES]; 6]; tb.slots];
    inverse_dynamics_regressor_plan::<A, f64>(&kin, &plan, rows, &mut out, &mut phi);
    (0..rows * cols)
        .map(|i| out[(i % cols) * rows + i / cols])
        .collect()
}

#[test]
fn plan_kernel_equals_the_straight_line_regressors_with_both_multiply_adds() {
    for (i, name) in ["krang.toml", "two-link.toml", "singlearm.urdf"]
        .into_iter()
        .enumerate()
    {
        let model = load(name);
        let own;
        let g = if name == "krang.toml" {
            krang()
        } else {
            own = generated(&model, RegressorForm::Loop);
            &own
        };
        let n = model.dof();
        let mut r = SplitMix64::new(71 + i as u64);
        let mut uniform = move || r.next_f64();
        let mut worst: f64 = 0.0;
        for _ in 0..25 {
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
                for looped in [
                    plan_value::<Plain>(g, id, n, cols, &params, &q, &u, &ud),
                    plan_value::<Fused>(g, id, n, cols, &params, &q, &u, &ud),
                ] {
                    assert!(
                        looped.iter().all(|v| v.is_finite()),
                        "{name} {id:?}: entry not written"
                    );
                    for (a, b) in looped.iter().zip(&straight) {
                        worst = worst.max((a - b).abs() / scale);
                    }
                }
            }
        }
        println!("{name}: plan kernel = straight line to {worst:.1e}");
        assert!(worst <= 1e-12, "{name}: {worst:e}");
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
