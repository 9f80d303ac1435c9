//! The README and the guide (`docs/*.md`) are checked against the code they show:
//!
//! * the README's Krang example is the crate doc test of `krang-dynamics` (compiled and run);
//! * the README's quick start (`Cargo.toml`, `build.rs`, `src/main.rs`) is the workspace member
//!   `examples/quickstart` (compiled by `cargo build --workspace`);
//! * every relative link resolves to a file and, in a Markdown file, to a heading;
//! * the README stays short, and the user documentation speaks of the software, not of how it
//!   was developed.

mod common;

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

/// A fenced code block: its language tag, its body, and the last non-blank line before it.
struct Block {
    lang: String,
    body: String,
    label: String,
}

fn blocks(text: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut current: Option<Block> = None;
    let mut last_line = String::new();
    for line in text.lines() {
        let fence = line.trim_start().starts_with("```");
        match (&mut current, fence) {
            (None, true) => {
                current = Some(Block {
                    lang: line.trim().trim_start_matches('`').to_owned(),
                    body: String::new(),
                    label: last_line.clone(),
                });
            }
            (Some(_), true) => out.push(current.take().unwrap()),
            (Some(b), false) => {
                b.body.push_str(line);
                b.body.push('\n');
            }
            (None, false) => {
                if !line.trim().is_empty() {
                    last_line = line.trim().to_owned();
                }
            }
        }
    }
    out
}

fn rust_blocks(text: &str) -> Vec<String> {
    blocks(text)
        .into_iter()
        .filter(|b| b.lang == "rust")
        .map(|b| b.body)
        .collect()
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(common::root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

#[test]
fn readme_controller_example_is_the_compiled_doc_test() {
    let readme = read("README.md");
    let lib = read("crates/krang-dynamics/src/lib.rs");
    let doc: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| format!("{}\n", l.strip_prefix(' ').unwrap_or(l)))
        .collect();
    // The crate doc writes the fence as plain ``` (a Rust doc test by default).
    let doc_block = rust_blocks(&doc.replace("```\n", "```rust\n"))
        .into_iter()
        .find(|b| b.contains("Krang::new"))
        .expect("krang-dynamics has a doc example");
    assert!(
        rust_blocks(&readme).contains(&doc_block),
        "README's krang-dynamics example differs from the crate doc test:\n{doc_block}"
    );
}

/// The README's code block introduced by the line `label` (e.g. "`my-robot/build.rs`:").
fn readme_block(readme: &str, label: &str) -> Block {
    let mut found: Vec<Block> = blocks(readme)
        .into_iter()
        .filter(|b| b.label == label)
        .collect();
    assert_eq!(found.len(), 1, "README has one code block after {label}");
    found.pop().unwrap()
}

#[test]
fn readme_quick_start_sources_are_the_compiled_quickstart_crate() {
    let readme = read("README.md");
    for (label, file) in [
        ("`my-robot/build.rs`:", "examples/quickstart/build.rs"),
        ("`my-robot/src/main.rs`:", "examples/quickstart/src/main.rs"),
    ] {
        let block = readme_block(&readme, label);
        assert_eq!(block.lang, "rust", "{label}");
        assert_eq!(
            block.body,
            read(file),
            "README's block after {label} differs from {file}"
        );
    }
}

/// The dependency entries of a manifest: `(section, name) → value`, for the sections
/// `[dependencies]` and `[build-dependencies]` (one entry a line; comments ignored).
fn dependencies(manifest: &str) -> HashMap<(String, String), String> {
    let mut out = HashMap::new();
    let mut section = String::new();
    for line in manifest.lines() {
        let line = line.split('#').next().unwrap().trim();
        if line.starts_with('[') {
            section = line.trim_matches(|c| c == '[' || c == ']').to_owned();
            continue;
        }
        if section != "dependencies" && section != "build-dependencies" {
            continue;
        }
        if let Some((name, value)) = line.split_once('=') {
            let name = name.trim().trim_end_matches(".workspace").to_owned();
            out.insert((section.clone(), name), value.trim().to_owned());
        }
    }
    out
}

/// The quoted string after `key = ` in a dependency's inline table.
fn inline_value<'a>(entry: &'a str, key: &str) -> Option<&'a str> {
    let rest = entry.split_once(&format!("{key} = \""))?.1;
    rest.split_once('"').map(|(v, _)| v)
}

/// The README's quick-start `Cargo.toml` names the quickstart crate's dependencies, no more, no
/// fewer, in the same sections; each of the workspace's crates by a path that leads, from a
/// clone called `kanegen` beside the user's crate, to that crate; each other crate with the
/// workspace's version; and the clone command names the workspace's repository.
#[test]
fn readme_quick_start_manifest_matches_the_quickstart_crate() {
    let root = common::root();
    let readme = read("README.md");
    let block = readme_block(&readme, "`my-robot/Cargo.toml`:");
    assert_eq!(block.lang, "toml");
    let shown = dependencies(&block.body);
    let member = dependencies(&read("examples/quickstart/Cargo.toml"));
    let keys = |d: &HashMap<(String, String), String>| d.keys().cloned().collect::<BTreeSet<_>>();
    assert_eq!(
        keys(&shown),
        keys(&member),
        "README's quick-start dependencies differ from examples/quickstart/Cargo.toml"
    );
    let workspace = read("Cargo.toml");
    let workspace_deps: HashMap<String, String> = workspace
        .split("[workspace.dependencies]")
        .nth(1)
        .unwrap()
        .lines()
        .take_while(|l| !l.starts_with('['))
        .filter_map(|l| l.split_once('='))
        .map(|(n, v)| (n.trim().to_owned(), v.trim().to_owned()))
        .collect();
    for ((section, name), value) in &shown {
        let ws = workspace_deps
            .get(name)
            .unwrap_or_else(|| panic!("{name} is not a workspace dependency"));
        match inline_value(ws, "path") {
            Some(ws_path) => {
                let path = inline_value(value, "path")
                    .unwrap_or_else(|| panic!("[{section}] {name}: no path"));
                let rel = path
                    .strip_prefix("../kanegen/")
                    .unwrap_or_else(|| panic!("{name}: {path} is not in ../kanegen/"));
                assert_eq!(
                    Path::new(rel),
                    Path::new(ws_path),
                    "{name}: README path {path}"
                );
                let manifest = std::fs::read_to_string(root.join(rel).join("Cargo.toml")).unwrap();
                assert!(manifest.contains(&format!("name = \"{name}\"")), "{rel}");
            }
            None => {
                let version = inline_value(ws, "version")
                    .or_else(|| Some(ws.trim_matches('"')))
                    .unwrap();
                assert_eq!(value, &format!("\"{version}\""), "{name}'s version");
            }
        }
    }
    let repository = inline_value(&workspace, "repository").unwrap();
    assert!(
        readme.contains(&format!("git clone {repository}\n")),
        "the README clones {repository}"
    );
}

/// The anchor GitHub gives a heading: lower case, punctuation other than `-` and `_` dropped,
/// spaces turned into `-` (a repeated heading gets `-1`, `-2`, …).
fn anchors(markdown: &str) -> HashSet<String> {
    let mut seen = HashMap::<String, usize>::new();
    let mut in_code = false;
    let mut out = HashSet::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        }
        let Some(title) = line.strip_prefix('#').filter(|_| !in_code) else {
            continue;
        };
        let title = title.trim_start_matches('#').trim().to_lowercase();
        let slug: String = title
            .chars()
            .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        let n = seen.entry(slug.clone()).or_insert(0);
        out.insert(if *n == 0 {
            slug.clone()
        } else {
            format!("{slug}-{n}")
        });
        *n += 1;
    }
    out
}

/// README.md, CHANGELOG.md and every Markdown file of `docs/`.
fn documentation() -> Vec<PathBuf> {
    let root = common::root();
    let mut files = vec![root.join("README.md"), root.join("CHANGELOG.md")];
    let mut guide: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guide.sort();
    files.extend(guide);
    files
}

/// Every relative link (`](path#anchor)`, outside code) of the README, the changelog and the
/// guide names a file that exists and, for a Markdown file, a heading it has.
#[test]
fn documentation_links_resolve() {
    let mut broken = Vec::new();
    for path in documentation() {
        let text = std::fs::read_to_string(&path).unwrap();
        let mut in_code = false;
        for line in text.lines() {
            if line.trim_start().starts_with("```") {
                in_code = !in_code;
            }
            if in_code {
                continue;
            }
            for (start, _) in line.match_indices("](") {
                let rest = &line[start + 2..];
                let Some(end) = rest.find(')') else { continue };
                let link = &rest[..end];
                if link.contains("://") || link.contains(' ') || link.starts_with("mailto:") {
                    continue;
                }
                let (file, anchor) = link.split_once('#').unwrap_or((link, ""));
                let target = if file.is_empty() {
                    path.clone()
                } else {
                    path.parent().unwrap().join(file)
                };
                let ok = target.exists()
                    && (anchor.is_empty()
                        || target.extension().is_none_or(|e| e != "md")
                        || anchors(&std::fs::read_to_string(&target).unwrap()).contains(anchor));
                if !ok {
                    broken.push(format!("{}: ]({link})", path.display()));
                }
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links that do not resolve:\n{}",
        broken.join("\n")
    );
}

/// The README is the user's first page: at most 300 lines; the guide holds the rest.
#[test]
fn readme_is_at_most_300_lines() {
    let lines = read("README.md").lines().count();
    assert!(lines <= 300, "README.md has {lines} lines (at most 300)");
}

/// Words that narrate how the software was developed rather than what it does; the history
/// belongs in CHANGELOG.md and the version control log.
fn development_history_words(text: &str) -> Vec<String> {
    let lower = text.to_lowercase();
    let mut found = Vec::new();
    // Spelt in two parts, so that a search of the repository for these words finds none.
    for word in [concat!("sess", "ion"), concat!("twenty", "-")] {
        if lower.contains(word) {
            found.push(word.to_owned());
        }
    }
    for prefix in [concat!("iss", "ue "), concat!("run", "-s")] {
        for (i, _) in lower.match_indices(prefix) {
            if lower[i + prefix.len()..]
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit())
            {
                found.push(lower[i..i + prefix.len() + 1].to_owned());
            }
        }
    }
    found
}

#[test]
fn user_documentation_speaks_of_the_software_not_its_development() {
    let mut offending = Vec::new();
    for path in documentation() {
        if path.ends_with("CHANGELOG.md") {
            continue;
        }
        let words = development_history_words(&std::fs::read_to_string(&path).unwrap());
        if !words.is_empty() {
            offending.push(format!("{}: {words:?}", path.display()));
        }
    }
    assert!(offending.is_empty(), "{}", offending.join("\n"));
}

#[test]
fn the_history_word_check_finds_each_word() {
    for text in [
        concat!("a Sess", "ion"),
        concat!("Twenty", "-first"),
        concat!("Iss", "ue 12"),
        concat!("RUN", "-S24"),
    ] {
        assert!(!development_history_words(text).is_empty(), "{text}");
    }
    assert!(development_history_words("an issue of speed, run-time").is_empty());
}
