//! Names that reach generated code (see `kanegen_model::names`): every hostile name of a TOML or
//! URDF description is a typed [`K::BadName`] naming the item, the name as written and the fix;
//! none panics, none loads into a model whose generated code would be wrong or not compile.

use kanegen_model::{BadName, Model, ModelErrorKind as K, UrdfOptions};

mod common;
use common::{VALID, mutate};

/// `VALID` with speed `qd1` renamed `to`.
fn speed1(to: &str) -> String {
    mutate(&[
        (r#"speeds = ["qd1""#, &format!(r#"speeds = ["{to}""#)),
        (r#"speed = "qd1""#, &format!(r#"speed = "{to}""#)),
    ])
}

/// The `BadName` error of `text`: (item, name, problem, fix), with the file label and the
/// message checked to name the item and the name.
fn bad_name(text: &str) -> (String, String, String, String) {
    let e = Model::from_toml_str(text, "bad.toml").expect_err("the names are invalid");
    assert_eq!(e.file, "bad.toml");
    let msg = e.to_string();
    match e.kind {
        K::BadName(b) => {
            let BadName {
                item,
                name,
                problem,
                fix,
            } = *b;
            assert!(
                msg.contains(&item) && msg.contains(&format!("`{name}`")),
                "{msg}"
            );
            (item, name, problem, fix)
        }
        other => panic!("expected BadName, got {other:?} ({msg})"),
    }
}

#[test]
fn the_valid_description_loads() {
    Model::from_toml_str(VALID, "ok.toml").expect("valid");
}

#[test]
fn a_speed_named_like_a_generated_local_is_an_error() {
    for local in ["d1", "k12", "t3", "pc7"] {
        let (item, name, problem, fix) = bad_name(&speed1(local));
        assert_eq!(item, "speed of joint `q1`");
        assert_eq!(name, local);
        assert!(
            problem.contains("local variable of generated code"),
            "{problem}"
        );
        assert_eq!(fix, format!("rename it, e.g. `{local}_`"));
    }
}

#[test]
fn a_speed_named_like_the_sine_of_a_coordinate_is_an_error() {
    // The sine of coordinate `q_w` is the local `s_q_w`.
    let text = mutate(&[
        (r#"speeds = ["qd1", "qd2"]"#, r#"speeds = ["s_q_w", "qd2"]"#),
        (r#"speed = "qd1""#, r#"speed = "s_q_w""#),
        (r#"name = "q2""#, r#"name = "q_w""#),
    ]);
    let (item, name, problem, fix) = bad_name(&text);
    assert_eq!(
        (item.as_str(), name.as_str()),
        ("speed of joint `q1`", "s_q_w")
    );
    assert!(
        problem.contains("also the name of the sine of coordinate `q_w`"),
        "{problem}"
    );
    assert_eq!(fix, "rename one of them");
}

#[test]
fn speeds_that_are_equal_once_sanitised_are_an_error_proposing_a_free_name() {
    let text = mutate(&[
        (r#"speeds = ["qd1", "qd2"]"#, r#"speeds = ["qd-a", "qd_a"]"#),
        (r#"speed = "qd1""#, r#"speed = "qd-a""#),
        (r#"speed = "qd2""#, r#"speed = "qd_a""#),
    ]);
    let (_, name, problem, fix) = bad_name(&text);
    assert_eq!(name, "qd-a");
    assert!(problem.contains("not a Rust identifier"), "{problem}");
    // `qd_a` is taken by the other speed.
    assert_eq!(fix, "rename it, e.g. `qd_a_2`");
}

#[test]
fn coordinates_equal_ignoring_case_are_an_error() {
    // Both would be the index constant `QA`.
    let text = mutate(&[
        (r#"name = "q1""#, r#"name = "qa""#),
        (r#"name = "q2""#, r#"name = "QA""#),
    ]);
    let (item, name, problem, _) = bad_name(&text);
    assert_eq!(
        (item.as_str(), name.as_str()),
        ("coordinate of joint `QA`", "QA")
    );
    assert!(
        problem.contains("ignoring case") && problem.contains("`qa`"),
        "{problem}"
    );
}

#[test]
fn keywords_and_underscore_are_errors_not_panics() {
    for (kw, fix) in [
        ("self", "self_"),
        ("Self", "Self_"),
        ("_", "__"),
        ("type", "type_"),
    ] {
        let (_, name, problem, f) = bad_name(&speed1(kw));
        assert_eq!(name, kw);
        assert!(problem.contains("keyword"), "{problem}");
        assert_eq!(f, format!("rename it, e.g. `{fix}`"));
    }
}

#[test]
fn names_generated_code_binds_are_errors() {
    // A sample of the generated code's locals and every item name of a generated module.
    let locals = ["p", "q", "u", "ud", "m", "out", "s", "sin_q"];
    for &reserved in locals.iter().chain(kanegen_model::names::RESERVED_ITEMS) {
        let (_, name, _, _) = bad_name(&speed1(reserved));
        assert_eq!(name, reserved);
    }
}

#[test]
fn a_parameter_named_like_a_generated_item_is_an_error() {
    let text = mutate(&[("L1 = 0.5", "DOF = 0.5"), (r#""L1""#, r#""DOF""#)]);
    let (item, name, problem, _) = bad_name(&text);
    assert_eq!((item.as_str(), name.as_str()), ("parameter", "DOF"));
    assert!(
        problem.contains("item of the generated module"),
        "{problem}"
    );
}

#[test]
fn a_parameter_that_is_not_an_identifier_is_an_error() {
    let text = mutate(&[("L1 = 0.5", "\"L-1\" = 0.5"), (r#""L1""#, r#""L-1""#)]);
    // `L-1` is not even a length symbol.
    let e = Model::from_toml_str(&text, "bad.toml").expect_err("invalid");
    assert!(matches!(e.kind, K::BadLength { .. }), "{:?}", e.kind);
    // A body name that is no identifier gives parameters that are none.
    let text = VALID
        .replace("m2 =", "\"m2-x\" =")
        .replace("MX2 ", "\"MX2-x\" ")
        .replace("MY2 ", "\"MY2-x\" ")
        .replace("MZ2 ", "\"MZ2-x\" ")
        .replace("XX2 ", "\"XX2-x\" ")
        .replace("XY2 ", "\"XY2-x\" ")
        .replace("XZ2 ", "\"XZ2-x\" ")
        .replace("YY2 ", "\"YY2-x\" ")
        .replace("YZ2 ", "\"YZ2-x\" ")
        .replace("ZZ2 ", "\"ZZ2-x\" ")
        .replace("frame = \"2\"\n", "frame = \"2\"\nname = \"2-x\"\n");
    let (item, name, _, fix) = bad_name(&text);
    assert_eq!(item, "parameter of the body on frame `2`");
    assert_eq!(name, "m2-x");
    assert_eq!(fix, "rename it, e.g. `m2_x`");
}

#[test]
fn a_model_name_that_gives_a_generated_type_is_an_error() {
    for model in ["params", "self", "option"] {
        let text = mutate(&[(r#"name = "two-link""#, &format!(r#"name = "{model}""#))]);
        let (item, name, problem, _) = bad_name(&text);
        assert_eq!((item.as_str(), name.as_str()), ("model name", model));
        assert!(problem.contains("wrapper type"), "{problem}");
    }
}

#[test]
fn a_model_name_with_a_newline_is_an_error() {
    let text = mutate(&[(
        r#"name = "two-link""#,
        r#"name = "r\npub fn injected() -> u32 { 42 }""#,
    )]);
    let (item, name, problem, _) = bad_name(&text);
    assert_eq!(item, "model name");
    assert!(name.starts_with(r"r\npub fn"), "{name}");
    assert!(problem.contains("'\\n'"), "{problem}");
}

/// A one-link URDF whose robot, link and joint names are `robot`, `link` and `joint`.
fn urdf(robot: &str, link: &str, joint: &str) -> String {
    format!(
        r#"<robot name="{robot}">
  <link name="base"/>
  <link name="{link}">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <joint name="{joint}" type="revolute">
    <parent link="base"/><child link="{link}"/><axis xyz="0 0 1"/>
  </joint>
</robot>"#
    )
}

#[test]
fn urdf_names_are_sanitised_then_checked() {
    // Keywords and `_` as joint and link names are fine: their identifiers have prefixes.
    for n in ["self", "Self", "_", "type"] {
        let m = Model::from_urdf_str(&urdf("r", n, n), "r.urdf", &UrdfOptions::default())
            .unwrap_or_else(|e| panic!("{n}: {e}"));
        assert_eq!(m.speeds[0].name, format!("qd_{n}"));
    }
    // A robot name with a newline cannot become the model name; `UrdfOptions::name` fixes it.
    let text = urdf("r&#10;pub fn injected() -> u32 { 42 }", "l", "j");
    let e = Model::from_urdf_str(&text, "r.urdf", &UrdfOptions::default()).expect_err("newline");
    assert!(
        matches!(&e.kind, K::BadName(b) if b.item == "model name" && b.fix.contains("UrdfOptions::name")),
        "{:?}",
        e.kind
    );
    let named = UrdfOptions {
        name: Some("r".into()),
        ..UrdfOptions::default()
    };
    Model::from_urdf_str(&text, "r.urdf", &named).expect("named");
    // `Self` as robot name would give the wrapper type `Self`.
    let e = Model::from_urdf_str(&urdf("self", "l", "j"), "r.urdf", &UrdfOptions::default())
        .expect_err("Self");
    assert!(matches!(e.kind, K::BadName(_)), "{:?}", e.kind);
}

#[test]
fn urdf_joints_equal_ignoring_case_are_an_error_naming_both_joints() {
    let text = urdf("r", "l", "qa").replace(
        "</robot>",
        r#"<link name="l2"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="QA" type="revolute"><parent link="l"/><child link="l2"/><axis xyz="0 0 1"/></joint>
</robot>"#,
    );
    let e = Model::from_urdf_str(&text, "r.urdf", &UrdfOptions::default()).expect_err("qa/QA");
    let msg = e.to_string();
    assert!(
        msg.contains("joint `QA`") && msg.contains("joint `qa`") && msg.contains("ignoring case"),
        "{msg}"
    );
}
