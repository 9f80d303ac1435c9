//! The Coriolis matrix at the generator level: the symbolic derivation (`Derivation::evaluate`)
//! and the lowered program (`Lowered::evaluate`) give the same C(q, u); `C u` equals the
//! derivation's c and the reference recursion's c; `Ṁ − 2C` is skew-symmetric (Ṁ by central
//! differences of the derivation's M). TOML models (wheeled and fixed base, runtime and baked
//! parameters) and a small URDF robot with a prismatic joint on a two-wheeled base.

use kanegen::FunctionId;
use kanegen::model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen::{Builder, Generated, Options, ParamMode};
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};

fn model(name: &str) -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    Model::from_toml_file(path.join(name)).expect("model loads")
}

/// `max |a − b| / max(max |b|, floor)`.
fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    let scale = b.iter().fold(floor, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

fn mat_vec(c: &[f64], u: &[f64]) -> Vec<f64> {
    let n = u.len();
    (0..n)
        .map(|r| (0..n).map(|k| c[r * n + k] * u[k]).sum())
        .collect()
}

/// Worst `[|C_derivation − C_lowered|, |C u − c_derivation|, |C u − c_reference|, skew defect]`.
fn check(label: &str, g: &Generated, draws: usize, seed: u64) -> [f64; 4] {
    let model = &g.model;
    let n = model.dof();
    let mut rng = SplitMix64::new(seed);
    let mut uniform = move || rng.next_f64();
    let mut worst = [0.0f64; 4];
    let pi = std::f64::consts::PI;
    for draw in 0..draws {
        let p = if draw == 0 || g.derivation.options.params == ParamMode::Baked {
            model.param_values()
        } else {
            random_physical_params(model, &mut uniform)
        };
        let q = uniform_vec(&mut uniform, n, -pi, pi);
        let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
        let z = vec![0.0; n];
        let cd = g
            .derivation
            .evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &z);
        let cl = g
            .lowered
            .evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &z);
        worst[0] = worst[0].max(rel_err(&cl, &cd, 1.0));
        let cu = mat_vec(&cd, &u);
        let c = g.derivation.evaluate(FunctionId::Coriolis, &p, &q, &u, &z);
        worst[1] = worst[1].max(rel_err(&cu, &c, 1.0));
        let reference = Reference::<f64>::with_params(model, &p);
        let c_ref: Vec<f64> = reference.coriolis(&q, &u).iter().copied().collect();
        worst[2] = worst[2].max(rel_err(&cu, &c_ref, 1.0));
        // Ṁ along q̇ (joint rates = their speeds; the base's x, ψ do not enter M): central
        // differences with one Richardson step, h = 1e-3.
        let mut qd = u.clone();
        if let Some(w) = model.wheeled_base() {
            qd[w.x_speed] = 0.0;
            qd[w.psi_speed] = 0.0;
        }
        let m_at = |t: f64| {
            let qt: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + t * b).collect();
            g.derivation
                .evaluate(FunctionId::MassMatrix, &p, &qt, &z, &z)
        };
        let d = |h: f64| -> Vec<f64> {
            m_at(h)
                .iter()
                .zip(m_at(-h))
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let (d1, d2) = (d(1e-3), d(5e-4));
        let mdot: Vec<f64> = d2
            .iter()
            .zip(&d1)
            .map(|(f, c)| (4.0 * f - c) / 3.0)
            .collect();
        let scale = mdot.iter().chain(&cd).fold(1.0f64, |s, x| s.max(x.abs()));
        for r in 0..n {
            for k in 0..n {
                let e = mdot[r * n + k] - cd[r * n + k] - cd[k * n + r];
                worst[3] = worst[3].max(e.abs() / scale);
            }
        }
    }
    eprintln!(
        "{label} ({n} speeds, {draws} draws): derivation vs lowered {:.1e}, C u vs c {:.1e}, \
         vs reference c {:.1e}, skew defect of Mdot - 2C {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst[0] < 1e-12, "{label}: derivation vs lowered {worst:?}");
    assert!(worst[1] < 1e-12, "{label}: C u vs c {worst:?}");
    assert!(worst[2] < 1e-10, "{label}: C u vs reference {worst:?}");
    assert!(worst[3] < 1e-8, "{label}: Mdot - 2C not skew {worst:?}");
    worst
}

fn generated(m: Model, params: ParamMode) -> Generated {
    Builder::from_model(m)
        .options(Options {
            params,
            ..Options::default()
        })
        .generate()
        .expect("generates")
}

#[test]
fn derivation_and_lowered_coriolis_matrix_agree_and_satisfy_both_properties() {
    check(
        "krang",
        &generated(model("krang.toml"), ParamMode::Runtime),
        20,
        1,
    );
    check(
        "krang, baked",
        &generated(model("krang.toml"), ParamMode::Baked),
        5,
        2,
    );
    check(
        "krang-fixed-wheels",
        &generated(model("krang-fixed-wheels.toml"), ParamMode::Runtime),
        20,
        3,
    );
    check(
        "two-link",
        &generated(model("two-link.toml"), ParamMode::Runtime),
        100,
        4,
    );
}

/// A two-wheeled base with a prismatic lift on a skew axis, a revolute joint on a skew axis
/// below it, and a fixed-joint merge.
const LIFT: &str = include_str!("data/lift.urdf");

#[test]
fn prismatic_joint_on_a_wheeled_base_coriolis_matrix_satisfies_both_properties() {
    let spec = WheeledBaseSpec::new(
        "left_wheel_joint",
        "right_wheel_joint",
        "chassis",
        [0.0, 0.0, 1.0],
        0.2,
    );
    let m = Model::from_urdf_str(LIFT, "lift.urdf", &UrdfOptions::wheeled(spec)).unwrap();
    assert_eq!(m.dof(), 5, "ẋ, ψ̇, pitch, lift, shoulder");
    check("lift.urdf", &generated(m, ParamMode::Runtime), 200, 5);
}
