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

/// Whether `c` may start an identifier: `_` or a character of Unicode's `XID_Start` (letters of
/// every script), as rustc decides.
fn is_start(c: char) -> bool {
    c == '_' || unicode_ident::is_xid_start(c)
}

/// Whether `c` may continue an identifier: `XID_Continue` (letters, digits, `_`, combining
/// marks), as rustc decides.
fn is_continue(c: char) -> bool {
    unicode_ident::is_xid_continue(c)
}

/// `name` in Unicode normalisation form C, the form rustc gives identifiers (`e` followed by a
/// combining acute accent becomes `é`).
pub fn nfc(name: &str) -> String {
    use unicode_normalization::UnicodeNormalization;
    name.nfc().collect()
}

/// Whether `name` is a Rust identifier as written: in NFC, an `XID_Start` character or `_`
/// followed by `XID_Continue` characters (rustc's rule: `q_ψ`, `m_肘` and `qd_imu` are; `4l`,
/// `a-b` are not), and no keyword ([`is_keyword`]).
pub fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(is_start)
        && chars.all(is_continue)
        && !is_keyword(name)
        && nfc(name) == name
}

/// A name (of a parameter, speed, coordinate, link or joint) as a Rust identifier.
///
/// The rule, applied in this order:
///
/// 1. the name is normalised to NFC (as rustc normalises identifiers);
/// 2. every ASCII character other than a letter, a digit or `_` becomes `_` (`base-link` →
///    `base_link`); every other character that cannot continue a Rust identifier (not
///    `XID_Continue`: symbols, punctuation, emoji) becomes its code point escaped in ASCII,
///    `_u{hex}_` without braces (`a→b` → `a_u2192_b`), so distinct names stay distinct; letters
///    of every script are kept (`肘`, `ψ`, `Gelenk_ä`);
/// 3. if the result is empty or does not start with `_` or an `XID_Start` character (a digit, a
///    combining mark), `_` is put in front (`4l` → `_4l`);
/// 4. if the result is a Rust keyword or `_` ([`is_keyword`]), `_` is appended (`self` →
///    `self_`, `type` → `type_`; `-`, `_` and the empty name → `__`).
///
/// Names that already are identifiers, such as `MX4l`, `qd_imu`, `q_LJ1` or `q_ψ`, are returned
/// unchanged; the result is always an identifier ([`is_identifier`]). Distinct names can give
/// the same result only through ASCII punctuation (`a-b` and `a_b`):
/// [`Model::check_names`](crate::Model::check_names) reports that.
pub fn sanitize_identifier(name: &str) -> String {
    let mut s = String::with_capacity(name.len());
    for c in nfc(name).chars() {
        if c.is_ascii() {
            s.push(if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            });
        } else if is_continue(c) {
            s.push(c);
        } else {
            s.push_str(&format!("_u{:x}_", u32::from(c)));
        }
    }
    if !s.starts_with(is_start) {
        s.insert(0, '_');
    }
    if is_keyword(&s) {
        s.push('_');
    }
    s
}

/// Characters that rustc rejects in comments and literals (`text_direction_codepoint_*` lints:
/// the bidirectional embeddings, overrides and isolates), the left-to-right and right-to-left
/// marks, and control characters (newlines included): what a generated comment, a string
/// literal or a cargo build-script line cannot carry as written.
pub fn is_unprintable(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{200E}' | '\u{200F}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}'
        )
}

/// `text` with every [`is_unprintable`] character escaped as Rust escapes it (`\n`,
/// `\u{202e}`): one line that a generated comment or a cargo instruction can carry.
pub fn escape_unprintable(text: &str) -> String {
    if !text.chars().any(is_unprintable) {
        return text.to_owned();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if is_unprintable(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
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
    fn ascii_punctuation_becomes_underscores() {
        assert_eq!(id("base-link"), "base_link");
        assert_eq!(id("a b.c"), "a_b_c");
    }

    #[test]
    fn letters_of_every_script_are_kept() {
        for name in ["Gelenk_ä", "肘", "ψ", "q_ψ", "m_肘", "Ψ_1"] {
            assert_eq!(id(name), name);
            assert!(super::is_identifier(name), "{name}");
        }
    }

    #[test]
    fn names_are_normalised_to_nfc() {
        // `e` + combining acute accent is `é`.
        assert_eq!(id("caf\u{65}\u{301}"), "caf\u{e9}");
        assert!(!super::is_identifier("caf\u{65}\u{301}"));
    }

    #[test]
    fn other_characters_are_escaped_so_that_names_stay_distinct() {
        assert_eq!(id("a→b"), "a_u2192_b");
        assert_eq!(id("a⇒b"), "a_u21d2_b");
        assert_eq!(id("😀"), "_u1f600_");
        // A combining mark cannot start an identifier.
        assert_eq!(id("\u{301}a"), "_\u{301}a");
    }

    #[test]
    fn unprintable_characters_are_escaped() {
        use super::escape_unprintable as esc;
        assert_eq!(
            esc("a\nb\r\u{202e}c\u{200f}"),
            "a\\nb\\r\\u{202e}c\\u{200f}"
        );
        assert_eq!(esc("肘 ψ"), "肘 ψ");
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
