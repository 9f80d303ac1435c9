//! Operational frames and the frames of URDF links merged by fixed joints:
//!
//! * a URDF link merged into its parent by fixed joints keeps its frame, and its generated pose
//!   is the pose of the moving frame it was merged into composed with the fixed joints' origins
//!   (rpy composed here with nalgebra's Euler angles, independently of the importer); the
//!   dynamics do not change (M, c, g with and without the link frames);
//! * a TOML `[[frame]]` (rotation, symbolic translation), a `Builder::frame` tool frame and a
//!   `UrdfOptions::frames` tool frame have the pose of their parent composed with their offset,
//!   for random parameters and states;
//! * malformed frames (taken name, unknown parent, improper rotation, non-finite translation)
//!   are typed errors from every entry point.
//!
//! Poses, Jacobians and bias accelerations of these frames against the reference recursion and
//! central differences are in `kinematics.rs` (Krang's hands, the slider's merged `bracket`).

use kanegen::model::{Model, ModelErrorKind, OperationalFrame, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::{Matrix3, Rotation3, Vector3};

fn models_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models")
}

/// A fixed-base arm with a link fixed to the root, two fixed links in a row (oblique rpy) between
/// two revolute joints, and a massless tool link at the end.
const MERGED: &str = r#"<robot name="merged">
  <link name="world"/>
  <link name="plate"><inertial><origin xyz="0 0 0.02"/><mass value="2"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0 0 0.15"/><mass value="3"/>
    <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.01"/></inertial></link>
  <link name="sensor"><inertial><origin xyz="0.01 0 0"/><mass value="0.2"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <link name="camera"/>
  <link name="fore"><inertial><origin xyz="0 0 0.1" rpy="0.1 0 0"/><mass value="1.5"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.004"/></inertial></link>
  <link name="tool0"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="plate"/>
    <origin xyz="0.1 0 0.05" rpy="0 0 0.3"/></joint>
  <joint name="j1" type="revolute"><parent link="plate"/><child link="upper"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="sensor_mount" type="fixed"><parent link="upper"/><child link="sensor"/>
    <origin xyz="0.05 0.02 0.3" rpy="0.4 -0.2 1.1"/></joint>
  <joint name="cam" type="fixed"><parent link="sensor"/><child link="camera"/>
    <origin xyz="0 0.01 0.03" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j2" type="revolute"><parent link="sensor"/><child link="fore"/>
    <origin xyz="0.1 0 0" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="tip" type="fixed"><parent link="fore"/><child link="tool0"/>
    <origin xyz="0 0 0.25" rpy="0 1.2 0"/></joint>
</robot>"#;

/// A rigid transform `(R, p)`.
type Tf = (Matrix3<f64>, Vector3<f64>);

/// A URDF `<origin xyz rpy>`: `R = Rz(yaw) Ry(pitch) Rx(roll)`.
fn origin(xyz: [f64; 3], rpy: [f64; 3]) -> Tf {
    let r = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    (*r.matrix(), Vector3::from(xyz))
}

fn compose(a: &Tf, b: &Tf) -> Tf {
    (a.0 * b.0, a.0 * b.1 + a.1)
}

fn all_functions() -> Options {
    Options {
        functions: FunctionSet::all(),
        ..Options::default()
    }
}

/// The pose of frame `name` from the lowered `frame_pose` program.
fn pose(g: &Generated, params: &[f64], name: &str, q: &[f64]) -> Tf {
    let l = g
        .model
        .link_index(name)
        .unwrap_or_else(|| panic!("frame `{name}` exists"));
    let zero = vec![0.0; q.len()];
    let x = g
        .lowered
        .evaluate_at(FunctionId::FramePose, Some(l), params, q, &zero, &zero);
    (
        Matrix3::from_fn(|i, j| x[i * 4 + j]),
        Vector3::new(x[3], x[7], x[11]),
    )
}

fn assert_tf_close(a: &Tf, b: &Tf, what: &str) {
    let e = (a.0 - b.0).abs().max().max((a.1 - b.1).abs().max());
    assert!(e < 1e-12, "{what}: pose differs by {e:e}");
}

#[test]
fn merged_fixed_links_keep_their_frames_at_the_parent_pose_composed_with_the_fixed_joints() {
    let model =
        Model::from_urdf_str(MERGED, "merged.urdf", &UrdfOptions::default()).expect("URDF imports");
    let names: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
    for link in [
        "world", "plate", "upper", "sensor", "camera", "fore", "tool0",
    ] {
        assert!(
            names.contains(&link),
            "link `{link}` addressable: {names:?}"
        );
    }
    let g = Builder::from_model(model.clone())
        .options(all_functions())
        .generate()
        .expect("generates");
    let mut rng = SplitMix64::new(11);
    let mut uniform = move || rng.next_f64();
    let params = model.param_values();
    let plate = origin([0.1, 0.0, 0.05], [0.0, 0.0, 0.3]);
    let sensor_mount = origin([0.05, 0.02, 0.3], [0.4, -0.2, 1.1]);
    let cam = origin([0.0, 0.01, 0.03], [0.1, 0.2, 0.3]);
    let tip = origin([0.0, 0.0, 0.25], [0.0, 1.2, 0.0]);
    for _ in 0..20 {
        let q = uniform_vec(&mut uniform, 2, -3.0, 3.0);
        // Fixed to the fixed root: constant.
        assert_tf_close(&pose(&g, &params, "plate", &q), &plate, "plate");
        let upper = pose(&g, &params, "upper", &q);
        let sensor = compose(&upper, &sensor_mount);
        assert_tf_close(&pose(&g, &params, "sensor", &q), &sensor, "sensor");
        let camera = compose(&sensor, &cam);
        assert_tf_close(&pose(&g, &params, "camera", &q), &camera, "camera");
        let fore = pose(&g, &params, "fore", &q);
        assert_tf_close(
            &pose(&g, &params, "tool0", &q),
            &compose(&fore, &tip),
            "tool0",
        );
    }
}

#[test]
fn link_frames_do_not_change_the_dynamics() {
    let with = Model::from_urdf_str(MERGED, "merged.urdf", &UrdfOptions::default()).unwrap();
    let options = UrdfOptions {
        link_frames: false,
        ..UrdfOptions::default()
    };
    let without = Model::from_urdf_str(MERGED, "merged.urdf", &options).unwrap();
    assert_eq!(with.links.len(), without.links.len() + 4);
    assert_eq!(with.params, without.params);
    let a = Builder::from_model(with).generate().unwrap();
    let b = Builder::from_model(without).generate().unwrap();
    let mut rng = SplitMix64::new(12);
    let mut uniform = move || rng.next_f64();
    let params = random_physical_params(&a.model, &mut uniform);
    for _ in 0..5 {
        let q = uniform_vec(&mut uniform, 2, -3.0, 3.0);
        let u = uniform_vec(&mut uniform, 2, -2.0, 2.0);
        let ud = uniform_vec(&mut uniform, 2, -5.0, 5.0);
        for id in [
            FunctionId::MassMatrix,
            FunctionId::Coriolis,
            FunctionId::Gravity,
            FunctionId::InverseDynamics,
        ] {
            let x = a.lowered.evaluate_at(id, None, &params, &q, &u, &ud);
            let y = b.lowered.evaluate_at(id, None, &params, &q, &u, &ud);
            assert_eq!(x, y, "{id}");
        }
    }
}

#[test]
fn toml_frames_sit_at_their_offset_from_the_parent_for_any_parameters() {
    let text = std::fs::read_to_string(models_dir().join("two-link.toml")).unwrap();
    let text = format!(
        "{text}\n[[frame]]\nname = \"tool\"\nparent = \"2\"\nrotation = [[0, -1, 0], [0, 0, -1], [1, 0, 0]]\ntranslation = [0.1, \"-L1\", \"L2\"]\n\n[[frame]]\nname = \"tool_tip\"\nparent = \"tool\"\ntranslation = [0, 0, 0.05]\n"
    );
    let model = Model::from_toml_str(&text, "two-link+tool.toml").expect("loads");
    assert_eq!(model.links.len(), 5);
    let g = Builder::from_model(model.clone())
        .options(all_functions())
        .generate()
        .expect("generates");
    assert!(g.source.contains("ToolTip"), "Frame::ToolTip generated");
    let mut rng = SplitMix64::new(13);
    let mut uniform = move || rng.next_f64();
    let (l1, l2) = (
        model.param_index("L1").unwrap(),
        model.param_index("L2").unwrap(),
    );
    let r = Matrix3::new(0.0, -1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0);
    for _ in 0..10 {
        let params = random_physical_params(&model, &mut uniform);
        let q = uniform_vec(&mut uniform, 2, -3.0, 3.0);
        let parent = pose(&g, &params, "2", &q);
        let offset = (r, Vector3::new(0.1, -params[l1], params[l2]));
        let tool = compose(&parent, &offset);
        assert_tf_close(&pose(&g, &params, "tool", &q), &tool, "tool");
        let tip = compose(&tool, &(Matrix3::identity(), Vector3::new(0.0, 0.0, 0.05)));
        assert_tf_close(&pose(&g, &params, "tool_tip", &q), &tip, "tool_tip");
    }
}

#[test]
fn builder_and_urdf_options_add_tool_frames() {
    let r = *Rotation3::from_euler_angles(0.3, -0.1, 0.7).matrix();
    let rows = [0, 1, 2].map(|i| [0, 1, 2].map(|j| r[(i, j)]));
    let tool = OperationalFrame::new("tool", "L7_EFF", [0.01, -0.02, 0.107]).with_rotation(rows);
    let urdf = models_dir().join("singlearm.urdf");
    let from_builder = Builder::new(&urdf)
        .frame(tool.clone())
        .functions(FunctionSet::kinematics())
        .generate()
        .expect("generates");
    let from_options = Builder::urdf(&urdf, UrdfOptions::default().frame(tool.clone()))
        .functions(FunctionSet::kinematics())
        .generate()
        .expect("generates");
    let toml = Builder::new(models_dir().join("two-link.toml"))
        .frame(OperationalFrame::new("tool", "2", [0.0, 0.3, 0.0]))
        .functions(FunctionSet::kinematics())
        .generate()
        .expect("generates");
    assert_eq!(toml.model.links.last().unwrap().name, "tool");
    let mut rng = SplitMix64::new(14);
    let mut uniform = move || rng.next_f64();
    let params = from_builder.model.param_values();
    let offset = (r, Vector3::new(0.01, -0.02, 0.107));
    for _ in 0..10 {
        let q = uniform_vec(&mut uniform, 7, -3.0, 3.0);
        let want = compose(&pose(&from_builder, &params, "L7_EFF", &q), &offset);
        assert_tf_close(&pose(&from_builder, &params, "tool", &q), &want, "Builder");
        assert_tf_close(&pose(&from_options, &params, "tool", &q), &want, "options");
    }
}

/// A number as TOML writes it (`nan` for NaN).
fn toml_number(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else {
        format!("{x:?}")
    }
}

fn toml_array(v: [f64; 3]) -> String {
    format!("[{}]", v.map(toml_number).join(", "))
}

/// The `ModelErrorKind`s of adding a frame through `[[frame]]` (two-link model),
/// `Model::add_frame` (two-link model) and `UrdfOptions::frames` (the arm; parent `2` becomes
/// `L7_EFF`, name `1` becomes `L1`).
fn errors(name: &str, parent: &str, rot: [[f64; 3]; 3], tr: [f64; 3]) -> Vec<ModelErrorKind> {
    let text = std::fs::read_to_string(models_dir().join("two-link.toml")).unwrap();
    let section = format!(
        "{text}\n[[frame]]\nname = \"{name}\"\nparent = \"{parent}\"\nrotation = [{}]\ntranslation = {}\n",
        rot.map(toml_array).join(", "),
        toml_array(tr)
    );
    let toml = Model::from_toml_str(&section, "bad-frame.toml").expect_err("rejected");
    assert_eq!(toml.file, "bad-frame.toml");
    let frame = OperationalFrame::new(name, parent, tr).with_rotation(rot);
    let mut model = Model::from_toml_file(models_dir().join("two-link.toml")).unwrap();
    let before = model.clone();
    let added = model.add_frame(&frame).expect_err("rejected");
    assert_eq!(model, before, "a rejected frame leaves the model unchanged");
    let urdf_frame = OperationalFrame {
        name: if name == "1" {
            "L1".into()
        } else {
            name.into()
        },
        parent: if parent == "2" {
            "L7_EFF".into()
        } else {
            parent.into()
        },
        ..frame
    };
    let options = UrdfOptions::default().frame(urdf_frame);
    let urdf =
        Model::from_urdf_file(models_dir().join("singlearm.urdf"), &options).expect_err("rejected");
    vec![toml.kind, added.kind, urdf.kind]
}

#[test]
fn malformed_frames_are_typed_errors_naming_the_frame() {
    let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for kind in errors("1", "2", id, [0.0; 3]) {
        assert!(
            matches!(&kind, ModelErrorKind::Duplicate { what: "frame", .. }),
            "{kind}"
        );
    }
    for kind in errors("tool", "nowhere", id, [0.0; 3]) {
        let ModelErrorKind::BadFrame { frame, detail } = &kind else {
            panic!("{kind}")
        };
        assert_eq!(frame, "tool");
        assert!(detail.contains("`nowhere` is not defined"), "{kind}");
    }
    let mirror = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
    for kind in errors("tool", "2", mirror, [0.0; 3]) {
        let ModelErrorKind::BadFrame { detail, .. } = &kind else {
            panic!("{kind}")
        };
        assert!(detail.contains("not a proper rotation"), "{kind}");
    }
    let [toml, added, urdf]: [ModelErrorKind; 3] = errors("tool", "2", id, [0.0, 0.0, f64::NAN])
        .try_into()
        .unwrap();
    assert!(matches!(toml, ModelErrorKind::BadLength { .. }), "{toml}");
    for kind in [added, urdf] {
        let ModelErrorKind::BadFrame { detail, .. } = &kind else {
            panic!("{kind}")
        };
        assert!(detail.contains("not a finite number"), "{kind}");
    }
}
