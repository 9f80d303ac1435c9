//! The three Pinocchio cases of `models/krang/reference-values.json`: parameters by symbol name, `q`, `u`, `u̇` → `M`, `c`, `g`, `τ`, compared to 1e-9 relative to
//! the largest entry of each quantity.

mod common;

use std::path::PathBuf;

use kanegen_reference::Reference;
use nalgebra::{DMatrix, DVector};
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
    let n = model.dof();
    let cases = json["cases"].as_array().expect("`cases` array");
    assert_eq!(cases.len(), 3, "expected three cases");
    for case in cases {
        let name = case["name"].as_str().unwrap_or("?");
        let given = case["params"].as_object().expect("`params` object");
        let mut params = model.param_values();
        for (i, p) in model.params.iter().enumerate() {
            params[i] = given
                .get(&p.name)
                .and_then(Value::as_f64)
                .unwrap_or_else(|| panic!("case {name}: parameter {} missing", p.name));
        }
        assert_eq!(
            given.len(),
            model.params.len(),
            "case {name}: extra parameters"
        );
        let (q, u, ud) = (
            numbers(&case["q"], "q"),
            numbers(&case["u"], "u"),
            numbers(&case["ud"], "ud"),
        );
        let rows: Vec<Vec<f64>> = case["M"]
            .as_array()
            .expect("`M` rows")
            .iter()
            .map(|r| numbers(r, "M row"))
            .collect();
        let m_ref = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
        let c_ref = DVector::from_vec(numbers(&case["c"], "c"));
        let g_ref = DVector::from_vec(numbers(&case["g"], "g"));
        let tau_ref = DVector::from_vec(numbers(&case["tau"], "tau"));

        let r = Reference::with_params(&model, &params);
        let checks = [
            ("M", common::rel_err_mat(&r.mass_matrix(&q), &m_ref, 1e-300)),
            (
                "c",
                common::rel_err_vec(&r.coriolis(&q, &u), &c_ref, 1e-300),
            ),
            ("g", common::rel_err_vec(&r.gravity(&q), &g_ref, 1e-300)),
            (
                "tau",
                common::rel_err_vec(&r.inverse_dynamics(&q, &u, &ud), &tau_ref, 1e-300),
            ),
        ];
        for (what, e) in checks {
            eprintln!("{name}: {what} rel err {e:.3e}");
            assert!(e < 1e-9, "case {name}: {what} differs, rel err {e:.3e}");
        }
    }
}
