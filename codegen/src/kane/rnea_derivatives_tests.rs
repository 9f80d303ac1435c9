//! The analytic recursion of `rnea_derivatives.rs` against forward mode (`Arena::diff` over τ's recursion, the
//! derivation this module replaced): the same matrices to rounding on random parameters and
//! states, for every kind of joint and base the models have.

use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};

use super::ctx::Ctx;
use super::{mimic, names_of};
use crate::expr::{Arena, ExprId, Values};
use crate::options::{Options, ParamMode};
use crate::registry::{Dim, Shape};

fn models_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models")
}

/// `[∂τ/∂q | ∂τ/∂u]` (projected onto the independent speeds) by one of the two derivations.
fn derive(
    model: &Model,
    params: ParamMode,
    analytic: bool,
) -> (Arena, Vec<(usize, usize, ExprId)>) {
    let mut arena = Arena::new(names_of(model));
    arena.hoist_params = params.is_runtime();
    if model.is_floating() {
        arena.set_floating();
    }
    mimic::declare(&mut arena, model);
    let links = model.links.len();
    let mut cx = Ctx {
        ar: &mut arena,
        model,
        options: Options {
            params,
            ..Options::default()
        },
        rot: vec![None; links],
        pos: vec![None; links],
        root_rot: vec![None; links],
        root_pos: vec![None; links],
        keep_inertial: false,
    };
    let entries = if analytic {
        cx.inverse_dynamics_derivatives_analytic()
    } else {
        cx.inverse_dynamics_derivatives_forward_mode()
    };
    let shape = Shape::Dense {
        rows: Dim::N,
        cols: Dim::TwoN,
    };
    let entries = mimic::project(cx.ar, model, shape, entries);
    (arena, entries)
}

/// Random coordinates: angles in ±π, a floating base's position in ±π and its quaternion unit.
pub(super) fn random_coordinates(model: &Model, uni: &mut impl FnMut() -> f64) -> Vec<f64> {
    let pi = std::f64::consts::PI;
    let mut q = uniform_vec(uni, model.nq(), -pi, pi);
    if model.is_floating() {
        let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
        q[3..7].iter_mut().for_each(|x| *x /= norm);
    }
    q
}

fn dense(ar: &Arena, entries: &[(usize, usize, ExprId)], n: usize, x: &Values<'_>) -> Vec<f64> {
    let v = ar.eval(x);
    let mut out = vec![0.0; n * 2 * n];
    for &(r, c, e) in entries {
        out[r * 2 * n + c] = v[e.index()];
    }
    out
}

/// Worst `max |analytic − forward| / max(max |forward|, 1)` over `draws` random draws.
fn compare(label: &str, model: &Model, params: ParamMode, draws: usize, seed: u64) {
    let (a, ea) = derive(model, params, true);
    let (f, ef) = derive(model, params, false);
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
        let q = random_coordinates(model, &mut uni);
        let u = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
        let ud = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
        let x = Values {
            params: &p,
            q: &q,
            u: &u,
            ud: &ud,
        };
        let (da, df) = (dense(&a, &ea, n, &x), dense(&f, &ef, n, &x));
        let scale = df.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        for (i, (x, y)) in da.iter().zip(&df).enumerate() {
            let e = (x - y).abs() / scale;
            assert!(
                e < 1e-11,
                "{label}: draw {draw}, entry [{}, {}]: analytic {x} vs forward mode {y}",
                i / (2 * n),
                i % (2 * n)
            );
            worst = worst.max(e);
        }
    }
    eprintln!("{label}: {draws} draws, worst relative difference {worst:.1e}");
}

#[test]
fn analytic_derivatives_equal_forward_mode_on_trees_and_wheeled_bases() {
    let toml = |name: &str| Model::from_toml_file(models_dir().join(name)).expect("loads");
    compare("krang", &toml("krang.toml"), ParamMode::Runtime, 10, 1);
    compare("krang, baked", &toml("krang.toml"), ParamMode::Baked, 2, 2);
    compare(
        "fixed wheels",
        &toml("krang-fixed-wheels.toml"),
        ParamMode::Runtime,
        10,
        3,
    );
    compare(
        "two-link",
        &toml("two-link.toml"),
        ParamMode::Runtime,
        50,
        4,
    );
    let arm = Model::from_urdf_file(models_dir().join("singlearm.urdf"), &UrdfOptions::default())
        .expect("imports");
    compare("arm", &arm, ParamMode::Runtime, 20, 5);
}

#[test]
fn analytic_derivatives_equal_forward_mode_with_prismatic_and_mimic_joints() {
    let gripper = Model::from_urdf_file(
        models_dir().join("mimic_gripper.urdf"),
        &UrdfOptions::default(),
    )
    .expect("imports");
    assert!(!gripper.mimics.is_empty());
    compare("mimic gripper", &gripper, ParamMode::Runtime, 50, 6);
    let spec = WheeledBaseSpec::new(
        "left_wheel_joint",
        "right_wheel_joint",
        "chassis",
        [0.0, 0.0, 1.0],
        0.2,
    );
    let lift = Model::from_urdf_str(LIFT, "lift.urdf", &UrdfOptions::wheeled(spec)).unwrap();
    compare("lift on a wheeled base", &lift, ParamMode::Runtime, 50, 7);
}

/// A floating base: the orientation columns `Φ_i · (0; e_k × g_b)` of the recursion against
/// `−M[:, v] [g_b]×`, the joints' columns and ∂τ/∂u against forward mode.
#[test]
fn analytic_derivatives_equal_forward_mode_on_floating_bases() {
    let hopper = Model::from_toml_file(models_dir().join("floating-hopper.toml")).expect("loads");
    assert!(hopper.is_floating());
    compare("floating hopper", &hopper, ParamMode::Runtime, 20, 9);
    compare("floating hopper, baked", &hopper, ParamMode::Baked, 2, 10);
    let solo = Model::from_urdf_file(
        models_dir().join("../tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports");
    compare("solo 12, floating", &solo, ParamMode::Runtime, 5, 11);
}

/// ∂τ/∂u = 2C on a tree; on Krang's wheeled base and on a floating base, on every joint's
/// column (the base's columns take `V_0 × S` where a joint has `2 Ψ̇`, so they differ).
#[test]
fn on_a_tree_and_on_every_joint_column_the_speed_derivative_is_twice_the_coriolis_matrix() {
    use crate::registry::{FunctionId, FunctionSet};
    let toml = |name: &str| Model::from_toml_file(models_dir().join(name)).expect("loads");
    for (name, model, first_joint_column) in [
        ("fixed wheels", toml("krang-fixed-wheels.toml"), 0),
        ("two-link", toml("two-link.toml"), 0),
        ("krang", toml("krang.toml"), 2),
        ("floating hopper", toml("floating-hopper.toml"), 6),
    ] {
        let options = Options {
            params: ParamMode::Runtime,
            functions: FunctionSet::default()
                .with(FunctionId::CoriolisMatrix)
                .with(FunctionId::InverseDynamicsDerivatives),
        };
        let d = super::derive(&model, options);
        let n = model.dof();
        let mut rng = SplitMix64::new(8);
        let mut uni = move || rng.next_f64();
        for _ in 0..10 {
            let p = random_physical_params(&model, &mut uni);
            let q = random_coordinates(&model, &mut uni);
            let u = uniform_vec(&mut uni, n, -2.0, 2.0);
            let ud = uniform_vec(&mut uni, n, -2.0, 2.0);
            let c = d.evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &ud);
            let dt = d.evaluate(FunctionId::InverseDynamicsDerivatives, &p, &q, &u, &ud);
            let scale = c.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for r in 0..n {
                for k in first_joint_column..n {
                    let e = (dt[r * 2 * n + n + k] - 2.0 * c[r * n + k]).abs() / scale;
                    assert!(e < 1e-12, "{name}: ∂τ_{r}/∂u_{k} vs 2 C[{r},{k}]: {e:e}");
                }
            }
        }
    }
}

/// A two-wheeled base with a prismatic lift on a skew axis, a revolute joint on a skew axis
/// below it, and a fixed-joint merge (shared with `tests/coriolis_matrix.rs`).
const LIFT: &str = include_str!("../../tests/data/lift.urdf");
