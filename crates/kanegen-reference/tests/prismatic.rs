//! Prismatic joints (none in the Krang models): a polar arm (revolute about z, then a slider
//! along x) against its closed-form dynamics, and a revolute–prismatic–revolute chain with
//! gravity for energy conservation (which exercises the slider's Coriolis term 2 ω × u e).

mod common;

use kanegen_model::Model;
use kanegen_reference::Reference;
use kanegen_reference::random::{random_physical_params, uniform_vec};
use nalgebra::{DMatrix, DVector};

fn body_params(name: &str) -> String {
    format!(
        "m{name} = 1.0\nMX{name} = 0.0\nMY{name} = 0.0\nMZ{name} = 0.0\nXX{name} = 0.1\n\
         XY{name} = 0.0\nXZ{name} = 0.0\nYY{name} = 0.1\nYZ{name} = 0.0\nZZ{name} = 0.1\n"
    )
}

/// Frame 1 turns about z0 by q1; frame 2 (turned, `1A2(0)` ≠ 1) slides along x1 = z2 by q2 from
/// `[L1, 0, 0]`; with `third`,
/// frame 3 turns about y2 by q3 at `[0, 0, -L2]` from frame 2.
fn model(third: bool) -> Model {
    let mut text = String::from(
        r#"
[model]
name = "slider"
speeds = SPEEDS

[base]
type = "fixed"
frame = "0"

[gravity]
symbol = "g"
direction = [0, 0, -1]

[parameters]
g = 9.81
L1 = 0.3
"#,
    );
    text = text.replace(
        "SPEEDS",
        if third {
            r#"["qd1", "qd2", "qd3"]"#
        } else {
            r#"["qd1", "qd2"]"#
        },
    );
    if third {
        text += "L2 = 0.2\n";
    }
    text += &body_params("1");
    text += &body_params("2");
    if third {
        text += &body_params("3");
    }
    text += r#"
[[joint]]
name = "q1"
type = "revolute"
parent = "0"
child = "1"
speed = "qd1"
axis = [0, 0, 1]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]

[[joint]]
name = "q2"
type = "prismatic"
parent = "1"
child = "2"
speed = "qd2"
axis = [0, 0, 1]
rotation = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
translation = ["L1", 0, 0]

[[body]]
frame = "1"

[[body]]
frame = "2"
"#;
    if third {
        text += r#"
[[joint]]
name = "q3"
type = "revolute"
parent = "2"
child = "3"
speed = "qd3"
axis = [0, 1, 0]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, "-L2"]

[[body]]
frame = "3"
"#;
    }
    Model::from_toml_str(&text, "slider.toml").expect("valid test model")
}

#[test]
fn polar_arm_matches_closed_form() {
    let model = model(false);
    let mut rnd = common::uniform(11);
    let idx = |n: &str| model.param_index(n).unwrap();
    for _ in 0..50 {
        let mut p = random_physical_params(&model, &mut rnd);
        // Body 2: a point mass at its origin (frame 2 is turned: the slider axis x1 is its z2).
        for n in [
            "MX2", "MY2", "MZ2", "XX2", "XY2", "XZ2", "YY2", "YZ2", "ZZ2",
        ] {
            p[idx(n)] = 0.0;
        }
        let r = Reference::with_params(&model, &p);
        let q = uniform_vec(&mut rnd, 2, -1.0, 1.0);
        let u = uniform_vec(&mut rnd, 2, -2.0, 2.0);
        let (m2, zz1, l1) = (p[idx("m2")], p[idx("ZZ1")], p[idx("L1")]);
        let rho = l1 + q[1];
        let m = DMatrix::from_row_slice(2, 2, &[zz1 + m2 * rho * rho, 0.0, 0.0, m2]);
        let c = DVector::from_vec(vec![2.0 * m2 * rho * u[0] * u[1], -m2 * rho * u[0] * u[0]]);
        let e = common::rel_err_mat(&r.mass_matrix(&q), &m, 1e-300);
        assert!(e < 1e-12, "M: {e:e}");
        let e = common::rel_err_vec(&r.coriolis(&q, &u), &c, 1.0);
        assert!(e < 1e-12, "c: {e:e}");
        assert!(
            r.gravity(&q).amax() < 1e-12,
            "horizontal arm: no gravity terms"
        );
    }
}

#[test]
fn revolute_prismatic_revolute_chain_conserves_energy() {
    let model = model(true);
    let mut rnd = common::uniform(12);
    for _ in 0..3 {
        let p = random_physical_params(&model, &mut rnd);
        let r = Reference::with_params(&model, &p);
        let mut q = DVector::from_vec(uniform_vec(&mut rnd, 3, -1.0, 1.0));
        let mut u = DVector::from_vec(uniform_vec(&mut rnd, 3, -1.0, 1.0));
        let f = |q: &DVector<f64>, u: &DVector<f64>| {
            let rhs = -r.inverse_dynamics(q.as_slice(), u.as_slice(), &[0.0; 3]);
            let ud = r.mass_matrix(q.as_slice()).cholesky().unwrap().solve(&rhs);
            (u.clone(), ud)
        };
        let energy = |q: &DVector<f64>, u: &DVector<f64>| {
            r.kinetic_energy(q.as_slice(), u.as_slice()) + r.potential_energy(q.as_slice())
        };
        let e0 = energy(&q, &u);
        let t0 = r.kinetic_energy(q.as_slice(), u.as_slice());
        let dt = 1e-3;
        for _ in 0..500 {
            let (k1q, k1u) = f(&q, &u);
            let (k2q, k2u) = f(&(&q + &k1q * (dt / 2.0)), &(&u + &k1u * (dt / 2.0)));
            let (k3q, k3u) = f(&(&q + &k2q * (dt / 2.0)), &(&u + &k2u * (dt / 2.0)));
            let (k4q, k4u) = f(&(&q + &k3q * dt), &(&u + &k3u * dt));
            q += (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (dt / 6.0);
            u += (k1u + k2u * 2.0 + k3u * 2.0 + k4u) * (dt / 6.0);
        }
        let drift = (energy(&q, &u) - e0).abs() / t0;
        assert!(drift < 1e-6, "relative drift of T + V: {drift:e}");
        // And T = ½uᵀMu, g = ∂V/∂q at the final state.
        let quad = 0.5 * u.dot(&(r.mass_matrix(q.as_slice()) * &u));
        let t = r.kinetic_energy(q.as_slice(), u.as_slice());
        assert!((t - quad).abs() < 1e-10 * quad);
        let h = 1e-6;
        let g = r.gravity(q.as_slice());
        for i in 0..3 {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += h;
            qm[i] -= h;
            let d =
                (r.potential_energy(qp.as_slice()) - r.potential_energy(qm.as_slice())) / (2.0 * h);
            assert!(
                (d - g[i]).abs() < 1e-6 * g.amax().max(1.0),
                "g[{i}] {} vs {d}",
                g[i]
            );
        }
    }
}
