//! Big models end in a module or a typed error, never in an aborted allocation or a rustc run
//! of unbounded cost: the generator estimates a module's size from the model's shape before
//! deriving anything ([`kanegen::estimate`]), refuses a model whose estimated memory exceeds
//! what the process may use, and a build script for an unoptimised build refuses a module too
//! large for rustc's debug builds (docs/big-models.md).

use std::path::PathBuf;
use std::process::{Command, Output};

use kanegen::model::{
    Base, Gravity, Joint, JointKind, Length, Link, Model, Mount, Param, ParamKind, Speed,
};
use kanegen::{Builder, Error, FunctionSet, Options};

/// A serial chain of `n` revolute links as URDF (axes cycling z, y, x; full inertias).
fn chain_urdf(n: usize) -> String {
    let axes = ["0 0 1", "0 1 0", "1 0 0"];
    let mut s =
        format!("<?xml version=\"1.0\"?>\n<robot name=\"chain{n}\">\n  <link name=\"l0\"/>\n");
    for i in 1..=n {
        s.push_str(&format!(
            "  <link name=\"l{i}\"><inertial><origin xyz=\"0.01 0.02 0.05\"/><mass value=\"1\"/>\
             <inertia ixx=\"0.01\" ixy=\"0.001\" ixz=\"0.0005\" iyy=\"0.012\" iyz=\"0.0002\" izz=\"0.009\"/></inertial></link>\n\
             <joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0.01 0.02 0.1\"/><axis xyz=\"{}\"/>\
             <limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>\n",
            i - 1,
            axes[i % 3]
        ));
    }
    s.push_str("</robot>\n");
    s
}

/// A serial chain of `n` revolute links built in memory, without bodies and unvalidated: enough
/// for the size estimate, which runs before the model is checked or derived.
fn chain_in_memory(n: usize) -> Model {
    let joint = |i: usize| Joint {
        name: format!("q{i}"),
        kind: JointKind::Revolute { speed: i - 1 },
        axis: [0.0, 0.0, 1.0],
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0, 0.0, 0.1].map(|coef| Length { coef, symbol: None }),
    };
    let mut links = vec![Link {
        name: "0".into(),
        mount: None,
        body: None,
    }];
    for i in 1..=n {
        links.push(Link {
            name: format!("l{i}"),
            mount: Some(Mount {
                parent: i - 1,
                joint: joint(i),
            }),
            body: None,
        });
    }
    Model {
        name: format!("chain{n}"),
        description: String::new(),
        source: "memory".into(),
        params: vec![Param {
            name: "g".into(),
            value: 9.81,
            kind: ParamKind::Gravity,
        }],
        speeds: (1..=n)
            .map(|i| Speed {
                name: format!("qd{i}"),
                coordinate: format!("q{i}"),
            })
            .collect(),
        links,
        base: Base::Fixed,
        gravity: Gravity {
            symbol: 0,
            direction: [0.0, 0.0, -1.0],
        },
        mimics: Vec::new(),
    }
}

#[test]
fn a_2000_link_chain_is_a_typed_error_before_anything_is_derived() {
    let model = chain_in_memory(2000);
    let e = kanegen::estimate(&model, &Options::default());
    assert_eq!(e.pairs, 2000 * 2001 / 2);
    let err = Builder::from_model(model)
        .memory_limit(6 << 30)
        .generate()
        .unwrap_err();
    assert!(matches!(err, Error::TooLarge { .. }), "{err}");
    let msg = err.to_string();
    for part in [
        "model `chain2000` is too large",
        "of memory",
        "6.0 GB",
        "Builder::functions",
    ] {
        assert!(msg.contains(part), "{msg} lacks {part}");
    }
}

/// The estimate is within a factor of two of the module emitted for a short chain, for the
/// default functions and for the mass matrix alone.
#[test]
fn the_estimate_is_within_a_factor_of_two_of_the_module() {
    let text = chain_urdf(12);
    let model = Model::from_urdf_str(&text, "chain12.urdf", &Default::default()).unwrap();
    for functions in [FunctionSet::default(), "mass_matrix".parse().unwrap()] {
        let options = Options {
            functions,
            ..Options::default()
        };
        let estimate = kanegen::estimate(&model, &options).rust_bytes as f64;
        let g = Builder::from_model(model.clone())
            .options(options)
            .generate()
            .unwrap();
        let ratio = g.source.len() as f64 / estimate;
        assert!((0.5..2.0).contains(&ratio), "{ratio}: {functions:?}");
    }
}

/// A scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kanegen-big-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The command line under an address-space limit of `kib` KiB (`ulimit -v`): the limit the
/// generator reads is the process's own.
#[cfg(target_os = "linux")]
fn cli_limited(kib: u64, urdf: &std::path::Path) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" stats \"$1\"",))
        .arg(env!("CARGO_BIN_EXE_kanegen"))
        .arg(urdf)
        .output()
        .unwrap()
}

#[cfg(target_os = "linux")]
#[test]
fn the_command_line_under_a_memory_limit_ends_in_a_typed_error() {
    let dir = scratch("ulimit");
    let urdf = dir.join("chain300.urdf");
    std::fs::write(&urdf, chain_urdf(300)).unwrap();
    let o = cli_limited(2_000_000, &urdf);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert!(stderr.contains("model `chain300` is too large"), "{stderr}");
    assert!(
        stderr.contains("more than the 1.9 GB this process may use"),
        "{stderr}"
    );
    assert!(!stderr.contains("memory allocation"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Runs [`child`] in a new process as a build script of a crate built at `opt_level`.
fn run_child(what: &str, out_dir: &PathBuf, opt_level: &str) -> Output {
    Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "child", "--nocapture", "--test-threads=1"])
        .env("KANEGEN_BIG_MODELS_CHILD", what)
        .env("OUT_DIR", out_dir)
        .env("CARGO", "cargo")
        .env("OPT_LEVEL", opt_level)
        .output()
        .unwrap()
}

/// The child process of the tests below (does nothing unless `KANEGEN_BIG_MODELS_CHILD` is
/// set): a build script generating a chain.
#[test]
fn child() {
    let Some(what) = std::env::var_os("KANEGEN_BIG_MODELS_CHILD") else {
        return;
    };
    let dir = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    let (n, limit) = match what.to_str().unwrap() {
        "chain100" => (100, kanegen::DEFAULT_UNOPTIMISED_LIMIT),
        "chain4" => (4, 1_000),
        other => panic!("unknown child task {other}"),
    };
    let urdf = dir.join(format!("chain{n}.urdf"));
    std::fs::write(&urdf, chain_urdf(n)).unwrap();
    Builder::new(urdf).unoptimised_limit(limit).run();
}

/// The `cargo::error` lines a child printed.
fn errors(o: &Output) -> Vec<String> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| l.split_once("cargo::error=").map(|(_, e)| e.to_owned()))
        .collect()
}

#[test]
fn a_100_link_chain_for_a_debug_build_is_a_typed_error_before_rustc_runs() {
    let dir = scratch("debug100");
    let o = run_child("chain100", &dir, "0");
    let errors = errors(&o);
    assert_eq!(errors.len(), 1, "{o:?}");
    for part in [
        "model `chain100` is too large",
        "unoptimised (debug) build",
        "opt-level = 1",
        "Builder::unoptimised_limit",
    ] {
        assert!(errors[0].contains(part), "{} lacks {part}", errors[0]);
    }
    assert!(!dir.join("chain100.rs").exists());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_unoptimised_limit_applies_only_to_unoptimised_builds() {
    let dir = scratch("optlevel");
    let o = run_child("chain4", &dir, "0");
    assert_eq!(errors(&o).len(), 1, "{o:?}");
    assert!(!dir.join("chain4.rs").exists());
    let o = run_child("chain4", &dir, "1");
    assert!(errors(&o).is_empty(), "{o:?}");
    assert!(dir.join("chain4.rs").is_file());
    let _ = std::fs::remove_dir_all(dir);
}
