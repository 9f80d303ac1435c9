//! What a build prints besides the generated file: the URDF import notes that change or question
//! the model's numbers, summarised one line per kind ([`summary`]), and lines made safe for
//! cargo's one-line build-script instructions ([`one_line`]).
//!
//! The import records every decision as a note in prose (`joint `j1` <origin> rpy roll: 1.5708
//! snapped to π/2 (…)`); the emitter writes them all into the generated file's header. A build
//! prints only the kinds below, each once, with its count, the first few names and the
//! [`UrdfOptions`](crate::model::UrdfOptions) field that decides it; a non-physical link
//! inertia (loaded as written or repaired) gets a line of its own, with its numbers (the first
//! five; the rest are summarised in one line). Notes of what the caller
//! asked for by name (`drop_links`, a `mimic` mode, the wheeled base's constants) and of links
//! fixed to the base (no effect on the dynamics) are left to the header.

/// How many names a summary line shows before `and N more`.
const NAMES_SHOWN: usize = 3;
/// How many notes of a kind printed one line each ([`Kind::each`]) are printed before the rest
/// are summarised in one line (a generated tree with the same inertia on every link).
const EACH_SHOWN: usize = 5;

/// One kind of note: how to recognise it, what its line says, where its names are.
struct Kind {
    /// Whether a note is of this kind.
    matches: fn(&str) -> bool,
    /// The names a note contributes (each counts once toward the line's count).
    names: fn(&str) -> Vec<String>,
    /// Whether the count is of notes (angles) rather than of distinct names (links).
    count_notes: bool,
    /// Whether each note is a line of its own (the note, then the remedy) instead of a count:
    /// for what questions the model's numbers link by link (non-physical inertias).
    each: bool,
    /// Singular and plural noun.
    noun: (&'static str, &'static str),
    /// What happened to them.
    what: &'static str,
    /// The option that decides it.
    remedy: &'static str,
}

/// The first name between backticks of a note (`joint `j1` <origin> …` → `j1`).
fn first_quoted(note: &str) -> Vec<String> {
    let mut parts = note.splitn(3, '`');
    match (parts.next(), parts.next(), parts.next()) {
        (Some(_), Some(name), Some(_)) => vec![name.to_owned()],
        _ => Vec::new(),
    }
}

/// The comma-separated names after `marker` (`merged into `a` through fixed joints: b, c`).
fn listed_after(note: &str, marker: &str) -> Vec<String> {
    note.split_once(marker)
        .map(|(_, list)| list.split(", ").map(str::to_owned).collect())
        .unwrap_or_default()
}

const KINDS: &[Kind] = &[
    Kind {
        matches: |n| n.contains(" snapped to "),
        names: first_quoted,
        count_notes: true,
        each: false,
        noun: ("angle", "angles"),
        what: "snapped to a multiple of π/2",
        remedy: "UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written",
    },
    Kind {
        matches: |n| n.starts_with("merged into `") && n.contains(" through fixed joints: "),
        names: |n| listed_after(n, " through fixed joints: "),
        count_notes: false,
        each: false,
        noun: ("link", "links"),
        what: "merged through fixed joints (mass and inertia added to the parent's parameters)",
        remedy: "UrdfOptions::link_frames keeps a frame for each",
    },
    Kind {
        matches: |n| n.contains("principal moments") && n.ends_with("; kept as written"),
        names: first_quoted,
        count_notes: false,
        each: true,
        noun: ("non-physical inertia", "non-physical inertias"),
        what: "loaded as written",
        remedy: "UrdfOptions::non_physical_inertia = NonPhysicalInertia::Repair repairs it, Error refuses it",
    },
    Kind {
        matches: |n| n.contains("; repaired to the principal moments "),
        names: first_quoted,
        count_notes: false,
        each: true,
        noun: ("non-physical inertia", "non-physical inertias"),
        what: "repaired to the nearest physical one",
        remedy: "UrdfOptions::non_physical_inertia = NonPhysicalInertia::Note keeps it as written, Error refuses it",
    },
    Kind {
        matches: |n| {
            n.contains(": zero mass with a nonzero rotational inertia")
                && n.ends_with(": kept as a body with m = 0")
        },
        names: first_quoted,
        count_notes: false,
        each: false,
        noun: ("zero-mass link", "zero-mass links"),
        what: "kept as a body with its rotational inertia",
        remedy: "UrdfOptions::zero_mass_inertia = ZeroMassInertia::Drop drops their inertia",
    },
    Kind {
        matches: |n| {
            n.contains(": zero mass with a nonzero rotational inertia")
                && n.ends_with(": dropped (zero_mass_inertia = Drop)")
        },
        names: first_quoted,
        count_notes: false,
        each: false,
        noun: ("zero-mass link", "zero-mass links"),
        what: "without its rotational inertia",
        remedy: "UrdfOptions::zero_mass_inertia = ZeroMassInertia::Keep keeps it",
    },
    Kind {
        matches: |n| n.contains(": radius of gyration ") && n.ends_with(": inertia dropped"),
        names: first_quoted,
        count_notes: false,
        each: false,
        noun: ("implausible inertia", "implausible inertias"),
        what: "dropped",
        remedy: "UrdfOptions::absurd_inertia and max_radius_of_gyration decide",
    },
    Kind {
        matches: |n| n.contains(": radius of gyration ") && n.ends_with(": kept as written"),
        names: first_quoted,
        count_notes: false,
        each: false,
        noun: ("implausible inertia", "implausible inertias"),
        what: "kept as written",
        remedy: "UrdfOptions::absurd_inertia and max_radius_of_gyration decide",
    },
    Kind {
        matches: |n| {
            (n.starts_with("wheel `")
                && (n.contains(": not axisymmetric") || n.contains(" off the axle")))
                || n.starts_with("wheel masses differ")
        },
        names: |n| {
            let names = first_quoted(n);
            if names.is_empty() {
                vec!["wheel masses".into()]
            } else {
                names
            }
        },
        count_notes: true,
        each: false,
        noun: ("wheel constant", "wheel constants"),
        what: "averaged or simplified",
        remedy: "WheeledBaseSpec::wheel_mass, wheel_axle_inertia and wheel_diametral_inertia set them",
    },
];

/// The summary lines of the import `notes` of the model loaded from `source`, one per kind
/// present (one per note for non-physical inertias, which question a link's numbers: the
/// first five, then a summary line of the rest), in a fixed order:
///
/// ```text
/// kanegen: arm.urdf: 2 angles snapped to a multiple of π/2 (j1, j2); UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written
/// ```
///
/// Notes of no listed kind print nothing (the generated file's header has them all).
pub(crate) fn summary(source: &str, notes: &[String]) -> Vec<String> {
    let mut lines = Vec::new();
    for kind in KINDS {
        let matching: Vec<&String> = notes.iter().filter(|n| (kind.matches)(n)).collect();
        let mut rest = &matching[..];
        let mut more = "";
        if kind.each {
            let shown = matching.len().min(EACH_SHOWN);
            for note in &matching[..shown] {
                lines.push(one_line(&format!(
                    "kanegen: {source}: {note}; {}",
                    kind.remedy
                )));
            }
            rest = &matching[shown..];
            more = "more ";
        }
        let mut count = 0;
        let mut names: Vec<String> = Vec::new();
        for note in rest {
            let found = (kind.names)(note);
            count += if kind.count_notes { 1 } else { found.len() };
            for name in found {
                if !names.contains(&name) {
                    names.push(name);
                }
            }
        }
        if count == 0 {
            continue;
        }
        let noun = if count == 1 { kind.noun.0 } else { kind.noun.1 };
        let mut shown = names
            .iter()
            .take(NAMES_SHOWN)
            .map(String::as_str)
            .collect::<Vec<_>>()
            .join(", ");
        if names.len() > NAMES_SHOWN {
            shown.push_str(&format!(" and {} more", names.len() - NAMES_SHOWN));
        }
        let line = format!(
            "kanegen: {source}: {count} {more}{noun} {} ({shown}); {}",
            kind.what, kind.remedy
        );
        lines.push(one_line(&line));
    }
    lines
}

/// The lines of `lines` that this process has not returned before (each summary line is
/// printed once per build script, however many modules it generates from one model).
pub(crate) fn not_printed_yet(lines: Vec<String>) -> Vec<String> {
    static PRINTED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let mut printed = PRINTED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    lines
        .into_iter()
        .filter(|line| {
            let new = !printed.contains(line);
            if new {
                printed.push(line.clone());
            }
            new
        })
        .collect()
}

/// `text` as one line that cannot end or extend a cargo instruction: control characters
/// (newlines included) and bidirectional-text controls are escaped (`\n`, `\u{202e}`), by the
/// one escaping rule of [`kanegen_model::escape_unprintable`].
pub(crate) fn one_line(text: &str) -> String {
    kanegen_model::escape_unprintable(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_counted_once_and_cut_after_three() {
        let notes: Vec<String> = [
            "joint `j1` <origin> rpy roll: 1.5708 snapped to π/2 (…)",
            "joint `j1` <origin> rpy yaw: 1.5708 snapped to π/2 (…)",
            "joint `j2` <origin> rpy roll: -1.5708 snapped to -π/2 (…)",
            "link `l3` <inertial><origin> rpy pitch: 3.1416 snapped to π (…)",
            "joint `j4` <origin> rpy roll: 3.14 snapped to π (…)",
            "merged into `base` through fixed joints: flange, tool",
            "dropped (drop_links): gripper (0.5 kg in all)",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            summary("arm.urdf", &notes),
            [
                "kanegen: arm.urdf: 5 angles snapped to a multiple of π/2 (j1, j2, l3 and 1 more); UrdfOptions::snap_angles = AngleSnap::Off keeps angles as written",
                "kanegen: arm.urdf: 2 links merged through fixed joints (mass and inertia added to the parent's parameters) (flange, tool); UrdfOptions::link_frames keeps a frame for each",
            ]
        );
        assert!(summary("arm.urdf", &[]).is_empty());
    }

    #[test]
    fn non_physical_inertias_get_a_line_each_then_a_summary() {
        let notes: Vec<String> = (0..7)
            .map(|i| {
                format!(
                    "link `l{i}`: the inertia (…) has the principal moments 1, 1, 3 about the \
                     centre of mass: triangle inequality, by 33.33 % of the largest; kept as written"
                )
            })
            .collect();
        let lines = summary("tree.urdf", &notes);
        assert_eq!(lines.len(), 6, "{lines:?}");
        for (i, line) in lines[..5].iter().enumerate() {
            assert!(
                line.starts_with(&format!("kanegen: tree.urdf: link `l{i}`: ")),
                "{line}"
            );
            assert!(
                line.ends_with("Repair repairs it, Error refuses it"),
                "{line}"
            );
        }
        assert_eq!(
            lines[5],
            "kanegen: tree.urdf: 2 more non-physical inertias loaded as written (l5, l6); \
             UrdfOptions::non_physical_inertia = NonPhysicalInertia::Repair repairs it, Error refuses it"
        );
    }

    #[test]
    fn a_line_is_printed_once_per_process() {
        let line = || vec!["kanegen: once.urdf: a line printed once".to_owned()];
        assert_eq!(not_printed_yet(line()), line());
        assert!(not_printed_yet(line()).is_empty());
    }

    #[test]
    fn lines_stay_one_line() {
        assert_eq!(one_line("a\nb\r\u{202e}c"), "a\\nb\\r\\u{202e}c");
    }
}
