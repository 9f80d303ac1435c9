//! URDF import: rpy convention, axes, snapping, fixed-joint merging (Huygens–Steiner and
//! rotation), names, the wheeled base (Krang: 0A1(0) and e1 of the fixed-wheels report (Zafar 2014)) and the shipped URDFs.
#![allow(clippy::approx_constant)] // the rounded angles of real URDF files are the point here

use std::path::PathBuf;

use kanegen_model::{
    AbsurdInertia, AngleSnap, Base, JointKind, Model, UrdfImport, UrdfOptions, WheeledBaseSpec,
};
use nalgebra::{Matrix3, Rotation3, Vector3};

fn models() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[(i, j)]))
}

fn close(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3], tol: f64) -> bool {
    (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() <= tol))
}

/// `Rz(y) Ry(p) Rx(r)` from nalgebra's axis-angle rotations (independent of the importer).
fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), r);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), p);
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), y);
    (rz * ry * rx).into_inner()
}

fn param(m: &Model, name: &str) -> f64 {
    m.params[m
        .param_index(name)
        .unwrap_or_else(|| panic!("no parameter {name}"))]
    .value
}

/// Khalil's parameters `(m, MS, J about the origin)` of a body in frame `o` from a rigid part
/// (mass, COM and inertia about the COM given in frame `f`, whose pose in `o` is `(r, p)`).
fn khalil(
    m: f64,
    c: Vector3<f64>,
    ig: Matrix3<f64>,
    r: Matrix3<f64>,
    p: Vector3<f64>,
) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let c = r * c + p;
    let j =
        r * ig * r.transpose() + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * m;
    (m, c * m, j)
}

const ARM: &str = r#"<robot name="test-arm">
  <link name="world"/>
  <link name="upper-arm">
    <inertial>
      <origin xyz="0.01 0.02 0.3" rpy="0.2 -0.4 0.7"/>
      <mass value="3.0"/>
      <inertia ixx="0.05" ixy="0.001" ixz="-0.002" iyy="0.04" iyz="0.003" izz="0.02"/>
    </inertial>
  </link>
  <link name="flange">
    <inertial>
      <origin xyz="0.05 -0.01 0.02" rpy="0.3 0.1 -0.2"/>
      <mass value="0.8"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.004"/>
    </inertial>
  </link>
  <link name="slider">
    <inertial>
      <origin xyz="0 0 0.05"/>
      <mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/>
    </inertial>
  </link>
  <link name="marker"/>
  <joint name="shoulder" type="continuous">
    <parent link="world"/>
    <child link="upper-arm"/>
    <origin xyz="0 0 0.5" rpy="0.3 -0.5 1.1"/>
    <axis xyz="0 0 2"/>
  </joint>
  <joint name="flange_mount" type="fixed">
    <parent link="upper-arm"/>
    <child link="flange"/>
    <origin xyz="0.1 0.2 0.6" rpy="0.5 0.25 -1.0"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="flange"/>
    <child link="slider"/>
    <origin xyz="0 0.03 0.1" rpy="0 1.5708 0"/>
    <axis xyz="1 1 0"/>
  </joint>
  <joint name="marker_mount" type="fixed">
    <parent link="slider"/>
    <child link="marker"/>
  </joint>
</robot>"#;

#[test]
fn rpy_axes_kinds_and_names() {
    let m = Model::from_urdf_str(ARM, "arm.urdf", &UrdfOptions::default()).unwrap();
    assert_eq!(m.name, "test-arm");
    assert_eq!(m.base, Base::Fixed);
    let names: Vec<&str> = m.links.iter().map(|l| l.name.as_str()).collect();
    // The moving frames first, then the links merged by fixed joints (UrdfOptions::link_frames).
    assert_eq!(names, ["world", "upper-arm", "slider", "flange", "marker"]);
    let flange = m.links[3].mount.as_ref().unwrap();
    assert_eq!((flange.parent, flange.joint.kind), (1, JointKind::Fixed));
    assert!(m.links[3].body.is_none() && m.links[4].body.is_none());
    let speeds: Vec<(&str, &str)> = m
        .speeds
        .iter()
        .map(|s| (s.name.as_str(), s.coordinate.as_str()))
        .collect();
    assert_eq!(
        speeds,
        [("qd_shoulder", "q_shoulder"), ("qd_slide", "q_slide")]
    );
    let j = m.links[1].joint().unwrap();
    assert_eq!(
        j.kind,
        JointKind::Revolute { speed: 0 },
        "continuous = revolute"
    );
    assert_eq!(j.axis, [0.0, 0.0, 1.0], "axis normalised");
    assert!(close(&j.rotation, &rows(&rpy(0.3, -0.5, 1.1)), 1e-15));
    assert_eq!(
        j.translation.map(|s| (s.coef, s.symbol)),
        [(0.0, None), (0.0, None), (0.5, None)]
    );
    // Parameter names from the sanitised link names.
    for p in [
        "m_upper_arm",
        "MX_upper_arm",
        "XX_upper_arm",
        "ZZ_upper_arm",
        "m_slider",
        "g",
    ] {
        assert!(m.param_index(p).is_some(), "{p}");
    }
    assert_eq!(m.links[1].body.as_ref().unwrap().name, "upper_arm");
    assert!(m.links[0].body.is_none());
}

#[test]
fn fixed_joints_merge_inertia_and_reattach_children() {
    let m = Model::from_urdf_str(ARM, "arm.urdf", &UrdfOptions::default()).unwrap();
    // Body upper-arm = upper-arm + flange (in upper-arm's frame), computed independently.
    let ig_arm = Matrix3::new(0.05, 0.001, -0.002, 0.001, 0.04, 0.003, -0.002, 0.003, 0.02);
    let ig_arm = rpy(0.2, -0.4, 0.7) * ig_arm * rpy(0.2, -0.4, 0.7).transpose();
    let (m1, ms1, j1) = khalil(
        3.0,
        Vector3::new(0.01, 0.02, 0.3),
        ig_arm,
        Matrix3::identity(),
        Vector3::zeros(),
    );
    let r_mount = rpy(0.5, 0.25, -1.0);
    let p_mount = Vector3::new(0.1, 0.2, 0.6);
    let ig_fl = rpy(0.3, 0.1, -0.2)
        * Matrix3::from_diagonal(&Vector3::new(0.002, 0.003, 0.004))
        * rpy(0.3, 0.1, -0.2).transpose();
    let (m2, ms2, j2) = khalil(
        0.8,
        Vector3::new(0.05, -0.01, 0.02),
        ig_fl,
        r_mount,
        p_mount,
    );
    let (mass, ms, j) = (m1 + m2, ms1 + ms2, j1 + j2);
    assert!((param(&m, "m_upper_arm") - mass).abs() < 1e-15);
    for (i, a) in ["MX", "MY", "MZ"].iter().enumerate() {
        assert!(
            (param(&m, &format!("{a}_upper_arm")) - ms[i]).abs() < 1e-14,
            "{a}"
        );
    }
    for (name, (r, c)) in [
        ("XX", (0, 0)),
        ("XY", (0, 1)),
        ("XZ", (0, 2)),
        ("YY", (1, 1)),
        ("YZ", (1, 2)),
        ("ZZ", (2, 2)),
    ] {
        assert!(
            (param(&m, &format!("{name}_upper_arm")) - j[(r, c)]).abs() < 1e-14,
            "{name}"
        );
    }
    // The slider hangs from the merged flange: composed transform, prismatic axis normalised.
    let jt = m.links[2].joint().unwrap();
    assert_eq!(jt.kind, JointKind::Prismatic { speed: 1 });
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert!((jt.axis[0] - s).abs() < 1e-15 && (jt.axis[1] - s).abs() < 1e-15 && jt.axis[2] == 0.0);
    let r_slide = r_mount * rpy(0.0, std::f64::consts::FRAC_PI_2, 0.0);
    assert!(close(&jt.rotation, &rows(&r_slide), 1e-15));
    let p = p_mount + r_mount * Vector3::new(0.0, 0.03, 0.1);
    for i in 0..3 {
        assert!((jt.translation[i].coef - p[i]).abs() < 1e-15);
        assert!(jt.translation[i].symbol.is_none());
    }
    // The marker (no inertial) adds nothing.
    assert!((param(&m, "m_slider") - 0.5).abs() == 0.0);
}

#[test]
fn angles_are_snapped_by_default_and_kept_on_request() {
    let text = ARM.replace("rpy=\"0 1.5708 0\"", "rpy=\"3.1416 1.5708 -3.14\"");
    let snapped = UrdfImport::parse(&text, "arm.urdf", &UrdfOptions::default()).unwrap();
    let r = snapped.model.links[2].joint().unwrap().rotation;
    let r_mount = rpy(0.5, 0.25, -1.0);
    let exact = r_mount
        * rpy(
            std::f64::consts::PI,
            std::f64::consts::FRAC_PI_2,
            -std::f64::consts::PI,
        );
    assert!(close(&r, &rows(&exact), 1e-15));
    assert!(
        snapped
            .notes
            .iter()
            .any(|n| n.contains("joint `slide`") && n.contains("-3.14 snapped to -π")),
        "{:?}",
        snapped.notes
    );
    // Every snap is listed, with the precision it was read at.
    for note in [
        "3.1416 snapped to π (3.1416 is π rounded to 4 decimals",
        "1.5708 snapped to π/2 (1.5708 is π/2 rounded to 4 decimals",
        "-3.14 snapped to -π (-3.14 is -π rounded to 2 decimals",
    ] {
        assert!(
            snapped.notes.iter().any(|n| n.contains(note)),
            "{note}: {:?}",
            snapped.notes
        );
    }
    let raw = Model::from_urdf_str(
        &text,
        "arm.urdf",
        &UrdfOptions {
            snap_angles: AngleSnap::Off,
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    let r = raw.links[2].joint().unwrap().rotation;
    assert!(close(
        &r,
        &rows(&(r_mount * rpy(3.1416, 1.5708, -3.14))),
        1e-15
    ));
    assert!(!close(&r, &rows(&exact), 1e-4));
    // Rotations without snapping: exact float multiples of π/2 are still exact.
    let text = ARM.replace("rpy=\"0 1.5708 0\"", "rpy=\"0 1.5707963267948966 0\"");
    let raw = Model::from_urdf_str(
        &text,
        "arm.urdf",
        &UrdfOptions {
            snap_angles: AngleSnap::Off,
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    let r = raw.links[2].joint().unwrap().rotation;
    assert!(close(
        &r,
        &rows(&(r_mount * rpy(0.0, std::f64::consts::FRAC_PI_2, 0.0))),
        1e-15
    ));
}

fn krang_options() -> UrdfOptions {
    let mut spec = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    spec.pitch_name = "imu".into();
    UrdfOptions::wheeled(spec).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"])
}

#[test]
fn krang_wheeled_base_reproduces_the_frames_of_seed_002() {
    let import = UrdfImport::read(models().join("Krang.urdf"), &krang_options()).unwrap();
    let m = &import.model;
    assert_eq!(m.name, "Krang");
    assert_eq!(m.dof(), 19);
    let w = m.wheeled_base().expect("wheeled");
    assert_eq!((w.x_speed, w.psi_speed), (0, 1));
    let speeds: Vec<&str> = m.speeds.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        speeds,
        [
            "xd",
            "psid",
            "qd_imu",
            "qd_JWaist",
            "qd_JTorso",
            "qd_LJ1",
            "qd_LJ2",
            "qd_LJ3",
            "qd_LJ4",
            "qd_LJ5",
            "qd_LJ6",
            "qd_LJFT",
            "qd_RJ1",
            "qd_RJ2",
            "qd_RJ3",
            "qd_RJ4",
            "qd_RJ5",
            "qd_RJ6",
            "qd_RJFT"
        ]
    );
    assert_eq!(m.speeds[0].coordinate, "x");
    assert_eq!(m.speeds[1].coordinate, "psi");
    assert_eq!(m.links[0].name, "0");
    let pitch = m.links[1].joint().unwrap();
    assert_eq!(m.links[1].name, "Base");
    assert_eq!(
        pitch.rotation,
        [[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        "0A1(0)"
    );
    assert_eq!(pitch.axis, [-1.0, 0.0, 0.0], "e1");
    // Frame 0 at the wheel centres' midpoint, 3.5 mm along -x of Base = +y0 (toward the left wheel).
    let p: Vec<f64> = pitch.translation.iter().map(|s| s.coef).collect();
    assert!(
        p[0] == 0.0 && (p[1] - 0.0035).abs() < 1e-15 && p[2] == 0.0,
        "{p:?}"
    );
    // Wheel constants: R given, L from the joint origins, wheel inertia from the wheel links.
    assert_eq!(param(m, "R"), 0.25);
    assert!((param(m, "L") - 0.715).abs() < 1e-15);
    assert_eq!(param(m, "mw"), 4.66);
    assert!((param(m, "YYw") - 0.102019).abs() < 1e-15);
    assert!((param(m, "ZZw") - (0.0832724 + 0.086493) / 2.0).abs() < 1e-15);
    assert!(
        import.notes.iter().any(|n| n.contains("not axisymmetric")),
        "{:?}",
        import.notes
    );
    // Bodies: the 17 of the reports, wheels and plates excluded.
    assert_eq!(m.body_count(), 17);
    assert!(m.param_index("m_LWheel").is_none() && m.param_index("m_lgPlate1").is_none());
}

#[test]
fn krang_urdf_parameters_equal_those_of_krang_toml() {
    let urdf = Model::from_urdf_file(models().join("Krang.urdf"), &krang_options()).unwrap();
    let toml = Model::from_toml_file(models().join("krang.toml")).unwrap();
    let mut bodies = vec![("1", "Base"), ("2", "Spine"), ("3", "Bracket")];
    let names: Vec<(String, String)> = ["l", "r"]
        .iter()
        .flat_map(|side| {
            let (prefix, grip) = if *side == "l" {
                ("L", "lGripper")
            } else {
                ("R", "rGripper")
            };
            (1..=6)
                .map(move |k| (format!("{}{side}", k + 3), format!("{prefix}{k}")))
                .chain(std::iter::once((format!("10{side}"), grip.to_owned())))
        })
        .collect();
    bodies.extend(names.iter().map(|(a, b)| (a.as_str(), b.as_str())));
    for (report, link) in bodies {
        for prefix in ["m", "MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"] {
            let a = param(&toml, &format!("{prefix}{report}"));
            let b = param(&urdf, &format!("{prefix}_{link}"));
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "{prefix}{report} = {a}, {prefix}_{link} = {b}"
            );
        }
    }
}

#[test]
fn a_floating_joint_above_the_body_is_replaced_by_the_wheeled_base() {
    let text = std::fs::read_to_string(models().join("Krang.urdf")).unwrap().replace(
        "<robot name=\"Krang\">",
        "<robot name=\"Krang\">\n<link name=\"odom\"/>\n<joint name=\"odom_base\" type=\"floating\"><parent link=\"odom\"/><child link=\"Base\"/></joint>",
    );
    let with = UrdfImport::parse(&text, "Krang+odom.urdf", &krang_options()).unwrap();
    assert!(
        with.notes
            .iter()
            .any(|n| n.contains("floating joint `odom_base` replaced")),
        "{:?}",
        with.notes
    );
    let without = Model::from_urdf_file(models().join("Krang.urdf"), &krang_options()).unwrap();
    assert_eq!(with.model.links, without.links);
    assert_eq!(with.model.params, without.params);
    // Without the declaration it is an error.
    let e = Model::from_urdf_str(
        &text,
        "Krang+odom.urdf",
        &UrdfOptions::default().drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("floating joints are not supported"),
        "{e}"
    );
}

#[test]
fn shipped_urdfs_import_without_their_meshes() {
    let plates = ["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"];
    let arm =
        Model::from_urdf_file(models().join("singlearm.urdf"), &UrdfOptions::default()).unwrap();
    assert_eq!(
        (arm.dof(), arm.body_count(), arm.name.as_str()),
        (7, 7, "SingleArm")
    );
    let fixed = Model::from_urdf_file(
        models().join("krang_fixed_wheel.urdf"),
        &UrdfOptions::default().drop_links(plates),
    )
    .unwrap();
    // JLWheel (Base on the fixed wheel), JWaist, JTorso, JKinect and two 7-joint arms.
    assert_eq!((fixed.dof(), fixed.body_count()), (18, 18));
    // Absurd plates: dropped by policy instead of by name gives the same model.
    let dropped = Model::from_urdf_file(
        models().join("krang_fixed_wheel.urdf"),
        &UrdfOptions {
            absurd_inertia: AbsurdInertia::Drop,
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    assert_eq!(dropped.params, fixed.params);
    // Kept on request, they are merged into the grippers (adding ~0.18 kg·m²).
    let kept = Model::from_urdf_file(
        models().join("krang_fixed_wheel.urdf"),
        &UrdfOptions {
            absurd_inertia: AbsurdInertia::Keep,
            ..UrdfOptions::default()
        },
    )
    .unwrap();
    assert!(param(&kept, "ZZ_lGripper") - param(&fixed, "ZZ_lGripper") > 0.15);
}

#[test]
fn only_rounded_decimals_of_multiples_of_half_pi_are_snapped() {
    // A real 1.9e-4 rad yaw, a truncated π, a 1-decimal angle and a 2-decimal angle that is no
    // rounded multiple of π/2 are kept exactly; 4.7124 (3π/2 rounded) is snapped.
    let text = ARM.replace("rpy=\"0 1.5708 0\"", "rpy=\"0.00019 3.1415 1.5\"");
    let import = UrdfImport::parse(&text, "arm.urdf", &UrdfOptions::default()).unwrap();
    let r = import.model.links[2].joint().unwrap().rotation;
    let r_mount = rpy(0.5, 0.25, -1.0);
    assert!(close(
        &r,
        &rows(&(r_mount * rpy(0.00019, 3.1415, 1.5))),
        1e-15
    ));
    assert!(
        !import.notes.iter().any(|n| n.contains("joint `slide`")),
        "{:?}",
        import.notes
    );
    let text = ARM.replace("rpy=\"0 1.5708 0\"", "rpy=\"4.7124 1.57 0\"");
    let import = UrdfImport::parse(&text, "arm.urdf", &UrdfOptions::default()).unwrap();
    let r = import.model.links[2].joint().unwrap().rotation;
    let exact = rpy(
        3.0 * std::f64::consts::FRAC_PI_2,
        std::f64::consts::FRAC_PI_2,
        0.0,
    );
    assert!(close(&r, &rows(&(r_mount * exact)), 1e-15));
    // The lossy tolerance of earlier versions is an option.
    let text = ARM.replace("rpy=\"0 1.5708 0\"", "rpy=\"0.00019 0 0\"");
    let lossy = UrdfOptions {
        snap_angles: AngleSnap::Within(2e-3),
        ..UrdfOptions::default()
    };
    let import = UrdfImport::parse(&text, "arm.urdf", &lossy).unwrap();
    let r = import.model.links[2].joint().unwrap().rotation;
    assert!(close(&r, &rows(&r_mount), 1e-15));
    assert!(
        import
            .notes
            .iter()
            .any(|n| n.contains("0.00019 snapped to 0 (within"))
    );
}

/// `tests/data/tolerant.urdf`, real-world content: malformed visual, collision and material elements (an empty `<texture/>`,
/// a `<material>` inside `<geometry>`, a four-number mesh scale, a box with two sizes, a sphere
/// radius that is no number), a point mass (`upper`), a zero-mass rotor with rotational inertia
/// (`rotor`) and an inertia that breaks the triangle inequality by 0.99 % (`lower`).
const TOLERANT: &str = include_str!("data/tolerant.urdf");

/// `TOLERANT` without its visual, collision and material elements.
fn tolerant_without_visuals() -> String {
    let mut text = TOLERANT.to_owned();
    for element in [
        r#"<material name="grey"><texture/></material>"#,
        r#"<visual><geometry><mesh filename="package://x/base.dae" scale="1 1 1 1"/><material name="m"/></geometry></visual>"#,
        r#"<visual><geometry><box size="1 2"/></geometry><material name="red"><color rgba="1 0 0"/><texture/></material></visual>"#,
        r#"<collision><geometry><sphere radius="oops"/></geometry></collision>"#,
        "<collision/>",
    ] {
        assert_eq!(text.matches(element).count(), 1, "{element}");
        text = text.replace(element, "");
    }
    text
}

#[test]
fn visual_collision_and_material_content_never_aborts_an_import() {
    let with = Model::from_urdf_str(TOLERANT, "t.urdf", &UrdfOptions::default()).unwrap();
    let without = Model::from_urdf_str(
        &tolerant_without_visuals(),
        "t.urdf",
        &UrdfOptions::default(),
    )
    .unwrap();
    assert_eq!(with, without);
}

#[test]
fn point_masses_zero_mass_rotors_and_slightly_non_physical_inertias_load_with_notes() {
    let import = UrdfImport::parse(TOLERANT, "t.urdf", &UrdfOptions::default()).unwrap();
    let m = &import.model;
    assert_eq!((m.dof(), m.body_count()), (3, 3));
    // The rotor is a body with m = 0 and its inertia.
    assert_eq!(param(m, "m_rotor"), 0.0);
    assert_eq!(param(m, "ZZ_rotor"), 0.002);
    // The point mass: J = m (|S|² 1 − S Sᵀ) about the link origin.
    assert_eq!(param(m, "XX_upper"), 0.0);
    assert!((param(m, "YY_upper") - 2.0 * 0.09).abs() < 1e-15);
    for note in [
        "link `rotor`: zero mass with a nonzero rotational inertia",
        "kept as a body with m = 0",
        "link `lower`: the inertia (ixx 0.01, ixy 0, ixz 0, iyy 0.01, iyz 0, izz 0.0202)",
        "triangle inequality",
        "0.99 % of the largest; kept as written",
    ] {
        assert!(
            import.notes.iter().any(|n| n.contains(note)),
            "{note}: {:?}",
            import.notes
        );
    }
}

#[test]
fn inertia_options_make_slight_violations_errors_or_repair_them() {
    use kanegen_model::{ModelErrorKind as K, NonPhysicalInertia};
    let strict = UrdfOptions {
        non_physical_inertia: NonPhysicalInertia::Error,
        ..UrdfOptions::default()
    };
    let e = Model::from_urdf_str(TOLERANT, "t.urdf", &strict).unwrap_err();
    assert!(
        matches!(&e.kind, K::UrdfNonPhysicalInertial { link, .. } if link == "lower"),
        "{:?}",
        e.kind
    );
    let repair = UrdfOptions {
        non_physical_inertia: NonPhysicalInertia::Repair,
        ..UrdfOptions::default()
    };
    let import = UrdfImport::parse(TOLERANT, "t.urdf", &repair).unwrap();
    assert!(
        import.notes.iter().any(|n| n.contains("link `lower`")
            && n.contains(
                "repaired to the principal moments 1.006667e-2, 1.006667e-2, 2.013333e-2"
            )),
        "{:?}",
        import.notes
    );
    // The repaired inertia about the centre of mass: izz = ixx + iyy exactly.
    let m = &import.model;
    let izz = param(m, "ZZ_lower");
    let (ixx, iyy) = (param(m, "XX_lower"), param(m, "YY_lower") - 1.0 * 0.04);
    assert!(
        (izz - 1.0 * 0.04 - (ixx + iyy)).abs() < 1e-15,
        "{ixx} {iyy} {izz}"
    );
    // Beyond the tolerance it is an error whatever the policy.
    let far = TOLERANT.replace("izz=\"0.0202\"", "izz=\"0.03\"");
    assert!(Model::from_urdf_str(&far, "t.urdf", &repair).is_ok());
    let bounded = UrdfOptions {
        inertia_tolerance: 0.05,
        ..repair
    };
    let e = Model::from_urdf_str(&far, "t.urdf", &bounded).unwrap_err();
    assert!(
        matches!(e.kind, K::UrdfNonPhysicalInertial { .. }),
        "{:?}",
        e.kind
    );
}

#[test]
fn dropping_a_zero_mass_rotor_leaves_its_speed_without_inertia_a_singular_mass_matrix() {
    use kanegen_model::{ModelErrorKind as K, ZeroMassInertia};
    let drop = UrdfOptions {
        zero_mass_inertia: ZeroMassInertia::Drop,
        ..UrdfOptions::default()
    };
    let e = Model::from_urdf_str(TOLERANT, "t.urdf", &drop).unwrap_err();
    assert!(
        matches!(&e.kind, K::SingularMassMatrix { speed, .. } if speed == "qd_spin"),
        "{:?}",
        e.kind
    );
    assert!(
        e.to_string()
            .contains("speed `qd_spin` moves no mass or inertia"),
        "{e}"
    );
    // With the rotor kept as a point mass on its own axis, the same.
    let point = TOLERANT.replace(
        r#"<mass value="0"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.002"/>"#,
        r#"<mass value="0.5"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>"#,
    );
    let e = Model::from_urdf_str(&point, "t.urdf", &UrdfOptions::default()).unwrap_err();
    assert!(
        matches!(&e.kind, K::SingularMassMatrix { speed, .. } if speed == "qd_spin"),
        "{:?}",
        e.kind
    );
}
