//! Limits of the loaders. Size and nesting, checked before any parser runs: a file larger than
//! [`MAX_DESCRIPTION_BYTES`] is refused before it is read, and URDF elements nested deeper than
//! [`MAX_URDF_DEPTH`] are found by a streaming pass of quick-xml (which keeps a depth count,
//! not a stack frame per level), so that the recursive parsers behind urdf-rs never see them —
//! they overflowed their stack on a few thousand levels and took minutes on 200,000. And the
//! largest number a description may give for a parameter or an offset,
//! [`MAX_PARAMETER_MAGNITUDE`].

use std::path::Path;

use crate::error::{ModelError, ModelErrorKind as K};

/// The largest description file (TOML or URDF) the loaders read: 64 MiB. Real robot
/// descriptions are kilobytes to a few megabytes (meshes are separate files).
pub const MAX_DESCRIPTION_BYTES: u64 = 64 << 20;

/// The deepest URDF element nesting accepted (`<robot>` `<link>` `<inertial>` `<mass>` is four;
/// Gazebo and transmission extensions add a few).
pub const MAX_URDF_DEPTH: usize = 64;

/// The largest magnitude the loaders accept for a parameter value (mass, length, first moment,
/// inertia, gravity, in SI units) and for a constant of a joint's translation: 10⁹. A
/// thousand-tonne machine with kilometre links stays below it; a mass of 10³⁰⁰ does not, and it
/// made the loaders' own mass-matrix check overflow and report a "speed that moves no mass".
/// Checked by both loaders with the other parameter checks, and by the URDF importer on every
/// mass, inertia and origin as written ([`crate::ModelErrorKind::AbsurdValue`]); the generated
/// code's run-time `Params::validate` checks finiteness and signs, not magnitude.
pub const MAX_PARAMETER_MAGNITUDE: f64 = 1e9;

/// [`K::AbsurdValue`] for the first of `values` larger in magnitude than
/// [`MAX_PARAMETER_MAGNITUDE`]; `item` names the number (`` parameter `m1` ``).
pub(crate) fn check_magnitude(item: impl Fn() -> String, values: &[f64]) -> Result<(), K> {
    match values.iter().find(|v| v.abs() > MAX_PARAMETER_MAGNITUDE) {
        Some(&value) => Err(K::AbsurdValue {
            item: item(),
            value,
            limit: MAX_PARAMETER_MAGNITUDE,
        }),
        None => Ok(()),
    }
}

/// The text of description file `path`, if it is no larger than [`MAX_DESCRIPTION_BYTES`]
/// (checked from its metadata before reading, and again while reading).
pub(crate) fn read_description(path: &Path) -> Result<String, ModelError> {
    use std::io::Read as _;
    let label = path.display().to_string();
    let err = |kind| ModelError::new(&label, kind);
    let file = std::fs::File::open(path).map_err(|e| err(K::Io(e)))?;
    let bytes = file.metadata().map_err(|e| err(K::Io(e)))?.len();
    check_size(bytes).map_err(err)?;
    // A file that grows while it is read (or a special file without a size) stops at the limit.
    let mut text = String::new();
    file.take(MAX_DESCRIPTION_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(|e| err(K::Io(e)))?;
    check_size(text.len() as u64).map_err(err)?;
    Ok(text)
}

/// [`K::TooLarge`] for a description of `bytes` bytes above the limit.
pub(crate) fn check_size(bytes: u64) -> Result<(), K> {
    if bytes > MAX_DESCRIPTION_BYTES {
        return Err(K::TooLarge {
            bytes,
            limit: MAX_DESCRIPTION_BYTES,
        });
    }
    Ok(())
}

/// [`K::UrdfTooDeep`] if the elements of `text` nest deeper than [`MAX_URDF_DEPTH`]. Stops at
/// the first element that is too deep, or at the first XML error (which the URDF parser then
/// reports in its own words).
pub(crate) fn check_urdf_depth(text: &str) -> Result<(), K> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut depth = 0usize;
    loop {
        match reader.read_event() {
            Ok(Event::Start(e)) => {
                depth += 1;
                if depth > MAX_URDF_DEPTH {
                    return Err(K::UrdfTooDeep {
                        element: String::from_utf8_lossy(e.name().as_ref()).into_owned(),
                        limit: MAX_URDF_DEPTH,
                    });
                }
            }
            Ok(Event::End(_)) => depth = depth.saturating_sub(1),
            Ok(Event::Eof) | Err(_) => return Ok(()),
            Ok(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nesting_up_to_the_limit_passes_and_one_level_more_is_an_error() {
        let nested = |d: usize| format!("{}{}", "<a>".repeat(d), "</a>".repeat(d));
        assert!(check_urdf_depth(&nested(MAX_URDF_DEPTH)).is_ok());
        let e = check_urdf_depth(&nested(MAX_URDF_DEPTH + 1)).unwrap_err();
        assert!(matches!(e, K::UrdfTooDeep { limit: 64, .. }), "{e:?}");
    }

    #[test]
    fn a_file_above_the_limit_is_refused_before_it_is_read() {
        // A sparse file: its size is known from the metadata, nothing is read.
        let path = std::env::temp_dir().join(format!("kanegen-large-{}.toml", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_DESCRIPTION_BYTES + 1).unwrap();
        let toml = crate::Model::from_toml_file(&path).unwrap_err();
        let urdf = crate::Model::from_urdf_file(&path, &crate::UrdfOptions::default()).unwrap_err();
        std::fs::remove_file(&path).unwrap();
        for e in [toml, urdf] {
            assert!(matches!(e.kind, K::TooLarge { .. }), "{e}");
            assert!(
                e.to_string().contains("kanegen-large-"),
                "names the file: {e}"
            );
        }
    }

    #[test]
    fn sizes_above_the_limit_are_refused() {
        assert!(check_size(MAX_DESCRIPTION_BYTES).is_ok());
        let e = check_size(MAX_DESCRIPTION_BYTES + 1).unwrap_err();
        assert!(e.to_string().contains("67108865 bytes"), "{e}");
    }
}
