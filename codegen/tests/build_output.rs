//! What a build prints: the URDF import decisions that change the numbers, one
//! `cargo:warning=` line per kind ([`kanegen::Generated::warnings`]), and an error once.
//!
//! `Builder::build` and `Builder::run` print to standard output and may exit, so they run in a
//! child process: this test binary again, running only [`child`] with
//! `KANEGEN_BUILD_OUTPUT_CHILD` set.

use std::path::PathBuf;
use std::process::{Command, Output};

use kanegen::Builder;
use kanegen::model::{AngleSnap, UrdfImport, UrdfOptions};

/// A two-joint arm written the way CAD exports write it: `rpy="1.5708 …"` for π/2, and a tool
/// flange on a fixed joint.
const ARM: &str = r#"<?xml version="1.0"?>
<robot name="snap_arm">
  <link name="base"/>
  <link name="upper">
    <inertial><mass value="1.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="lower">
    <inertial><origin xyz="0 0 0.2"/><mass value="0.8"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="flange">
    <inertial><mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.3" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="0 0 0.4" rpy="-1.5708 0 1.5708"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <joint name="tool" type="fixed">
    <parent link="lower"/><child link="flange"/>
    <origin xyz="0 0 0.3"/>
  </joint>
</robot>"#;

/// The summary lines of [`ARM`] imported with the default options.
const WARNINGS: [&str; 2] = [
    "kanegen: arm.urdf: 3 angles snapped to a multiple of π/2 (shoulder, elbow); UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written",
    "kanegen: arm.urdf: 1 link merged through fixed joints (mass and inertia added to the parent's parameters) (flange); UrdfOptions::link_frames keeps a frame for each",
];

fn import(options: &UrdfOptions) -> UrdfImport {
    UrdfImport::parse(ARM, "arm.urdf", options).expect("the arm imports")
}

#[test]
fn snapped_angles_and_merged_links_are_summarised_once_per_kind() {
    let g = Builder::from_import(import(&UrdfOptions::default()))
        .generate()
        .expect("generates");
    assert_eq!(g.warnings(), WARNINGS);
    // Every note, one per angle, stays in the generated file's header.
    assert_eq!(g.notes.iter().filter(|n| n.contains("snapped")).count(), 3);
    for note in &g.notes {
        assert!(g.source.contains(note.as_str()), "{note}");
    }
}

#[test]
fn angles_kept_as_written_print_no_snap_warning() {
    let options = UrdfOptions {
        snap_angles: AngleSnap::Off,
        ..UrdfOptions::default()
    };
    let g = Builder::from_import(import(&options))
        .generate()
        .expect("generates");
    assert_eq!(g.warnings(), WARNINGS[1..]);
}

#[test]
fn toml_models_print_no_warnings() {
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/two-link.toml");
    let g = Builder::new(model).generate().expect("generates");
    assert!(g.warnings().is_empty());
}

/// A file of the workspace's `tests/data/` (URDF files with vendors' non-physical inertias).
fn data(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(file)
}

/// The warning line of a link inertia loaded as written.
fn kept_line(source: &str, link: &str, detail: &str) -> String {
    format!(
        "kanegen: {source}: link `{link}`: {detail}; kept as written; \
         UrdfOptions::non_physical_inertia = NonPhysicalInertia::Repair repairs it, Error refuses it"
    )
}

#[test]
fn each_non_physical_inertia_is_a_warning_line_of_its_own() {
    let two = ARM
        .replace(
            r#"<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="lower">"#,
            r#"<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.03"/></inertial>
  </link>
  <link name="lower">"#,
        )
        .replace(
            r#"<mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/>"#,
            r#"<mass value="0.1"/><inertia ixx="-0.0001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/>"#,
        );
    let import = UrdfImport::parse(&two, "arm.urdf", &UrdfOptions::default()).unwrap();
    let g = Builder::from_import(import).generate().expect("generates");
    let upper = "the inertia (ixx 0.01, ixy 0, ixz 0, iyy 0.01, iyz 0, izz 0.03) has the principal \
                 moments 1.000000e-2, 1.000000e-2, 3.000000e-2 about the centre of mass: triangle \
                 inequality: the largest exceeds the sum of the other two, by 33.33 % of the largest";
    let flange = "the inertia (ixx -0.0001, ixy 0, ixz 0, iyy 0.001, iyz 0, izz 0.001) has the \
                  principal moments -1.000000e-4, 1.000000e-3, 1.000000e-3 about the centre of \
                  mass: not positive semi-definite, by 10.00 % of the largest";
    assert_eq!(
        g.warnings(),
        [
            WARNINGS[0].to_owned(),
            WARNINGS[1].to_owned(),
            kept_line("arm.urdf", "upper", upper),
            kept_line("arm.urdf", "flange", flange),
        ]
    );
}

#[test]
fn a_build_prints_each_non_physical_inertia_once() {
    let dir = scratch("inertias");
    let o = run_child("inertias", &dir, true);
    assert!(o.status.success(), "{o:?}");
    let stdout = String::from_utf8(o.stdout).unwrap();
    let printed: Vec<&str> = stdout
        .lines()
        .filter_map(|l| l.split_once("cargo:warning=").map(|(_, w)| w))
        .filter(|w| w.contains("non_physical_inertia"))
        .collect();
    let source = data("pr2_sensor_mount.urdf").display().to_string();
    let detail = "the inertia (ixx 0.001, ixy 0, ixz 0, iyy 0.001, iyz 0, izz 0.01) has the \
                  principal moments 1.000000e-3, 1.000000e-3, 1.000000e-2 about the centre of \
                  mass: triangle inequality: the largest exceeds the sum of the other two, by \
                  80.00 % of the largest";
    assert_eq!(
        printed,
        [kept_line(&source, "sensor_mount_link", detail)],
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// A scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "kanegen-build-output-{name}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs [`child`] in a new process with `what` to do, as a build script would run
/// (`CARGO` and `OUT_DIR` set) or not.
fn run_child(what: &str, out_dir: &PathBuf, in_cargo: bool) -> Output {
    let mut cmd = Command::new(std::env::current_exe().unwrap());
    cmd.args(["--exact", "child", "--nocapture", "--test-threads=1"])
        .env("KANEGEN_BUILD_OUTPUT_CHILD", what)
        .env("OUT_DIR", out_dir);
    if in_cargo {
        cmd.env("CARGO", "cargo");
    } else {
        cmd.env_remove("CARGO");
    }
    cmd.output().unwrap()
}

/// The child process of the tests below (does nothing unless `KANEGEN_BUILD_OUTPUT_CHILD` is
/// set).
#[test]
fn child() {
    let Some(what) = std::env::var_os("KANEGEN_BUILD_OUTPUT_CHILD") else {
        return;
    };
    match what.to_str().unwrap() {
        "build" => {
            // Two modules of one model (runtime and baked parameters): the lines print once.
            let builder = Builder::from_import(import(&UrdfOptions::default()));
            builder.clone().run();
            builder.baked(true).run();
        }
        "inertias" => {
            // Two modules of a model with non-physical inertias: one line per link, once.
            let builder = Builder::urdf(data("pr2_sensor_mount.urdf"), UrdfOptions::default());
            builder.clone().run();
            builder.baked(true).run();
        }
        "fail" => Builder::new("no-such-model.toml").run(),
        other => panic!("unknown child task {other}"),
    }
}

#[test]
fn a_build_prints_each_warning_line_once() {
    let dir = scratch("build");
    let o = run_child("build", &dir, true);
    assert!(o.status.success(), "{o:?}");
    let stdout = String::from_utf8(o.stdout).unwrap();
    // (The test harness writes `test child ... ` before the first line.)
    let printed: Vec<&str> = stdout
        .lines()
        .filter_map(|l| l.split_once("cargo:warning=").map(|(_, w)| w))
        .collect();
    assert_eq!(printed, WARNINGS);
    // In-memory models have no file to watch; the module is named after the model.
    assert!(!stdout.contains("cargo:rerun-if-changed"), "{stdout}");
    assert!(dir.join("snap_arm.rs").is_file());
    assert!(dir.join("snap_arm_baked.rs").is_file());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_build_script_error_is_printed_once() {
    let dir = scratch("fail");
    let o = run_child("fail", &dir, true);
    let stdout = String::from_utf8(o.stdout.clone()).unwrap();
    let stderr = String::from_utf8(o.stderr.clone()).unwrap();
    // One `cargo::error` line, nothing on stderr, and a status of 0: cargo fails the build on
    // the line and prints it once (a failing status would make it dump both streams too).
    let errors: Vec<&str> = stdout.lines().filter(|l| l.contains("kanegen: ")).collect();
    assert_eq!(errors.len(), 1, "{stdout}");
    assert!(
        errors[0].contains("cargo::error=kanegen: no-such-model.toml"),
        "{stdout}"
    );
    assert!(!stderr.contains("kanegen"), "{stderr}");
    assert!(o.status.success(), "{o:?}");
    // Outside cargo: on stderr, once, and a failing status.
    let o = run_child("fail", &dir, false);
    let stdout = String::from_utf8(o.stdout.clone()).unwrap();
    let stderr = String::from_utf8(o.stderr.clone()).unwrap();
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert!(!stdout.contains("kanegen: "), "{stdout}");
    assert_eq!(
        stderr.matches("error: kanegen: no-such-model.toml").count(),
        1,
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_command_line_prints_the_warnings_on_stderr() {
    let dir = scratch("cli");
    let urdf = dir.join("arm.urdf");
    std::fs::write(&urdf, ARM).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_kanegen"))
        .args(["stats", urdf.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{o:?}");
    let stderr = String::from_utf8(o.stderr).unwrap();
    let label = urdf.display().to_string();
    let want: Vec<String> = WARNINGS
        .iter()
        .map(|w| format!("warning: {}", w.replace("arm.urdf", &label)))
        .collect();
    assert_eq!(stderr.lines().collect::<Vec<_>>(), want);
    let _ = std::fs::remove_dir_all(dir);
}
