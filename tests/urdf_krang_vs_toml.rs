//! Krang.urdf imported with the two-wheeled base declaration against the hand-written
//! `models/krang.toml`: with the URDF's small lateral offsets zeroed (JWaist x, JTorso x, wheel
//! joints symmetric about the Base origin) and its rounded angles snapped, the two models are the
//! same system. Given the same parameters (mapped by meaning: report body ↔ URDF link, and the
//! wheel constants), M, c, g and τ agree to 1e-9 at random states, through the reference
//! recursion and through the generated (lowered) programs of the URDF model.
//!
//! The one difference of coordinates: the URDF's last joint (LJFT/RJFT) has another zero angle,
//! q7(URDF) = q7(report) − π/2 (see MODEL-NOTES).

mod common;

use common::*;
use kanegen::Builder;
use kanegen::FunctionId;
use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen_reference::Reference;
use kanegen_reference::random::random_physical_params;

const TOL: f64 = 1e-9;

/// Krang.urdf with the lateral offsets the reports drop set to zero.
fn symmetric_krang_urdf() -> String {
    let mut text = std::fs::read_to_string(root().join("models/Krang.urdf")).unwrap();
    for (from, to) in [
        (
            r#"<origin xyz="0.026 0.499 -0.091" rpy="0 0 0"/>"#,
            r#"<origin xyz="0 0.499 -0.091" rpy="0 0 0"/>"#,
        ),
        (
            r#"<origin xyz="-0.0285 0.584 0.1088" rpy="0 3.1416 0"/>"#,
            r#"<origin xyz="0 0.584 0.1088" rpy="0 3.1416 0"/>"#,
        ),
        (
            r#"<origin xyz="-0.354 0.0 0" rpy="0 0 0"/>"#,
            r#"<origin xyz="-0.34 0.0 0" rpy="0 0 0"/>"#,
        ),
        (
            r#"<origin xyz="0.361 0.0 0" rpy="0 0 0"/>"#,
            r#"<origin xyz="0.34 0.0 0" rpy="0 0 0"/>"#,
        ),
    ] {
        assert_eq!(text.matches(from).count(), 1, "{from}");
        text = text.replace(from, to);
    }
    text
}

fn urdf_model(text: &str) -> Model {
    let mut spec = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    spec.pitch_name = "imu".into();
    let options =
        UrdfOptions::wheeled(spec).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]);
    Model::from_urdf_str(text, "Krang.urdf (offsets zeroed)", &options).unwrap()
}

/// Report body ↔ URDF link.
fn bodies() -> Vec<(String, String)> {
    let mut b: Vec<(String, String)> = [("1", "Base"), ("2", "Spine"), ("3", "Bracket")]
        .map(|(a, b)| (a.into(), b.into()))
        .into();
    for (side, prefix, grip) in [("l", "L", "lGripper"), ("r", "R", "rGripper")] {
        for k in 1..=6 {
            b.push((format!("{}{side}", k + 3), format!("{prefix}{k}")));
        }
        b.push((format!("10{side}"), grip.into()));
    }
    b
}

/// The URDF model's parameter vector holding the values of `toml_params`, mapped by meaning.
fn map_params(toml: &Model, toml_params: &[f64], urdf: &Model) -> Vec<f64> {
    let mut p = vec![f64::NAN; urdf.params.len()];
    let mut set = |u: &str, t: &str| {
        let i = urdf
            .param_index(u)
            .unwrap_or_else(|| panic!("URDF model lacks {u}"));
        p[i] = toml_params[toml
            .param_index(t)
            .unwrap_or_else(|| panic!("TOML model lacks {t}"))];
    };
    for s in ["g", "R", "L", "mw", "YYw", "ZZw"] {
        set(s, s);
    }
    for (report, link) in bodies() {
        for prefix in ["m", "MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"] {
            set(&format!("{prefix}_{link}"), &format!("{prefix}{report}"));
        }
    }
    assert!(
        p.iter().all(|x| x.is_finite()),
        "every URDF parameter is mapped"
    );
    p
}

#[test]
fn symmetric_krang_urdf_equals_krang_toml() {
    let toml = model("krang.toml");
    let urdf = urdf_model(&symmetric_krang_urdf());
    assert_eq!(urdf.dof(), toml.dof());
    let n = toml.dof();
    let g = Builder::from_model(urdf.clone()).generate().unwrap();
    let (lj7, rj7) = (
        urdf.speed_index("qd_LJFT").unwrap(),
        urdf.speed_index("qd_RJFT").unwrap(),
    );
    assert_eq!(
        (lj7, rj7),
        (
            toml.speed_index("qd7l").unwrap(),
            toml.speed_index("qd7r").unwrap()
        )
    );
    let mut r = rng(2024);
    let mut worst = [0.0f64; 4];
    for draw in 0..60 {
        // The TOML defaults first (the URDF's values), then random inertial and wheel parameters;
        // lengths stay at the TOML defaults, which are the URDF's numbers.
        let mut pt = toml.param_values();
        if draw > 0 {
            let random = random_physical_params(&toml, &mut r);
            for (i, param) in toml.params.iter().enumerate() {
                if param.kind != kanegen_model::ParamKind::Length {
                    pt[i] = random[i];
                }
            }
        }
        let pu = map_params(&toml, &pt, &urdf);
        let (qt, u, ud) = random_state(&mut r, n);
        let mut qu = qt.clone();
        qu[lj7] -= std::f64::consts::FRAC_PI_2;
        qu[rj7] -= std::f64::consts::FRAC_PI_2;
        let rt = Reference::<f64>::with_params(&toml, &pt);
        let ru = Reference::<f64>::with_params(&urdf, &pu);
        let expected = [
            drows(&rt.mass_matrix(&qt)),
            dvec(&rt.coriolis(&qt, &u)),
            dvec(&rt.gravity(&qt)),
            dvec(&rt.inverse_dynamics(&qt, &u, &ud)),
        ];
        let from_urdf = [
            drows(&ru.mass_matrix(&qu)),
            dvec(&ru.coriolis(&qu, &u)),
            dvec(&ru.gravity(&qu)),
            dvec(&ru.inverse_dynamics(&qu, &u, &ud)),
        ];
        for (i, f) in [
            FunctionId::MassMatrix,
            FunctionId::Coriolis,
            FunctionId::Gravity,
            FunctionId::InverseDynamics,
        ]
        .iter()
        .enumerate()
        {
            let generated = g.lowered.evaluate(*f, &pu, &qu, &u, &ud);
            worst[i] = worst[i]
                .max(rel_err(&from_urdf[i], &expected[i], 1.0))
                .max(rel_err(&generated, &expected[i], 1.0));
        }
    }
    eprintln!(
        "Krang.urdf (offsets zeroed) vs krang.toml: worst relative error M {:.1e} c {:.1e} g {:.1e} tau {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst.iter().all(|e| *e < TOL), "{worst:?} exceeds {TOL}");
}

#[test]
fn the_lateral_offsets_are_what_differs() {
    // Without zeroing, the 2.5 mm lateral shift and the 3.5 mm off-centre axle change the
    // dynamics measurably (so the test above is not vacuous): the yaw inertia in M. (g does not
    // change: the shifts are along the pitch and waist axes, and the wheel rows have no gravity.)
    let toml = model("krang.toml");
    let raw = std::fs::read_to_string(root().join("models/Krang.urdf")).unwrap();
    let urdf = urdf_model(&raw);
    let pt = toml.param_values();
    let pu = map_params(&toml, &pt, &urdf);
    let mut r = rng(7);
    let (qt, _, _) = random_state(&mut r, toml.dof());
    let mut qu = qt.clone();
    for j in ["qd_LJFT", "qd_RJFT"] {
        qu[urdf.speed_index(j).unwrap()] -= std::f64::consts::FRAC_PI_2;
    }
    let mt = drows(&Reference::<f64>::with_params(&toml, &pt).mass_matrix(&qt));
    let mu = drows(&Reference::<f64>::with_params(&urdf, &pu).mass_matrix(&qu));
    let e = rel_err(&mu, &mt, 1.0);
    eprintln!("raw Krang.urdf vs krang.toml: relative difference of M {e:.1e}");
    assert!(e > 1e-4, "relative difference {e:e}");
}
