//! The URDF text before parsing: the elements the generator never needs are removed
//! ([`without_unused_elements`]), and typed errors are given for what the URDF parser would only
//! report generically (an unknown joint type, a number that is not one).

use crate::error::ModelErrorKind as K;

/// Numeric attributes of URDF elements (inside a top-level `<link>` or `<joint>`) and how many
/// numbers each holds.
const NUMERIC: &[(&str, &[(&str, usize)])] = &[
    ("origin", &[("xyz", 3), ("rpy", 3)]),
    ("axis", &[("xyz", 3)]),
    ("mass", &[("value", 1)]),
    (
        "inertia",
        &[
            ("ixx", 1),
            ("ixy", 1),
            ("ixz", 1),
            ("iyy", 1),
            ("iyz", 1),
            ("izz", 1),
        ],
    ),
    (
        "limit",
        &[("lower", 1), ("upper", 1), ("effort", 1), ("velocity", 1)],
    ),
    ("dynamics", &[("damping", 1), ("friction", 1)]),
    ("mimic", &[("multiplier", 1), ("offset", 1)]),
];

/// Elements that carry nothing the dynamics need (appearance and collision geometry); removed
/// with their content before parsing, so that their content is never read.
const UNUSED: &[&str] = &["visual", "collision", "material"];

const JOINT_TYPES: &[&str] = &[
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// Deepest element nesting accepted (a URDF needs about five levels): deeper text is a typed
/// error instead of overflowing the stack of the recursive XML parser.
pub(super) const MAX_DEPTH: usize = 64;

/// One start or end tag.
struct Tag<'a> {
    /// Byte offsets of the tag in the text: `text[start..end]` is `<…>`.
    start: usize,
    end: usize,
    name: &'a str,
    attrs: Vec<(&'a str, &'a str)>,
    closing: bool,
    self_closing: bool,
}

/// The tags of an XML text, skipping comments, declarations and CDATA; `None` where the text is
/// not tag-shaped (the URDF parser then reports it).
fn tags(text: &str) -> Option<Vec<Tag<'_>>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('<') {
        rest = &rest[i..];
        for (open, close) in [
            ("<!--", "-->"),
            ("<![CDATA[", "]]>"),
            ("<?", "?>"),
            ("<!", ">"),
        ] {
            if rest.starts_with(open) {
                let end = rest.find(close)?;
                rest = &rest[end + close.len()..];
                break;
            }
        }
        if !rest.starts_with('<') || rest.starts_with("<!") || rest.starts_with("<?") {
            continue;
        }
        let start = text.len() - rest.len();
        let closing = rest.starts_with("</");
        let mut s = &rest[if closing { 2 } else { 1 }..];
        let name_end = s.find(|c: char| c.is_whitespace() || c == '>' || c == '/')?;
        let name = &s[..name_end];
        s = &s[name_end..];
        let mut attrs = Vec::new();
        let self_closing;
        loop {
            s = s.trim_start();
            if let Some(r) = s.strip_prefix("/>") {
                self_closing = true;
                s = r;
                break;
            }
            if let Some(r) = s.strip_prefix('>') {
                self_closing = false;
                s = r;
                break;
            }
            let eq = s.find('=')?;
            let key = s[..eq].trim();
            let v = s[eq + 1..].trim_start();
            let quote = v.chars().next().filter(|c| *c == '"' || *c == '\'')?;
            let v = &v[1..];
            let end = v.find(quote)?;
            attrs.push((key, &v[..end]));
            s = &v[end + 1..];
        }
        out.push(Tag {
            start,
            end: text.len() - s.len(),
            name,
            attrs,
            closing,
            self_closing,
        });
        rest = s;
    }
    Some(out)
}

/// `text` without the [`UNUSED`] elements (each removed with its content; the XML stays well
/// formed). The text unchanged if it is not tag-shaped or an element is not closed (the URDF
/// parser then reports the problem).
pub(super) fn without_unused_elements(text: &str) -> std::borrow::Cow<'_, str> {
    let Some(tags) = tags(text) else {
        return text.into();
    };
    let mut out = String::new();
    let mut copied = 0;
    let mut i = 0;
    while i < tags.len() {
        let t = &tags[i];
        if t.closing || !UNUSED.contains(&t.name) {
            i += 1;
            continue;
        }
        // The matching end tag: the first `</name>` at this element's depth.
        let mut end = i;
        if !t.self_closing {
            let mut depth = 0usize;
            end = match tags[i..].iter().position(|u| {
                if u.name == t.name && !u.self_closing {
                    if u.closing {
                        depth -= 1;
                    } else {
                        depth += 1;
                    }
                }
                depth == 0
            }) {
                Some(k) => i + k,
                None => return text.into(),
            };
        }
        out.push_str(&text[copied..t.start]);
        copied = tags[end].end;
        i = end + 1;
    }
    if copied == 0 {
        return text.into();
    }
    out.push_str(&text[copied..]);
    out.into()
}

/// A typed error for the malformations that the URDF parser would only report generically: an
/// unknown joint type, a bad number. `None` if none is found (or the text is not tag-shaped).
pub(super) fn diagnose(text: &str) -> Option<K> {
    let tags = tags(text)?;
    // Open elements; the enclosing top-level link or joint.
    let mut depth = 0usize;
    let mut context: Option<String> = None;
    for t in &tags {
        if depth > MAX_DEPTH {
            return Some(K::UrdfParse {
                detail: format!(
                    "elements are nested more than {MAX_DEPTH} levels deep (at <{}>)",
                    t.name
                ),
            });
        }
        if t.closing {
            depth = depth.saturating_sub(1);
            if depth <= 1 {
                context = None;
            }
            continue;
        }
        let attr = |k: &str| t.attrs.iter().find(|(a, _)| *a == k).map(|(_, v)| *v);
        if depth == 1 && (t.name == "link" || t.name == "joint") {
            let name = attr("name").unwrap_or("?");
            if t.name == "joint" {
                let kind = attr("type").unwrap_or("");
                if !JOINT_TYPES.contains(&kind) {
                    return Some(K::UrdfUnknownJointType {
                        joint: name.to_owned(),
                        kind: kind.to_owned(),
                    });
                }
            }
            context = Some(format!("{} `{name}`", t.name));
        } else if depth >= 2
            && let Some(ctx) = &context
            && let Some((_, numeric)) = NUMERIC.iter().find(|(e, _)| *e == t.name)
        {
            for &(key, count) in *numeric {
                let Some(v) = attr(key) else { continue };
                let parts: Vec<&str> = v.split_whitespace().collect();
                let ok = parts.len() == count
                    && parts
                        .iter()
                        .all(|p| p.parse::<f64>().is_ok_and(f64::is_finite));
                if !ok {
                    return Some(K::UrdfBadNumber {
                        element: format!("{ctx} <{}>", t.name),
                        attribute: key.to_owned(),
                        text: v.to_owned(),
                        expected: if count == 1 {
                            "a finite number".into()
                        } else {
                            format!("{count} finite numbers separated by spaces")
                        },
                    });
                }
            }
        }
        if !t.self_closing {
            depth += 1;
        }
    }
    None
}
