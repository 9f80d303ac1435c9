//! URDF import: rpy convention, axes, snapping, fixed-joint merging (Huygens–Steiner and
//! rotation), names, the wheeled base (Krang: 0A1(0) and e1 of seed 002) and the shipped URDFs.
#![allow(clippy::approx_constant)] // the rounded angles of real URDF files are the point here

use std::path::PathBuf;

use kanegen_model::{
    AbsurdInertia, Base, JointKind, Model, UrdfImport, UrdfOptions, WheeledBaseSpec,
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
    assert_eq!(names, ["world", "upper-arm", "slider"]);
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
    assert!(
        snapped
            .notes
            .iter()
            .any(|n| n.contains("2 rotation angles within")),
        "{:?}",
        snapped.notes
    );
    let raw = Model::from_urdf_str(
        &text,
        "arm.urdf",
        &UrdfOptions {
            snap_angles: None,
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
            snap_angles: None,
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
