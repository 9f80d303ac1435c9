//! README.md shows the controller example of `krang-dynamics`; that example is compiled and run as
//! the crate's doc test. These tests keep the two identical, and check that every relative link
//! of the README and of `docs/measurement-log.md` points at a file and a heading that exist.

mod common;

fn code_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match (&mut current, line.trim_start().starts_with("```")) {
            (None, true) if line.trim() == "```rust" => current = Some(String::new()),
            (Some(b), true) => {
                blocks.push(std::mem::take(b));
                current = None;
            }
            (Some(b), false) => {
                b.push_str(line);
                b.push('\n');
            }
            _ => {}
        }
    }
    blocks
}

#[test]
fn readme_controller_example_is_the_compiled_doc_test() {
    let readme = std::fs::read_to_string(common::root().join("README.md")).unwrap();
    let lib =
        std::fs::read_to_string(common::root().join("crates/krang-dynamics/src/lib.rs")).unwrap();
    let doc: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| format!("{}\n", l.strip_prefix(' ').unwrap_or(l)))
        .collect();
    // The crate doc writes the fence as plain ``` (a Rust doc test by default).
    let doc_block = code_blocks(&doc.replace("```\n", "```rust\n"))
        .into_iter()
        .find(|b| b.contains("Krang::new"))
        .expect("krang-dynamics has a doc example");
    assert!(
        code_blocks(&readme).contains(&doc_block),
        "README's krang-dynamics example differs from the crate doc test:\n{doc_block}"
    );
}

/// The anchor GitHub gives a heading: lower case, punctuation other than `-` and `_` dropped,
/// spaces turned into `-` (a repeated heading gets `-1`, `-2`, …).
fn anchors(markdown: &str) -> std::collections::HashSet<String> {
    let mut seen = std::collections::HashMap::<String, usize>::new();
    let mut in_code = false;
    let mut out = std::collections::HashSet::new();
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

/// Every relative link of README.md and docs/measurement-log.md (`](path#anchor)`) names a file
/// that exists and, for a Markdown file, a heading it has: the speed history moved from the
/// README to the log in the eleventh session, and the two link into each other.
#[test]
fn readme_and_measurement_log_links_resolve() {
    let root = common::root();
    let mut broken = Vec::new();
    for doc in ["README.md", "docs/measurement-log.md"] {
        let path = root.join(doc);
        let text = std::fs::read_to_string(&path).unwrap();
        for (start, _) in text.match_indices("](") {
            let rest = &text[start + 2..];
            let Some(end) = rest.find(')') else { continue };
            let link = &rest[..end];
            if link.contains("://") || link.contains(' ') {
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
                broken.push(format!("{doc}: ]({link})"));
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links that do not resolve:\n{}",
        broken.join("\n")
    );
}
