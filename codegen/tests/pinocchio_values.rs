//! The symbolic derivation, evaluated numerically, against the three Pinocchio cases of
//! `models/krang/reference-values.json` (an independent library).

use kanegen::kane::derive;
use kanegen::model::Model;
use kanegen::{FunctionId, Options, ParamMode};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn vecf(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

#[test]
fn symbolic_krang_matches_pinocchio_reference_values() {
    let path = root().join("models/krang/reference-values.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (the Pinocchio reference values)", path.display()));
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let model = Model::from_toml_file(root().join("models/krang.toml")).unwrap();
    let d = derive(
        &model,
        Options {
            params: ParamMode::Runtime,
            ..Options::default()
        },
    );
    let low = kanegen::lower::lower(&d);
    for f in &low.functions {
        let p = &f.program;
        eprintln!("{}: {} stmts, {}", p.name, p.stmts.len(), p.ops);
    }
    eprintln!(
        "precompute: {} stmts, {}",
        low.precompute.stmts.len(),
        low.precompute.ops
    );
    for case in json["cases"].as_array().unwrap() {
        let mut params = model.param_values();
        for (k, v) in case["params"].as_object().unwrap() {
            let i = model
                .param_index(k)
                .unwrap_or_else(|| panic!("unknown {k}"));
            params[i] = v.as_f64().unwrap();
        }
        let q = vecf(&case["q"]);
        let u = vecf(&case["u"]);
        let ud = vecf(&case["ud"]);
        let z = vec![0.0; 19];
        let m: Vec<f64> = case["M"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(vecf)
            .collect();
        let name = case["name"].as_str().unwrap();
        let em = rel_err(&d.evaluate(FunctionId::MassMatrix, &params, &q, &z, &z), &m);
        let ec = rel_err(
            &d.evaluate(FunctionId::Coriolis, &params, &q, &u, &z),
            &vecf(&case["c"]),
        );
        let eg = rel_err(
            &d.evaluate(FunctionId::Gravity, &params, &q, &z, &z),
            &vecf(&case["g"]),
        );
        let et = rel_err(
            &d.evaluate(FunctionId::InverseDynamics, &params, &q, &u, &ud),
            &vecf(&case["tau"]),
        );
        eprintln!("{name}: M {em:.2e} c {ec:.2e} g {eg:.2e} tau {et:.2e}");
        let lm = rel_err(
            &low.evaluate(FunctionId::MassMatrix, &params, &q, &z, &z),
            &m,
        );
        let lc = rel_err(
            &low.evaluate(FunctionId::Coriolis, &params, &q, &u, &z),
            &vecf(&case["c"]),
        );
        let lg = rel_err(
            &low.evaluate(FunctionId::Gravity, &params, &q, &z, &z),
            &vecf(&case["g"]),
        );
        let lt = rel_err(
            &low.evaluate(FunctionId::InverseDynamics, &params, &q, &u, &ud),
            &vecf(&case["tau"]),
        );
        eprintln!("{name} (lowered): M {lm:.2e} c {lc:.2e} g {lg:.2e} tau {lt:.2e}");
        assert!(
            lm < 1e-9 && lc < 1e-9 && lg < 1e-9 && lt < 1e-9,
            "{name} lowered"
        );
        assert!(em < 1e-9 && ec < 1e-9 && eg < 1e-9 && et < 1e-9, "{name}");
        // The Coriolis matrix times u is Pinocchio's c.
        let cm = low.evaluate(FunctionId::CoriolisMatrix, &params, &q, &u, &z);
        let cu: Vec<f64> = (0..19)
            .map(|r| (0..19).map(|k| cm[r * 19 + k] * u[k]).sum())
            .collect();
        let ecm = rel_err(&cu, &vecf(&case["c"]));
        eprintln!("{name}: C u vs c {ecm:.2e}");
        assert!(ecm < 1e-9, "{name}: C u");
    }
}
