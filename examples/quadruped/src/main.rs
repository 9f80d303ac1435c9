//! Solo 12 moving its centre of mass along a circle on four point contacts (see the library
//! docs and docs/contacts.md). Writes three PNG figures to the directory given as the first
//! argument (default `target/quadruped`) and prints a summary:
//!
//! ```text
//! cargo run --release -p quadruped-example -- docs/plots
//! ```

use std::error::Error;
use std::path::PathBuf;
use std::time::Instant;

use quadruped_example::generated::Solo;
use quadruped_example::sim::{self, Sample, Scenario};
use quadruped_example::wbc::Settings;

// The chart code of krang-dynamics' `simulate` example (text from font8x8, no system fonts);
// this example uses a part of it.
#[allow(dead_code)]
#[path = "../../../crates/krang-dynamics/examples/simulate/plot.rs"]
mod plot;

type Res<T> = Result<T, Box<dyn Error>>;

use plot::{BLACK_, GREY, PALETTE, Panel, Series};

fn series(log: &[Sample], f: impl Fn(&Sample) -> f64) -> Vec<(f64, f64)> {
    log.iter().map(|s| (s.t, f(s))).collect()
}

const LEGS: [&str; 4] = ["FL", "FR", "HL", "HR"];

fn main() -> Res<()> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or("target/quadruped".into()));
    std::fs::create_dir_all(&out)?;
    // The dynamics: the generated module (Solo 12 on a floating base).
    let robot = Solo::default();
    let scenario = Scenario::default();
    let settings = Settings::default();
    let start = Instant::now();
    let log = sim::run(&robot, &scenario, &settings)?;
    let per_step = start.elapsed().as_secs_f64() / log.len() as f64;
    let s = sim::summarize(&log, scenario.ramp);
    println!(
        "{} steps of {} ms, {:.2} ms per step (QP and simulation)",
        log.len(),
        scenario.dt * 1e3,
        per_step * 1e3
    );
    println!(
        "centre of mass on a circle of {} cm: error max {:.2} mm, rms {:.2} mm (after {} s)",
        scenario.radius * 100.0,
        s.max_com_error * 1e3,
        s.rms_com_error * 1e3,
        scenario.ramp
    );
    println!(
        "contact forces: smallest normal {:.2} N, largest |tangential|/normal {:.3} (μ = {}); feet drift ≤ {:.1e} m",
        s.min_normal, s.max_friction_ratio, settings.mu, s.max_foot_drift
    );
    println!(
        "joint torques: largest |τ| {:.3} N m (limit {})",
        s.max_torque, settings.torque_limit
    );

    let com = Panel {
        title: "Centre of mass: position and reference".into(),
        y_label: "position (m)",
        series: vec![
            Series::line("x", PALETTE[0], series(&log, |s| s.com.x)),
            Series::dashed("x ref", PALETTE[0], series(&log, |s| s.com_ref.x)),
            Series::line("y", PALETTE[1], series(&log, |s| s.com.y)),
            Series::dashed("y ref", PALETTE[1], series(&log, |s| s.com_ref.y)),
        ],
    };
    let err = Panel {
        title: "Centre-of-mass error |c - c_ref|".into(),
        y_label: "error (mm)",
        series: vec![Series::line(
            "",
            BLACK_,
            series(&log, |s| (s.com - s.com_ref).norm() * 1e3),
        )],
    };
    plot::figure(&out.join("quadruped_com.png"), (1200, 900), &[com, err])?;

    let normal = Panel {
        title: "Normal contact forces".into(),
        y_label: "force (N)",
        series: (0..4)
            .map(|k| Series::line(LEGS[k], PALETTE[k], series(&log, |s| s.lambda[3 * k + 2])))
            .collect(),
    };
    let mut cone: Vec<Series> = (0..4)
        .map(|k| {
            Series::line(
                LEGS[k],
                PALETTE[k],
                series(&log, |s| {
                    s.lambda[3 * k].hypot(s.lambda[3 * k + 1]) / s.lambda[3 * k + 2]
                }),
            )
        })
        .collect();
    cone.push(Series::dashed(
        "friction coefficient",
        GREY,
        series(&log, |_| settings.mu),
    ));
    let cone = Panel {
        title: "Friction cones: tangential / normal force".into(),
        y_label: "ratio",
        series: cone,
    };
    plot::figure(
        &out.join("quadruped_forces.png"),
        (1200, 900),
        &[normal, cone],
    )?;

    let names = ["HAA", "HFE", "KFE"];
    let panels: Vec<Panel> = (0..3)
        .map(|j| Panel {
            title: format!("Joint torques, {} joints", names[j]),
            y_label: "torque (N m)",
            series: (0..4)
                .map(|k| Series::line(LEGS[k], PALETTE[k], series(&log, |s| s.tau[3 * k + j])))
                .collect(),
        })
        .collect();
    plot::figure(&out.join("quadruped_torques.png"), (1200, 1200), &panels)?;
    println!("figures in {}", out.display());
    Ok(())
}
