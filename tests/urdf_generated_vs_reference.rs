//! URDF models through the generator: the symbolic derivation (`Derivation::evaluate`) and the
//! lowered programs (`Lowered::evaluate`) against the numeric reference recursion (and the
//! Coriolis matrix: `C u = c`, `Ṁ − 2C` skew-symmetric), on random
//! physical parameters and states, for every shipped URDF (fixed and two-wheeled bases) and for
//! small synthetic robots exercising prismatic joints, fixed-joint merging with rotated inertials,
//! and a wheeled body that is not the URDF root.

mod common;

use common::*;
use kanegen::Builder;
use kanegen::FunctionId;
use kanegen_model::{AngleSnap, Model, UrdfOptions, WheeledBaseSpec};
use kanegen_reference::Reference;
use kanegen_reference::random::random_physical_params;

const TOL: f64 = 1e-10;
/// Ṁ from Richardson-extrapolated central differences (see `common::mdot_central`).
const SKEW_TOL: f64 = 1e-8;
const FUNCTIONS: [FunctionId; 4] = [
    FunctionId::MassMatrix,
    FunctionId::Coriolis,
    FunctionId::Gravity,
    FunctionId::InverseDynamics,
];

fn urdf(name: &str, options: &UrdfOptions) -> Model {
    Model::from_urdf_file(root().join("models").join(name), options).expect("URDF imports")
}

fn plates() -> [&'static str; 4] {
    ["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"]
}

fn krang_options() -> UrdfOptions {
    let mut spec = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    spec.pitch_name = "imu".into();
    UrdfOptions::wheeled(spec).drop_links(plates())
}

/// Worst relative error of the derivation and of the lowered programs against the reference,
/// per function, over `draws` random parameter sets and states.
fn check(label: &str, model: &Model, draws: usize, seed: u64) {
    let g = Builder::from_model(model.clone())
        .generate()
        .expect("generates");
    let n = model.dof();
    let mut r = rng(seed);
    let mut worst = [0.0f64; 6];
    for draw in 0..draws {
        let p = if draw == 0 {
            model.param_values()
        } else {
            random_physical_params(model, &mut r)
        };
        let (q, u, ud) = random_state(&mut r, n);
        let reference = Reference::<f64>::with_params(model, &p);
        let expected = [
            drows(&reference.mass_matrix(&q)),
            dvec(&reference.coriolis(&q, &u)),
            dvec(&reference.gravity(&q)),
            dvec(&reference.inverse_dynamics(&q, &u, &ud)),
        ];
        for (i, f) in FUNCTIONS.iter().enumerate() {
            let d = g.derivation.evaluate(*f, &p, &q, &u, &ud);
            let l = g.lowered.evaluate(*f, &p, &q, &u, &ud);
            worst[i] =
                worst[i]
                    .max(rel_err(&d, &expected[i], 1.0))
                    .max(rel_err(&l, &expected[i], 1.0));
        }
        // Coriolis matrix: C u = c, and Ṁ − 2C skew-symmetric (Ṁ by central differences of
        // the derivation's M along q̇).
        let mdot = mdot_central(
            &|q: &[f64]| {
                g.derivation
                    .evaluate(FunctionId::MassMatrix, &p, q, &u, &ud)
            },
            &q,
            &coordinate_rates(model, &u),
            1e-3,
        );
        for c in [
            g.derivation
                .evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &ud),
            g.lowered
                .evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &ud),
        ] {
            let cu: Vec<f64> = (0..n)
                .map(|r| (0..n).map(|k| c[r * n + k] * u[k]).sum())
                .collect();
            worst[4] = worst[4].max(rel_err(&cu, &expected[1], 1.0));
            worst[5] = worst[5].max(skew_defect(&mdot, &c, n, 1.0));
        }
    }
    eprintln!(
        "{label} ({n} speeds, {draws} draws): worst relative error M {:.1e} c {:.1e} g {:.1e} tau {:.1e}; \
         C u vs c {:.1e}, skew defect of Mdot - 2C {:.1e}",
        worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]
    );
    assert!(
        worst[..5].iter().all(|e| *e < TOL),
        "{label}: {worst:?} exceeds {TOL}"
    );
    assert!(worst[5] < SKEW_TOL, "{label}: skew defect {:e}", worst[5]);
}

#[test]
fn singlearm_fixed_base() {
    let m = urdf("singlearm.urdf", &UrdfOptions::default());
    assert_eq!(m.dof(), 7);
    check("singlearm.urdf", &m, 100, 1);
}

#[test]
fn singlearm_without_snapping() {
    let m = urdf(
        "singlearm.urdf",
        &UrdfOptions {
            snap_angles: AngleSnap::Off,
            ..UrdfOptions::default()
        },
    );
    check("singlearm.urdf, angles as written", &m, 50, 2);
}

#[test]
fn krang_fixed_wheel_tree() {
    let m = urdf(
        "krang_fixed_wheel.urdf",
        &UrdfOptions::default().drop_links(plates()),
    );
    assert_eq!(m.dof(), 18);
    check("krang_fixed_wheel.urdf", &m, 30, 3);
}

#[test]
fn krang_two_wheeled_base() {
    let m = urdf("Krang.urdf", &krang_options());
    assert_eq!(m.dof(), 19);
    check("Krang.urdf, wheeled base", &m, 30, 4);
}

/// Fixed-joint merges with rotated inertials and offsets, a prismatic joint below a merged
/// link, continuous joints, a massless link, a non-trivial gravity direction.
const SYNTHETIC_ARM: &str = r#"<robot name="synthetic-arm">
  <link name="world"/>
  <link name="column"><inertial><origin xyz="0 0 0.4" rpy="0.1 0.2 0.3"/><mass value="4"/>
    <inertia ixx="0.2" ixy="0.01" ixz="0" iyy="0.25" iyz="-0.02" izz="0.05"/></inertial></link>
  <link name="housing"><inertial><origin xyz="0.05 0.02 -0.01" rpy="-0.4 0.7 1.2"/><mass value="1.2"/>
    <inertia ixx="0.004" ixy="0" ixz="0.001" iyy="0.006" iyz="0" izz="0.005"/></inertial></link>
  <link name="carriage"><inertial><origin xyz="0.1 0 0.02"/><mass value="0.9"/>
    <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.004"/></inertial></link>
  <link name="wrist"/>
  <link name="hand"><inertial><origin xyz="0 0.03 0.08" rpy="1.5708 0 0"/><mass value="0.6"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.0015" iyz="0" izz="0.0008"/></inertial></link>
  <link name="finger"><inertial><origin xyz="0.01 0 0.02"/><mass value="0.1"/>
    <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.00005"/></inertial></link>
  <joint name="yaw" type="continuous"><parent link="world"/><child link="column"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0 0 0.5"/><axis xyz="0 0 1"/></joint>
  <joint name="housing_fix" type="fixed"><parent link="column"/><child link="housing"/>
    <origin xyz="0.2 0.1 0.8" rpy="0.3 -0.6 0.9"/></joint>
  <joint name="slide" type="prismatic"><parent link="housing"/><child link="carriage"/>
    <origin xyz="0 0.05 0.1" rpy="0 3.1416 0"/><axis xyz="1 0 1"/><limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="wrist_fix" type="fixed"><parent link="carriage"/><child link="wrist"/>
    <origin xyz="0.3 0 0" rpy="0 0 -1.5708"/></joint>
  <joint name="roll" type="revolute"><parent link="wrist"/><child link="hand"/>
    <origin xyz="0 0 0.05" rpy="0.2 0 0"/><axis xyz="0.6 0 0.8"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="finger_fix" type="fixed"><parent link="hand"/><child link="finger"/>
    <origin xyz="0 0.02 0.12" rpy="0 0.5 0"/></joint>
</robot>"#;

#[test]
fn synthetic_arm_with_prismatic_joint_and_fixed_merges() {
    let options = UrdfOptions {
        gravity_direction: [0.0, -0.6, -0.8],
        ..UrdfOptions::default()
    };
    let m = Model::from_urdf_str(SYNTHETIC_ARM, "synthetic-arm.urdf", &options).unwrap();
    assert_eq!(m.dof(), 3);
    assert_eq!(m.body_count(), 3);
    check("synthetic arm", &m, 200, 5);
}

/// A two-wheeled robot whose body link `chassis` hangs (fixed) below a massless root, with
/// wheels along y, up = +z, and an arm joint on the chassis.
const SEGWAY: &str = r#"<robot name="segway">
  <link name="base_footprint"/>
  <link name="chassis"><inertial><origin xyz="0.01 0 0.3"/><mass value="20"/>
    <inertia ixx="1.2" ixy="0" ixz="0.01" iyy="1.1" iyz="0" izz="0.4"/></inertial></link>
  <link name="left_wheel"><inertial><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial></link>
  <link name="right_wheel"><inertial><mass value="2"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.04" iyz="0" izz="0.02"/></inertial></link>
  <link name="mast"><inertial><origin xyz="0 0 0.2"/><mass value="3"/>
    <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.01"/></inertial></link>
  <joint name="footprint_fix" type="fixed"><parent link="base_footprint"/><child link="chassis"/>
    <origin xyz="0 0 0.2" rpy="0 0 0.3"/></joint>
  <joint name="left_wheel_joint" type="continuous"><parent link="chassis"/><child link="left_wheel"/>
    <origin xyz="0 0.25 0"/><axis xyz="0 1 0"/></joint>
  <joint name="right_wheel_joint" type="continuous"><parent link="chassis"/><child link="right_wheel"/>
    <origin xyz="0 -0.25 0"/><axis xyz="0 1 0"/><mimic joint="left_wheel_joint"/></joint>
  <joint name="mast_joint" type="revolute"><parent link="chassis"/><child link="mast"/>
    <origin xyz="0.05 0 0.5" rpy="0 0.2 0"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;

#[test]
fn synthetic_segway_with_the_body_below_the_root() {
    let spec = WheeledBaseSpec::new(
        "left_wheel_joint",
        "right_wheel_joint",
        "chassis",
        [0.0, 0.0, 1.0],
        0.2,
    );
    let m = Model::from_urdf_str(SEGWAY, "segway.urdf", &UrdfOptions::wheeled(spec)).unwrap();
    assert_eq!(m.dof(), 4);
    let pitch = m.links[1].joint().unwrap();
    // y0 toward the left wheel = +y of chassis; z0 = +z; x0 = y0 × z0 = +x.
    assert_eq!(
        pitch.rotation,
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert_eq!(pitch.axis, [0.0, 1.0, 0.0]);
    let w = m.wheeled_base().unwrap();
    assert_eq!(m.params[w.track].value, 0.5);
    assert_eq!(m.params[w.wheel_axle_inertia].value, 0.04);
    assert_eq!(m.params[w.wheel_diametral_inertia].value, 0.02);
    check("synthetic segway", &m, 200, 6);
}

/// Point mass, zero-mass rotor (m = 0, J ≠ 0), a slightly non-physical inertia and malformed
/// visuals (see `kanegen-model`'s URDF import tests): the first draw uses the file's values.
#[test]
fn point_masses_and_a_zero_mass_rotor() {
    let text = include_str!("../crates/kanegen-model/tests/data/tolerant.urdf");
    let m = Model::from_urdf_str(text, "tolerant.urdf", &UrdfOptions::default()).unwrap();
    check("tolerant.urdf", &m, 20, 6);
}

/// The validation's mass matrix (from the kinetic energy, `kinetic_energy_mass_matrix`) is the
/// reference's (from inverse dynamics), for every shipped model.
#[test]
fn the_validation_mass_matrix_is_the_reference_mass_matrix() {
    let text = include_str!("../crates/kanegen-model/tests/data/tolerant.urdf");
    let models = [
        model("krang.toml"),
        model("krang-fixed-wheels.toml"),
        model("two-link.toml"),
        urdf("singlearm.urdf", &UrdfOptions::default()),
        urdf("Krang.urdf", &krang_options()),
        Model::from_urdf_str(text, "tolerant.urdf", &UrdfOptions::default()).unwrap(),
    ];
    let mut r = rng(7);
    for m in &models {
        let p = m.param_values();
        let reference = Reference::<f64>::with_params(m, &p);
        for _ in 0..5 {
            let (q, _, _) = random_state(&mut r, m.dof());
            let expected = drows(&reference.mass_matrix(&q));
            let got = drows(&kanegen_model::kinetic_energy_mass_matrix(m, &q, &p));
            let e = rel_err(&got, &expected, 1.0);
            assert!(e < 1e-12, "{}: {e:e}", m.name);
        }
    }
}
