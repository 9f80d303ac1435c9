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

/// One start or end tag.
struct Tag {
    /// Byte offsets of the tag in the text: `text[start..end]` is `<…>`.
    start: usize,
    end: usize,
    name: String,
    /// Attribute names and their unescaped values.
    attrs: Vec<(String, String)>,
    closing: bool,
    self_closing: bool,
}

/// The tags of an XML text (quick-xml's events; comments, declarations, CDATA and text
/// skipped); `None` if the text is not well-formed XML (the URDF parser then reports it).
fn tags(text: &str) -> Option<Vec<Tag>> {
    use quick_xml::events::Event;
    let utf8 = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = Vec::new();
    loop {
        let start = usize::try_from(reader.buffer_position()).ok()?;
        let event = reader.read_event().ok()?;
        let end = usize::try_from(reader.buffer_position()).ok()?;
        let (element, self_closing) = match &event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(e) => {
                out.push(Tag {
                    start,
                    end,
                    name: utf8(e.name().as_ref()),
                    attrs: Vec::new(),
                    closing: true,
                    self_closing: false,
                });
                continue;
            }
            Event::Eof => return Some(out),
            _ => continue,
        };
        let mut attrs = Vec::new();
        for a in element.attributes() {
            let a = a.ok()?;
            attrs.push((utf8(a.key.as_ref()), a.unescape_value().ok()?.into_owned()));
        }
        out.push(Tag {
            start,
            end,
            name: utf8(element.name().as_ref()),
            attrs,
            closing: false,
            self_closing,
        });
    }
}

/// `text` without the [`UNUSED`] elements (each removed with its content; the XML stays well
/// formed). The text unchanged if it is not well-formed XML (the URDF
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
        if t.closing || !UNUSED.contains(&t.name.as_str()) {
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
/// unknown joint type, a bad number. `None` if none is found (or the text is not well-formed XML).
pub(super) fn diagnose(text: &str) -> Option<K> {
    let tags = tags(text)?;
    // Open elements; the enclosing top-level link or joint.
    let mut depth = 0usize;
    let mut context: Option<String> = None;
    for t in &tags {
        if t.closing {
            depth = depth.saturating_sub(1);
            if depth <= 1 {
                context = None;
            }
            continue;
        }
        let attr = |k: &str| {
            t.attrs
                .iter()
                .find(|(a, _)| a == k)
                .map(|(_, v)| v.as_str())
        };
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unused_elements_are_removed_with_their_content_and_nothing_else() {
        let text = r#"<robot name="r"><!-- <visual> in a comment stays -->
<link name="a"><visual><geometry><mesh filename="a>b.stl"/></geometry></visual><inertial/></link>
<link name="b"><collision/><material name="m"><color rgba="1 0 0 1"/></material></link></robot>"#;
        let out = without_unused_elements(text);
        assert_eq!(
            out,
            r#"<robot name="r"><!-- <visual> in a comment stays -->
<link name="a"><inertial/></link>
<link name="b"></link></robot>"#
        );
    }

    #[test]
    fn text_that_is_not_well_formed_xml_is_left_to_the_urdf_parser() {
        let text = r#"<robot name="r"><link name="a"><visual></link></robot>"#;
        assert_eq!(without_unused_elements(text), text);
        assert!(diagnose(text).is_none());
    }

    #[test]
    fn a_bad_number_names_its_link_element_and_attribute() {
        let text = r#"<robot name="r"><link name="arm"><inertial><mass value="1 2"/></inertial></link></robot>"#;
        let Some(K::UrdfBadNumber {
            element, attribute, ..
        }) = diagnose(text)
        else {
            panic!("expected a bad-number error");
        };
        assert_eq!(element, "link `arm` <mass>");
        assert_eq!(attribute, "value");
    }
}
