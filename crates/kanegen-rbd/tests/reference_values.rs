//! The three Pinocchio cases of `models/krang/reference-values.json`: parameters by symbol name
//! (matched to `ParamId`s with `model.param_index`), `q`, `u`, `u̇` → `M`, `c`, `g`, `τ`,
//! compared to 1e-9 relative to the largest entry of each quantity.

mod common;

use std::path::PathBuf;

use kanegen_rbd::Rbd;
use nalgebra::SVector;
use serde_json::Value;

fn numbers(v: &Value, what: &str) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("`{what}` is not an array"))
        .iter()
        .map(|x| {
            x.as_f64()
                .unwrap_or_else(|| panic!("`{what}`: not a number"))
        })
        .collect()
}

#[test]
fn pinocchio_reference_values_match() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/krang/reference-values.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (the Pinocchio reference values)", path.display()));
    let json: Value = serde_json::from_str(&text).expect("reference-values.json is valid JSON");
    let model = common::load_model("krang");
    let cases = json["cases"].as_array().expect("`cases` array");
    assert_eq!(cases.len(), 3, "expected three cases");
    for case in cases {
        let name = case["name"].as_str().unwrap_or("?");
        let given = case["params"].as_object().expect("`params` object");
        let mut params = model.param_values();
        for (symbol, value) in given {
            let id = model
                .param_index(symbol)
                .unwrap_or_else(|| panic!("case {name}: unknown parameter {symbol}"));
            params[id] = value.as_f64().expect("numeric parameter");
        }
        assert_eq!(
            given.len(),
            model.params.len(),
            "case {name}: parameters missing"
        );
        let vec19 = |key: &str| SVector::<f64, 19>::from_column_slice(&numbers(&case[key], key));
        let (q, u, ud) = (vec19("q"), vec19("u"), vec19("ud"));
        let m_ref: Vec<f64> = case["M"]
            .as_array()
            .expect("`M` rows")
            .iter()
            .flat_map(|r| numbers(r, "M row"))
            .collect();

        let rbd = Rbd::<19>::new(&model, &params).expect("builds");
        // Row-major copy of M to compare with the JSON rows.
        let m = rbd.mass_matrix(&q).transpose();
        let checks = [
            ("M", common::rel_err(m.as_slice(), &m_ref, 1e-300)),
            (
                "c",
                common::rel_err(
                    rbd.coriolis(&q, &u).as_slice(),
                    &numbers(&case["c"], "c"),
                    1e-300,
                ),
            ),
            (
                "g",
                common::rel_err(
                    rbd.gravity(&q).as_slice(),
                    &numbers(&case["g"], "g"),
                    1e-300,
                ),
            ),
            (
                "tau",
                common::rel_err(
                    rbd.inverse_dynamics(&q, &u, &ud).as_slice(),
                    &numbers(&case["tau"], "tau"),
                    1e-300,
                ),
            ),
        ];
        for (what, e) in checks {
            println!("{name}: {what} rel err {e:.3e}");
            assert!(e < 1e-9, "case {name}: {what} differs, rel err {e:.3e}");
        }
    }
}
