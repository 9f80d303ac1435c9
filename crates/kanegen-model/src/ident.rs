//! Model names as Rust identifiers: the one rule shared by the URDF importer and code emission.

/// Words that are Rust keywords but cannot be written as raw identifiers (`r#self` is not valid
/// Rust), nor is `_` an identifier; [`sanitize_identifier`] appends `_` to them.
const NOT_RAW: &[&str] = &["_", "crate", "self", "Self", "super"];

/// A name (of a parameter, speed, coordinate, link or joint) as a Rust identifier.
///
/// The rule, applied in this order:
///
/// 1. every character other than an ASCII letter, an ASCII digit or `_` becomes `_`
///    (`base-link` → `base_link`, `Gelenk_ä` → `Gelenk__`);
/// 2. if the result is empty or starts with a digit, `_` is put in front (`4l` → `_4l`);
/// 3. if the result is `_`, `crate`, `self`, `Self` or `super` (which are no identifiers and
///    cannot be raw identifiers either), `_` is appended (`self` → `self_`; `-`, `_` and the empty name
///    → `__`).
///
/// Names that already are identifiers, such as `MX4l`, `qd_imu` or `q_LJ1`, are returned
/// unchanged. The result is an identifier, or another Rust keyword such as `type` or `fn`, which
/// generated code writes as a raw identifier (`r#type`). Distinct names can give the same result
/// (`a-b` and `a_b`); callers that need distinct identifiers check for that.
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
    if NOT_RAW.contains(&s.as_str()) {
        s.push('_');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::sanitize_identifier as id;

    #[test]
    fn identifiers_are_kept() {
        for name in ["MX4l", "qd_imu", "q_LJ1", "g", "_x", "type", "Params"] {
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
    fn words_that_cannot_be_raw_identifiers_get_an_underscore_appended() {
        assert_eq!(id("_"), "__");
        assert_eq!(id("-"), "__");
        assert_eq!(id(""), "__");
        assert_eq!(id("self"), "self_");
        assert_eq!(id("Self"), "Self_");
        assert_eq!(id("super"), "super_");
        assert_eq!(id("crate"), "crate_");
    }
}
