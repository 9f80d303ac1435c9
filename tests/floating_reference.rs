//! Generated floating-base modules against the independent free-flyer recursion
//! [`kanegen_reference::FreeFlyer`], on random physical parameter sets and random states: the
//! hopper (`models/floating-hopper.toml`, every function a floating base has), Solo 12
//! (`tests/corpus/solo12.urdf` on a floating base, 18 speeds) and the humanoid
//! `tests/corpus/simple_humanoid.urdf` (floating, 35 speeds), all from this package's build
//! script.
//!
//! Compared: M, c, g, τ, the nonlinear effects, the centre of mass, every frame's world pose,
//! every frame's Jacobian and bias acceleration, the centroidal momentum matrix A_G and bias
//! Ȧ_G u, and ∂τ/∂q (tangent space) and ∂τ/∂u. The generated Jacobians and bias accelerations are
//! in the base frame's axes and the reference's in the world's: the test rotates the generated
//! ones by the base rotation `R0` (`J_world = blockdiag(R0, R0) J_base`).

#[path = "../codegen/tests/support/free_flyer.rs"]
mod free_flyer;

use kanegen::model::{Model, UrdfOptions};
use kanegen_reference::FreeFlyer;
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector};

#[allow(dead_code)]
mod hopper {
    include!(concat!(env!("OUT_DIR"), "/floating_hopper.rs"));
}

#[allow(dead_code)]
mod solo {
    include!(concat!(env!("OUT_DIR"), "/solo12_floating.rs"));
}

#[allow(dead_code)]
mod humanoid {
    include!(concat!(env!("OUT_DIR"), "/simple_humanoid_floating.rs"));
}

fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A deterministic pseudo-random stream in [0, 1).
fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut r = kanegen_reference::random::SplitMix64::new(seed);
    move || r.next_f64()
}

fn random_vec(uniform: &mut impl FnMut() -> f64, n: usize, a: f64) -> Vec<f64> {
    (0..n).map(|_| a * (2.0 * uniform() - 1.0)).collect()
}

/// `max |a − b| / max(max |b|, 1)`.
fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

fn dm<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_column_slice(R, C, m.as_slice())
}

fn dv(v: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(v.len(), 1, v.as_slice())
}

/// `blockdiag(R, R) m` for a matrix with six rows.
fn rotate_rows(r: &Matrix3<f64>, m: &DMatrix<f64>) -> DMatrix<f64> {
    let mut out = m.clone();
    for c in 0..m.ncols() {
        for b in 0..2 {
            let v = r * m.fixed_view::<3, 1>(3 * b, c);
            out.fixed_view_mut::<3, 1>(3 * b, c).copy_from(&v);
        }
    }
    out
}

/// Compares every generated function of module `$m` (wrapper `$robot`) with the reference, for
/// `$sets` random parameter sets and `$states` random states per set.
macro_rules! compare_with_reference {
    ($m:ident, $robot:ident, $model:expr, $seed:expr, $sets:expr, $states:expr) => {{
        use $m::{DOF, Frame, NQ, PARAM_COUNT, Params, $robot};
        let model: Model = $model;
        let names: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, Params::NAMES, "parameter order");
        let mut uniform = stream($seed);
        let tol = 1e-9;
        for _ in 0..$sets {
            let values = kanegen_reference::random::random_physical_params(&model, &mut uniform);
            let reference = FreeFlyer::<f64>::with_params(&model, &values).expect("free flyer");
            let mut array = [0.0; PARAM_COUNT];
            array.copy_from_slice(&values);
            let robot = $robot::new(Params::from_array(array));
            for _ in 0..$states {
                let qv = free_flyer::random_configuration(&model, &mut uniform);
                let uv = random_vec(&mut uniform, DOF, 2.0);
                let udv = random_vec(&mut uniform, DOF, 5.0);
                let q = SVector::<f64, NQ>::from_column_slice(&qv);
                let u = SVector::<f64, DOF>::from_column_slice(&uv);
                let ud = SVector::<f64, DOF>::from_column_slice(&udv);
                let check = |what: &str, got: DMatrix<f64>, want: DMatrix<f64>| {
                    let e = rel(&got, &want);
                    assert!(e < tol, "{}: {what}: relative error {e:e}", model.name);
                };
                check("M", dm(&robot.mass_matrix(&q)), reference.mass_matrix(&qv));
                check(
                    "c",
                    dm(&robot.coriolis(&q, &u)),
                    dv(&reference.coriolis(&qv, &uv)),
                );
                check("g", dm(&robot.gravity(&q)), dv(&reference.gravity(&qv)));
                check(
                    "τ",
                    dm(&robot.inverse_dynamics(&q, &u, &ud)),
                    dv(&reference.inverse_dynamics(&qv, &uv, &udv)),
                );
                check(
                    "nonlinear effects",
                    dm(&robot.nonlinear_effects(&q, &u)),
                    dv(&reference.nonlinear_effects(&qv, &uv)),
                );
                let com = reference.center_of_mass(&qv);
                check(
                    "centre of mass",
                    dm(&robot.center_of_mass(&q)),
                    DMatrix::from_column_slice(3, 1, com.as_slice()),
                );
                check(
                    "A_G",
                    dm(&robot.centroidal_momentum_matrix(&q)),
                    reference.centroidal_momentum_matrix(&qv),
                );
                let bias = reference.centroidal_momentum_bias(&qv, &uv);
                check(
                    "Ȧ_G u",
                    dm(&robot.centroidal_momentum_bias(&q, &u)),
                    DMatrix::from_column_slice(6, 1, bias.as_slice()),
                );
                let (dq, du) = reference.inverse_dynamics_derivatives(&qv, &uv, &udv);
                let d = robot.inverse_dynamics_derivatives(&q, &u, &ud);
                check("∂τ/∂q", dm(&d.fixed_columns::<DOF>(0).into_owned()), dq);
                check("∂τ/∂u", dm(&d.fixed_columns::<DOF>(DOF).into_owned()), du);
                let (r0, _) = reference.base_pose(&qv);
                for frame in Frame::ALL {
                    let index = model
                        .links
                        .iter()
                        .position(|l| l.name == frame.name())
                        .expect("every generated frame is a link of the model");
                    let (rot, pos) = reference.frame_pose(&qv, index);
                    let pose = robot.frame_pose(&q, frame);
                    let got_rot = pose.rotation.to_rotation_matrix().into_inner();
                    check(
                        &format!("pose of {}", frame.name()),
                        DMatrix::from_iterator(
                            12,
                            1,
                            got_rot
                                .iter()
                                .chain(pose.translation.vector.iter())
                                .copied(),
                        ),
                        DMatrix::from_iterator(12, 1, rot.iter().chain(pos.iter()).copied()),
                    );
                    check(
                        &format!("Jacobian of {}", frame.name()),
                        rotate_rows(&r0, &dm(&robot.frame_jacobian(&q, frame))),
                        reference.frame_jacobian(&qv, index),
                    );
                    let a = reference.frame_bias_acceleration(&qv, &uv, index);
                    check(
                        &format!("bias acceleration of {}", frame.name()),
                        rotate_rows(&r0, &dm(&robot.frame_bias_acceleration(&q, &u, frame))),
                        DMatrix::from_column_slice(6, 1, a.as_slice()),
                    );
                }
            }
        }
    }};
}

#[test]
fn floating_hopper_every_function_equals_the_free_flyer_reference() {
    let model = Model::from_toml_file(root().join("models/floating-hopper.toml")).expect("loads");
    compare_with_reference!(hopper, FloatingHopper, model, 0x48_01, 8, 4);
}

#[test]
fn floating_solo12_every_generated_function_equals_the_free_flyer_reference() {
    let model = Model::from_urdf_file(
        root().join("tests/corpus/solo12.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports");
    compare_with_reference!(solo, Solo, model, 0x48_02, 4, 3);
}

#[test]
fn floating_humanoid_every_generated_function_equals_the_free_flyer_reference() {
    let model = Model::from_urdf_file(
        root().join("tests/corpus/simple_humanoid.urdf"),
        &UrdfOptions::floating(),
    )
    .expect("imports");
    // Unoptimised, each statement of the 35-speed functions keeps its own stack slot: more than
    // the 2 MB of a test thread (docs/big-models.md). Optimised builds need a few KB.
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(move || compare_with_reference!(humanoid, SimpleHumanoid, model, 0x48_03, 3, 3))
        .expect("a thread can be spawned")
        .join()
        .expect("the comparison passes");
}
