//! One test per typed error of the URDF import: a small valid arm is mutated into a malformed
//! one, and the exact variant, the element it names and the message are checked.

use kanegen_model::{
    AbsurdInertia, Model, ModelError, ModelErrorKind as K, UrdfOptions, WheeledBaseSpec,
};

/// A base with two revolute links; `L2` has a fixed child `tool`.
const VALID: &str = r#"<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="L1">
    <inertial>
      <origin xyz="0 0 0.2"/>
      <mass value="2.0"/>
      <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.01"/>
    </inertial>
    <visual><geometry><mesh filename="package://missing/L1.dae"/></geometry></visual>
  </link>
  <link name="L2">
    <inertial>
      <origin xyz="0.1 0 0" rpy="0 0 0.3"/>
      <mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/>
    </inertial>
  </link>
  <link name="tool">
    <inertial>
      <mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/>
    </inertial>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/>
    <child link="L1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <joint name="j2" type="continuous">
    <parent link="L1"/>
    <child link="L2"/>
    <origin xyz="0 0 0.4" rpy="1.5708 0 0"/>
    <axis xyz="0 1 0"/>
  </joint>
  <joint name="tool_mount" type="fixed">
    <parent link="L2"/>
    <child link="tool"/>
    <origin xyz="0.3 0 0"/>
  </joint>
</robot>
"#;

const FILE: &str = "bad.urdf";

/// `VALID` with each `(from, to)` applied; every `from` must occur exactly once.
fn mutate(edits: &[(&str, &str)]) -> String {
    let mut s = VALID.to_owned();
    for (from, to) in edits {
        assert_eq!(
            s.matches(from).count(),
            1,
            "`{from}` must occur exactly once"
        );
        s = s.replace(from, to);
    }
    s
}

fn import(text: &str) -> Result<Model, ModelError> {
    Model::from_urdf_str(text, FILE, &UrdfOptions::default())
}

/// The error of `text`, with the file label and message fragments checked.
fn error_of(text: &str, fragments: &[&str]) -> K {
    let e = import(text).expect_err("the description is malformed");
    assert_eq!(e.file, FILE);
    let msg = e.to_string();
    for f in fragments {
        assert!(msg.contains(f), "message `{msg}` lacks `{f}`");
    }
    e.kind
}

/// The error of `text` imported with non-physical inertias refused
/// (`NonPhysicalInertia::Error`), with message fragments checked.
fn strict_error_of(text: &str, fragments: &[&str]) -> K {
    let options = UrdfOptions {
        non_physical_inertia: kanegen_model::NonPhysicalInertia::Error,
        ..UrdfOptions::default()
    };
    let e = Model::from_urdf_str(text, FILE, &options).expect_err("the inertia is refused");
    let msg = e.to_string();
    for f in fragments {
        assert!(msg.contains(f), "message `{msg}` lacks `{f}`");
    }
    e.kind
}

/// `actual` is `expected`, field by field (error kinds are not `PartialEq`: the I/O error that
/// one of them holds is not).
fn assert_kind(actual: &K, expected: K) {
    assert_eq!(format!("{actual:?}"), format!("{expected:?}"));
}

#[test]
fn the_valid_description_imports() {
    let m = import(VALID).unwrap();
    assert_eq!(m.dof(), 2);
    assert_eq!(m.body_count(), 2);
}

#[test]
fn malformed_xml_is_a_parse_error() {
    let kind = error_of(
        &mutate(&[("<link name=\"base\"/>", "<link name=\"base\">")]),
        &["not a readable URDF"],
    );
    assert!(matches!(kind, K::UrdfParse { .. }), "{kind:?}");
}

#[test]
fn a_joint_without_a_parent_element_is_a_parse_error() {
    let kind = error_of(
        &mutate(&[("<parent link=\"L1\"/>", "")]),
        &["not a readable URDF"],
    );
    assert!(matches!(kind, K::UrdfParse { .. }), "{kind:?}");
}

#[test]
fn missing_parent_link() {
    let kind = error_of(
        &mutate(&[("<parent link=\"L1\"/>", "<parent link=\"L7\"/>")]),
        &["joint `j2`", "parent link `L7`"],
    );
    assert_kind(
        &kind,
        K::UrdfMissingParentLink {
            joint: "j2".into(),
            parent: "L7".into(),
        },
    );
}

#[test]
fn missing_child_link() {
    let kind = error_of(
        &mutate(&[("<child link=\"tool\"/>", "<child link=\"tol\"/>")]),
        &["joint `tool_mount`", "child link `tol`"],
    );
    assert_kind(
        &kind,
        K::UrdfMissingChildLink {
            joint: "tool_mount".into(),
            child: "tol".into(),
        },
    );
}

#[test]
fn two_roots() {
    let kind = error_of(
        &mutate(&[(
            "<link name=\"base\"/>",
            "<link name=\"base\"/><link name=\"stray\"/>",
        )]),
        &["2 root links", "base, stray", "exactly one root"],
    );
    assert_kind(
        &kind,
        K::UrdfTwoRoots {
            roots: vec!["base".into(), "stray".into()],
        },
    );
}

#[test]
fn two_parents() {
    let kind = error_of(
        &mutate(&[("<child link=\"tool\"/>", "<child link=\"L1\"/>")]),
        &["link `L1`", "`j1` and `tool_mount`"],
    );
    assert_kind(
        &kind,
        K::UrdfTwoParents {
            link: "L1".into(),
            first: "j1".into(),
            second: "tool_mount".into(),
        },
    );
}

#[test]
fn a_cycle() {
    // base -> L1 -> L2 -> tool, and tool -> L1 instead of base -> L1: base is alone, L1..tool cycle.
    let kind = error_of(
        &mutate(&[("<parent link=\"base\"/>", "<parent link=\"tool\"/>")]),
        &["not reachable from the base frame"],
    );
    assert!(matches!(kind, K::Cycle { .. }), "{kind:?}");
}

#[test]
fn unknown_joint_type() {
    let kind = error_of(
        &mutate(&[("type=\"continuous\"", "type=\"screw\"")]),
        &[
            "joint `j2`",
            "unknown joint type `screw`",
            "revolute, continuous, prismatic or fixed",
        ],
    );
    assert_kind(
        &kind,
        K::UrdfUnknownJointType {
            joint: "j2".into(),
            kind: "screw".into(),
        },
    );
}

#[test]
fn bad_number_in_an_origin() {
    let kind = error_of(
        &mutate(&[("rpy=\"1.5708 0 0\"", "rpy=\"1.5708 0\"")]),
        &[
            "joint `j2` <origin>",
            "rpy=\"1.5708 0\"",
            "3 finite numbers",
        ],
    );
    assert_kind(
        &kind,
        K::UrdfBadNumber {
            element: "joint `j2` <origin>".into(),
            attribute: "rpy".into(),
            text: "1.5708 0".into(),
            expected: "3 finite numbers separated by spaces".into(),
        },
    );
}

#[test]
fn bad_number_in_an_inertia() {
    let kind = error_of(
        &mutate(&[("<mass value=\"1.5\"/>", "<mass value=\"1,5\"/>")]),
        &["link `L2` <mass>", "value=\"1,5\"", "a finite number"],
    );
    assert!(
        matches!(&kind, K::UrdfBadNumber { element, attribute, .. } if element == "link `L2` <mass>" && attribute == "value"),
        "{kind:?}"
    );
    let kind = error_of(
        &mutate(&[("ixx=\"0.03\"", "ixx=\"nan\"")]),
        &["link `L1` <inertia>", "ixx=\"nan\""],
    );
    assert!(matches!(kind, K::UrdfBadNumber { .. }), "{kind:?}");
}

#[test]
fn mimic_joint_of_a_missing_master_is_a_typed_error() {
    // (A mimic joint of an existing joint imports as an exact constraint: tests/mimic.rs.)
    let kind = error_of(
        &mutate(&[(
            "<axis xyz=\"0 1 0\"/>",
            "<axis xyz=\"0 1 0\"/><mimic joint=\"j9\" multiplier=\"2\"/>",
        )]),
        &[
            "joint `j2` <mimic>",
            "master joint `j9`",
            "not a moving joint",
        ],
    );
    assert!(
        matches!(&kind, K::UrdfBadMimic { joint, .. } if joint == "j2"),
        "{kind:?}"
    );
    let ok = import(&mutate(&[(
        "<axis xyz=\"0 1 0\"/>",
        "<axis xyz=\"0 1 0\"/><mimic joint=\"j1\" multiplier=\"2\"/>",
    )]))
    .expect("a mimic of an existing joint imports");
    assert_eq!(ok.mimics.len(), 1);
}

#[test]
fn floating_joint_is_unsupported_without_a_base_declaration() {
    let kind = error_of(
        &mutate(&[("type=\"revolute\"", "type=\"floating\"")]),
        &[
            "joint `j1`",
            "floating joints are not supported",
            "UrdfBase::Wheeled",
        ],
    );
    assert!(
        matches!(&kind, K::UrdfUnsupportedJoint { joint, kind, .. } if joint == "j1" && kind == "floating"),
        "{kind:?}"
    );
}

#[test]
fn planar_joint_is_unsupported_without_a_base_declaration() {
    let kind = error_of(
        &mutate(&[("type=\"continuous\"", "type=\"planar\"")]),
        &["joint `j2`", "planar joints are not supported"],
    );
    assert!(
        matches!(&kind, K::UrdfUnsupportedJoint { joint, kind, .. } if joint == "j2" && kind == "planar"),
        "{kind:?}"
    );
}

#[test]
fn spherical_joint_is_unsupported() {
    let kind = error_of(
        &mutate(&[("type=\"continuous\"", "type=\"spherical\"")]),
        &[
            "joint `j2`",
            "spherical joints are not supported",
            "three revolute joints",
        ],
    );
    assert!(matches!(kind, K::UrdfUnsupportedJoint { .. }), "{kind:?}");
}

#[test]
fn zero_axis() {
    let kind = error_of(
        &mutate(&[("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>")]),
        &["URDF joint `j2`", "no direction"],
    );
    assert!(matches!(kind, K::Invalid { .. }), "{kind:?}");
}

#[test]
fn duplicate_link() {
    let kind = error_of(
        &mutate(&[(
            "<link name=\"base\"/>",
            "<link name=\"base\"/><link name=\"base\"/>",
        )]),
        &["URDF link `base` is defined twice"],
    );
    assert_kind(
        &kind,
        K::Duplicate {
            what: "URDF link",
            name: "base".into(),
        },
    );
}

#[test]
fn names_that_collide_after_sanitising() {
    // `L-1` and `L_1` both become `L_1` (parameters m_L_1, ...).
    let text = mutate(&[
        ("<link name=\"L1\">", "<link name=\"L-1\">"),
        ("<child link=\"L1\"/>", "<child link=\"L-1\"/>"),
        ("<parent link=\"L1\"/>", "<parent link=\"L-1\"/>"),
        ("<link name=\"L2\">", "<link name=\"L_1\">"),
        ("<child link=\"L2\"/>", "<child link=\"L_1\"/>"),
        ("<parent link=\"L2\"/>", "<parent link=\"L_1\"/>"),
    ]);
    let kind = error_of(&text, &["`m_L_1`", "`L-1`", "`L_1`", "sanitising"]);
    assert!(matches!(kind, K::BadName(_)), "{kind:?}");
}

#[test]
fn negative_mass_is_an_error_in_urdf_terms() {
    let kind = error_of(
        &mutate(&[("<mass value=\"1.5\"/>", "<mass value=\"-1.5\"/>")]),
        &[
            "URDF link `L2` <inertial>",
            "<mass value=\"-1.5\"> is negative",
        ],
    );
    assert!(
        matches!(&kind, K::UrdfNonPhysicalInertial { link, .. } if link == "L2"),
        "{kind:?}"
    );
}

/// A non-physical link inertia loads as written by default (with a note); beyond
/// `inertia_tolerance` it is an error in URDF terms that names the options.
#[test]
fn a_non_physical_link_inertia_beyond_the_tolerance_is_an_error_in_urdf_terms() {
    // Triangle inequality broken by 40 %: 0.01 + 0.02 < 0.05.
    let text = mutate(&[("izz=\"0.02\"", "izz=\"0.05\"")]);
    assert!(import(&text).is_ok());
    let options = UrdfOptions {
        inertia_tolerance: 0.05,
        ..UrdfOptions::default()
    };
    let e = Model::from_urdf_str(&text, FILE, &options).unwrap_err();
    let msg = e.to_string();
    for f in [
        "URDF link `L2` <inertial>",
        "ixx 0.01",
        "izz 0.05",
        "triangle inequality",
        "40.00 %",
        "UrdfOptions::inertia_tolerance (0.05)",
        "inertia_tolerance at least 0.4000",
    ] {
        assert!(msg.contains(f), "message `{msg}` lacks `{f}`");
    }
    assert!(
        matches!(&e.kind, K::UrdfNonPhysicalInertial { link, .. } if link == "L2"),
        "{:?}",
        e.kind
    );
}

/// ANYmal B's and HyQ's placeholder inertia `1e-6` in all six entries is semi-definite
/// (principal moments 0, 0, 3e-6; the eigen-solver gives −2e−22) but breaks the triangle
/// inequality by 100 %: the error names the triangle inequality, not semi-definiteness.
#[test]
fn a_rounding_negative_principal_moment_is_not_called_indefinite() {
    let kind = strict_error_of(
        &mutate(&[(
            r#"<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/>"#,
            r#"<inertia ixx="0.000001" ixy="0.000001" ixz="0.000001" iyy="0.000001" iyz="0.000001" izz="0.000001"/>"#,
        )]),
        &[
            "URDF link `L2` <inertial>",
            "triangle inequality",
            "100.00 %",
        ],
    );
    let msg = format!("{kind}");
    assert!(!msg.contains("not positive semi-definite"), "{msg}");
}

#[test]
fn absurd_inertia_is_an_error_by_default_and_can_be_dropped() {
    // Krang's gripper plates: 0.1 g with 0.09 kg·m² (radius of gyration ~30 m).
    let text = mutate(&[(
        "<mass value=\"0.5\"/>\n      <inertia ixx=\"0.001\" ixy=\"0\" ixz=\"0\" iyy=\"0.001\" iyz=\"0\" izz=\"0.001\"/>",
        "<mass value=\"0.0001\"/>\n      <inertia ixx=\"0.102019\" ixy=\"2.45462e-05\" ixz=\"0.00713022\" iyy=\"0.0832724\" iyz=\"-0.00131733\" izz=\"0.086493\"/>",
    )]);
    let kind = error_of(
        &text,
        &["link `tool`", "radius of gyration 32.", "drop_links"],
    );
    assert!(
        matches!(&kind, K::UrdfAbsurdInertia { link, radius, .. } if link == "tool" && *radius > 30.0),
        "{kind:?}"
    );
    let options = UrdfOptions {
        absurd_inertia: AbsurdInertia::Drop,
        ..UrdfOptions::default()
    };
    let import = kanegen_model::UrdfImport::parse(&text, FILE, &options).unwrap();
    assert!(
        import
            .notes
            .iter()
            .any(|n| n.contains("`tool`") && n.contains("inertia dropped"))
    );
    let by_drop =
        Model::from_urdf_str(&text, FILE, &UrdfOptions::default().drop_links(["tool"])).unwrap();
    assert_eq!(import.model.params, by_drop.params);
}

#[test]
fn bad_options() {
    let e =
        Model::from_urdf_str(VALID, FILE, &UrdfOptions::default().drop_links(["L9"])).unwrap_err();
    assert!(
        matches!(&e.kind, K::UrdfBadOption { option, .. } if option == "drop_links"),
        "{e}"
    );
    assert!(e.to_string().contains("no link `L9`"), "{e}");
    let wheeled = UrdfOptions::wheeled(WheeledBaseSpec::new(
        "jl",
        "jr",
        "base",
        [0.0, 0.0, 1.0],
        0.2,
    ));
    let e = Model::from_urdf_str(VALID, FILE, &wheeled).unwrap_err();
    assert!(
        matches!(&e.kind, K::UrdfBadOption { option, .. } if option == "base.left_wheel_joint"),
        "{e}"
    );
    // The body of a wheeled base cannot hang from a revolute joint.
    let wheeled =
        UrdfOptions::wheeled(WheeledBaseSpec::new("j2", "j1", "L1", [0.0, 0.0, 1.0], 0.2));
    let e = Model::from_urdf_str(VALID, FILE, &wheeled).unwrap_err();
    assert!(
        matches!(&e.kind, K::UrdfBadOption { option, .. } if option == "base.body_link"),
        "{e}"
    );
    let e = Model::from_urdf_str(
        VALID,
        FILE,
        &UrdfOptions {
            gravity_direction: [0.0, 0.0, -2.0],
            ..UrdfOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(&e.kind, K::UrdfBadOption { option, detail }
            if option == "gravity_direction" && detail.contains("not a unit vector (norm 2)")),
        "{e}"
    );
}

#[test]
fn a_missing_file_is_an_io_error() {
    let e = Model::from_urdf_file("no/such/robot.urdf", &UrdfOptions::default()).unwrap_err();
    assert_eq!(e.file, "no/such/robot.urdf");
    assert!(
        matches!(&e.kind, K::Io(io) if io.kind() == std::io::ErrorKind::NotFound),
        "{e}"
    );
    let source = std::error::Error::source(&e.kind).expect("the I/O error is the source");
    assert!(
        source.downcast_ref::<std::io::Error>().is_some(),
        "{source}"
    );
}

#[test]
fn a_zero_track_is_a_non_physical_wheel_constant() {
    let urdf = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/Krang.urdf");
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.track = Some(0.0);
    let opts =
        UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]);
    let e = Model::from_urdf_file(&urdf, &opts).expect_err("zero track");
    assert!(
        matches!(&e.kind, K::NonPhysicalWheel { symbol, value, .. } if symbol == "L" && *value == 0.0),
        "{:?}",
        e.kind
    );
}

#[test]
fn a_nan_mass_is_a_bad_number() {
    let kind = error_of(
        &mutate(&[("<mass value=\"1.5\"/>", "<mass value=\"NaN\"/>")]),
        &["link `L2`", "NaN"],
    );
    assert!(matches!(kind, K::UrdfBadNumber { .. }), "{kind:?}");
}

#[test]
fn deeply_nested_xml_is_a_typed_error_not_a_stack_overflow() {
    let depth = 200_000;
    let text = format!(
        "<robot name=\"r\"><link name=\"a\">{}{}</link></robot>",
        "<x>".repeat(depth),
        "</x>".repeat(depth)
    );
    let start = std::time::Instant::now();
    let kind = error_of(&text, &["nested more than 64 levels"]);
    assert!(matches!(kind, K::UrdfTooDeep { limit: 64, .. }), "{kind:?}");
    assert!(start.elapsed().as_secs() < 5, "{:?}", start.elapsed());
}

#[test]
fn an_absurdly_large_mass_or_offset_names_the_number() {
    // Finite but beyond any robot (`MAX_PARAMETER_MAGNITUDE`): named where it is written,
    // before merging a fixed child overflowed to a NaN inertia ("`XX_L2` = NaN is not a finite
    // number") or the mass-matrix check blamed a speed that "moves no mass".
    let limit = kanegen_model::MAX_PARAMETER_MAGNITUDE;
    for (from, to, item, value) in [
        (
            r#"<mass value="1.5"/>"#,
            r#"<mass value="1e300"/>"#,
            "URDF link `L2` <inertial> (mass, inertia, origin xyz)",
            1e300,
        ),
        (
            r#"<origin xyz="0.1 0 0" rpy="0 0 0.3"/>"#,
            r#"<origin xyz="0.1 -5e10 0" rpy="0 0 0.3"/>"#,
            "URDF link `L2` <inertial> (mass, inertia, origin xyz)",
            -5e10,
        ),
        (
            r#"<origin xyz="0.3 0 0"/>"#,
            r#"<origin xyz="3e200 0 0"/>"#,
            "URDF joint `tool_mount` <origin xyz>",
            3e200,
        ),
    ] {
        let kind = error_of(&mutate(&[(from, to)]), &[item, "absurdly large"]);
        assert_kind(
            &kind,
            K::AbsurdValue {
                item: item.into(),
                value,
                limit,
            },
        );
    }
}

#[test]
fn a_robot_whose_joints_are_all_fixed_is_an_error() {
    let kind = error_of(
        &mutate(&[
            (
                r#"<joint name="j1" type="revolute">"#,
                r#"<joint name="j1" type="fixed">"#,
            ),
            (
                r#"<joint name="j2" type="continuous">"#,
                r#"<joint name="j2" type="fixed">"#,
            ),
        ]),
        &["no moving joint"],
    );
    assert_kind(&kind, K::NoSpeeds);
}
