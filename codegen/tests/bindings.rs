//! The bindings crates: Krang's committed Python package (`python/krang_dynamics`) and C library
//! (`c/krang`) are what `kanegen python` and `kanegen c` write for `models/krang.toml`, and the
//! modules bindings cannot wrap are typed errors. What the crates compute is tested in
//! `python/tests` (`.ci/bindings`). After a change of the generator, accept the new files with
//! `KANEGEN_ACCEPT_GOLDEN=1 cargo test -p kanegen --test bindings`.

use std::path::{Path, PathBuf};

use kanegen::bindings::{BindingsError, BindingsOptions, KanegenSource};
use kanegen::{Builder, Error, FunctionId, FunctionSet};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Writes the crate with `write` into `committed` (accepting) or into a scratch directory, and
/// checks that every file equals the committed one (in `Cargo.toml`, the lines of the kanegen
/// path dependencies differ with the directory and are left out).
fn check(committed: &Path, write: impl Fn(&Path, &BindingsOptions) -> Result<Vec<PathBuf>, Error>) {
    let accept = std::env::var_os("KANEGEN_ACCEPT_GOLDEN").is_some();
    let dir = if accept {
        committed.to_path_buf()
    } else {
        std::env::temp_dir().join(format!(
            "kanegen-bindings-{}-{}",
            std::process::id(),
            committed.file_name().unwrap().to_string_lossy()
        ))
    };
    let options = BindingsOptions {
        name: Some(
            committed
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned(),
        ),
        kanegen: KanegenSource::Path(root()),
    };
    let written = write(&dir, &options).expect("the crate is written");
    let without_paths = |text: String| -> String {
        text.lines()
            .filter(|l| !l.starts_with("kanegen-"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    for path in written {
        let relative = path.strip_prefix(&dir).unwrap();
        let fresh = std::fs::read_to_string(&path).unwrap();
        let old = std::fs::read_to_string(committed.join(relative)).unwrap_or_default();
        assert!(
            without_paths(fresh) == without_paths(old),
            "{} is out of date: run `KANEGEN_ACCEPT_GOLDEN=1 cargo test -p kanegen --test \
             bindings` and commit it",
            committed.join(relative).display()
        );
    }
    if !accept {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn committed_krang_python_package_is_what_kanegen_python_writes() {
    let functions = FunctionSet::default()
        .union(FunctionSet::kinematics())
        .with(FunctionId::NonlinearEffects);
    let builder = Builder::new(root().join("models/krang.toml"))
        .functions(functions)
        .mirrored_lanes(true);
    check(&root().join("python/krang_dynamics"), |dir, o| {
        builder.python_crate(dir, o)
    });
}

#[test]
fn committed_krang_c_library_is_what_kanegen_c_writes() {
    let builder = Builder::new(root().join("models/krang.toml")).mirrored_lanes(true);
    check(&root().join("c/krang"), |dir, o| builder.c_crate(dir, o));
}

#[test]
fn baked_and_f32_modules_and_bad_names_are_refused() {
    let dir = std::env::temp_dir().join(format!("kanegen-bindings-refused-{}", std::process::id()));
    let model = root().join("models/two-link.toml");
    let o = BindingsOptions::default();
    let refused = |r: Result<Vec<PathBuf>, Error>| {
        matches!(r, Err(Error::Bindings(BindingsError::Unsupported { .. })))
    };
    assert!(refused(
        Builder::new(&model).baked(true).python_crate(&dir, &o)
    ));
    assert!(refused(
        Builder::new(&model)
            .precision(kanegen::Precision::F32)
            .c_crate(&dir, &o)
    ));
    for name in ["", "1robot", "my-robot", "robot.py"] {
        let o = BindingsOptions {
            name: Some(name.into()),
            ..BindingsOptions::default()
        };
        let r = Builder::new(&model).python_crate(&dir, &o);
        assert!(
            matches!(r, Err(Error::Bindings(BindingsError::BadName { .. }))),
            "{name}"
        );
    }
    assert!(!dir.exists(), "nothing is written for a refused crate");
}

/// A floating model's `q` has NQ = DOF + 1 entries, which the bindings' arrays do not hold: both
/// kinds of crate are refused with a typed error naming the model and the fix, and nothing is
/// written.
#[test]
fn floating_base_models_are_refused_with_a_typed_error() {
    let dir =
        std::env::temp_dir().join(format!("kanegen-bindings-floating-{}", std::process::id()));
    let model = root().join("models/floating-hopper.toml");
    let o = BindingsOptions::default();
    for r in [
        Builder::new(&model).python_crate(&dir, &o),
        Builder::new(&model).c_crate(&dir, &o),
    ] {
        let err = r.expect_err("a floating base is refused");
        let text = err.to_string();
        assert!(
            matches!(err, Error::Bindings(BindingsError::FloatingBase { .. })),
            "{text}"
        );
        assert!(
            text.contains("floating-hopper") && text.contains("NQ"),
            "{text}"
        );
    }
    assert!(!dir.exists(), "nothing is written for a refused crate");
}
