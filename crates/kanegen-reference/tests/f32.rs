//! The reference instantiated with `f32` agrees with `f64`.

mod common;

use kanegen_reference::Reference;
use kanegen_reference::random::{random_physical_params, uniform_vec};
use nalgebra::{DMatrix, DVector};

fn up_m(m: &DMatrix<f32>) -> DMatrix<f64> {
    m.map(f64::from)
}

fn up_v(v: &DVector<f32>) -> DVector<f64> {
    v.map(f64::from)
}

fn down(x: &[f64]) -> Vec<f32> {
    x.iter().map(|&v| v as f32).collect()
}

#[test]
fn f32_agrees_with_f64() {
    let mut rnd = common::uniform(31);
    for name in ["two-link", "krang", "krang-fixed-wheels"] {
        let model = common::load_model(name);
        for k in 0..4 {
            let p = if k == 0 {
                model.param_values()
            } else {
                random_physical_params(&model, &mut rnd)
            };
            let r64 = Reference::<f64>::with_params(&model, &p);
            let r32 = Reference::<f32>::with_params(&model, &down(&p));
            let n = model.dof();
            // States exactly representable in f32, so both see the same input.
            let round = |v: Vec<f64>| v.iter().map(|&x| f64::from(x as f32)).collect::<Vec<_>>();
            let q = round(uniform_vec(&mut rnd, n, -3.0, 3.0));
            let u = round(uniform_vec(&mut rnd, n, -2.0, 2.0));
            let ud = round(uniform_vec(&mut rnd, n, -2.0, 2.0));
            let (q32, u32, ud32) = (down(&q), down(&u), down(&ud));
            let checks = [
                (
                    "M",
                    common::rel_err_mat(
                        &up_m(&r32.mass_matrix(&q32)),
                        &r64.mass_matrix(&q),
                        1e-300,
                    ),
                ),
                (
                    "g",
                    common::rel_err_vec(&up_v(&r32.gravity(&q32)), &r64.gravity(&q), 1e-300),
                ),
                (
                    "c",
                    common::rel_err_vec(
                        &up_v(&r32.coriolis(&q32, &u32)),
                        &r64.coriolis(&q, &u),
                        r64.gravity(&q).amax(),
                    ),
                ),
                (
                    "tau",
                    common::rel_err_vec(
                        &up_v(&r32.inverse_dynamics(&q32, &u32, &ud32)),
                        &r64.inverse_dynamics(&q, &u, &ud),
                        1e-300,
                    ),
                ),
            ];
            for (what, e) in checks {
                assert!(e < 1e-3, "{name} set {k}: {what} f32 vs f64 rel err {e:e}");
            }
            let t32 = f64::from(r32.kinetic_energy(&q32, &u32));
            let t64 = r64.kinetic_energy(&q, &u);
            assert!((t32 - t64).abs() < 1e-3 * t64, "T: {t32} vs {t64}");
            let v32 = f64::from(r32.potential_energy(&q32));
            let v64 = r64.potential_energy(&q);
            assert!(
                (v32 - v64).abs() < 1e-3 * v64.abs().max(1.0),
                "V: {v32} vs {v64}"
            );
        }
    }
}
