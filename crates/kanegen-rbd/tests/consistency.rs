//! Self-consistency of the recursions on all three shipped models (and a synthetic model with
//! fixed, prismatic and non-axis-aligned joints), at 250 random states each, with default and
//! random physical parameters:
//!
//! * CRBA vs RNEA: `M[:, i] = τ(q, 0, eᵢ) − τ(q, 0, 0)`; `g = τ(q, 0, 0)`; `c(q, 0) = 0`;
//!   `τ(q, u, u̇) = M u̇ + c + g`;
//! * `M` symmetric positive definite;
//! * kinetic energy: `½ uᵀ M u` (and [`Rbd::kinetic_energy`]) equal the sum of the body kinetic
//!   energies computed directly from the joint-axis Jacobians in the test;
//! * power balance: `uᵀ c = ½ uᵀ Ṁ u` (`Ṁ` by central differences along `q̇ = u`);
//! * fixed-base models: `c` equals Lagrange's `Ṁ u − ½ ∂(uᵀ M u)/∂q` (finite differences).

mod common;

use std::f64::consts::PI;

use common::{Rng, direct_kinetic_energy, load_model, random_params, rel_err};
use kanegen_model::Model;
use kanegen_rbd::Rbd;
use nalgebra::{SMatrix, SVector};

const STATES: usize = 250;

fn check_state<const N: usize>(
    model: &Model,
    params: &[f64],
    rbd: &Rbd<N>,
    rng: &mut Rng,
    what: &str,
) {
    let q = rng.vec::<N>(-PI, PI);
    let u = rng.vec::<N>(-2.0, 2.0);
    let ud = rng.vec::<N>(-3.0, 3.0);
    let zero = SVector::<f64, N>::zeros();
    let m = rbd.mass_matrix(&q);
    let g = rbd.gravity(&q);
    let c = rbd.coriolis(&q, &u);
    let tau = rbd.inverse_dynamics(&q, &u, &ud);
    let tau0 = rbd.inverse_dynamics(&q, &zero, &zero);
    let scale = m.amax().max(g.amax()).max(c.amax()).max(1e-300);

    // g = τ(q, 0, 0).
    let e = rel_err(g.as_slice(), tau0.as_slice(), scale);
    assert!(e < 1e-13, "{what}: g vs τ(q,0,0): {e:e}");
    // c(q, 0) = 0.
    let c0 = rbd.coriolis(&q, &zero);
    assert!(c0.amax() == 0.0, "{what}: c(q, 0) = {c0}");
    // Columns of M from the RNEA.
    for i in 0..N {
        let mut ei = zero;
        ei[i] = 1.0;
        let col = rbd.inverse_dynamics(&q, &zero, &ei) - tau0;
        let e = rel_err(col.as_slice(), m.column(i).as_slice(), scale);
        assert!(
            e < 1e-12,
            "{what}: M column {i}: {e:e}\n{col}\n{}",
            m.column(i)
        );
    }
    // The full equation.
    let expected = m * ud + c + g;
    let e = rel_err(
        tau.as_slice(),
        expected.as_slice(),
        scale * (1.0 + ud.amax()),
    );
    assert!(e < 1e-12, "{what}: τ vs M u̇ + c + g: {e:e}");
    // Symmetric positive definite.
    assert_eq!(m, m.transpose(), "{what}: M not exactly symmetric");
    assert!(
        m.cholesky().is_some(),
        "{what}: M not positive definite\n{m}"
    );
    // Kinetic energy.
    let ke_m = 0.5 * u.dot(&(m * u));
    let ke_direct = direct_kinetic_energy(model, params, q.as_slice(), u.as_slice());
    let ke_rbd = rbd.kinetic_energy(&q, &u);
    let e = (ke_m - ke_direct).abs() / ke_direct;
    assert!(
        e < 1e-12,
        "{what}: ½uᵀMu = {ke_m} vs direct {ke_direct}: {e:e}"
    );
    let e = (ke_rbd - ke_direct).abs() / ke_direct;
    assert!(
        e < 1e-12,
        "{what}: kinetic_energy = {ke_rbd} vs direct {ke_direct}: {e:e}"
    );
    // Power balance uᵀ c = ½ uᵀ Ṁ u.
    let h = 1e-6;
    let mdot = (rbd.mass_matrix(&(q + u * h)) - rbd.mass_matrix(&(q - u * h))) / (2.0 * h);
    let lhs = u.dot(&c);
    let rhs = 0.5 * u.dot(&(mdot * u));
    let e = (lhs - rhs).abs() / (scale * u.norm_squared());
    assert!(e < 1e-7, "{what}: uᵀc = {lhs} vs ½uᵀṀu = {rhs}: {e:e}");
}

fn consistency<const N: usize>(model: &Model, seed: u64) {
    let mut rng = Rng::new(seed);
    for case in 0..STATES {
        let params = if case % 5 == 0 {
            model.param_values()
        } else {
            random_params(model, &mut rng)
        };
        let rbd = Rbd::<N>::new(model, &params).expect("builds");
        let what = format!("{} case {case}", model.name);
        check_state(model, &params, &rbd, &mut rng, &what);
    }
}

/// `c = Ṁ u − ½ ∂(uᵀ M u)/∂q` for holonomic (fixed-base) models, by central differences.
fn lagrange<const N: usize>(model: &Model, seed: u64) {
    let mut rng = Rng::new(seed);
    for case in 0..STATES {
        let params = random_params(model, &mut rng);
        let rbd = Rbd::<N>::new(model, &params).expect("builds");
        let q = rng.vec::<N>(-PI, PI);
        let u = rng.vec::<N>(-2.0, 2.0);
        let h = 1e-6;
        let dm: Vec<SMatrix<f64, N, N>> = (0..N)
            .map(|k| {
                let mut dq = SVector::<f64, N>::zeros();
                dq[k] = h;
                (rbd.mass_matrix(&(q + dq)) - rbd.mass_matrix(&(q - dq))) / (2.0 * h)
            })
            .collect();
        let mdot = dm
            .iter()
            .zip(u.iter())
            .fold(SMatrix::<f64, N, N>::zeros(), |acc, (d, uk)| acc + d * *uk);
        let mut expected = mdot * u;
        for i in 0..N {
            expected[i] -= 0.5 * u.dot(&(dm[i] * u));
        }
        let c = rbd.coriolis(&q, &u);
        let scale = rbd.mass_matrix(&q).amax() * u.norm_squared();
        let e = rel_err(c.as_slice(), expected.as_slice(), scale);
        assert!(
            e < 1e-7,
            "{} case {case}: c vs Lagrange: {e:e}\n{c}\n{expected}",
            model.name
        );
    }
}

#[test]
fn two_link_crba_rnea_energy_consistent() {
    consistency::<2>(&load_model("two-link"), 1);
}

#[test]
fn krang_fixed_wheels_crba_rnea_energy_consistent() {
    consistency::<17>(&load_model("krang-fixed-wheels"), 2);
}

#[test]
fn krang_crba_rnea_energy_consistent() {
    consistency::<19>(&load_model("krang"), 3);
}

#[test]
fn two_link_coriolis_matches_lagrange() {
    lagrange::<2>(&load_model("two-link"), 4);
}

#[test]
fn krang_fixed_wheels_coriolis_matches_lagrange() {
    lagrange::<17>(&load_model("krang-fixed-wheels"), 5);
}

/// A model exercising what Krang does not have: a body on the (wheeled) base frame, a fixed
/// joint with a non-permutation rotation carrying a body and a child, a prismatic joint,
/// non-axis-aligned axes, and speeds in an order unrelated to the link order. (Speeds are named
/// apart from their coordinates and from generated locals such as `d2`: the loader checks that.)
fn synthetic(wheeled: bool) -> Model {
    let frames = ["0", "1", "f", "2", "3", "4"];
    let mut params = String::from("g = 9.81\nL1 = 0.3\nL2 = 0.2\n");
    if wheeled {
        params.push_str("R = 0.25\nL = 0.68\nmw = 4.66\nYYw = 0.1456\nZZw = 0.0751\n");
    }
    let mut bodies = String::new();
    for f in frames {
        if f == "0" && !wheeled {
            continue;
        }
        params.push_str(&format!(
            "m{f} = 1.0\nMX{f} = 0.01\nMY{f} = 0.02\nMZ{f} = 0.03\nXX{f} = 0.1\nXY{f} = 0.0\nXZ{f} = 0.0\nYY{f} = 0.1\nYZ{f} = 0.0\nZZ{f} = 0.1\n"
        ));
        bodies.push_str(&format!("[[body]]\nframe = \"{f}\"\n\n"));
    }
    let (c30, s30) = (0.866_025_403_784_438_6_f64, 0.5_f64);
    let (speeds, base) = if wheeled {
        (
            r#"["qd3", "xd", "qd_x2", "qd1", "psid", "qd4"]"#,
            "type = \"wheeled\"\nframe = \"0\"\nx_speed = \"xd\"\npsi_speed = \"psid\"\nradius = \"R\"\ntrack = \"L\"\nwheel_mass = \"mw\"\nwheel_axle_inertia = \"YYw\"\nwheel_diametral_inertia = \"ZZw\"\n",
        )
    } else {
        (
            r#"["qd3", "qd_x2", "qd1", "qd4"]"#,
            "type = \"fixed\"\nframe = \"0\"\n",
        )
    };
    let text = format!(
        r#"[model]
name = "synthetic"
speeds = {speeds}

[base]
{base}
[gravity]
symbol = "g"
direction = [0, 0, -1]

[parameters]
{params}
[[joint]]
name = "q1"
type = "revolute"
parent = "0"
child = "1"
speed = "qd1"
axis = [0.6, 0, 0.8]
rotation = [[0, 0, -1], [-1, 0, 0], [0, 1, 0]]
translation = [0, 0, "L2"]

[[joint]]
name = "fix"
type = "fixed"
parent = "1"
child = "f"
rotation = [[{c30}, -{s30}, 0], [{s30}, {c30}, 0], [0, 0, 1]]
translation = ["L1", 0, 0.1]

[[joint]]
name = "x2"
type = "prismatic"
parent = "f"
child = "2"
speed = "qd_x2"
axis = [0, 1, 0]
rotation = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
translation = [0, "-L2", 0]

[[joint]]
name = "q3"
type = "revolute"
parent = "2"
child = "3"
speed = "qd3"
axis = [0, 0, -1]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0.05, 0, "L1"]

[[joint]]
name = "q4"
type = "revolute"
parent = "1"
child = "4"
speed = "qd4"
axis = [0, 0.6, -0.8]
rotation = [[0, 1, 0], [1, 0, 0], [0, 0, -1]]
translation = [0, "L1", 0]

{bodies}"#
    );
    Model::from_toml_str(&text, "synthetic.toml").unwrap_or_else(|e| panic!("synthetic: {e}"))
}

#[test]
fn synthetic_fixed_prismatic_general_axes_consistent() {
    let wheeled = synthetic(true);
    let rbd = Rbd::<6>::with_default_params(&wheeled).expect("builds");
    assert_eq!(rbd.moving_links(), 4, "the fixed joint is merged");
    consistency::<6>(&wheeled, 6);
    let fixed = synthetic(false);
    consistency::<4>(&fixed, 7);
    lagrange::<4>(&fixed, 8);
}

#[test]
fn wrong_dof_or_param_count_is_an_error() {
    let model = load_model("krang");
    let e = Rbd::<17>::with_default_params(&model).unwrap_err();
    assert!(e.to_string().contains("Rbd::<19>"), "{e}");
    let e = Rbd::<19>::new(&model, &[1.0, 2.0]).unwrap_err();
    assert!(e.to_string().contains("parameter values"), "{e}");
}

#[test]
fn f32_scalar_agrees_with_f64() {
    let model = load_model("krang");
    let p64 = model.param_values();
    let p32: Vec<f32> = p64.iter().map(|&x| x as f32).collect();
    let r64 = Rbd::<19>::new(&model, &p64).expect("builds");
    let r32 = Rbd::<19, f32>::new(&model, &p32).expect("builds");
    let mut rng = Rng::new(32);
    for _ in 0..50 {
        let q = rng.vec::<19>(-PI, PI);
        let u = rng.vec::<19>(-2.0, 2.0);
        let ud = rng.vec::<19>(-3.0, 3.0);
        let (q32, u32, ud32) = (q.cast::<f32>(), u.cast::<f32>(), ud.cast::<f32>());
        let pairs = [
            (
                r32.mass_matrix(&q32).cast::<f64>().as_slice().to_vec(),
                r64.mass_matrix(&q).as_slice().to_vec(),
            ),
            (
                r32.gravity(&q32).cast::<f64>().as_slice().to_vec(),
                r64.gravity(&q).as_slice().to_vec(),
            ),
            (
                r32.inverse_dynamics(&q32, &u32, &ud32)
                    .cast::<f64>()
                    .as_slice()
                    .to_vec(),
                r64.inverse_dynamics(&q, &u, &ud).as_slice().to_vec(),
            ),
        ];
        for (a, b) in &pairs {
            let e = rel_err(a, b, 1e-300);
            assert!(e < 1e-4, "f32 vs f64: {e:e}");
        }
    }
}
