//! Statement comments in the reports' style (`let k12 = …; // w2.x`).
//!
//! prettyplease formats a syntax tree, which has no comments, so the labels are attached
//! afterwards: every `let NAME = …;` of the formatted source gets the label of statement `NAME`
//! of the function it is in (local names are numbered per function).

use std::collections::HashMap;

use super::print::comment_text;
use crate::lower::Program;

/// Statement labels, by function name and local name.
#[derive(Default)]
pub(super) struct Labels<'a> {
    by_function: HashMap<&'a str, HashMap<&'a str, String>>,
}

impl<'a> Labels<'a> {
    /// Record the labels of program `p`, emitted as the function `function`.
    pub fn add(&mut self, function: &'a str, p: &'a Program) {
        let labels = p
            .stmts
            .iter()
            .filter(|s| !s.comment.is_empty())
            .map(|s| (s.name.as_str(), comment_text(&s.comment)))
            .collect();
        self.by_function.insert(function, labels);
    }

    /// `src` with `// label` appended to every labelled `let` statement (labels come from model
    /// names: they are escaped by [`comment_text`]).
    pub fn apply(&self, src: &str) -> String {
        let mut out = String::with_capacity(src.len() * 5 / 4);
        let mut pending: Option<&str> = None;
        let empty = HashMap::new();
        let mut current = &empty;
        for line in src.lines() {
            let t = line.trim_start();
            if let Some(rest) = t.strip_prefix("pub fn ") {
                current = self.by_function.get(leading_ident(rest)).unwrap_or(&empty);
            }
            if pending.is_none()
                && let Some(rest) = t.strip_prefix("let ")
            {
                pending = current.get(leading_ident(rest)).map(String::as_str);
            }
            out.push_str(line);
            if let Some(c) = pending
                && t.ends_with(';')
            {
                out.push_str(" // ");
                out.push_str(c);
                pending = None;
            }
            out.push('\n');
        }
        out
    }
}

fn leading_ident(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}
