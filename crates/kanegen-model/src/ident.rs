//! Model names as Rust identifiers: the one rule shared by the URDF importer and code emission.

/// Rust's strict and reserved keywords of every edition (2015–2024), and `_`: none of them is
/// an identifier that generated code may bind (`r#self`, `r#Self`, `r#_` do not even exist as
/// raw identifiers).
const KEYWORDS: &[&str] = &[
    "_", "abstract", "as", "async", "await", "become", "box", "break", "const", "continue",
    "crate", "do", "dyn", "else", "enum", "extern", "false", "final", "fn", "for", "gen", "if",
    "impl", "in", "let", "loop", "macro", "match", "mod", "move", "mut", "override", "priv", "pub",
    "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "try", "type",
    "typeof", "unsafe", "unsized", "use", "virtual", "where", "while", "yield",
];

/// Whether `name` is a Rust keyword (of any edition) or `_`.
pub fn is_keyword(name: &str) -> bool {
    KEYWORDS.contains(&name)
}

/// A name (of a parameter, speed, coordinate, link or joint) as a Rust identifier.
///
/// The rule, applied in this order:
///
/// 1. every character other than an ASCII letter, an ASCII digit or `_` becomes `_`
///    (`base-link` → `base_link`, `Gelenk_ä` → `Gelenk__`);
/// 2. if the result is empty or starts with a digit, `_` is put in front (`4l` → `_4l`);
/// 3. if the result is a Rust keyword or `_` ([`is_keyword`]), `_` is appended (`self` →
///    `self_`, `type` → `type_`; `-`, `_` and the empty name → `__`).
///
/// Names that already are identifiers, such as `MX4l`, `qd_imu` or `q_LJ1`, are returned
/// unchanged; the result is always an identifier and never a keyword. Distinct names can give
/// the same result (`a-b` and `a_b`): [`Model::check_names`](crate::Model::check_names) reports
/// that.
pub fn sanitize_identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    if is_keyword(&s) {
        s.push('_');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::sanitize_identifier as id;

    #[test]
    fn identifiers_are_kept() {
        for name in ["MX4l", "qd_imu", "q_LJ1", "g", "_x", "Params", "types"] {
            assert_eq!(id(name), name);
        }
    }

    #[test]
    fn other_characters_become_underscores() {
        assert_eq!(id("base-link"), "base_link");
        assert_eq!(id("a b.c"), "a_b_c");
        assert_eq!(id("Gelenk_ä"), "Gelenk__");
    }

    #[test]
    fn a_leading_digit_gets_an_underscore_in_front() {
        assert_eq!(id("4l"), "_4l");
        assert_eq!(id("1"), "_1");
    }

    #[test]
    fn keywords_get_an_underscore_appended() {
        assert_eq!(id("type"), "type_");
        assert_eq!(id("gen"), "gen_");
        assert_eq!(id("_"), "__");
        assert_eq!(id("-"), "__");
        assert_eq!(id(""), "__");
        assert_eq!(id("self"), "self_");
        assert_eq!(id("Self"), "Self_");
        assert_eq!(id("super"), "super_");
        assert_eq!(id("crate"), "crate_");
    }
}
