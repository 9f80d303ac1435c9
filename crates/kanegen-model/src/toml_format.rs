//! The TOML description format (parsed with serde/toml) and its conversion to the IR.
//!
//! ```toml
//! [model]
//! name = "two-link"
//! description = "Seed 002 Appendix B"
//! speeds = ["qd_imu", "qd_w"]          # the order of u
//!
//! [base]
//! type = "fixed"                        # or "wheeled" (see WheeledBase)
//! frame = "0"
//!
//! [gravity]
//! symbol = "g"
//! direction = [0, 0, -1]                # unit vector in the base frame
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
//! ```

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
        let text = std::fs::read_to_string(path).map_err(|e| ModelError::new(&label, K::Io(e)))?;
        Self::from_toml_str(&text, &label)
    }

    /// Parse and validate a TOML description held in memory; `file` labels error messages.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Model, ModelError> {
        let err = |kind| ModelError::new(file, kind);
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
    fn lookup(&mut self, item: &str, name: &str, kind: ParamKind) -> Result<ParamId, K> {
        let &i = self.index.get(name).ok_or_else(|| K::UndefinedSymbol {
            item: item.to_owned(),
            symbol: name.to_owned(),
        })?;
        self.used[i] = true;
        self.params[i].kind = kind;
        Ok(i)
    }
}

fn parse_length(entry: &LengthEntry, joint: &str, syms: &mut Symbols) -> Result<Scalar, K> {
    match entry {
        LengthEntry::Number(v) if v.is_finite() => Ok(Scalar::number(*v)),
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
            let valid = name
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !valid {
                return Err(K::BadLength {
                    joint: joint.to_owned(),
                    text: text.clone(),
                });
            }
            let p = syms.lookup(&format!("joint `{joint}`"), name, ParamKind::Length)?;
            Ok(Scalar {
                coef,
                symbol: Some(p),
            })
        }
    }
}

fn build(f: File, file: &str) -> Result<Model, K> {
    // Parameters, in file order.
    let mut syms = Symbols {
        params: Vec::new(),
        index: HashMap::new(),
        used: Vec::new(),
    };
    for (name, value) in &f.parameters {
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
        if !v.is_finite() {
            return Err(K::NonFiniteParameter {
                name: name.clone(),
                value: v,
            });
        }
        syms.index.insert(name.clone(), syms.params.len());
        syms.params.push(Param {
            name: name.clone(),
            value: v,
            kind: ParamKind::Length,
        });
        syms.used.push(false);
    }

    // Speeds.
    let mut speeds: Vec<Speed> = Vec::new();
    for s in &f.model.speeds {
        if speeds.iter().any(|x| &x.name == s) {
            return Err(K::Duplicate {
                what: "speed",
                name: s.clone(),
            });
        }
        speeds.push(Speed {
            name: s.clone(),
            coordinate: String::new(),
        });
    }
    // Who drives each speed (for SpeedTwice / SpeedNever).
    let mut driver: Vec<Option<String>> = vec![None; speeds.len()];
    let mut drive = |speed: &str, who: String, coordinate: &str, speeds: &mut Vec<Speed>| {
        let i = speeds
            .iter()
            .position(|s| s.name == speed)
            .ok_or_else(|| K::UnknownSpeed {
                item: who.clone(),
                speed: speed.to_owned(),
            })?;
        if let Some(first) = &driver[i] {
            return Err(K::SpeedTwice {
                speed: speed.to_owned(),
                first: first.clone(),
                second: who,
            });
        }
        driver[i] = Some(who);
        speeds[i].coordinate = coordinate.to_owned();
        Ok(i)
    };

    // Base.
    let (base_frame, base) = match &f.base {
        BaseSection::Fixed { frame } => (frame.clone(), None),
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
            let xs = drive(
                x_speed,
                "the wheeled base (x_speed)".into(),
                "x",
                &mut speeds,
            )?;
            let ps = drive(
                psi_speed,
                "the wheeled base (psi_speed)".into(),
                "psi",
                &mut speeds,
            )?;
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
            (frame.clone(), Some(w))
        }
    };

    // Gravity.
    let gsym = syms.lookup("gravity", &f.gravity.symbol, ParamKind::Gravity)?;
    let dir = f.gravity.direction;
    validate::check_gravity_direction(dir).map_err(|detail| K::Invalid {
        item: "gravity".into(),
        detail,
    })?;

    // Frames and joints: a tree rooted at the base frame.
    let mut joint_names: Vec<&str> = Vec::new();
    let mut child_of: HashMap<&str, usize> = HashMap::new();
    for (k, j) in f.joints.iter().enumerate() {
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
    for j in &f.joints {
        if j.parent != base_frame && !child_of.contains_key(j.parent.as_str()) {
            return Err(K::UnknownParent {
                joint: j.name.clone(),
                parent: j.parent.clone(),
            });
        }
    }
    // Topological order: repeatedly place the joints whose parent is placed, in file order.
    let mut links = vec![Link {
        name: base_frame.clone(),
        parent: None,
        joint: None,
        body: None,
    }];
    let mut placed: HashMap<String, usize> = HashMap::from([(base_frame.clone(), 0)]);
    let mut remaining: Vec<usize> = (0..f.joints.len()).collect();
    while !remaining.is_empty() {
        let before = remaining.len();
        let mut next = Vec::new();
        for k in remaining {
            let j = &f.joints[k];
            match placed.get(&j.parent) {
                Some(&p) => {
                    let joint = build_joint(j, &mut syms, &mut drive, &mut speeds)?;
                    placed.insert(j.child.clone(), links.len());
                    links.push(Link {
                        name: j.child.clone(),
                        parent: Some(p),
                        joint: Some(joint),
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
            let mut seen = vec![false; f.joints.len()];
            while !seen[k] {
                seen[k] = true;
                k = child_of[f.joints[k].parent.as_str()];
            }
            let j = &f.joints[k];
            return Err(K::Cycle {
                joint: j.name.clone(),
                frame: j.child.clone(),
            });
        }
        remaining = next;
    }

    // Bodies.
    let mut body_names: Vec<String> = Vec::new();
    for b in &f.bodies {
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

    for (i, s) in speeds.iter().enumerate() {
        if driver[i].is_none() {
            return Err(K::SpeedNever {
                speed: s.name.clone(),
            });
        }
    }
    if let Some(i) = syms.used.iter().position(|u| !u) {
        return Err(K::UnusedParameter {
            name: syms.params[i].name.clone(),
        });
    }

    let model = Model {
        name: f.model.name,
        description: f.model.description,
        source: file.to_owned(),
        params: syms.params,
        speeds,
        links,
        base: match base {
            Some(w) => Base::Wheeled(w),
            None => Base::Fixed,
        },
        gravity: Gravity {
            symbol: gsym,
            direction: dir,
        },
    };
    validate::check_physics(&model)?;
    Ok(model)
}

type Drive<'a> = dyn FnMut(&str, String, &str, &mut Vec<Speed>) -> Result<usize, K> + 'a;

fn build_joint(
    j: &JointSection,
    syms: &mut Symbols,
    drive: &mut Drive<'_>,
    speeds: &mut Vec<Speed>,
) -> Result<Joint, K> {
    let kind = match j.kind {
        JointType::Revolute => JointKind::Revolute,
        JointType::Prismatic => JointKind::Prismatic,
        JointType::Fixed => JointKind::Fixed,
    };
    let speed = match (kind, &j.speed) {
        (JointKind::Fixed, None) => None,
        (JointKind::Fixed, Some(s)) => {
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
        (_, Some(s)) => Some(drive(s, format!("joint `{}`", j.name), &j.name, speeds)?),
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
        speed,
    })
}
