//! README.md shows the controller example of `krang-dynamics`; that example is compiled and run as
//! the crate's doc test. This test keeps the two identical.

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
