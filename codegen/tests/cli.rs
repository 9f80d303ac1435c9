//! The `kanegen` command line, run as a binary: what `stats` and `show` print, options checked
//! before any work, and quiet output to a closed pipe.

use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn model(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../models")
        .join(name)
        .display()
        .to_string()
}

fn kanegen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kanegen"))
        .args(args)
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

#[test]
fn stats_explains_its_columns_and_what_to_run_next() {
    let o = kanegen(&["stats", &model("two-link.toml")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("function") && out.contains("inverse_dynamics"),
        "{out}"
    );
    for key in [
        "  K  ",
        "  D  ",
        "  temps",
        "  adds, muls, divs",
        "  sin/cos",
        "  flops",
        "  fma",
        "  live",
        "  lanes",
    ] {
        assert!(
            out.contains(key),
            "no explanation of `{}`:\n{out}",
            key.trim()
        );
    }
    assert!(out.contains("per call"), "{out}");
    assert!(out.contains("next:\n  kanegen listing MODEL"), "{out}");
}

#[test]
fn stats_counts_the_lane_pairs_of_mirrored_subtrees() {
    let row = |out: &str, name: &str| -> String {
        out.lines()
            .find(|l| l.starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no row {name}:\n{out}"))
            .to_owned()
    };
    let krang = model("krang.toml");
    let plain = stdout(&kanegen(&["stats", &krang]));
    let lanes = kanegen(&["stats", &krang, "--mirrored-lanes"]);
    assert!(lanes.status.success(), "{}", stderr(&lanes));
    let lanes = stdout(&lanes);
    for f in ["mass_matrix", "coriolis", "inverse_dynamics"] {
        let (a, b) = (row(&plain, f), row(&lanes, f));
        assert!(a.trim_end().ends_with(" -"), "{a}");
        let pairs: usize = b
            .split_whitespace()
            .last()
            .unwrap()
            .parse()
            .expect("a count");
        assert!(pairs > 100, "{b}");
        // The same operations, paired or not.
        let flops = |r: &str| r.split_whitespace().nth(8).map(str::to_owned);
        assert_eq!(flops(&a), flops(&b), "{a}\n{b}");
    }
}

#[test]
fn emit_batch_and_batch_feature_emit_the_batched_functions_gated_or_not() {
    let two_link = model("two-link.toml");
    let plain = stdout(&kanegen(&["emit", &two_link]));
    let batch = stdout(&kanegen(&["emit", &two_link, "--batch"]));
    let gated = stdout(&kanegen(&[
        "emit",
        &two_link,
        "--batch-feature",
        "sampling",
    ]));
    assert!(!plain.contains("pub fn mass_matrix_batch"));
    assert!(batch.contains("pub fn mass_matrix_batch_soa_into"));
    assert!(!batch.contains("cfg(feature"));
    assert!(gated.contains("pub fn mass_matrix_batch_soa_into"));
    assert!(gated.contains("#[cfg(feature = \"sampling\")]"));
    // The same module as the builder makes (`codegen/tests/batch_feature.rs` checks the gates).
    let built = kanegen::Builder::new(&two_link)
        .batch_feature("sampling")
        .generate()
        .unwrap()
        .source;
    assert_eq!(gated, built);
}

#[test]
fn show_prints_units_and_rounded_numbers() {
    let out = stdout(&kanegen(&["show", &model("two-link.toml")]));
    // 2.942658192538247 kg·m² in the file: six significant digits and the unit.
    assert!(
        out.contains("XX1 =      2.94266 kg·m²  inertia about the frame origin"),
        "{out}"
    );
    assert!(out.contains("m1  =       75.767 kg     mass"), "{out}");
    assert!(
        out.contains("MX1 =   -0.0475817 kg·m   first moment"),
        "{out}"
    );
    assert!(out.contains("XY1 =   9.23085e-5 kg·m²"), "{out}");
    assert!(out.contains("g   =         9.81 m/s²"), "{out}");
    assert!(out.contains("L1  =        0.499 m      length"), "{out}");
    assert!(
        out.contains("u[ 0] = qd_imu in rad/s (rate of q_imu in rad)"),
        "{out}"
    );
    assert!(out.contains("[body 1: m = 75.767 kg]"), "{out}");
    let krang = stdout(&kanegen(&["show", &model("krang.toml")]));
    assert!(
        krang.contains("u[ 0] = xd in m/s (rate of x in m)"),
        "{krang}"
    );
    assert!(krang.contains(" m      wheel radius"), "{krang}");
}

#[test]
fn unknown_commands_and_options_are_rejected_before_any_work() {
    // The model file does not exist: had any work started, that would be the error.
    let missing = "no-such-model.toml";
    for (args, message) in [
        (vec!["frobnicate", missing], "unknown command `frobnicate`"),
        (
            vec!["--baked", "stats", missing],
            "expected a command before `--baked`",
        ),
        (vec!["stats", missing, "--fast"], "unknown option `--fast`"),
        (
            vec!["show", missing, "--baked"],
            "`show` does not take `--baked`",
        ),
        (
            vec!["show", missing, "--functions", "all"],
            "`show` does not take `--functions`",
        ),
        (
            vec!["stats", missing, "--out", "x.rs"],
            "`stats` does not take `--out`",
        ),
        (
            vec!["listing", missing, "--f32"],
            "`listing` does not take `--f32`",
        ),
        (
            vec!["stats", missing, "--batch"],
            "`stats` does not take `--batch`",
        ),
        (
            vec!["emit", missing, "--batch-feature", "--f32"],
            "--batch-feature needs a cargo feature name",
        ),
        (
            vec!["stats", missing, "extra.toml"],
            "unexpected argument `extra.toml`",
        ),
        (vec!["emit"], "`emit` needs a model file"),
        (vec!["emit", missing, "--out"], "--out needs a value"),
        (
            vec!["stats", missing, "--functions", "everything"],
            "everything",
        ),
        (
            vec!["emit", missing, "--functions", ""],
            "--functions names no function",
        ),
        (
            vec!["stats", missing, "--functions", " , "],
            "--functions names no function",
        ),
        (vec![], "no command given"),
    ] {
        let o = kanegen(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(err.contains("usage: kanegen"), "{args:?}: {err}");
        assert!(
            !err.contains(missing) || message.contains(missing),
            "{args:?}: {err}"
        );
        assert!(o.stdout.is_empty(), "{args:?}");
    }
    // A well-formed command line on a missing file: the file error, status 1.
    let o = kanegen(&["stats", missing]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(missing), "{}", stderr(&o));
    assert!(kanegen(&["--help"]).status.success());
}

#[test]
fn help_lists_every_generated_function_and_group() {
    let o = kanegen(&["--help"]);
    assert!(o.status.success());
    let help = stdout(&o);
    for f in kanegen::FunctionId::all() {
        assert!(
            help.contains(f.name()),
            "`{}` missing from --help:\n{help}",
            f.name()
        );
    }
    for group in ["default ", "kinematics ", "regressors ", "all "] {
        assert!(
            help.contains(&format!("  {group}")),
            "group `{group}`:\n{help}"
        );
    }
    assert!(help.lines().all(|l| l.chars().count() <= 100), "{help}");
}

#[test]
fn output_to_a_closed_pipe_ends_quietly() {
    for args in [
        vec!["stats".to_owned(), model("two-link.toml")],
        vec!["show".to_owned(), model("krang.toml")],
        vec!["emit".to_owned(), model("two-link.toml")],
        vec!["listing".to_owned(), model("two-link.toml")],
        vec!["--help".to_owned()],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_kanegen"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the reading end before the command writes (as `| head -0` would).
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {:?} {}",
            o.status,
            stderr(&o)
        );
        assert!(o.stderr.is_empty(), "{args:?}: {}", stderr(&o));
    }
}
