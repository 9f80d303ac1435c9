//! The real-world corpus (`tests/corpus/`, sources and licences in `tests/corpus/SOURCES.md`):
//! fifteen third-party robot descriptions of different kinds — arms with grippers, legged robots,
//! humanoids, hands, a dual-arm robot and mobile manipulators — each imported with the default
//! `UrdfOptions`, generated (derivation, lowering and emission of M, c, g, τ), and the lowered
//! programs (the interpreter of the straight-line code that is emitted; no rustc per file)
//! compared with the numeric reference recursion on random states, at the file's own
//! parameters and at random physical parameters.
//!
//! Each file is imported with the defaults, as a fixed-base tree rooted at its root link (as the
//! files are written: the free-flyer is what Pinocchio adds on load, not part of the URDF);
//! `tests/floating_base.rs` and `codegen/tests/floating_base.rs` check legged robots on a
//! floating base (`UrdfOptions::floating()`).

mod common;
#[path = "common/raw_urdf.rs"]
mod raw_urdf;

use common::*;
use kanegen::{Builder, FunctionId, Options};
use kanegen_model::{MimicMode, Model, ModelErrorKind, UrdfImport, UrdfOptions};
use kanegen_reference::Reference;
use kanegen_reference::random::random_physical_params;
use raw_urdf::RawUrdf;

/// Relative to the largest entry (absolute below 1).
const TOL: f64 = 1e-10;

/// One corpus file and what its import must give.
struct Entry {
    /// `tests/corpus/<file>.urdf`.
    file: &'static str,
    /// Speeds of the imported tree (every moving joint, `<mimic>` joints included); the
    /// generated functions take `dof − mimic` independent speeds (exact mimic constraints).
    dof: usize,
    /// Joints with a `<mimic>` element.
    mimic: usize,
    /// Whether the mimic joints and their masters are made fixed (see [`mimic_as_independent`]).
    fix_mimic: bool,
    /// The largest violation of inertia physics among its links (semi-definiteness or the
    /// triangle inequality, relative to the largest principal moment) if it exceeds 5 %: the
    /// defaults load such inertias as written (as Pinocchio loads them), with a note per link,
    /// and a `UrdfOptions::inertia_tolerance` below this value refuses the file.
    non_physical: Option<f64>,
}

/// The corpus, as listed in `tests/corpus/SOURCES.md` and docs/urdf.md.
const CORPUS: &[Entry] = &[
    Entry {
        file: "panda",
        dof: 9,
        mimic: 1,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "ur5_gripper",
        dof: 6,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "kinova",
        dof: 6,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "baxter",
        dof: 19,
        mimic: 2,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "anymal_c",
        dof: 12,
        mimic: 0,
        fix_mimic: false,
        non_physical: Some(1.0),
    },
    Entry {
        file: "anymal_b_kinova",
        dof: 18,
        mimic: 0,
        fix_mimic: false,
        non_physical: Some(1.0),
    },
    Entry {
        file: "solo12",
        dof: 12,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "hyq",
        dof: 12,
        mimic: 0,
        fix_mimic: false,
        non_physical: Some(1.0),
    },
    Entry {
        file: "bolt",
        dof: 6,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "romeo",
        dof: 31,
        mimic: 44,
        fix_mimic: true,
        non_physical: Some(0.7958),
    },
    Entry {
        file: "simple_humanoid",
        dof: 29,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "allegro_right_hand",
        dof: 16,
        mimic: 0,
        fix_mimic: false,
        non_physical: Some(0.2824),
    },
    Entry {
        file: "finger_edu",
        dof: 3,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
    Entry {
        file: "pr2",
        dof: 30,
        mimic: 10,
        fix_mimic: false,
        non_physical: Some(0.8),
    },
    Entry {
        file: "twodofs",
        dof: 2,
        mimic: 0,
        fix_mimic: false,
        non_physical: None,
    },
];

fn text(entry: &Entry) -> String {
    let path = root()
        .join("tests/corpus")
        .join(format!("{}.urdf", entry.file));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A file with its `<mimic>` elements removed, i.e. each mimic joint an independent coordinate —
/// Pinocchio's behaviour, as `MimicMode::Independent` imports it. With `fixed`, mimic joints and
/// the joints they copy are made fixed instead (Romeo: its hands' links are massless, so a hand
/// joint moves nothing and M is singular, a typed error, with or without the constraints).
fn mimic_as_independent(text: &str, fixed: bool) -> String {
    let mut robot = urdf_rs::read_from_string(text).expect("corpus file parses");
    let masters: Vec<String> = robot
        .joints
        .iter()
        .filter_map(|j| j.mimic.as_ref().map(|m| m.joint.clone()))
        .collect();
    for joint in &mut robot.joints {
        let mimics = joint.mimic.take().is_some();
        if fixed && (mimics || masters.contains(&joint.name)) {
            joint.joint_type = urdf_rs::JointType::Fixed;
        }
    }
    urdf_rs::write_to_string(&robot).expect("urdf-rs writes what it read")
}

/// The text the corpus imports: the file as it is (mimic joints as exact constraints), except
/// for the files whose mimic joints are fixed.
fn imported_text(entry: &Entry) -> String {
    let text = text(entry);
    if entry.fix_mimic {
        mimic_as_independent(&text, entry.fix_mimic)
    } else {
        text
    }
}

fn import(entry: &Entry) -> UrdfImport {
    let text = imported_text(entry);
    UrdfImport::parse(&text, entry.file, &options(entry))
        .unwrap_or_else(|e| panic!("{}: {e}", entry.file))
}

/// The import options of a corpus file: the defaults.
fn options(_entry: &Entry) -> UrdfOptions {
    UrdfOptions::default()
}

/// Worst relative errors of the lowered M, c, g, τ against the reference over `draws` draws
/// (the first at the file's own parameters). With mimic joints the reference runs on the whole
/// tree at the expanded state (`q_all = T q + b`, `u_all = T u`, `u̇_all = T u̇`) and its results
/// are projected (`Tᵀ M T`, `Tᵀ c`, …).
fn check(entry: &Entry, draws: usize) -> [f64; 4] {
    let model: Model = import(entry).model;
    assert_eq!(model.dof(), entry.dof, "{}: speeds", entry.file);
    let constrained = if entry.fix_mimic { 0 } else { entry.mimic };
    assert_eq!(model.mimics.len(), constrained, "{}: mimics", entry.file);
    let functions = [
        FunctionId::MassMatrix,
        FunctionId::Coriolis,
        FunctionId::Gravity,
        FunctionId::InverseDynamics,
    ];
    let options = Options {
        functions: functions.into_iter().collect(),
        ..Options::default()
    };
    let g = Builder::from_model(model.clone())
        .options(options)
        .generate()
        .unwrap_or_else(|e| panic!("{}: generation: {e}", entry.file));
    assert!(g.source.contains("pub fn mass_matrix"), "{}", entry.file);
    let n = model.independent_dof();
    let mut r = rng(0xC0 + n as u64);
    let mut worst = [0.0f64; 4];
    for draw in 0..draws {
        let p = if draw == 0 {
            model.param_values()
        } else {
            random_physical_params(&model, &mut r)
        };
        let (q, u, ud) = random_state(&mut r, n);
        let reference = Reference::<f64>::with_params(&model, &p);
        let (qa, ua, uda) = (
            model.expand_coordinates(&q),
            model.expand_speeds(&u),
            model.expand_speeds(&ud),
        );
        let expected = [
            model.project_matrix(&drows(&reference.mass_matrix(&qa))),
            model.project_forces(&dvec(&reference.coriolis(&qa, &ua))),
            model.project_forces(&dvec(&reference.gravity(&qa))),
            model.project_forces(&dvec(&reference.inverse_dynamics(&qa, &ua, &uda))),
        ];
        for (i, f) in functions.iter().enumerate() {
            let l = g.lowered.evaluate(*f, &p, &q, &u, &ud);
            assert!(l.iter().all(|x| x.is_finite()), "{}: {f:?}", entry.file);
            worst[i] = worst[i].max(rel_err(&l, &expected[i], 1.0));
        }
    }
    eprintln!(
        "{:<20} {:>3} speeds, {} draws: worst relative error M {:.1e} c {:.1e} g {:.1e} tau {:.1e}",
        entry.file, n, draws, worst[0], worst[1], worst[2], worst[3]
    );
    assert!(
        worst.iter().all(|e| *e < TOL),
        "{}: {worst:?} exceeds {TOL}",
        entry.file
    );
    worst
}

/// Draws per file: fewer for the large trees (the reference recursion costs O(n²) per call).
fn draws(entry: &Entry) -> usize {
    if entry.dof > 20 { 4 } else { 10 }
}

#[test]
fn every_corpus_robot_matches_the_reference() {
    for entry in CORPUS {
        check(entry, draws(entry));
    }
}

/// Every corpus robot (mimic joints, fixed-joint merges, many branches) is emitted with the
/// batched functions in both layouts and with mirrored subtrees in lanes, without an error or
/// a panic. Regression: batched emission for a model with mimic joints panicked (an index out
/// of bounds), which no Krang-only test could see. (The emitted batched source is compiled
/// for Krang, with runtime and baked parameters, and the mimic gripper by the build scripts.)
#[test]
fn every_corpus_robot_emits_batched_and_lane_paired_code() {
    for entry in CORPUS {
        let model: Model = import(entry).model;
        let functions = [FunctionId::MassMatrix, FunctionId::Coriolis];
        let options = Options {
            functions: functions.into_iter().collect(),
            ..Options::default()
        };
        let g = kanegen::Builder::from_model(model)
            .options(options)
            .batch(true)
            .mirrored_lanes(true)
            .generate()
            .unwrap_or_else(|e| panic!("{}: generation: {e}", entry.file));
        for f in ["mass_matrix_batch_into<", "coriolis_batch_soa_into<"] {
            assert!(g.source.contains(f), "{}: {f}", entry.file);
        }
    }
}

#[test]
fn corpus_covers_ten_robots_of_different_kinds() {
    assert!(CORPUS.len() >= 10);
    let listed = std::fs::read_to_string(root().join("tests/corpus/SOURCES.md")).unwrap();
    for entry in CORPUS {
        assert!(
            listed.contains(&format!("`{}.urdf`", entry.file)),
            "{} has no source and licence in SOURCES.md",
            entry.file
        );
    }
}

/// Every import decision (merged fixed links, kept zero-mass inertias, tolerated inertias,
/// snapped angles) is listed; a file without fixed joints would list nothing, the corpus does.
#[test]
fn corpus_imports_list_their_decisions() {
    for entry in CORPUS {
        let import = import(entry);
        if text(entry).contains("type=\"fixed\"") {
            assert!(!import.notes.is_empty(), "{}: no notes", entry.file);
        }
    }
}

/// Romeo's finger links are massless: with its 44 mimic finger joints as independent
/// coordinates (Pinocchio's behaviour) a hand joint moves nothing and the import is the typed
/// `SingularMassMatrix` error naming the hand's speed, which is why the corpus fixes them.
#[test]
fn romeo_with_independent_mimic_fingers_has_a_singular_mass_matrix() {
    let entry = CORPUS.iter().find(|e| e.file == "romeo").unwrap();
    let text = mimic_as_independent(&text(entry), false);
    let Err(err) = UrdfImport::parse(&text, entry.file, &options(entry)) else {
        panic!("romeo with independent mimic fingers loads");
    };
    assert!(
        matches!(&err.kind, ModelErrorKind::SingularMassMatrix { speed, .. } if speed == "qd_LHand"),
        "{err}"
    );
}

/// The files with mimic joints import with exact constraints by default (one speed fewer per
/// mimic joint) and as Pinocchio does with `MimicMode::Independent` (every joint a speed).
#[test]
fn corpus_files_with_mimic_joints_import_with_exact_constraints() {
    for entry in CORPUS.iter().filter(|e| e.mimic > 0 && !e.fix_mimic) {
        let exact = UrdfImport::parse(&text(entry), entry.file, &options(entry))
            .unwrap_or_else(|e| panic!("{}: {e}", entry.file))
            .model;
        assert_eq!(exact.dof(), entry.dof, "{}", entry.file);
        assert_eq!(
            exact.independent_dof(),
            entry.dof - entry.mimic,
            "{}",
            entry.file
        );
        let independent = UrdfImport::parse(
            &text(entry),
            entry.file,
            &UrdfOptions {
                mimic: MimicMode::Independent,
                ..options(entry)
            },
        )
        .unwrap_or_else(|e| panic!("{}: {e}", entry.file))
        .model;
        assert_eq!(independent.independent_dof(), entry.dof, "{}", entry.file);
    }
}

/// The files whose inertias break physics by more than 5 % load with the default options, with
/// a note for each such link, and are typed errors in URDF terms (naming a link, `<inertial>`
/// and the option) with the tolerance just below their worst violation: the recorded violation
/// is the file's worst.
#[test]
fn corpus_files_with_non_physical_inertias_load_with_notes_and_a_tolerance_refuses_them() {
    for entry in CORPUS {
        let mut text = text(entry);
        if entry.mimic > 0 {
            text = mimic_as_independent(&text, entry.fix_mimic);
        }
        let defaults = UrdfImport::parse(&text, entry.file, &UrdfOptions::default())
            .unwrap_or_else(|e| panic!("{}: {e}", entry.file));
        let Some(violation) = entry.non_physical else {
            continue;
        };
        assert!(
            defaults
                .notes
                .iter()
                .any(|n| n.ends_with("; kept as written") && n.contains("principal moments")),
            "{}: {:?}",
            entry.file,
            defaults.notes
        );
        let below = UrdfOptions {
            inertia_tolerance: violation - 1e-3,
            ..UrdfOptions::default()
        };
        let err = UrdfImport::parse(&text, entry.file, &below)
            .err()
            .unwrap_or_else(|| panic!("{}: the worst violation is below {violation}", entry.file));
        assert!(
            matches!(err.kind, ModelErrorKind::UrdfNonPhysicalInertial { .. }),
            "{}: {err}",
            entry.file
        );
        assert!(err.to_string().contains("inertia_tolerance"), "{err}");
        let at = UrdfOptions {
            inertia_tolerance: violation + 1e-6,
            ..UrdfOptions::default()
        };
        assert!(
            UrdfImport::parse(&text, entry.file, &at).is_ok(),
            "{}: a violation above {violation}",
            entry.file
        );
    }
}

/// The importer against the raw URDF: for every corpus file, g(q) of the generated code is the
/// gradient of the potential energy and ½ uᵀ M(q) u the kinetic energy, both computed directly
/// from the URDF's joints and `<inertial>`s as written (central differences), so fixed-joint
/// merging, rpy conventions, axis normalisation and inertia rotation are checked independently of
/// the importer (the reference recursion reads the importer's model).
#[test]
fn corpus_dynamics_match_energies_of_the_raw_urdf() {
    for entry in CORPUS {
        let model = import(entry).model;
        let raw = RawUrdf::new(&imported_text(entry), &model);
        let (worst_g, worst_t) = raw.energy_errors(&model, 3, 7 + model.dof() as u64);
        eprintln!(
            "{:<20} g vs dV/dq {:.1e}, kinetic energy {:.1e}",
            entry.file, worst_g, worst_t
        );
        assert!(
            worst_g < 1e-6 && worst_t < 1e-6,
            "{}: {worst_g:e} {worst_t:e}",
            entry.file
        );
    }
}
