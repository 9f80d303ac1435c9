//! The Pinocchio export (`kanegen::pinocchio`) describes the same mechanical system as the
//! model: a small forward pass over the exported tree (written here from Pinocchio's joint
//! conventions, independently of the exporter) gives the kinetic energy `½ uᵀ M u` and the
//! potential energy of the reference recursion on random parameters and states — which pins
//! down M (every entry, signs of flipped axes included), the wheel terms and g. The agreement
//! of c, τ and C with Pinocchio itself is checked by `benches/pinocchio/run.sh` (it downloads
//! Pinocchio, so it is not part of CI).

use kanegen::model::{Model, UrdfOptions, WheeledBaseSpec};
use kanegen::pinocchio::{ExportError, PinJointType, PinocchioModel, export};
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn model(file: &str) -> Model {
    let path = root().join("models").join(file);
    if file.ends_with(".urdf") {
        Model::from_urdf_file(&path, &UrdfOptions::default()).unwrap()
    } else {
        Model::from_toml_file(&path).unwrap()
    }
}

fn m3(a: &[[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| a[r][c])
}

/// Kinetic and potential energy of the exported tree at Pinocchio's `(q, v)`.
fn energies(pm: &PinocchioModel, q: &[f64], v: &[f64]) -> (f64, f64) {
    // Per joint id (0 = universe): world rotation, origin, angular velocity, origin velocity.
    let mut frames = vec![(
        Matrix3::identity(),
        Vector3::zeros(),
        Vector3::zeros(),
        Vector3::zeros(),
    )];
    for j in &pm.joints {
        let (r0, p0, w0, v0): (Matrix3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>) =
            frames[j.parent];
        let r_pre = r0 * m3(&j.rotation);
        let p_pre = p0 + r0 * Vector3::from(j.translation);
        let (iq, iv) = (j.idx_q, j.idx_v);
        let (mut rot, mut pos, mut w, mut vel) = (r_pre, p_pre, w0, v0 + w0.cross(&(p_pre - p0)));
        let axis = |k: usize| Vector3::ith(k, 1.0);
        let (rev, pri) = match j.kind {
            PinJointType::Revolute(k) => (Some(axis(k)), None),
            PinJointType::RevoluteUnaligned(a) => (Some(Vector3::from(a)), None),
            PinJointType::Prismatic(k) => (None, Some(axis(k))),
            PinJointType::PrismaticUnaligned(a) => (None, Some(Vector3::from(a))),
            PinJointType::Planar | PinJointType::FreeFlyer => (None, None),
        };
        if let Some(e) = rev {
            rot = r_pre * Rotation3::from_axis_angle(&Unit::new_normalize(e), q[iq]).matrix();
            w += r_pre * e * v[iv];
        }
        if let Some(e) = pri {
            pos += r_pre * e * q[iq];
            vel = v0 + w0.cross(&(pos - p0)) + r_pre * e * v[iv];
        }
        if j.kind == PinJointType::Planar {
            let theta = q[iq + 3].atan2(q[iq + 2]);
            rot = r_pre * Rotation3::from_axis_angle(&Vector3::z_axis(), theta).matrix();
            pos += r_pre * Vector3::new(q[iq], q[iq + 1], 0.0);
            vel = v0 + w0.cross(&(pos - p0)) + rot * Vector3::new(v[iv], v[iv + 1], 0.0);
            w += rot * Vector3::new(0.0, 0.0, v[iv + 2]);
        }
        if j.kind == PinJointType::FreeFlyer {
            // Position and quaternion (x, y, z, w) base → parent; (v, ω) in the joint's frame.
            let quat = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[iq + 6],
                q[iq + 3],
                q[iq + 4],
                q[iq + 5],
            ));
            rot = r_pre * quat.to_rotation_matrix().matrix();
            pos += r_pre * Vector3::new(q[iq], q[iq + 1], q[iq + 2]);
            vel = v0 + w0.cross(&(pos - p0)) + rot * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
            w += rot * Vector3::new(v[iv + 3], v[iv + 4], v[iv + 5]);
        }
        frames.push((rot, pos, w, vel));
    }
    let g = Vector3::from(pm.gravity);
    let (mut t, mut u) = (0.0, 0.0);
    for b in &pm.bodies {
        let (rj, pj, w, vj) = frames[b.joint];
        let rb = rj * m3(&b.rotation);
        let pb = pj + rj * Vector3::from(b.translation);
        let com = pb + rb * Vector3::from(b.com);
        let vc = vj + w.cross(&(com - pj));
        let inertia = rb * m3(&b.inertia_com) * rb.transpose();
        t += 0.5 * b.mass * vc.norm_squared() + 0.5 * w.dot(&(inertia * w));
        u -= b.mass * g.dot(&com);
    }
    t += 0.5
        * pm.armature
            .iter()
            .zip(v)
            .map(|(a, x)| a * x * x)
            .sum::<f64>();
    (t, u)
}

/// Exports `m` with random parameters and compares the energies with the reference recursion.
fn check_energies(name: &str, m: &Model, draws: usize) {
    let mut rng = SplitMix64::new(14);
    let mut uniform = move || rng.next_f64();
    let n = m.dof();
    let mut worst = 0.0f64;
    for draw in 0..draws {
        let params = if draw == 0 {
            m.param_values()
        } else {
            random_physical_params(m, &mut uniform)
        };
        let pm = export(m, &params).unwrap();
        assert_eq!(pm.speeds.len(), n);
        let reference = Reference::<f64>::with_params(m, &params);
        let q = uniform_vec(&mut uniform, n, -3.0, 3.0);
        let u = uniform_vec(&mut uniform, n, -2.0, 2.0);
        let (t, v) = energies(&pm, &pm.configuration(&q), &pm.velocity(&u));
        let (t_ref, v_ref) = (
            reference.kinetic_energy(&q, &u),
            reference.potential_energy(&q),
        );
        let scale = t_ref.abs().max(v_ref.abs()).max(1e-3);
        let err = ((t - t_ref).abs().max((v - v_ref).abs())) / scale;
        worst = worst.max(err);
        assert!(
            err < 1e-12,
            "{name}, draw {draw}: T {t} vs {t_ref}, V {v} vs {v_ref} (relative {err:e})"
        );
    }
    eprintln!("{name}: worst relative energy difference {worst:e} over {draws} draws");
}

#[test]
fn exported_krang_has_the_references_kinetic_and_potential_energy() {
    check_energies("krang", &model("krang.toml"), 200);
}

#[test]
fn exported_fixed_base_models_have_the_references_energies() {
    check_energies("krang-fixed-wheels", &model("krang-fixed-wheels.toml"), 100);
    check_energies("two-link", &model("two-link.toml"), 100);
    check_energies("singlearm", &model("singlearm.urdf"), 100);
}

/// Fixed joints (bodies appended to the moving ancestor), a prismatic joint along a negative
/// axis, a revolute joint about a skew axis.
const CHAIN: &str = r#"
[model]
name = "chain"
speeds = ["qd_a", "qd_b", "qd_d"]

[base]
type = "fixed"
frame = "0"

[gravity]
symbol = "g"
direction = [0, 0, -1]

[parameters]
g = 9.81
L1 = 0.3
mb = 2.0
MXb = 0.1
MYb = 0.0
MZb = 0.05
XXb = 0.05
XYb = 0.0
XZb = 0.0
YYb = 0.05
YZb = 0.0
ZZb = 0.05
mc = 1.0
MXc = 0.0
MYc = 0.1
MZc = 0.0
XXc = 0.03
XYc = 0.0
XZc = 0.0
YYc = 0.02
YZc = 0.0
ZZc = 0.03
md = 0.5
MXd = 0.05
MYd = 0.0
MZd = 0.0
XXd = 0.01
XYd = 0.0
XZd = 0.0
YYd = 0.02
YZd = 0.0
ZZd = 0.02

[[joint]]
name = "q_a"
type = "revolute"
parent = "0"
child = "a"
speed = "qd_a"
axis = [0, 0, 1]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, "L1"]

[[joint]]
name = "q_b"
type = "prismatic"
parent = "a"
child = "b"
speed = "qd_b"
axis = [0, -1, 0]
rotation = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
translation = ["L1", 0, 0.1]

[[joint]]
name = "fix_c"
type = "fixed"
parent = "b"
child = "c"
rotation = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
translation = [0.2, 0, "-L1"]

[[joint]]
name = "q_d"
type = "revolute"
parent = "c"
child = "d"
speed = "qd_d"
axis = [0.6, 0, 0.8]
rotation = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
translation = [0, 0.1, 0]

[[body]]
frame = "b"

[[body]]
frame = "c"

[[body]]
frame = "d"
"#;

#[test]
fn fixed_joints_negative_and_skew_axes_export_exactly() {
    let m = Model::from_toml_str(CHAIN, "chain.toml").unwrap();
    let pm = export(&m, &m.param_values()).unwrap();
    let kinds: Vec<PinJointType> = pm.joints.iter().map(|j| j.kind).collect();
    assert_eq!(
        kinds,
        [
            PinJointType::Revolute(2),
            PinJointType::Prismatic(1),
            PinJointType::RevoluteUnaligned([0.6, 0.0, 0.8]),
        ],
        "no Pinocchio joint for the fixed joint"
    );
    let signs: Vec<f64> = pm.speeds.iter().map(|s| s.sign).collect();
    assert_eq!(signs, [1.0, -1.0, 1.0]);
    // Body c rides on joint b (2) with the fixed joint's placement.
    let c = pm.bodies.iter().find(|b| b.name == "c").unwrap();
    assert_eq!((c.joint, c.translation), (2, [0.2, 0.0, -0.3]));
    assert_eq!(pm.joints[2].parent, 2);
    check_energies("chain", &m, 100);
}

/// A wheeled base with a prismatic lift on a skew axis and a revolute joint on a skew axis.
const LIFT: &str = r#"<robot name="lift">
  <link name="chassis"><inertial><origin xyz="0.01 0 0.3"/><mass value="20"/>
    <inertia ixx="1.2" ixy="0" ixz="0.01" iyy="1.1" iyz="0" izz="0.4"/></inertial></link>
  <link name="left_wheel"><inertial><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial></link>
  <link name="right_wheel"><inertial><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial></link>
  <link name="carriage"><inertial><origin xyz="0.02 0.01 0.1" rpy="0.3 0 0.2"/><mass value="3"/>
    <inertia ixx="0.05" ixy="0.001" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.2 0 0.01"/><mass value="1.5"/>
    <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <joint name="left_wheel_joint" type="continuous"><parent link="chassis"/><child link="left_wheel"/>
    <origin xyz="0 0.25 0"/><axis xyz="0 1 0"/></joint>
  <joint name="right_wheel_joint" type="continuous"><parent link="chassis"/><child link="right_wheel"/>
    <origin xyz="0 -0.25 0"/><axis xyz="0 1 0"/></joint>
  <joint name="lift" type="prismatic"><parent link="chassis"/><child link="carriage"/>
    <origin xyz="0.05 0.02 0.5" rpy="0.1 0.2 0"/><axis xyz="0.3 0 0.954"/>
    <limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="shoulder" type="revolute"><parent link="carriage"/><child link="arm"/>
    <origin xyz="0 0.1 0.2" rpy="0 0 0.4"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"#;

#[test]
fn wheeled_base_with_skew_prismatic_joint_exports_exactly() {
    let spec = WheeledBaseSpec::new(
        "left_wheel_joint",
        "right_wheel_joint",
        "chassis",
        [0.0, 0.0, 1.0],
        0.2,
    );
    let m = Model::from_urdf_str(LIFT, "lift.urdf", &UrdfOptions::wheeled(spec)).unwrap();
    check_energies("lift", &m, 100);
}

#[test]
fn krang_export_is_a_planar_base_and_aligned_joints() {
    let m = model("krang.toml");
    let pm = export(&m, &m.param_values()).unwrap();
    assert_eq!((pm.nq, pm.nv, pm.joints.len()), (21, 20, 18));
    assert_eq!(pm.joints[0].kind, PinJointType::Planar);
    assert!(
        pm.joints[1..]
            .iter()
            .all(|j| matches!(j.kind, PinJointType::Revolute(_))),
        "Krang's axes are all ± coordinate axes"
    );
    // ẋ → v_x, ψ̇ → ω_z; v_y (index 1) is no speed of the model.
    assert_eq!((pm.speeds[0].v, pm.speeds[1].v), (0, 2));
    assert!(pm.speeds.iter().all(|s| s.v != 1));
    // Wheel spin as armature: 2 YYw/R² on v_x, YYw L²/(2R²) on ω_z.
    let (yy, r, l) = (0.1456, 0.25, 0.68);
    assert!((pm.armature[0] - 2.0 * yy / (r * r)).abs() < 1e-15);
    assert!((pm.armature[2] - yy * l * l / (2.0 * r * r)).abs() < 1e-15);
    let text = pm.to_text();
    assert!(text.starts_with("kanegen-pinocchio 1\nmodel krang nq 21 nv 20 dof 19\n"));
    assert!(text.ends_with("end\n"));
    assert_eq!(text.lines().filter(|l| l.starts_with("joint ")).count(), 18);
    assert_eq!(text.lines().filter(|l| l.starts_with("body ")).count(), 18);
    assert!(text.contains("\ncoordinate psi planar_psi 2 1.0\n"));
    assert!(text.contains("\ncoordinate q_imu joint 4 -1.0\n"));
    // Shortest round-trip numbers: the text gives back the exact values.
    let m1 = text.lines().find(|l| l.starts_with("body 1 ")).unwrap();
    let mass: f64 = m1.split_whitespace().nth(15).unwrap().parse().unwrap();
    assert_eq!(mass, 75.767);
}

#[test]
fn unexportable_models_are_typed_errors() {
    let mut m = model("krang.toml");
    let params = m.param_values();
    assert!(matches!(
        export(&m, &params[1..]),
        Err(ExportError::ParamCount { expected: 185, .. })
    ));
    let mut massless = params.clone();
    massless[m.param_index("m4l").unwrap()] = 0.0;
    let err = export(&m, &massless).unwrap_err();
    assert!(
        matches!(&err, ExportError::MasslessFirstMoment { body, .. } if body == "4l"),
        "{err}"
    );
    assert!(err.to_string().contains("krang.toml"), "{err}");
    m.gravity.direction = [0.0, -1.0, 0.0];
    let err = export(&m, &params).unwrap_err();
    assert!(
        matches!(err, ExportError::GravityNotVertical { .. }),
        "{err}"
    );
}

#[test]
fn names_with_whitespace_stay_one_token_of_the_text_format() {
    let mut m = model("two-link.toml");
    m.name = "two link\trobot".into();
    let text = export(&m, &m.param_values()).unwrap().to_text();
    assert!(
        text.contains("\nmodel two_link_robot nq 2 nv 2 dof 2\n"),
        "{text}"
    );
}

/// The free-flyer export of Solo 12 and a humanoid has the kinetic and potential energy of the
/// free-flyer reference recursion (`kanegen_reference::FreeFlyer`): the same configuration and
/// speeds, one to one.
#[test]
fn free_flyer_export_has_the_energies_of_the_free_flyer_recursion() {
    use kanegen::pinocchio::export_free_flyer;
    use kanegen_reference::FreeFlyer;
    let mut rng = SplitMix64::new(15);
    let mut uniform = move || rng.next_f64();
    for file in ["solo12", "simple_humanoid"] {
        let path = root().join("tests/corpus").join(format!("{file}.urdf"));
        let m = Model::from_urdf_file(&path, &UrdfOptions::default()).unwrap();
        let pm = export_free_flyer(&m, &m.param_values()).unwrap();
        assert_eq!((pm.nq, pm.nv), (m.dof() + 7, m.dof() + 6));
        assert_eq!(pm.speeds.len(), m.dof() + 6);
        assert_eq!(pm.coordinates.len(), m.dof() + 7);
        assert_eq!(pm.joints[0].kind, PinJointType::FreeFlyer);
        let ff = FreeFlyer::<f64>::new(&m).unwrap();
        for _ in 0..5 {
            let mut q = uniform_vec(&mut uniform, ff.nq(), -1.5, 1.5);
            let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[3..7].iter_mut().for_each(|x| *x /= norm);
            let u = uniform_vec(&mut uniform, ff.dof(), -2.0, 2.0);
            let (t, v) = energies(&pm, &pm.configuration(&q), &pm.velocity(&u));
            let (t_ref, v_ref) = (ff.kinetic_energy(&q, &u), ff.potential_energy(&q));
            let scale = t_ref.abs().max(v_ref.abs()).max(1e-3);
            assert!(
                (t - t_ref).abs() < 1e-12 * scale,
                "{file}: T {t} vs {t_ref}"
            );
            assert!(
                (v - v_ref).abs() < 1e-12 * scale,
                "{file}: V {v} vs {v_ref}"
            );
        }
    }
    let krang = model("krang.toml");
    let err = export_free_flyer(&krang, &krang.param_values()).unwrap_err();
    assert!(matches!(err, ExportError::WheeledFreeFlyer { .. }));
}

/// A model with a floating base goes through `export` directly: the free flyer is its base, the
/// coordinates and speeds are its generated module's one to one (names included), and the energies
/// are those of the free-flyer reference recursion at random physical parameters.
#[test]
fn floating_models_export_through_the_free_flyer() {
    use kanegen::model::Base;
    use kanegen_reference::FreeFlyer;
    let mut rng = SplitMix64::new(48);
    let mut uniform = move || rng.next_f64();
    let solo = Model::from_urdf_file(
        root().join("tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .unwrap();
    let hopper = Model::from_toml_file(root().join("models/floating-hopper.toml")).unwrap();
    for m in [solo, hopper] {
        assert!(matches!(m.base, Base::Floating));
        let params = random_physical_params(&m, &mut uniform);
        let pm = export(&m, &params).unwrap();
        assert_eq!(pm.joints[0].kind, PinJointType::FreeFlyer);
        assert_eq!((pm.nq, pm.nv), (m.nq(), m.dof()));
        assert_eq!(pm.coordinate_names, m.coordinate_names(), "{}", m.name);
        let speed_names: Vec<&str> = pm.speeds.iter().map(|s| s.name.as_str()).collect();
        let model_speeds: Vec<&str> = m.speeds.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(speed_names, model_speeds, "{}", m.name);
        let ff = FreeFlyer::<f64>::with_params(&m, &params).unwrap();
        for _ in 0..5 {
            let mut q = uniform_vec(&mut uniform, ff.nq(), -1.5, 1.5);
            let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[3..7].iter_mut().for_each(|x| *x /= norm);
            let u = uniform_vec(&mut uniform, ff.dof(), -2.0, 2.0);
            let (t, v) = energies(&pm, &pm.configuration(&q), &pm.velocity(&u));
            let (t_ref, v_ref) = (ff.kinetic_energy(&q, &u), ff.potential_energy(&q));
            let scale = t_ref.abs().max(v_ref.abs()).max(1e-3);
            assert!(
                (t - t_ref).abs() < 1e-12 * scale,
                "{}: T {t} vs {t_ref}",
                m.name
            );
            assert!(
                (v - v_ref).abs() < 1e-12 * scale,
                "{}: V {v} vs {v_ref}",
                m.name
            );
        }
    }
}
