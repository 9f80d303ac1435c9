//! The 7-DOF Schunk LWA3 arm of `models/singlearm.urdf` (fixed base), its dynamics generated at
//! build time by kanegen (`build.rs`): prints M(q), g(q), τ and the forward dynamics at a
//! sample configuration.
//!
//! `cargo run -p urdf-arm-example`
#![forbid(unsafe_code)]

/// The generated module: `Params` (fields `m_L1`, `MX_L1`, …), `SPEED_NAMES`, `mass_matrix`,
/// `coriolis`, `gravity`, `inverse_dynamics` and the wrapper struct `SingleArm`.
// A binary uses only part of the generated API, which is written for a library crate.
#[allow(missing_docs, dead_code, clippy::wrong_self_convention)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/singlearm.rs"));
}

use arm::{DOF, Params, SPEED_NAMES, SingleArm};
use kanegen_runtime::RobotDynamics; // forward_dynamics, which every generated robot has
use nalgebra::SVector;

fn main() {
    let robot = SingleArm::new(Params::default()); // the URDF's masses and inertias
    let q = SVector::<f64, DOF>::from_column_slice(&[0.3, -0.5, 0.2, 1.0, -0.4, 0.6, 0.1]);
    let m = robot.mass_matrix(&q);
    let g = robot.gravity(&q);
    println!("speeds: {}", SPEED_NAMES.join(", "));
    println!("q = {}", q.transpose());
    println!("M(q) ={m:.5}");
    println!("g(q) = {:.5}", g.transpose());
    let u = SVector::<f64, DOF>::from_element(0.5);
    let ud = SVector::<f64, DOF>::zeros();
    let tau = robot.inverse_dynamics(&q, &u, &ud);
    println!("tau(q, u = 0.5, ud = 0) = {:.5}", tau.transpose());
    // Released with no torque: the accelerations of a simulator's first step.
    let at_rest = SVector::<f64, DOF>::zeros();
    let ud = robot
        .forward_dynamics(&q, &at_rest, &at_rest)
        .expect("the URDF's inertias give a positive definite M");
    println!("ud(q, u = 0, tau = 0) = {:.5}", ud.transpose());
}

#[cfg(test)]
mod tests {
    use super::arm::{DOF, Params, SingleArm};
    use kanegen_model::{Model, UrdfOptions};
    use kanegen_reference::Reference;
    use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
    use nalgebra::SVector;

    /// The generated functions agree with the reference recursion on the same model (imported
    /// with the same options as in build.rs), on random physical parameters and states.
    #[test]
    fn generated_dynamics_match_the_reference_recursion() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/singlearm.urdf");
        let model = Model::from_urdf_file(path, &UrdfOptions::default()).unwrap();
        assert_eq!(model.dof(), DOF);
        assert_eq!(Params::NAMES.len(), model.params.len());
        for (name, p) in Params::NAMES.iter().zip(&model.params) {
            assert_eq!(*name, p.name);
        }
        let mut rng = SplitMix64::new(11);
        let mut uniform = || rng.next_f64();
        let mut worst = 0.0f64;
        for draw in 0..200 {
            // The URDF's own values first, then random physical ones.
            let params = if draw == 0 {
                model.param_values()
            } else {
                random_physical_params(&model, &mut uniform)
            };
            let robot = SingleArm::new(Params::from_array(params.clone().try_into().unwrap()));
            let reference = Reference::<f64>::with_params(&model, &params);
            let q = uniform_vec(&mut uniform, DOF, -3.2, 3.2);
            let u = uniform_vec(&mut uniform, DOF, -2.0, 2.0);
            let ud = uniform_vec(&mut uniform, DOF, -5.0, 5.0);
            let (qs, us, uds) = (
                SVector::<f64, DOF>::from_column_slice(&q),
                SVector::<f64, DOF>::from_column_slice(&u),
                SVector::<f64, DOF>::from_column_slice(&ud),
            );
            let m_ref = reference.mass_matrix(&q);
            let m = robot.mass_matrix(&qs);
            let scale = m_ref.amax().max(1.0);
            for r in 0..DOF {
                for c in 0..DOF {
                    worst = worst.max((m[(r, c)] - m_ref[(r, c)]).abs() / scale);
                }
            }
            for (ours, theirs) in [
                (robot.coriolis(&qs, &us), reference.coriolis(&q, &u)),
                (robot.gravity(&qs), reference.gravity(&q)),
                (
                    robot.inverse_dynamics(&qs, &us, &uds),
                    reference.inverse_dynamics(&q, &u, &ud),
                ),
            ] {
                let scale = theirs.amax().max(1.0);
                for i in 0..DOF {
                    worst = worst.max((ours[i] - theirs[i]).abs() / scale);
                }
            }
        }
        assert!(worst < 1e-10, "worst relative error {worst:e}");
    }

    /// `Params::validate` accepts the URDF's values and every random physical parameter set of
    /// the reference's generator, and rejects a negative mass and an inertia that breaks the
    /// triangle inequality.
    #[test]
    fn validate_accepts_physical_parameters_and_rejects_others() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/singlearm.urdf");
        let model = Model::from_urdf_file(path, &UrdfOptions::default()).unwrap();
        Params::default().validate().unwrap();
        let mut rng = SplitMix64::new(5);
        let mut uniform = || rng.next_f64();
        for _ in 0..500 {
            let p = random_physical_params(&model, &mut uniform);
            Params::from_array(p.try_into().unwrap())
                .validate()
                .unwrap();
        }
        let mut p = Params::default();
        let mass = Params::NAMES.iter().find(|n| n.starts_with("m_")).unwrap();
        assert_eq!(p.set(mass, -1.0).unwrap_err().name(), *mass);
        let i = Params::NAMES.iter().position(|n| n == mass).unwrap();
        let mut values = p.to_array();
        values[i] = -1.0;
        let p = Params::from_array(values);
        assert_eq!(p.validate().unwrap_err().name(), *mass);
        let mut p = Params::default();
        let xx = Params::NAMES.iter().find(|n| n.starts_with("XX_")).unwrap();
        let zz = xx.replacen("XX", "ZZ", 1);
        let yy = xx.replacen("XX", "YY", 1);
        let big = p.get(&yy).unwrap() + p.get(&zz).unwrap() + 1.0;
        p.set(xx, big).unwrap();
        assert_eq!(
            p.validate().unwrap_err().problem(),
            kanegen_runtime::Problem::InertiaNotPhysical
        );
    }
}
