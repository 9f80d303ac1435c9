//! A short run of the example on the generated module: the centre of mass follows the circle,
//! the contact forces stay in their friction cones, the torques within their limits and the
//! feet where they touched down; and the same run on the independent free-flyer reference
//! recursion gives the same motion, forces and torques.

use quadruped_example::generated::Solo;
use quadruped_example::robot::ReferenceSolo;
use quadruped_example::sim::{self, Scenario};
use quadruped_example::wbc::Settings;

fn short() -> Scenario {
    Scenario {
        radius: 0.03,
        period: 0.6,
        ramp: 0.3,
        duration: 0.6,
        dt: 2e-3,
    }
}

#[test]
fn solo12_moves_its_centre_of_mass_along_a_circle_within_its_friction_cones() {
    let robot = Solo::default();
    let scenario = short();
    let settings = Settings::default();
    let log = sim::run(&robot, &scenario, &settings).unwrap();
    let s = sim::summarize(&log, scenario.ramp);
    // Millimetre tracking of a 3 cm circle turned in 0.6 s.
    assert!(s.max_com_error < 1e-3, "{s:?}");
    // The reference moved by several centimetres: the test is not passed by standing still.
    let reach = log
        .iter()
        .map(|x| (x.com - log[0].com).norm())
        .fold(0.0, f64::max);
    assert!(
        reach > 0.04,
        "the centre of mass moved by {reach} m at most"
    );
    assert!(s.max_friction_ratio <= settings.mu * (1.0 + 1e-6), "{s:?}");
    assert!(s.min_normal >= settings.min_normal * (1.0 - 1e-3), "{s:?}");
    assert!(
        s.max_torque <= settings.torque_limit * (1.0 + 1e-6),
        "{s:?}"
    );
    assert!(s.max_foot_drift < 1e-4, "{s:?}");
}

#[test]
fn generated_and_reference_runs_agree() {
    let scenario = Scenario {
        duration: 0.2,
        ..short()
    };
    let settings = Settings::default();
    let generated = sim::run(&Solo::default(), &scenario, &settings).unwrap();
    let reference = sim::run(&ReferenceSolo::load().unwrap(), &scenario, &settings).unwrap();
    assert_eq!(generated.len(), reference.len());
    for (g, r) in generated.iter().zip(&reference) {
        assert!(
            (g.com - r.com).amax() < 1e-9,
            "t = {}: centre of mass off by {:e}",
            g.t,
            (g.com - r.com).amax()
        );
        assert!(
            (g.lambda - r.lambda).amax() < 1e-6 * r.lambda.amax().max(1.0),
            "t = {}: contact forces",
            g.t
        );
        assert!(
            (g.tau - r.tau).amax() < 1e-6 * r.tau.amax().max(1.0),
            "t = {}: torques",
            g.t
        );
    }
}
