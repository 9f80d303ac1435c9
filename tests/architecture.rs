//! The source tree's shape: rules a reviewer would otherwise check by hand.
//!
//! Sources read: `codegen/src` and every `crates/*/src` (files under `generated/` are generator
//! output and skipped). Each crate's files are found by walking `mod` declarations from its roots
//! (`lib.rs`, `main.rs`, honouring `#[path]`), so every file has a module path.
//!
//! 1. **Size**: no file over [`MAX_LINES`] lines. A file owns one concern; split a longer one by
//!    concern (a module per part, each with a module doc saying what it owns).
//! 2. **No import cycles between the files of one crate** other than its root. File A depends on file B when A names
//!    an item of B: a `use crate::…`/`use super::…`/`use self::…`/`use child::…` line, or a
//!    qualified path such as `crate::a::b::f(…)` or `super::x::T` anywhere in the code (comments
//!    and string literals are not code; a `mod foo;` declaration alone is not a dependency). A
//!    path resolves to the file of its longest prefix that is a file module, so `super::Thing`
//!    from a child depends on the parent's `mod.rs`, and `crate::Thing` on the crate root. The
//!    fix for a cycle: move what both sides share into a leaf file that both import. The crate
//!    root (`lib.rs`, `main.rs`) is left out: it declares the modules and re-exports the public
//!    API, and the items it defines itself (error types, the crate's traits) serve every file.
//! 3. **Generator stages one way**: in `codegen/src` the stages run `expr` → `kane` → `lower` →
//!    `emit` (the model IR comes from the `kanegen-model` crate); a stage's files never import a
//!    later stage. Stage files may import the top-level files that describe what is generated
//!    (`options.rs`, `registry.rs`, `naming.rs`, …) but never the crate root `lib.rs`: they name an
//!    item by its defining module (`crate::options::Precision`, `kanegen_model::Model`), not by a
//!    root re-export, so the root stays the one file that ties stages together. Their tests
//!    (`mod tests`) may call the root to run the whole pipeline.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The most lines a source file may have.
const MAX_LINES: usize = 900;
/// The generator's stages (modules of `codegen/src`), in pipeline order.
const STAGES: [&str; 4] = ["expr", "kane", "lower", "emit"];

/// Source text with comments, string and character literals blanked (newlines kept).
fn strip(src: &str) -> Vec<char> {
    let c: Vec<char> = src.chars().collect();
    let at = |k: usize| c.get(k).copied().unwrap_or('\0');
    // The end of the literal that opens at `k` with the quote `q` (escapes skipped).
    let quoted = |mut k: usize, q: char| {
        k += 1;
        while k < c.len() && c[k] != q {
            k += if c[k] == '\\' { 2 } else { 1 };
        }
        k + 1
    };
    let (mut out, mut i) = (c.clone(), 0);
    while i < c.len() {
        let after_ident = i > 0 && (at(i - 1).is_alphanumeric() || at(i - 1) == '_');
        let r = if at(i) == 'b' { i + 1 } else { i };
        let hashes = (r + 1..c.len()).take_while(|&k| c[k] == '#').count();
        let end = if at(i) == '/' && at(i + 1) == '/' {
            (i..c.len()).find(|&k| c[k] == '\n').unwrap_or(c.len())
        } else if at(i) == '/' && at(i + 1) == '*' {
            let (mut depth, mut k) = (1, i + 2);
            while depth > 0 && k < c.len() {
                let two = (at(k), at(k + 1));
                depth += (two == ('/', '*')) as i32 - (two == ('*', '/')) as i32;
                k += if two == ('/', '*') || two == ('*', '/') {
                    2
                } else {
                    1
                };
            }
            k
        } else if !after_ident && at(r) == 'r' && at(r + 1 + hashes) == '"' {
            let close: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let mut k = r + hashes + 2;
            while k < c.len() && !c[k..].starts_with(&close) {
                k += 1;
            }
            k + close.len()
        } else if at(i) == '"' {
            quoted(i, '"')
        } else if at(i) == '\'' && (at(i + 1) == '\\' || at(i + 2) == '\'') {
            quoted(i, '\'')
        } else {
            i += 1;
            continue;
        };
        for ch in &mut out[i..end.min(c.len())] {
            if *ch != '\n' {
                *ch = ' ';
            }
        }
        i = end;
    }
    out
}

/// Identifiers and punctuation of stripped code, each with its line number.
fn tokens(code: &[char]) -> Vec<(String, usize)> {
    let (mut toks, mut line, mut i) = (Vec::new(), 1, 0);
    while i < code.len() {
        let ch = code[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch.is_alphanumeric() || ch == '_' {
            let s = i;
            while i < code.len() && (code[i].is_alphanumeric() || code[i] == '_') {
                i += 1;
            }
            toks.push((code[s..i].iter().collect(), line));
        } else if ch == ':' && code.get(i + 1) == Some(&':') {
            toks.push(("::".into(), line));
            i += 2;
        } else {
            toks.push((ch.to_string(), line));
            i += 1;
        }
    }
    toks
}

/// Expands a `use` tree (tokens between `use` and `;`) into full paths.
fn use_tree(t: &[String], prefix: &[String], out: &mut Vec<Vec<String>>) -> usize {
    let (mut path, mut i) = (prefix.to_vec(), 0);
    while i < t.len() {
        match t[i].as_str() {
            "::" => i += 1,
            "{" => {
                i += 1;
                while i < t.len() && t[i] != "}" {
                    i += use_tree(&t[i..], &path, out);
                    if t.get(i).map(String::as_str) == Some(",") {
                        i += 1;
                    }
                }
                return i + 1;
            }
            "," | "}" => break,
            "as" => i += 2,
            "*" => i += 1,
            s => {
                path.push(s.to_string());
                i += 1;
            }
        }
    }
    out.push(path);
    i
}

/// One crate's files: module path → file, and each file's dependencies on other files.
struct Crate {
    files: BTreeMap<Vec<String>, PathBuf>,
    deps: Deps,
}

/// Per file: the files it depends on, each with whether only test code (`mod tests`) does.
type Deps = BTreeMap<PathBuf, BTreeMap<PathBuf, bool>>;

fn is_ident(s: &str) -> bool {
    s.chars().all(|c| c.is_alphanumeric() || c == '_')
}

/// Walks `mod` declarations from `root`, recording every file under its module path.
fn collect(file: &Path, module: Vec<String>, files: &mut BTreeMap<Vec<String>, PathBuf>) {
    if file.components().any(|c| c.as_os_str() == "generated") {
        return;
    }
    let raw = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let lines: Vec<&str> = raw.lines().collect();
    let toks = tokens(&strip(&raw));
    let dir = file.parent().unwrap();
    let stem = file.file_stem().unwrap().to_str().unwrap();
    let child_dir = if ["lib", "main", "mod"].contains(&stem) {
        dir.to_path_buf()
    } else {
        dir.join(stem)
    };
    files.insert(module.clone(), file.to_path_buf());
    for w in toks.windows(3) {
        if w[0].0 == "mod" && is_ident(&w[1].0) && w[2].0 == ";" {
            let name = &w[1].0;
            let attr = lines[w[0].1.saturating_sub(2)].trim();
            let path = match attr
                .strip_prefix("#[path = \"")
                .and_then(|a| a.strip_suffix("\"]"))
            {
                Some(p) => dir.join(p),
                None if child_dir.join(format!("{name}.rs")).exists() => {
                    child_dir.join(format!("{name}.rs"))
                }
                None => child_dir.join(name).join("mod.rs"),
            };
            let mut m = module.clone();
            m.push(name.clone());
            collect(&path, m, files);
        }
    }
}

/// Resolves the dependencies of every file of the crate rooted at `root`.
fn read_crate(root: &Path) -> Crate {
    let mut files = BTreeMap::new();
    collect(root, Vec::new(), &mut files);
    let mut deps = BTreeMap::new();
    for (module, file) in &files {
        let toks: Vec<String> = tokens(&strip(&std::fs::read_to_string(file).unwrap()))
            .into_iter()
            .map(|t| t.0)
            .collect();
        let known = |m: &[String]| files.contains_key(m);
        // Per file depended on: whether only test code (`mod tests`) depends on it.
        let mut found: BTreeMap<PathBuf, bool> = BTreeMap::new();
        // Inline modules (`mod tests { … }`): (name, brace depth at which it closes).
        let (mut inline, mut depth): (Vec<(String, usize)>, usize) = (Vec::new(), 0);
        let mut i = 0;
        while i < toks.len() {
            let cur: Vec<String> = module
                .iter()
                .cloned()
                .chain(inline.iter().map(|m| m.0.clone()))
                .collect();
            let mut paths = Vec::new();
            match toks[i].as_str() {
                "{" => depth += 1,
                "}" => {
                    depth -= 1;
                    if inline.last().is_some_and(|m| m.1 == depth) {
                        inline.pop();
                    }
                }
                "mod" if toks.get(i + 2).map(String::as_str) == Some("{") => {
                    inline.push((toks[i + 1].clone(), depth));
                }
                "use" => {
                    let end = (i..toks.len())
                        .find(|&k| toks[k] == ";")
                        .unwrap_or(toks.len());
                    use_tree(&toks[i + 1..end], &[], &mut paths);
                    i = end;
                }
                s if (i == 0 || toks[i - 1] != "::")
                    && toks.get(i + 1).map(String::as_str) == Some("::")
                    && is_ident(s) =>
                {
                    let mut k = i;
                    let mut p = Vec::new();
                    while k < toks.len() && is_ident(&toks[k]) {
                        p.push(toks[k].clone());
                        if toks.get(k + 1).map(String::as_str) != Some("::") {
                            break;
                        }
                        k += 2;
                    }
                    paths.push(p);
                    i = k;
                }
                _ => {}
            }
            for p in paths {
                let mut base: Vec<String> = match p.first().map(String::as_str) {
                    Some("crate") => Vec::new(),
                    Some("self") | Some("super") => cur.clone(),
                    Some(m) if known(&[cur.clone(), vec![m.to_string()]].concat()) => cur.clone(),
                    _ => continue,
                };
                let mut rest = p.as_slice();
                if rest[0] == "crate" || rest[0] == "self" {
                    rest = &rest[1..];
                }
                while rest.first().map(String::as_str) == Some("super") {
                    base.pop();
                    rest = &rest[1..];
                }
                base.extend(rest.iter().cloned());
                let target = (0..=base.len())
                    .rev()
                    .find_map(|n| files.get(&base[..n]))
                    .unwrap();
                if target != file {
                    let in_tests = cur.iter().any(|m| m == "tests");
                    *found.entry(target.clone()).or_insert(true) &= in_tests;
                }
            }
            i += 1;
        }
        deps.insert(file.clone(), found);
    }
    Crate { files, deps }
}

/// Every crate root under `codegen/src` and `crates/*/src`.
fn roots() -> Vec<PathBuf> {
    let ws = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut dirs = vec![ws.join("codegen/src")];
    for e in std::fs::read_dir(ws.join("crates")).unwrap() {
        dirs.push(e.unwrap().path().join("src"));
    }
    dirs.sort();
    dirs.iter()
        .flat_map(|d| ["lib.rs", "main.rs"].map(|r| d.join(r)))
        .filter(|p| p.exists())
        .collect()
}

fn rel(p: &Path) -> String {
    p.strip_prefix(env!("CARGO_MANIFEST_DIR"))
        .unwrap_or(p)
        .display()
        .to_string()
}

/// The groups of files that depend on each other, directly or not: each an import cycle.
fn cycles(deps: &Deps) -> Vec<Vec<PathBuf>> {
    let reach = |from: &PathBuf| {
        let (mut seen, mut stack) = (BTreeSet::new(), vec![from]);
        while let Some(f) = stack.pop() {
            for g in deps[f].keys() {
                if seen.insert(g) {
                    stack.push(g);
                }
            }
        }
        seen
    };
    let reached: BTreeMap<_, _> = deps.keys().map(|f| (f, reach(f))).collect();
    let mut out: Vec<Vec<PathBuf>> = Vec::new();
    for (f, r) in &reached {
        let group: Vec<PathBuf> = r
            .iter()
            .filter(|g| reached[*g].contains(f))
            .map(|g| (*g).clone())
            .collect();
        if group.len() > 1 && !out.contains(&group) {
            out.push(group);
        }
    }
    out
}

#[test]
fn no_source_file_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for root in roots() {
        for file in read_crate(&root).files.values() {
            let n = std::fs::read_to_string(file).unwrap().lines().count();
            if n > MAX_LINES {
                long.push(format!("  {} ({n} lines)", rel(file)));
            }
        }
    }
    long.sort();
    long.dedup();
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines:\n{}\nsplit each by concern into modules (one concern a file, a module doc each)",
        long.join("\n")
    );
}

#[test]
fn no_import_cycle_between_the_files_of_a_crate() {
    let mut report = Vec::new();
    for root in roots() {
        let mut c = read_crate(&root);
        c.deps.remove(&root);
        c.deps
            .values_mut()
            .for_each(|d| d.retain(|f, _| *f != root));
        for scc in cycles(&c.deps) {
            report.push(format!("cycle among {} files:", scc.len()));
            for a in &scc {
                for b in c.deps[a].keys().filter(|b| scc.contains(b)) {
                    report.push(format!("  {} -> {}", rel(a), rel(b)));
                }
            }
        }
    }
    assert!(
        report.is_empty(),
        "{}\nmove what the files share into a leaf module that they import, so edges go one way",
        report.join("\n")
    );
}

#[test]
fn generator_stages_import_only_earlier_stages() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("codegen/src/lib.rs");
    let c = read_crate(&root);
    let stage_of: BTreeMap<&PathBuf, Option<usize>> = c
        .files
        .iter()
        .map(|(m, f)| {
            (
                f,
                m.first().and_then(|s| STAGES.iter().position(|x| x == s)),
            )
        })
        .collect();
    let mut bad = Vec::new();
    for (a, to) in &c.deps {
        let Some(sa) = stage_of[a] else { continue };
        for (b, only_tests) in to {
            match stage_of[b] {
                Some(sb) if sb > sa => bad.push(format!(
                    "  {} -> {} (stage `{}` imports the later stage `{}`)",
                    rel(a),
                    rel(b),
                    STAGES[sa],
                    STAGES[sb]
                )),
                None if *b == root && !only_tests => bad.push(format!(
                    "  {} -> {} (name the item by its defining module, not a root re-export)",
                    rel(a),
                    rel(b)
                )),
                _ => {}
            }
        }
    }
    assert!(
        bad.is_empty(),
        "stage files import later stages or the crate root:\n{}\nstages run expr -> kane -> lower -> emit",
        bad.join("\n")
    );
}
