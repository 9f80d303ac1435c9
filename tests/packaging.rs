//! What the publishable crates ship: both licence texts, `include` lists that name existing files,
//! and real copies (no symlinks, which break on Windows checkouts) of the shared model files and
//! licences that stay identical to the originals at the repository root.

mod common;

use std::path::{Path, PathBuf};

/// The workspace members, from the root `Cargo.toml`.
fn members() -> Vec<PathBuf> {
    let text = std::fs::read_to_string(common::root().join("Cargo.toml")).unwrap();
    let list = text
        .split("members = [")
        .nth(1)
        .and_then(|rest| rest.split(']').next())
        .expect("[workspace] members");
    list.split('"')
        .skip(1)
        .step_by(2)
        .map(|m| common::root().join(m))
        .collect()
}

/// The members that are published (no `publish = false`), with their manifests.
fn publishable() -> Vec<(PathBuf, String)> {
    let found: Vec<(PathBuf, String)> = members()
        .into_iter()
        .map(|dir| {
            let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
            (dir, manifest)
        })
        .filter(|(_, m)| !m.contains("publish = false"))
        .collect();
    let mut names: Vec<String> = found
        .iter()
        .flat_map(|(_, m)| strings(m, "name").into_iter().take(1))
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "kanegen",
            "kanegen-gpu",
            "kanegen-model",
            "kanegen-runtime",
            "krang-dynamics"
        ],
        "the publishable crates: the generator, the GPU runtime, the model, the runtime and \
         Krang's dynamics \
         (the baselines kanegen-reference and kanegen-rbd, the examples and the suite are \
         `publish = false`)"
    );
    found
}

/// The quoted strings of the manifest line that starts with `key = `.
fn strings(manifest: &str, key: &str) -> Vec<String> {
    manifest
        .lines()
        .find(|l| l.starts_with(&format!("{key} = ")))
        .map(|l| l.split('"').skip(1).step_by(2).map(str::to_owned).collect())
        .unwrap_or_default()
}

/// `path` is a regular file (not a symlink) with the bytes of `original`.
fn assert_real_copy(path: &Path, original: &Path) {
    let meta =
        std::fs::symlink_metadata(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        meta.file_type().is_file(),
        "{} is not a regular file",
        path.display()
    );
    assert!(
        std::fs::read(path).unwrap() == std::fs::read(original).unwrap(),
        "{} differs from {}: copy it again",
        path.display(),
        original.display()
    );
}

#[test]
fn the_repository_has_both_licence_texts() {
    let apache = std::fs::read_to_string(common::root().join("LICENSE-APACHE")).unwrap();
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    assert!(apache.contains("END OF TERMS AND CONDITIONS"));
    let mit = std::fs::read_to_string(common::root().join("LICENSE-MIT")).unwrap();
    assert!(mit.starts_with("MIT License"));
    let workspace = std::fs::read_to_string(common::root().join("Cargo.toml")).unwrap();
    assert!(workspace.contains(r#"license = "MIT OR Apache-2.0""#));
}

#[test]
fn every_publishable_crate_ships_both_licences_and_its_include_list_exists() {
    for (dir, manifest) in publishable() {
        let include = strings(&manifest, "include");
        assert!(!include.is_empty(), "{}: no include list", dir.display());
        for licence in ["LICENSE-MIT", "LICENSE-APACHE"] {
            assert!(
                include.iter().any(|i| i == licence),
                "{}: {licence}",
                dir.display()
            );
            assert_real_copy(&dir.join(licence), &common::root().join(licence));
        }
        for entry in include.iter().filter(|i| !i.contains('*')) {
            assert!(
                dir.join(entry).is_file(),
                "{}: include names missing {entry}",
                dir.display()
            );
        }
        for readme in strings(&manifest, "readme") {
            assert!(
                dir.join(&readme).is_file(),
                "{}: readme {readme}",
                dir.display()
            );
        }
    }
}

#[test]
fn krang_dynamics_model_files_are_real_copies_of_models() {
    let crate_dir = common::root().join("crates/krang-dynamics");
    for name in ["krang.toml", "krang-fixed-wheels.toml", "two-link.toml"] {
        assert_real_copy(
            &crate_dir.join(name),
            &common::root().join("models").join(name),
        );
    }
}

/// `"1.89"` or `"1.89.0"` as `(1, 89, 0)`.
fn version(v: &str) -> (u64, u64, u64) {
    let mut parts = v.split('.').map(|p| p.parse::<u64>().unwrap_or(0));
    let mut next = || parts.next().unwrap_or(0);
    (next(), next(), next())
}

/// The oldest Rust the published crates declare (`rust-version` in the root `Cargo.toml`, which
/// every publishable crate inherits) is no older than what any crate they depend on needs, so
/// that an older compiler is refused by cargo up front instead of failing deep in a dependency
/// (nalgebra 0.35 needs 1.89; `kanegen-runtime`'s x86-64-v4 copies need AVX-512 target
/// features, stable since 1.89). `cargo metadata` over the locked graph, all features.
#[test]
fn declared_rust_version_covers_every_dependency_of_the_published_crates() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--all-features",
            "--locked",
        ])
        .current_dir(common::root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = meta["packages"].as_array().unwrap();
    let by_id = |id: &str| packages.iter().find(|p| p["id"] == id).unwrap();
    let published: Vec<&serde_json::Value> = packages
        .iter()
        .filter(|p| {
            meta["workspace_members"]
                .as_array()
                .unwrap()
                .contains(&p["id"])
                && p["publish"] != serde_json::json!([])
        })
        .collect();
    assert_eq!(published.len(), 5, "the five publishable crates");
    let root = std::fs::read_to_string(common::root().join("Cargo.toml")).unwrap();
    let declared = strings(&root, "rust-version")
        .pop()
        .expect("[workspace.package] rust-version");
    let declared = declared.as_str();
    for p in &published {
        assert_eq!(
            p["rust_version"].as_str(),
            Some(declared),
            "{}: add `rust-version.workspace = true` to its [package]",
            p["name"].as_str().unwrap()
        );
    }
    // The normal and build dependencies of the published crates, transitively.
    let nodes = meta["resolve"]["nodes"].as_array().unwrap();
    let node = |id: &str| nodes.iter().find(|n| n["id"] == id).unwrap();
    let mut stack: Vec<String> = published
        .iter()
        .map(|p| p["id"].as_str().unwrap().to_owned())
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    while let Some(id) = stack.pop() {
        if !seen.insert(id.clone()) {
            continue;
        }
        for dep in node(&id)["deps"].as_array().unwrap() {
            let used = dep["dep_kinds"]
                .as_array()
                .unwrap()
                .iter()
                .any(|k| k["kind"] != "dev");
            if used {
                stack.push(dep["pkg"].as_str().unwrap().to_owned());
            }
        }
    }
    let mut too_new = Vec::new();
    for id in &seen {
        let p = by_id(id);
        if let Some(needs) = p["rust_version"].as_str()
            && version(needs) > version(declared)
        {
            too_new.push(format!(
                "{} {} needs {needs}",
                p["name"].as_str().unwrap(),
                p["version"].as_str().unwrap()
            ));
        }
    }
    assert!(
        too_new.is_empty(),
        "the workspace declares rust-version {declared} (root Cargo.toml), but {}: raise it",
        too_new.join(", ")
    );
}
