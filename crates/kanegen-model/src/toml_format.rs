//! The TOML description format (parsed with serde/toml) and its conversion to the IR.
//!
//! ```toml
//! [model]
//! name = "two-link"
//! description = "the fixed-wheels report (Zafar 2014), Appendix B"
//! speeds = ["qd_imu", "qd_w"]          # the order of u
//!
//! [base]
//! type = "fixed"                        # or "wheeled" (see WheeledBase) or "floating"
//! frame = "0"
//!
//! [gravity]
//! symbol = "g"
//! direction = [0, 0, -1]                # unit vector in the base frame (world frame if floating)
//!
//! [parameters]                          # every symbol with its default value (SI)
//! g = 9.81
//! L1 = 0.499
//!
//! [[joint]]
//! name = "q_imu"                        # the coordinate
//! type = "revolute"                     # revolute | prismatic | fixed
//! parent = "0"
//! child = "1"
//! speed = "qd_imu"
//! axis = [-1, 0, 0]                     # e_j in the child frame
//! rotation = [[0, 0, -1], [-1, 0, 0], [0, 1, 0]]   # iAj(0), by rows
//! translation = [0, "L1", "-L2"]        # iPj: numbers or [-]SYMBOL
//!
//! [[body]]
//! frame = "1"                           # symbols m1, MX1..MZ1, XX1..ZZ1 (suffix = name, default frame)
//!
//! [[frame]]                             # an operational frame: fixed to a frame, no body
//! name = "tool"
//! parent = "1"                          # a joint's child frame, the base frame or an earlier [[frame]]
//! rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]   # parentAframe by rows (default: identity)
//! translation = [0, 0, "L1"]            # the origin in the parent frame: numbers or [-]SYMBOL
//! ```
//!
//! A floating base (`type = "floating"`, with its `frame`) puts its six speeds
//! ([`FLOATING_BASE_SPEEDS`](crate::FLOATING_BASE_SPEEDS)) before those of `[model] speeds`, which
//! lists the joints' speeds only; see [`Base::Floating`](crate::Base::Floating).
//!
//! Operational frames are appended after the joints' frames, in file order (see
//! [`OperationalFrame`](crate::OperationalFrame)).

use std::collections::HashMap;
use std::path::Path;

use serde::Deserialize;

use crate::error::{ModelError, ModelErrorKind as K};
use crate::ir::*;
use crate::validate;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    model: ModelSection,
    base: BaseSection,
    gravity: GravitySection,
    parameters: toml::Table,
    #[serde(default, rename = "joint")]
    joints: Vec<JointSection>,
    #[serde(default, rename = "body")]
    bodies: Vec<BodySection>,
    #[serde(default, rename = "frame")]
    frames: Vec<FrameSection>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameSection {
    name: String,
    parent: String,
    #[serde(default = "identity")]
    rotation: [[f64; 3]; 3],
    translation: [LengthEntry; 3],
}

fn identity() -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelSection {
    name: String,
    #[serde(default)]
    description: String,
    speeds: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "lowercase", tag = "type")]
enum BaseSection {
    Fixed {
        frame: String,
    },
    Floating {
        frame: String,
    },
    Wheeled {
        frame: String,
        x_speed: String,
        psi_speed: String,
        radius: String,
        track: String,
        wheel_mass: String,
        wheel_axle_inertia: String,
        wheel_diametral_inertia: String,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct GravitySection {
    symbol: String,
    direction: [f64; 3],
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum JointType {
    Revolute,
    Prismatic,
    Fixed,
}

#[derive(Debug, Deserialize, Clone)]
#[serde(untagged)]
enum LengthEntry {
    Number(f64),
    Symbol(String),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointSection {
    name: String,
    #[serde(rename = "type")]
    kind: JointType,
    parent: String,
    child: String,
    #[serde(default)]
    speed: Option<String>,
    #[serde(default)]
    axis: Option<[f64; 3]>,
    rotation: [[f64; 3]; 3],
    translation: [LengthEntry; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BodySection {
    frame: String,
    #[serde(default)]
    name: Option<String>,
}

impl Model {
    /// Load and validate a TOML description file.
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<Model, ModelError> {
        let path = path.as_ref();
        let label = path.display().to_string();
        let text = crate::limits::read_description(path)?;
        Self::from_toml_str(&text, &label)
    }

    /// Parse and validate a TOML description held in memory; `file` labels error messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Model, ModelError> {
        let err = |kind| ModelError::new(file, kind);
        crate::limits::check_size(text.len() as u64).map_err(err)?;
        let parsed: File = toml::from_str(text).map_err(|e| err(K::Syntax(e.to_string())))?;
        build(parsed, file).map_err(err)
    }
}

/// Symbol table under construction: file-ordered parameters plus usage kinds.
struct Symbols {
    params: Vec<Param>,
    index: HashMap<String, ParamId>,
    used: Vec<bool>,
}

impl Symbols {
    /// The `[parameters]` table, in file order; every value a number (finite: checked with the
    /// model's other values by `validate::check_physics`).
    fn from_table(table: &toml::Table) -> Result<Self, K> {
        let mut syms = Symbols {
            params: Vec::new(),
            index: HashMap::new(),
            used: Vec::new(),
        };
        for (name, value) in table {
            let v = match value {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                other => {
                    return Err(K::Syntax(format!(
                        "parameter `{name}` must be a number, found {}",
                        other.type_str()
                    )));
                }
            };
            syms.index.insert(name.clone(), syms.params.len());
            syms.params.push(Param {
                name: name.clone(),
                value: v,
                kind: ParamKind::Length,
            });
            syms.used.push(false);
        }
        Ok(syms)
    }

    /// The parameter `name`, used by `item` as a `kind`.
    fn lookup(&mut self, item: &str, name: &str, kind: ParamKind) -> Result<ParamId, K> {
        let &i = self.index.get(name).ok_or_else(|| K::UndefinedSymbol {
            item: item.to_owned(),
            symbol: name.to_owned(),
        })?;
        self.used[i] = true;
        self.params[i].kind = kind;
        Ok(i)
    }

    /// The parameters, if every one is used.
    fn finish(self) -> Result<Vec<Param>, K> {
        if let Some(i) = self.used.iter().position(|u| !u) {
            return Err(K::UnusedParameter {
                name: self.params[i].name.clone(),
            });
        }
        Ok(self.params)
    }
}

/// The generalized speeds of `[model] speeds` and who drives each (a joint or the base).
struct Speeds {
    list: Vec<Speed>,
    driver: Vec<Option<String>>,
}

impl Speeds {
    /// The listed speeds, in order; names must be unique.
    fn new(names: &[String]) -> Result<Self, K> {
        let mut list: Vec<Speed> = Vec::new();
        for s in names {
            if list.iter().any(|x| &x.name == s) {
                return Err(K::Duplicate {
                    what: "speed",
                    name: s.clone(),
                });
            }
            list.push(Speed {
                name: s.clone(),
                coordinate: String::new(),
            });
        }
        Ok(Self {
            driver: vec![None; list.len()],
            list,
        })
    }

    /// `who` drives `speed`, the rate of `coordinate`; its index. A speed is driven once.
    fn drive(&mut self, speed: &str, who: String, coordinate: &str) -> Result<usize, K> {
        let i = self
            .list
            .iter()
            .position(|s| s.name == speed)
            .ok_or_else(|| K::UnknownSpeed {
                item: who.clone(),
                speed: speed.to_owned(),
            })?;
        if let Some(first) = &self.driver[i] {
            return Err(K::SpeedTwice {
                speed: speed.to_owned(),
                first: first.clone(),
                second: who,
            });
        }
        self.driver[i] = Some(who);
        self.list[i].coordinate = coordinate.to_owned();
        Ok(i)
    }

    /// The speeds, if every one is driven.
    fn finish(self) -> Result<Vec<Speed>, K> {
        if let Some(i) = self.driver.iter().position(Option::is_none) {
            return Err(K::SpeedNever {
                speed: self.list[i].name.clone(),
            });
        }
        Ok(self.list)
    }
}

fn parse_length(entry: &LengthEntry, joint: &str, syms: &mut Symbols) -> Result<Length, K> {
    match entry {
        LengthEntry::Number(v) if v.is_finite() => Ok(Length::number(*v)),
        LengthEntry::Number(v) => Err(K::BadLength {
            joint: joint.to_owned(),
            text: v.to_string(),
        }),
        LengthEntry::Symbol(text) => {
            let t = text.trim();
            let (coef, name) = match t.strip_prefix('-') {
                Some(rest) => (-1.0, rest.trim()),
                None => (1.0, t.strip_prefix('+').unwrap_or(t).trim()),
            };
            let valid = crate::ident::is_identifier(name);
            if !valid {
                return Err(K::BadLength {
                    joint: joint.to_owned(),
                    text: text.clone(),
                });
            }
            let p = syms.lookup(&format!("joint `{joint}`"), name, ParamKind::Length)?;
            Ok(Length {
                coef,
                symbol: Some(p),
            })
        }
    }
}

/// The model of a parsed description: parameters, speeds, base, gravity, the frame tree and the
/// bodies, each checked.
fn build(f: File, file: &str) -> Result<Model, K> {
    let mut syms = Symbols::from_table(&f.parameters)?;
    let mut speeds = match f.base {
        BaseSection::Floating { .. } => {
            let mut names: Vec<String> = FLOATING_BASE_SPEEDS.map(str::to_owned).to_vec();
            names.extend(f.model.speeds.iter().cloned());
            Speeds::new(&names)?
        }
        _ => Speeds::new(&f.model.speeds)?,
    };
    let (base_frame, base) = build_base(&f.base, &mut syms, &mut speeds)?;

    let gsym = syms.lookup("gravity", &f.gravity.symbol, ParamKind::Gravity)?;
    let dir = f.gravity.direction;
    validate::check_gravity_direction(dir).map_err(|detail| K::Invalid {
        item: "gravity".into(),
        detail,
    })?;

    let (mut links, placed) = build_frames(&f.joints, &base_frame, &mut syms, &mut speeds)?;
    add_bodies(&f.bodies, &placed, &mut links, &mut syms)?;
    let frame_offsets = f
        .frames
        .iter()
        .map(|fr| {
            let t = &fr.translation;
            Ok([
                parse_length(&t[0], &fr.name, &mut syms)?,
                parse_length(&t[1], &fr.name, &mut syms)?,
                parse_length(&t[2], &fr.name, &mut syms)?,
            ])
        })
        .collect::<Result<Vec<_>, K>>()?;

    let mut model = Model {
        name: f.model.name,
        description: f.model.description,
        source: file.to_owned(),
        speeds: speeds.finish()?,
        params: syms.finish()?,
        links,
        base,
        gravity: Gravity {
            symbol: gsym,
            direction: dir,
        },
        mimics: Vec::new(),
    };
    for (fr, translation) in f.frames.iter().zip(frame_offsets) {
        crate::frames::add_fixed_frame(
            &mut model,
            &fr.name,
            &fr.parent,
            fr.rotation,
            translation,
            &fr.name,
        )?;
    }
    crate::names::check(&model)?;
    validate::check_physics(&model, validate::TOLERANCE)?;
    Ok(model)
}

/// The base frame's name and the base (a wheeled base drives its two speeds).
fn build_base(
    section: &BaseSection,
    syms: &mut Symbols,
    speeds: &mut Speeds,
) -> Result<(String, Base), K> {
    match section {
        BaseSection::Fixed { frame } => Ok((frame.clone(), Base::Fixed)),
        BaseSection::Floating { frame } => {
            for (s, c) in FLOATING_BASE_SPEEDS.iter().zip(FLOATING_BASE_COORDINATES) {
                speeds.drive(s, "the floating base".into(), c)?;
            }
            Ok((frame.clone(), Base::Floating))
        }
        BaseSection::Wheeled {
            frame,
            x_speed,
            psi_speed,
            radius,
            track,
            wheel_mass,
            wheel_axle_inertia,
            wheel_diametral_inertia,
        } => {
            let item = "base";
            let xs = speeds.drive(x_speed, "the wheeled base (x_speed)".into(), "x")?;
            let ps = speeds.drive(psi_speed, "the wheeled base (psi_speed)".into(), "psi")?;
            let w = WheeledBase {
                x_speed: xs,
                psi_speed: ps,
                radius: syms.lookup(item, radius, ParamKind::Wheel)?,
                track: syms.lookup(item, track, ParamKind::Wheel)?,
                wheel_mass: syms.lookup(item, wheel_mass, ParamKind::Wheel)?,
                wheel_axle_inertia: syms.lookup(item, wheel_axle_inertia, ParamKind::Wheel)?,
                wheel_diametral_inertia: syms.lookup(
                    item,
                    wheel_diametral_inertia,
                    ParamKind::Wheel,
                )?,
            };
            Ok((frame.clone(), Base::Wheeled(w)))
        }
    }
}

/// Checks the joint and frame names: joints unique, no joint's child is the base frame, each
/// frame the child of one joint, every parent defined. The joint index by child frame.
fn index_joints<'a>(
    joints: &'a [JointSection],
    base_frame: &str,
) -> Result<HashMap<&'a str, usize>, K> {
    let mut joint_names: Vec<&str> = Vec::new();
    let mut child_of: HashMap<&str, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        if joint_names.contains(&j.name.as_str()) {
            return Err(K::Duplicate {
                what: "joint",
                name: j.name.clone(),
            });
        }
        joint_names.push(&j.name);
        if j.child == base_frame {
            return Err(K::BaseAsChild {
                joint: j.name.clone(),
                frame: j.child.clone(),
            });
        }
        if child_of.insert(&j.child, k).is_some() {
            return Err(K::Duplicate {
                what: "frame",
                name: j.child.clone(),
            });
        }
    }
    for j in joints {
        if j.parent != base_frame && !child_of.contains_key(j.parent.as_str()) {
            return Err(K::UnknownParent {
                joint: j.name.clone(),
                parent: j.parent.clone(),
            });
        }
    }
    Ok(child_of)
}

/// The frames in topological order (the base frame first, then repeatedly the joints whose parent
/// is placed, in file order), and the index of each frame by name.
fn build_frames(
    joints: &[JointSection],
    base_frame: &str,
    syms: &mut Symbols,
    speeds: &mut Speeds,
) -> Result<(Vec<Link>, HashMap<String, usize>), K> {
    let child_of = index_joints(joints, base_frame)?;
    let mut links = vec![Link {
        name: base_frame.to_owned(),
        mount: None,
        body: None,
    }];
    let mut placed: HashMap<String, usize> = HashMap::from([(base_frame.to_owned(), 0)]);
    let mut remaining: Vec<usize> = (0..joints.len()).collect();
    while !remaining.is_empty() {
        let before = remaining.len();
        let mut next = Vec::new();
        for k in remaining {
            let j = &joints[k];
            match placed.get(&j.parent) {
                Some(&p) => {
                    let joint = build_joint(j, syms, speeds)?;
                    placed.insert(j.child.clone(), links.len());
                    links.push(Link {
                        name: j.child.clone(),
                        mount: Some(Mount { parent: p, joint }),
                        body: None,
                    });
                }
                None => next.push(k),
            }
        }
        if next.len() == before {
            // Each unplaced joint's parent frame is the child of another unplaced joint: walk up
            // from one of them until a joint repeats; that joint is on a cycle (the first unplaced
            // joint may merely hang off one).
            let mut k = next[0];
            let mut seen = vec![false; joints.len()];
            while !seen[k] {
                seen[k] = true;
                k = child_of[joints[k].parent.as_str()];
            }
            let j = &joints[k];
            return Err(K::Cycle {
                joint: j.name.clone(),
                frame: j.child.clone(),
            });
        }
        remaining = next;
    }
    Ok((links, placed))
}

/// Attaches the bodies to their frames (`placed`: frame index by name); each body's symbols are
/// its prefixes (`m`, `MX`, ..., `ZZ`) followed by its name.
fn add_bodies(
    bodies: &[BodySection],
    placed: &HashMap<String, usize>,
    links: &mut [Link],
    syms: &mut Symbols,
) -> Result<(), K> {
    let mut body_names: Vec<String> = Vec::new();
    for b in bodies {
        let name = b.name.clone().unwrap_or_else(|| b.frame.clone());
        let Some(&li) = placed.get(&b.frame) else {
            return Err(K::UnknownFrame {
                body: name,
                frame: b.frame.clone(),
            });
        };
        if body_names.contains(&name) {
            return Err(K::Duplicate { what: "body", name });
        }
        if links[li].body.is_some() {
            return Err(K::Duplicate {
                what: "body on frame",
                name: b.frame.clone(),
            });
        }
        let item = format!("body `{name}`");
        let mut sym =
            |prefix: &str| syms.lookup(&item, &format!("{prefix}{name}"), ParamKind::Inertial);
        let body = Body {
            name: name.clone(),
            mass: sym("m")?,
            first_moment: [sym("MX")?, sym("MY")?, sym("MZ")?],
            inertia: [
                sym("XX")?,
                sym("XY")?,
                sym("XZ")?,
                sym("YY")?,
                sym("YZ")?,
                sym("ZZ")?,
            ],
        };
        body_names.push(name);
        links[li].body = Some(body);
    }
    Ok(())
}

/// The joint of a `[[joint]]` section: kind, driven speed, axis, rotation and translation, each
/// checked.
fn build_joint(j: &JointSection, syms: &mut Symbols, speeds: &mut Speeds) -> Result<Joint, K> {
    let kind = match (j.kind, &j.speed) {
        (JointType::Fixed, None) => JointKind::Fixed,
        (JointType::Fixed, Some(s)) => {
            return Err(K::JointSpeed {
                joint: j.name.clone(),
                detail: format!("a fixed joint drives no speed; remove `speed = \"{s}\"`"),
            });
        }
        (_, None) => {
            return Err(K::JointSpeed {
                joint: j.name.clone(),
                detail:
                    "a moving joint needs `speed = \"...\"` naming the generalized speed it drives"
                        .into(),
            });
        }
        (moving, Some(s)) => {
            let speed = speeds.drive(s, format!("joint `{}`", j.name), &j.name)?;
            match moving {
                JointType::Prismatic => JointKind::Prismatic { speed },
                _ => JointKind::Revolute { speed },
            }
        }
    };
    let axis = match (kind, j.axis) {
        (_, Some(a)) => a,
        (JointKind::Fixed, None) => [0.0, 0.0, 1.0],
        (_, None) => {
            return Err(K::JointSpeed {
                joint: j.name.clone(),
                detail: "a moving joint needs `axis = [x, y, z]` (unit vector in the child frame)"
                    .into(),
            });
        }
    };
    validate::check_axis(&j.name, axis)?;
    validate::check_rotation(&j.name, &j.rotation)?;
    let translation = [
        parse_length(&j.translation[0], &j.name, syms)?,
        parse_length(&j.translation[1], &j.name, syms)?,
        parse_length(&j.translation[2], &j.name, syms)?,
    ];
    Ok(Joint {
        name: j.name.clone(),
        kind,
        axis,
        rotation: j.rotation,
        translation,
    })
}
