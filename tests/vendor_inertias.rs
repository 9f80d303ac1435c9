//! Robot descriptions with the non-physical link inertias that vendors' files carry (CAD exports,
//! placeholder values on sensor links; `tests/data/SOURCES.md` lists what each file imitates)
//! load with the default `UrdfOptions`, as the reference libraries load them: each such inertia
//! is kept as written with one note naming the link, the generated M, c, g, τ agree with the
//! reference recursion, and the mass matrix and gravity agree with the energies computed from
//! the URDF as written. An inertia zero to rounding is zero, without a note.

mod common;
#[path = "common/raw_urdf.rs"]
mod raw_urdf;

use common::*;
use kanegen::{Builder, FunctionId, Options};
use kanegen_model::{ModelErrorKind, NonPhysicalInertia, UrdfImport, UrdfOptions};
use kanegen_reference::Reference;
use raw_urdf::RawUrdf;

/// One test file: its name, the links whose inertia is non-physical, and the violation printed
/// for each.
const FILES: &[(&str, &[(&str, &str)])] = &[
    (
        "anymal_c_camera",
        &[("depth_camera_front_camera", "triangle inequality")],
    ),
    (
        "tiago_antenna",
        &[("base_antenna_left_link", "not positive semi-definite")],
    ),
    ("allegro_link_11", &[("link_11.0", "triangle inequality")]),
    ("icub_ankle", &[]),
    (
        "pr2_sensor_mount",
        &[("sensor_mount_link", "triangle inequality")],
    ),
    ("xarm6_gripper_link3", &[("link3", "triangle inequality")]),
    ("xarm6_link3", &[("link3", "triangle inequality")]),
];

/// The size of each violation, as the note prints it (`by 50.68 % of the largest`).
const PERCENT: &[(&str, &str)] = &[
    ("anymal_c_camera", "50.68 %"),
    ("tiago_antenna", "100.37 %"),
    ("allegro_link_11", "20.37 %"),
    ("pr2_sensor_mount", "80.00 %"),
    ("xarm6_gripper_link3", "13.46 %"),
    ("xarm6_link3", "13.46 %"),
];

fn text(file: &str) -> String {
    std::fs::read_to_string(root().join(format!("tests/data/{file}.urdf"))).unwrap()
}

fn import(file: &str, options: &UrdfOptions) -> UrdfImport {
    UrdfImport::parse(&text(file), file, options).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// The notes of an import that keep a non-physical inertia as written.
fn kept_as_written(import: &UrdfImport) -> Vec<&String> {
    import
        .notes
        .iter()
        .filter(|n| n.contains("principal moments") && n.ends_with("; kept as written"))
        .collect()
}

#[test]
fn vendor_inertias_load_as_written_with_one_note_per_link() {
    for &(file, links) in FILES {
        let import = import(file, &UrdfOptions::default());
        let kept = kept_as_written(&import);
        assert_eq!(kept.len(), links.len(), "{file}: {kept:?}");
        for ((link, what), note) in links.iter().zip(&kept) {
            assert!(note.starts_with(&format!("link `{link}`: ")), "{note}");
            assert!(note.contains(what), "{note}");
            let percent = PERCENT.iter().find(|(f, _)| *f == file).unwrap().1;
            assert!(
                note.contains(&format!("by {percent} of the largest")),
                "{note}"
            );
        }
    }
}

#[test]
fn a_rounding_level_inertia_imports_silently_as_zero() {
    let import = import("icub_ankle", &UrdfOptions::default());
    assert!(
        !import.notes.iter().any(|n| n.contains("l_ankle_2")),
        "{:?}",
        import.notes
    );
    // A point mass of 0.2 kg at (0.03, 0.01, −0.02): J = m (|S|² 1 − S Sᵀ), nothing more.
    let m = &import.model;
    let p = |name: &str| m.params[m.param_index(name).unwrap()].value;
    let s = [0.03, 0.01, -0.02];
    let s2: f64 = s.iter().map(|x| x * x).sum();
    assert!((p("XX_l_ankle_2") - 0.2 * (s2 - s[0] * s[0])).abs() < 1e-15);
    assert!((p("XZ_l_ankle_2") + 0.2 * s[0] * s[2]).abs() < 1e-15);
    assert!((p("ZZ_l_ankle_2") - 0.2 * (s2 - s[2] * s[2])).abs() < 1e-15);
}

/// The generated dynamics (lowered M, c, g, τ) against the reference recursion at the file's
/// own parameters (the inertias as written), and g and M against the energies of the URDF.
#[test]
fn vendor_inertias_give_the_reference_dynamics() {
    let functions = [
        FunctionId::MassMatrix,
        FunctionId::Coriolis,
        FunctionId::Gravity,
        FunctionId::InverseDynamics,
    ];
    for &(file, _) in FILES {
        let model = import(file, &UrdfOptions::default()).model;
        let options = Options {
            functions: functions.into_iter().collect(),
            ..Options::default()
        };
        let g = Builder::from_model(model.clone())
            .options(options)
            .generate()
            .unwrap_or_else(|e| panic!("{file}: generation: {e}"));
        let n = model.dof();
        let p = model.param_values();
        let reference = Reference::<f64>::with_params(&model, &p);
        let mut r = rng(0x51 + n as u64);
        for _ in 0..10 {
            let (q, u, ud) = random_state(&mut r, n);
            let expected = [
                drows(&reference.mass_matrix(&q)),
                dvec(&reference.coriolis(&q, &u)),
                dvec(&reference.gravity(&q)),
                dvec(&reference.inverse_dynamics(&q, &u, &ud)),
            ];
            for (f, want) in functions.iter().zip(&expected) {
                let got = g.lowered.evaluate(*f, &p, &q, &u, &ud);
                let e = rel_err(&got, want, 1.0);
                assert!(e < 1e-12, "{file}: {f:?}: {e:e}");
            }
        }
        let raw = RawUrdf::new(&text(file), &model);
        let (worst_g, worst_t) = raw.energy_errors(&model, 3, 11);
        assert!(
            worst_g < 1e-6 && worst_t < 1e-6,
            "{file}: {worst_g:e} {worst_t:e}"
        );
    }
}

/// The options still refuse or repair them: `Error` refuses the first such link, a tolerance
/// below the violation refuses it too, `Repair` loads a physical inertia with a note.
#[test]
fn vendor_inertias_are_refused_or_repaired_on_request() {
    for &(file, links) in FILES {
        let Some((link, _)) = links.first() else {
            continue;
        };
        for options in [
            UrdfOptions {
                non_physical_inertia: NonPhysicalInertia::Error,
                ..UrdfOptions::default()
            },
            UrdfOptions {
                inertia_tolerance: 0.05,
                ..UrdfOptions::default()
            },
        ] {
            let e = UrdfImport::parse(&text(file), file, &options).unwrap_err();
            assert!(
                matches!(&e.kind, ModelErrorKind::UrdfNonPhysicalInertial { link: l, .. } if l == link),
                "{file}: {e}"
            );
        }
        let repaired = import(
            file,
            &UrdfOptions {
                non_physical_inertia: NonPhysicalInertia::Repair,
                ..UrdfOptions::default()
            },
        );
        assert!(
            repaired
                .notes
                .iter()
                .any(|n| n.starts_with(&format!("link `{link}`: ")) && n.contains("repaired")),
            "{file}: {:?}",
            repaired.notes
        );
    }
}
