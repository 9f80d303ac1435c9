//! Statement scheduling: the generated programs keep few values live at once (register pressure
//! is what limits the speed of long straight-line code), and scheduling does not change what
//! they compute.

use kanegen::kane::derive;
use kanegen::lower::lower;
use kanegen::model::Model;
use kanegen::{FunctionId, Options, ParamMode};

/// Krang derived with `mode` parameters and lowered.
fn lowered(mode: ParamMode) -> kanegen::lower::Lowered {
    lower(&derive(
        &krang(),
        Options {
            params: mode,
            ..Options::default()
        },
    ))
}

fn krang() -> Model {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    Model::from_toml_file(root.join("models/krang.toml")).expect("krang.toml loads")
}

/// Upper bounds on the values live at once in Krang's programs (with runtime parameters they
/// are 39, 111, 32, 111 and 144 — the Coriolis matrix in `subtree_order`, 455 in the
/// derivation's order and 236 when `subtree_order` took the entries by row only; the bounds
/// leave some room for changes to the derivation).
const MAX_LIVE: [(FunctionId, usize); 5] = [
    (FunctionId::MassMatrix, 45),
    (FunctionId::Coriolis, 125),
    (FunctionId::Gravity, 40),
    (FunctionId::InverseDynamics, 125),
    (FunctionId::CoriolisMatrix, 165),
];

#[test]
fn krang_programs_keep_few_values_live() {
    for mode in [ParamMode::Runtime, ParamMode::Baked] {
        let low = lowered(mode);
        for (name, bound) in MAX_LIVE {
            let live = low.function(name).expect("function exists").max_live();
            assert!(
                live <= bound,
                "{name} ({mode:?}): {live} values live at once, more than {bound}"
            );
        }
    }
}

#[test]
fn every_statement_follows_the_statements_it_reads() {
    let d = derive(&krang(), Options::default());
    let low = lower(&d);
    // The lowering's interpreter evaluates statements in order and would index past the end of
    // its locals if a statement read a later one; compare it with the derivation's evaluator.
    let params: Vec<f64> = krang().params.iter().map(|p| p.value).collect();
    let q: Vec<f64> = (0..19).map(|i| 0.1 * i as f64 - 0.7).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.3 - 0.05 * i as f64).collect();
    let ud: Vec<f64> = (0..19).map(|i| (i as f64 * 0.37).sin()).collect();
    for name in [
        FunctionId::MassMatrix,
        FunctionId::Coriolis,
        FunctionId::Gravity,
        FunctionId::InverseDynamics,
        FunctionId::CoriolisMatrix,
    ] {
        let a = low.evaluate(name, &params, &q, &u, &ud);
        let b = d.evaluate(name, &params, &q, &u, &ud);
        let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * scale, "{name}: {x} vs {y}");
        }
    }
}

/// `subtree_order` only reorders: on Krang's c, τ and Coriolis matrix (runtime and baked
/// parameters) every statement still follows what it reads (the interpreter would index past
/// its locals otherwise), the values are those of the lowered order bit for bit, and with
/// runtime parameters fewer values are live at once for c and τ (111 → 83 and 87; the lowered
/// Coriolis matrix is in this order already, and a second pass keeps its 144).
#[test]
fn subtree_order_keeps_the_values_and_lowers_the_values_live() {
    use kanegen::lower::subtree_order;
    let params: Vec<f64> = krang().params.iter().map(|p| p.value).collect();
    let q: Vec<f64> = (0..19).map(|i| 0.13 * i as f64 - 0.9).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.4 - 0.07 * i as f64).collect();
    let ud: Vec<f64> = (0..19).map(|i| (i as f64 * 0.53).cos()).collect();
    for mode in [ParamMode::Runtime, ParamMode::Baked] {
        let low = lowered(mode);
        for id in [
            FunctionId::Coriolis,
            FunctionId::InverseDynamics,
            FunctionId::CoriolisMatrix,
        ] {
            let before = low.evaluate(id, &params, &q, &u, &ud);
            let mut reordered = low.clone();
            let f = reordered
                .functions
                .iter_mut()
                .find(|f| f.id == id)
                .expect("function exists");
            let live = f.program.max_live();
            subtree_order(&mut f.program);
            let after = reordered.evaluate(id, &params, &q, &u, &ud);
            assert!(
                before
                    .iter()
                    .zip(&after)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{id} ({mode:?}): values changed"
            );
            let live_after = f_live(&reordered, id);
            if mode == ParamMode::Runtime && id != FunctionId::CoriolisMatrix {
                assert!(live_after < live, "{id}: {live} → {live_after} values live");
            } else if mode == ParamMode::Runtime {
                assert_eq!(live_after, live, "{id}: a second pass changed the order");
            }
        }
    }
}

fn f_live(low: &kanegen::lower::Lowered, id: FunctionId) -> usize {
    low.function(id).expect("function exists").max_live()
}

/// `restrict` (how a batched function with more result entries than one vectorized loop can
/// store is split into several loops): each part of Krang's Coriolis matrix, split by rows as
/// its batched function is (rows 0–11: 176 entries, 12–18: 84), gives its entries the whole
/// program's bits and nothing else, and holds only the statements its entries read (fewer than
/// the whole; together more: the statements both read are in both).
#[test]
fn restricted_programs_give_their_entries_bits_and_hold_only_what_they_read() {
    use kanegen::lower::restrict;
    let params: Vec<f64> = krang().params.iter().map(|p| p.value).collect();
    let q: Vec<f64> = (0..19).map(|i| 0.13 * i as f64 - 0.9).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.4 - 0.07 * i as f64).collect();
    let low = lowered(ParamMode::Runtime);
    let id = FunctionId::CoriolisMatrix;
    let whole = low.evaluate(id, &params, &q, &u, &[0.0; 19]);
    let full = low.function(id).expect("function exists");
    let mut statements = 0;
    for rows in [0..12, 12..19] {
        let mut part = low.clone();
        let f = part
            .functions
            .iter_mut()
            .find(|f| f.id == id)
            .expect("function exists");
        f.program = restrict(&f.program, |r, _| rows.contains(&r));
        assert!(f.program.stmts.len() < full.stmts.len());
        assert_eq!(f.program.sincos, full.sincos);
        statements += f.program.stmts.len();
        eprintln!(
            "rows {rows:?}: {} statements, {} flops (whole: {}, {})",
            f.program.stmts.len(),
            f.program.ops.flops(),
            full.stmts.len(),
            full.ops.flops()
        );
        let values = part.evaluate(id, &params, &q, &u, &[0.0; 19]);
        for (i, (a, b)) in whole.iter().zip(&values).enumerate() {
            let (r, c) = (i / 19, i % 19);
            let expected = if rows.contains(&r) { *a } else { 0.0 };
            assert_eq!(b.to_bits(), expected.to_bits(), "C[({r}, {c})]");
        }
    }
    assert!(statements > full.stmts.len());
}

/// Krang's module with the batched functions.
fn batched_krang() -> String {
    let g = kanegen::Builder::from_model(krang())
        .batch(true)
        .generate()
        .expect("generates");
    g.source
}

/// The body of the generated function `name` (generic, public or not): from its signature to
/// the next item.
fn function_body(source: &str, name: &str) -> String {
    let from = source
        .find(&format!("fn {name}<"))
        .unwrap_or_else(|| panic!("{name} is emitted"));
    let rest = &source[from + 1..];
    let to = ["\n    pub fn ", "\n    fn ", "\n    #[doc"]
        .iter()
        .filter_map(|end| rest.find(end))
        .min()
        .unwrap_or(rest.len());
    rest[..to].to_owned()
}

/// The emitted batched functions of Krang: the Coriolis matrix (260 entries, 53 lane inputs:
/// over the 240 locations one vectorized loop may touch) in two loops over the states, each
/// storing the entries whose deeper speed (`max(row, column)`) is in its range: 0–14 (the
/// trunk, the left arm and the right arm's first three joints, 180 entries) and 15–18 (80); M, c,
/// g and τ in one loop each. The loops are in the body both layouts share (`NAME_batch_body`).
#[test]
fn batched_coriolis_matrix_is_split_into_two_loops_by_the_deeper_speed_and_the_others_are_not() {
    let source = batched_krang();
    let body = |name: &str| function_body(&source, &format!("{name}_batch_body"));
    let loops = |text: &str| text.matches("for l in 0..L").count();
    for name in ["mass_matrix", "coriolis", "gravity", "inverse_dynamics"] {
        assert_eq!(loops(&body(name)), 1, "{name}");
    }
    let c = body("coriolis_matrix");
    assert_eq!(loops(&c), 2);
    let second = c.rfind("for l in 0..L").expect("two loops");
    // The deeper speed of every entry a loop stores (`out.set(row, column, l, …)`).
    let keys = |text: &str| -> Vec<usize> {
        let mut keys: Vec<usize> = text
            .match_indices("out.set(")
            .filter_map(|(i, _)| {
                let mut it = text[i + 8..].splitn(3, ',');
                let r: usize = it.next()?.trim().parse().ok()?;
                let c: usize = it.next()?.trim().parse().ok()?;
                Some(r.max(c))
            })
            .collect();
        keys.sort_unstable();
        keys.dedup();
        keys
    };
    // C[0, 0] (ẋ, ẋ) is structurally zero.
    assert_eq!(keys(&c[..second]), (1..15).collect::<Vec<_>>());
    assert_eq!(keys(&c[second..]), (15..19).collect::<Vec<_>>());
    assert_eq!(c[..second].matches("out.set(").count(), 180);
    assert_eq!(c[second..].matches("out.set(").count(), 80);
}

/// Both layouts run the one shared body (emitted once) between their own input conversion and
/// the entries no statement stores: the array of states transposes its inputs and completes
/// each state's result; the structure of arrays reads its inputs in place (c, g, τ: their
/// bodies store into local lane buffers; M and C, whose bodies store straight into the result
/// and read copies of the parameters, read the coordinates only through the sines and cosines
/// before the loop) or copies them (C's speeds, which its loops read), and copies or zeroes
/// whole entries, all lanes at once.
#[test]
fn both_batched_layouts_share_one_body_and_differ_only_in_inputs_and_the_entries_after_it() {
    let source = batched_krang();
    for (name, loops, buffered) in [
        ("mass_matrix", 1, false),
        ("coriolis", 1, true),
        ("gravity", 1, true),
        ("inverse_dynamics", 1, true),
        ("coriolis_matrix", 2, false),
    ] {
        let shared = format!("{name}_batch_body");
        assert_eq!(
            source.matches(&format!("fn {shared}<")).count(),
            1,
            "{name}"
        );
        assert_eq!(
            function_body(&source, &shared)
                .matches("for l in 0..L")
                .count(),
            loops,
            "{name}"
        );
        let body = function_body(&source, &shared);
        assert_eq!(body.contains("let p = &{ *p };"), !buffered, "{name}");
        assert_eq!(body.contains("out.set("), !buffered, "{name}");
        assert_eq!(
            body.matches("let mut entries").count(),
            if buffered { loops } else { 0 },
            "{name}"
        );
        assert_eq!(body.contains("out.set_lanes("), buffered, "{name}");
        let states = function_body(&source, &format!("{name}_batch_into"));
        let lanes = function_body(&source, &format!("{name}_batch_soa_into"));
        for (b, inputs) in [
            (&states, "lanes::inputs(q)"),
            (&lanes, "lanes::as_lanes(q)"),
        ] {
            assert!(b.contains(inputs), "{name}");
            assert!(b.contains(&format!("{shared}::<A, _, L>(")), "{name}");
            assert!(!b.contains("for l in 0..L"), "{name}");
        }
        assert!(!lanes.contains("out.iter_mut()"), "{name}");
    }
    // Speeds read in the loop: in place where it stores into a buffer (c), copied where it
    // stores straight into the result (C).
    let soa = |name: &str| function_body(&source, &format!("{name}_batch_soa_into"));
    assert!(soa("coriolis").contains("lanes::as_lanes(u)"));
    assert!(soa("coriolis_matrix").contains("lanes::inputs_soa(u)"));
    // M's lower triangle: copied after the shared body, per state or as whole entries.
    let m = function_body(&source, "mass_matrix_batch_into");
    assert!(m.contains("for m in out.iter_mut()"));
    assert!(m.contains("m[(1, 0)] = m[(0, 1)];"));
    let m = function_body(&source, "mass_matrix_batch_soa_into");
    assert!(m.contains("out[(1, 0)] = out[(0, 1)];"));
}

/// The batched bodies of τ, g and the Coriolis matrix run their statements in `subtree_order`
/// (`lower::batch_program`), which keeps fewer values live than the single-state order Krang's
/// module uses (mirrored lanes pair and reorder the single-state programs); c keeps its own
/// order (measured slower in subtree order). The same statements, reordered: the values are
/// those of the single-state program bit for bit.
#[test]
fn batched_bodies_of_tau_g_and_c_run_in_subtree_order_with_fewer_values_live() {
    use std::borrow::Cow;

    use kanegen::lower::{BATCH_SUBTREE_ORDER, batch_program};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let g = kanegen::Builder::new(root.join("models/krang.toml"))
        .mirrored_lanes(true)
        .generate()
        .expect("generates");
    let params: Vec<f64> = krang().params.iter().map(|p| p.value).collect();
    let q: Vec<f64> = (0..19).map(|i| 0.11 * i as f64 - 0.8).collect();
    let u: Vec<f64> = (0..19).map(|i| 0.35 - 0.06 * i as f64).collect();
    let ud: Vec<f64> = (0..19).map(|i| (i as f64 * 0.41).sin()).collect();
    for f in &g.lowered.functions {
        let batched = batch_program(f.id, &f.program);
        if BATCH_SUBTREE_ORDER.contains(&f.id) {
            assert!(matches!(batched, Cow::Owned(_)), "{}", f.id);
            let (before, after) = (f.program.max_live(), batched.max_live());
            assert!(after < before, "{}: {before} → {after} values live", f.id);
            let mut reordered = g.lowered.clone();
            let r = reordered
                .functions
                .iter_mut()
                .find(|r| r.id == f.id)
                .expect("function exists");
            r.program = batched.into_owned();
            let (a, b) = (
                g.lowered.evaluate(f.id, &params, &q, &u, &ud),
                reordered.evaluate(f.id, &params, &q, &u, &ud),
            );
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{}: values changed",
                f.id
            );
        } else {
            assert!(matches!(batched, Cow::Borrowed(_)), "{}", f.id);
        }
    }
}
