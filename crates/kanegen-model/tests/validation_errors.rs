//! One test per typed error of [`ModelErrorKind`]: a small valid two-link description is mutated
//! into a malformed one, and the exact variant, its fields, the file label and the message are checked.
//! Also: the shipped models load, and a missing file is an `Io` error naming the path.

use std::path::PathBuf;

use kanegen_model::{Model, ModelError, ModelErrorKind as K};

mod common;
use common::{VALID, mutate};

const FILE: &str = "bad.toml";

/// Load `text`, expect an error labelled `bad.toml` whose message names every item of `names`.
fn load_err(text: &str, names: &[&str]) -> ModelError {
    let err = match Model::from_toml_str(text, FILE) {
        Ok(_) => panic!("the description should have been rejected:\n{text}"),
        Err(e) => e,
    };
    assert_eq!(err.file, FILE);
    let msg = err.to_string();
    assert!(msg.starts_with("bad.toml: "), "message {msg:?}");
    for n in names {
        assert!(msg.contains(n), "message {msg:?} should name {n:?}");
    }
    err
}

/// Append a block (e.g. another `[[joint]]`) to `VALID`.
fn append(extra: &str) -> String {
    format!("{VALID}\n{extra}")
}

#[test]
fn valid_description_loads() {
    let m = Model::from_toml_str(VALID, FILE).expect("the test model is valid");
    assert_eq!(m.dof(), 2);
    assert_eq!(m.body_count(), 2);
    assert_eq!(m.links.len(), 3);
}

#[test]
fn malformed_toml_syntax() {
    let e = load_err(
        &mutate(&[(r#"name = "two-link""#, r#"name = "two-link"#)]),
        &["malformed description", "line"],
    );
    assert!(matches!(e.kind, K::Syntax(_)), "{:?}", e.kind);
}

#[test]
fn missing_section() {
    let e = load_err(
        &mutate(&[("[gravity]\nsymbol = \"g\"\ndirection = [0, 0, -1]\n", "")]),
        &["gravity"],
    );
    assert!(matches!(e.kind, K::Syntax(_)), "{:?}", e.kind);
}

#[test]
fn unknown_field() {
    let e = load_err(
        &mutate(&[("child = \"2\"\n", "child = \"2\"\ncolour = \"red\"\n")]),
        &["colour"],
    );
    assert!(
        matches!(&e.kind, K::Syntax(s) if s.contains("colour")),
        "{:?}",
        e.kind
    );
}

#[test]
fn unknown_joint_type() {
    let e = load_err(
        &mutate(&[(
            "type = \"revolute\"\nparent = \"1\"",
            "type = \"spherical\"\nparent = \"1\"",
        )]),
        &["spherical"],
    );
    assert!(
        matches!(&e.kind, K::Syntax(s) if s.contains("spherical")),
        "{:?}",
        e.kind
    );
}

#[test]
fn unknown_base_type() {
    let e = load_err(
        &mutate(&[(r#"type = "fixed""#, r#"type = "legged""#)]),
        &["legged"],
    );
    assert!(
        matches!(&e.kind, K::Syntax(s) if s.contains("legged")),
        "{:?}",
        e.kind
    );
}

#[test]
fn unknown_parent() {
    let e = load_err(
        &mutate(&[(r#"parent = "1""#, r#"parent = "7""#)]),
        &["`q2`", "`7`"],
    );
    assert!(
        matches!(&e.kind, K::UnknownParent { joint, parent } if joint == "q2" && parent == "7"),
        "{:?}",
        e.kind
    );
}

const CYCLE: &str = r#"
[[joint]]
name = "a"
type = "fixed"
parent = "fb"
child = "fa"
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]

[[joint]]
name = "b"
type = "fixed"
parent = "fa"
child = "fb"
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]
"#;

#[test]
fn cycle() {
    let e = load_err(&append(CYCLE), &["cycle", "`a`", "`fa`"]);
    assert!(
        matches!(&e.kind, K::Cycle { joint, frame } if joint == "a" && frame == "fa"),
        "{:?}",
        e.kind
    );
}

#[test]
fn cycle_reports_a_joint_on_the_cycle() {
    // `c` hangs off the cycle a <-> b and comes first in the file; it is unreachable too, but the
    // error must name a joint that is on the cycle.
    let dangling = r#"
[[joint]]
name = "c"
type = "fixed"
parent = "fa"
child = "fc"
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]
"#;
    let e = load_err(&append(&format!("{dangling}{CYCLE}")), &["cycle"]);
    assert!(
        matches!(&e.kind, K::Cycle { joint, frame }
            if (joint == "a" && frame == "fa") || (joint == "b" && frame == "fb")),
        "{:?}",
        e.kind
    );
}

#[test]
fn self_loop_is_a_cycle() {
    let e = load_err(
        &append(
            r#"
[[joint]]
name = "s"
type = "fixed"
parent = "fs"
child = "fs"
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]
"#,
        ),
        &["`s`"],
    );
    assert!(
        matches!(&e.kind, K::Cycle { joint, frame } if joint == "s" && frame == "fs"),
        "{:?}",
        e.kind
    );
}

#[test]
fn duplicate_joint_name() {
    let e = load_err(
        &mutate(&[(r#"name = "q2""#, r#"name = "q1""#)]),
        &["joint `q1`", "twice"],
    );
    assert!(
        matches!(&e.kind, K::Duplicate { what: "joint", name } if name == "q1"),
        "{:?}",
        e.kind
    );
}

#[test]
fn duplicate_frame() {
    // A second joint creating frame "2".
    let e = load_err(
        &append(
            r#"
[[joint]]
name = "extra"
type = "fixed"
parent = "1"
child = "2"
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]
"#,
        ),
        &["frame `2`", "twice"],
    );
    assert!(
        matches!(&e.kind, K::Duplicate { what: "frame", name } if name == "2"),
        "{:?}",
        e.kind
    );
}

#[test]
fn duplicate_speed() {
    let e = load_err(
        &mutate(&[(
            r#"speeds = ["qd1", "qd2"]"#,
            r#"speeds = ["qd1", "qd2", "qd1"]"#,
        )]),
        &["speed `qd1`", "twice"],
    );
    assert!(
        matches!(&e.kind, K::Duplicate { what: "speed", name } if name == "qd1"),
        "{:?}",
        e.kind
    );
}

#[test]
fn duplicate_body() {
    let e = load_err(
        &append("[[body]]\nframe = \"0\"\nname = \"2\"\n"),
        &["body `2`", "twice"],
    );
    assert!(
        matches!(&e.kind, K::Duplicate { what: "body", name } if name == "2"),
        "{:?}",
        e.kind
    );
}

#[test]
fn two_bodies_on_one_frame() {
    let e = load_err(
        &append("[[body]]\nframe = \"2\"\nname = \"2b\"\n"),
        &["`2`", "twice"],
    );
    assert!(
        matches!(&e.kind, K::Duplicate { what: "body on frame", name } if name == "2"),
        "{:?}",
        e.kind
    );
}

#[test]
fn body_on_unknown_frame() {
    let e = load_err(
        &append("[[body]]\nframe = \"9\"\n"),
        &["body `9`", "frame `9`"],
    );
    assert!(
        matches!(&e.kind, K::UnknownFrame { body, frame } if body == "9" && frame == "9"),
        "{:?}",
        e.kind
    );
}

#[test]
fn base_frame_as_child() {
    let e = load_err(
        &mutate(&[(r#"child = "2""#, r#"child = "0""#)]),
        &["`q2`", "`0`"],
    );
    assert!(
        matches!(&e.kind, K::BaseAsChild { joint, frame } if joint == "q2" && frame == "0"),
        "{:?}",
        e.kind
    );
}

#[test]
fn rotation_not_orthonormal() {
    let e = load_err(
        &mutate(&[(
            "rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]",
            "rotation = [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]",
        )]),
        &["`q2`", "not a proper rotation"],
    );
    assert!(
        matches!(&e.kind, K::BadRotation { joint, detail } if joint == "q2" && detail.contains("R Rᵀ")),
        "{:?}",
        e.kind
    );
}

#[test]
fn rotation_with_determinant_minus_one() {
    let e = load_err(
        &mutate(&[(
            "rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]",
            "rotation = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]",
        )]),
        &["`q2`", "det"],
    );
    assert!(
        matches!(&e.kind, K::BadRotation { joint, detail } if joint == "q2" && detail.contains("det R = -1")),
        "{:?}",
        e.kind
    );
}

#[test]
fn axis_not_unit() {
    let e = load_err(
        &mutate(&[(
            "speed = \"qd2\"\naxis = [-1, 0, 0]",
            "speed = \"qd2\"\naxis = [-1, 1, 0]",
        )]),
        &["`q2`", "unit"],
    );
    assert!(
        matches!(&e.kind, K::AxisNotUnit { joint, axis, norm }
            if joint == "q2" && *axis == [-1.0, 1.0, 0.0] && (norm - 2f64.sqrt()).abs() < 1e-12),
        "{:?}",
        e.kind
    );
}

#[test]
fn moving_joint_without_axis() {
    let e = load_err(
        &mutate(&[("speed = \"qd2\"\naxis = [-1, 0, 0]\n", "speed = \"qd2\"\n")]),
        &["`q2`", "axis"],
    );
    assert!(
        matches!(&e.kind, K::JointSpeed { joint, detail } if joint == "q2" && detail.contains("axis")),
        "{:?}",
        e.kind
    );
}

#[test]
fn mass_not_positive() {
    for (text, value) in [("m2 = 0.0", 0.0), ("m2 = -2.0", -2.0)] {
        let e = load_err(&mutate(&[("m2 = 2.0", text)]), &["body `2`", "`m2`"]);
        assert!(
            matches!(&e.kind, K::NonPositiveMass { body, symbol, value: v }
                if body == "2" && symbol == "m2" && *v == value),
            "{:?}",
            e.kind
        );
    }
}

#[test]
fn inertia_not_positive_semi_definite() {
    // I_G[y][y] = YY2 − m(Sx² + Sz²) = −0.01.
    let e = load_err(
        &mutate(&[("YY2 = 0.01", "YY2 = -0.01")]),
        &["body `2`", "not physical"],
    );
    assert!(
        matches!(&e.kind, K::NonPhysicalInertia { body, detail }
            if body == "2" && detail.contains("not positive semi-definite")),
        "{:?}",
        e.kind
    );
}

#[test]
fn inertia_breaks_triangle_inequality() {
    // I_G = diag(0.03, 0.01, 0.05): positive definite, but 0.03 + 0.01 < 0.05.
    let e = load_err(
        &mutate(&[("ZZ2 = 0.05", "ZZ2 = 0.07")]),
        &["body `2`", "not physical"],
    );
    assert!(
        matches!(&e.kind, K::NonPhysicalInertia { body, detail }
            if body == "2" && detail.contains("triangle") && !detail.contains("positive definite")),
        "{:?}",
        e.kind
    );
}

#[test]
fn undefined_length_symbol() {
    let e = load_err(
        &mutate(&[(r#""L1", "-L2""#, r#""L3", "-L2""#)]),
        &["joint `q2`", "`L3`"],
    );
    assert!(
        matches!(&e.kind, K::UndefinedSymbol { item, symbol } if item == "joint `q2`" && symbol == "L3"),
        "{:?}",
        e.kind
    );
}

#[test]
fn undefined_body_symbol() {
    let e = load_err(&mutate(&[("MX1 = 0.0\n", "")]), &["body `1`", "`MX1`"]);
    assert!(
        matches!(&e.kind, K::UndefinedSymbol { item, symbol } if item == "body `1`" && symbol == "MX1"),
        "{:?}",
        e.kind
    );
}

#[test]
fn undefined_gravity_symbol() {
    let e = load_err(&mutate(&[("g = 9.81\n", "")]), &["gravity", "`g`"]);
    assert!(
        matches!(&e.kind, K::UndefinedSymbol { item, symbol } if item == "gravity" && symbol == "g"),
        "{:?}",
        e.kind
    );
}

#[test]
fn misspelt_parameter_is_undefined_where_used() {
    // Misspelling a needed parameter: the body's symbol is then missing.
    let e = load_err(
        &mutate(&[("XZ2 = 0.0", "XZ_2 = 0.0")]),
        &["body `2`", "`XZ2`"],
    );
    assert!(
        matches!(&e.kind, K::UndefinedSymbol { item, symbol } if item == "body `2`" && symbol == "XZ2"),
        "{:?}",
        e.kind
    );
}

#[test]
fn unused_parameter() {
    // A misspelt extra (`Ll` for `L1`) that nothing uses.
    let e = load_err(
        &mutate(&[("L1 = 0.5\n", "L1 = 0.5\nLl = 0.5\n")]),
        &["`Ll`", "declared but not used"],
    );
    assert!(
        matches!(&e.kind, K::UnusedParameter { name } if name == "Ll"),
        "{:?}",
        e.kind
    );
}

#[test]
fn bad_length_text() {
    for bad in ["2*L1", "L 1", "--L1", "", "0.5"] {
        let e = load_err(
            &mutate(&[(r#""L1", "-L2""#, &format!(r#""{bad}", "-L2""#))]),
            &["joint `q2`", &format!("`{bad}`")],
        );
        assert!(
            matches!(&e.kind, K::BadLength { joint, text } if joint == "q2" && text == bad),
            "{bad:?}: {:?}",
            e.kind
        );
    }
}

#[test]
fn non_finite_translation() {
    let e = load_err(
        &mutate(&[(
            r#"translation = [0, "L1", "-L2"]"#,
            r#"translation = [nan, "L1", "-L2"]"#,
        )]),
        &["joint `q2`"],
    );
    assert!(
        matches!(&e.kind, K::BadLength { joint, .. } if joint == "q2"),
        "{:?}",
        e.kind
    );
}

#[test]
fn absurdly_large_parameter_or_translation() {
    // Finite but beyond any robot: a mass of 10³⁰⁰ kg made the loader's positive-definiteness
    // check overflow and blame a speed that "moves no mass"; now the number itself is named.
    let limit = kanegen_model::MAX_PARAMETER_MAGNITUDE;
    for (from, to, item, value) in [
        ("m1 = 2.0", "m1 = 1e300", "parameter `m1`", 1e300),
        ("L1 = 0.5", "L1 = -2e9", "parameter `L1`", -2e9),
        (
            r#"translation = [0, "L1", "-L2"]"#,
            r#"translation = [1e12, "L1", "-L2"]"#,
            "joint `q2` translation (x)",
            1e12,
        ),
    ] {
        let e = load_err(&mutate(&[(from, to)]), &[item, "absurdly large", "1e9"]);
        assert!(
            matches!(&e.kind, K::AbsurdValue { item: i, value: v, limit: l }
                if i == item && *v == value && *l == limit),
            "{to}: {:?}",
            e.kind
        );
    }
    // The limit itself is accepted.
    let at_limit = mutate(&[("m1 = 2.0", "m1 = 1e9")]);
    assert!(Model::from_toml_str(&at_limit, FILE).is_ok());
}

#[test]
fn a_model_without_speeds_is_an_error() {
    // Every joint fixed: nothing moves, and the centre-of-mass functions divided by a total
    // mass of zero (a panic of the generator) before this was an error of its own.
    let text = mutate(&[
        (r#"speeds = ["qd1", "qd2"]"#, "speeds = []"),
        (
            "type = \"revolute\"\nparent = \"0\"\nchild = \"1\"\nspeed = \"qd1\"\naxis = [-1, 0, 0]\n",
            "type = \"fixed\"\nparent = \"0\"\nchild = \"1\"\n",
        ),
        (
            "type = \"revolute\"\nparent = \"1\"\nchild = \"2\"\nspeed = \"qd2\"\naxis = [-1, 0, 0]\n",
            "type = \"fixed\"\nparent = \"1\"\nchild = \"2\"\n",
        ),
    ]);
    let e = load_err(&text, &["no moving joint", "revolute"]);
    assert!(matches!(e.kind, K::NoSpeeds), "{:?}", e.kind);
}

#[test]
fn speed_driven_twice() {
    let e = load_err(
        &mutate(&[(r#"speed = "qd2""#, r#"speed = "qd1""#)]),
        &["`qd1`", "`q1`", "`q2`"],
    );
    assert!(
        matches!(&e.kind, K::SpeedTwice { speed, first, second }
            if speed == "qd1" && first == "joint `q1`" && second == "joint `q2`"),
        "{:?}",
        e.kind
    );
}

#[test]
fn speed_never_driven() {
    let e = load_err(
        &mutate(&[(
            r#"speeds = ["qd1", "qd2"]"#,
            r#"speeds = ["qd1", "qd2", "qd3"]"#,
        )]),
        &["`qd3`"],
    );
    assert!(
        matches!(&e.kind, K::SpeedNever { speed } if speed == "qd3"),
        "{:?}",
        e.kind
    );
}

#[test]
fn joint_speed_not_listed() {
    let e = load_err(
        &mutate(&[(r#"speed = "qd2""#, r#"speed = "qd9""#)]),
        &["`q2`", "`qd9`"],
    );
    assert!(
        matches!(&e.kind, K::UnknownSpeed { item, speed } if item == "joint `q2`" && speed == "qd9"),
        "{:?}",
        e.kind
    );
}

#[test]
fn fixed_joint_with_speed() {
    let e = load_err(
        &mutate(&[(
            "type = \"revolute\"\nparent = \"1\"",
            "type = \"fixed\"\nparent = \"1\"",
        )]),
        &["`q2`", "fixed"],
    );
    assert!(
        matches!(&e.kind, K::JointSpeed { joint, detail }
            if joint == "q2" && detail.contains("fixed") && detail.contains("qd2")),
        "{:?}",
        e.kind
    );
}

#[test]
fn moving_joint_without_speed() {
    let e = load_err(&mutate(&[("speed = \"qd2\"\n", "")]), &["`q2`", "speed"]);
    assert!(
        matches!(&e.kind, K::JointSpeed { joint, detail } if joint == "q2" && detail.contains("speed")),
        "{:?}",
        e.kind
    );
}

#[test]
fn gravity_direction_not_unit() {
    for dir in ["[0, 0, -2]", "[0, 0, 0]", "[nan, 0, -1]", "[inf, 0, 0]"] {
        let e = load_err(
            &mutate(&[("direction = [0, 0, -1]", &format!("direction = {dir}"))]),
            &["gravity", "unit"],
        );
        assert!(
            matches!(&e.kind, K::Invalid { item, detail } if item == "gravity" && detail.contains("unit")),
            "{dir}: {:?}",
            e.kind
        );
    }
}

#[test]
fn non_finite_parameter() {
    for (text, name) in [("L1 = nan", "L1"), ("L1 = inf", "L1"), ("g = -inf", "g")] {
        let from = if name == "g" { "g = 9.81" } else { "L1 = 0.5" };
        let e = load_err(&mutate(&[(from, text)]), &[&format!("`{name}`"), "finite"]);
        assert!(
            matches!(&e.kind, K::NonFiniteParameter { name: n, value } if n == name && !value.is_finite()),
            "{text}: {:?}",
            e.kind
        );
    }
}

#[test]
fn non_numeric_parameter() {
    let e = load_err(
        &mutate(&[("L1 = 0.5", r#"L1 = "0.5""#)]),
        &["`L1`", "number"],
    );
    assert!(
        matches!(&e.kind, K::Syntax(s) if s.contains("`L1`") && s.contains("string")),
        "{:?}",
        e.kind
    );
}

#[test]
fn wheeled_base_speed_not_listed() {
    let wheeled = mutate(&[
        (
            "[base]\ntype = \"fixed\"\nframe = \"0\"\n",
            "[base]\ntype = \"wheeled\"\nframe = \"0\"\nx_speed = \"xd\"\npsi_speed = \"psid\"\n\
             radius = \"R\"\ntrack = \"L\"\nwheel_mass = \"mw\"\nwheel_axle_inertia = \"YYw\"\n\
             wheel_diametral_inertia = \"ZZw\"\n",
        ),
        (
            "g = 9.81\n",
            "g = 9.81\nR = 0.25\nL = 0.68\nmw = 4.66\nYYw = 0.1456\nZZw = 0.0751\n",
        ),
    ]);
    let e = load_err(&wheeled, &["`xd`"]);
    assert!(
        matches!(&e.kind, K::UnknownSpeed { item, speed } if item.contains("x_speed") && speed == "xd"),
        "{:?}",
        e.kind
    );
    // With the speeds listed it loads.
    let ok = wheeled.replacen(
        r#"speeds = ["qd1", "qd2"]"#,
        r#"speeds = ["xd", "psid", "qd1", "qd2"]"#,
        1,
    );
    let m = Model::from_toml_str(&ok, FILE).expect("valid wheeled model");
    assert_eq!(m.dof(), 4);
    assert!(m.wheeled_base().is_some());
}

fn models_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

#[test]
fn shipped_models_load() {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(models_dir()).expect("models/ exists") {
        let path = entry.expect("directory entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let m = Model::from_toml_file(&path)
                .unwrap_or_else(|e| panic!("{} should load: {e}", path.display()));
            found.push((m.name.clone(), m.dof(), m.body_count()));
        }
    }
    found.sort();
    assert_eq!(
        found,
        vec![
            ("floating-hopper".to_owned(), 9, 4),
            ("krang".to_owned(), 19, 17),
            ("krang-fixed-wheels".to_owned(), 17, 17),
            ("two-link".to_owned(), 2, 2),
        ]
    );
}

#[test]
fn missing_file_is_io_error_naming_the_path() {
    let path = models_dir().join("no-such-model.toml");
    let err = Model::from_toml_file(&path).expect_err("the file does not exist");
    let label = path.display().to_string();
    assert_eq!(err.file, label);
    assert!(
        matches!(&err.kind, K::Io(io) if io.kind() == std::io::ErrorKind::NotFound),
        "{:?}",
        err.kind
    );
    // The I/O error is kept as the source, not only as text.
    let source = std::error::Error::source(&err.kind).expect("the I/O error is the source");
    assert!(
        source.downcast_ref::<std::io::Error>().is_some(),
        "{source}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("no-such-model.toml") && msg.contains("cannot read"),
        "{msg}"
    );
}

/// `VALID` on a wheeled base with the wheel constants `R`, `L`, `mw`, `YYw`, `ZZw` of `wheel`.
fn wheeled(wheel: &str) -> String {
    mutate(&[
        (
            "[base]\ntype = \"fixed\"\nframe = \"0\"\n",
            "[base]\ntype = \"wheeled\"\nframe = \"0\"\nx_speed = \"xd\"\npsi_speed = \"psid\"\n\
             radius = \"R\"\ntrack = \"L\"\nwheel_mass = \"mw\"\nwheel_axle_inertia = \"YYw\"\n\
             wheel_diametral_inertia = \"ZZw\"\n",
        ),
        ("g = 9.81\n", &format!("g = 9.81\n{wheel}\n")),
        (
            r#"speeds = ["qd1", "qd2"]"#,
            r#"speeds = ["xd", "psid", "qd1", "qd2"]"#,
        ),
    ])
}

#[test]
fn non_physical_wheel_constants_are_errors() {
    const GOOD: [(&str, &str); 5] = [
        ("R", "0.25"),
        ("L", "0.68"),
        ("mw", "4.66"),
        ("YYw", "0.1456"),
        ("ZZw", "0.0751"),
    ];
    let with = |symbol: &str, value: &str| {
        GOOD.iter()
            .map(|(s, v)| format!("{s} = {}\n", if *s == symbol { value } else { v }))
            .collect::<String>()
    };
    Model::from_toml_str(&wheeled(&with("", "")), FILE).expect("the wheeled model is valid");
    for (symbol, value) in [
        ("R", "0"),
        ("R", "-0.25"),
        ("L", "0"),
        ("mw", "-1"),
        ("YYw", "-0.1"),
        ("ZZw", "-0.1"),
    ] {
        let e = load_err(
            &wheeled(&with(symbol, value)),
            &[&format!("`{symbol}`"), "must be"],
        );
        assert!(
            matches!(&e.kind, K::NonPhysicalWheel { symbol: s, .. } if s == symbol),
            "{symbol} = {value}: {:?}",
            e.kind
        );
    }
    // Massless wheels are allowed (their inertia terms vanish).
    let massless = with("mw", "0")
        .replace("YYw = 0.1456", "YYw = 0")
        .replace("ZZw = 0.0751", "ZZw = 0");
    Model::from_toml_str(&wheeled(&massless), FILE).expect("massless wheels");
}

#[test]
fn a_nan_mass_is_an_error() {
    for (text, name) in [
        ("m1 = nan", "m1"),
        ("XX2 = inf", "XX2"),
        ("MY1 = -inf", "MY1"),
    ] {
        let from = format!("{} = ", name);
        let line = VALID
            .lines()
            .find(|l| l.starts_with(&from))
            .expect("parameter line");
        let e = load_err(&mutate(&[(line, text)]), &[&format!("`{name}`"), "finite"]);
        assert!(
            matches!(&e.kind, K::NonFiniteParameter { name: n, .. } if n == name),
            "{text}: {:?}",
            e.kind
        );
    }
}
