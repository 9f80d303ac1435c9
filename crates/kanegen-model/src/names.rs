//! The names generated code gives model quantities, and the one validation of every name that
//! reaches generated code ([`Model::check_names`]).
//!
//! A generated module is written in terms of the model's names:
//!
//! * every generated function body binds, as local variables, the coordinates (`q_imu`), the
//!   speeds (`qd_imu`), the accelerations ([`accel`]: `qdd_imu`), the sines and cosines of the
//!   coordinates ([`sin`], [`cos`]: `s_q_imu`, `c_q_imu`), and its own locals: the inputs `q`,
//!   `u`, `ud`, `p`, `pc`, the results `m`, `out`, the statements `k1, k2, …` (kinematic),
//!   `d1, …` (inertial), `t1, …` (common subexpressions), `pc1, …` (parameter-only terms), and
//!   the few names of [`RESERVED_LOCALS`];
//! * the index constants are the upper-cased coordinates (`index::Q_IMU`);
//! * the parameters are the fields of `Params` (`p.MX4l`);
//! * the wrapper type is [`type_name`] of the model name (`krang-fixed-wheels` →
//!   `KrangFixedWheels`), next to the module's items ([`RESERVED_ITEMS`]).
//!
//! Frame, joint and body names appear only in comments, documentation and string literals.
//!
//! The rule ([`Model::check_names`], run by both loaders after the URDF importer's
//! [`crate::sanitize_identifier`], and by the generator on any model):
//!
//! 1. coordinates, speeds and parameters are Rust identifiers as written (rustc's rule: an
//!    `XID_Start` character or `_`, then `XID_Continue` characters — letters of every script,
//!    digits, `_` — in Unicode normalisation form C) and no Rust keyword; the error proposes
//!    the sanitised spelling;
//! 2. none of them is a name that generated code binds itself ([`is_reserved`]): `k<digits>`,
//!    `d<digits>`, `t<digits>`, `pc<digits>`, [`RESERVED_LOCALS`], [`RESERVED_ITEMS`], or the
//!    model's wrapper type;
//! 3. the local names of a function body (coordinates, speeds, accelerations, sines, cosines)
//!    are distinct ignoring case (so a speed `s_q_w` cannot shadow the sine of `q_w`, and
//!    `qa`/`QA`, or `q_ψ`/`q_Ψ`, cannot both give one index constant); parameters are distinct;
//! 4. the model's wrapper type is not a keyword or a name of [`RESERVED_ITEMS`], and the model
//!    name has no control or bidirectional-override characters (it is written into comments and
//!    documentation);
//! 5. frame, joint and body names have no control or bidirectional-override characters
//!    ([`crate::is_unprintable`]): a newline in a frame name is an error naming the frame.
//!
//! The generated locals keep their short shapes (`k12`, `d3`): generated code stays as readable
//! as the reports, and the rule rejects model names of those shapes instead.

use std::collections::HashMap;

use crate::error::{BadName, ModelError, ModelErrorKind as K};
use crate::ident::{escape_unprintable, is_keyword, is_unprintable, sanitize_identifier};
use crate::ir::{JointKind, Model};

/// Names that generated function bodies bind or call besides the model's names and the
/// statement locals (`k1`, `d1`, `t1`, `pc1`, `d5_d90`): the two-lane multiply-add `lanes`, inputs (`p`, `pc`, `q`, `u`, `ud`, and `_p`,
/// `_pc` when unused), results (`m`, `out`), the symmetric copy loop (`s`, `c`, `r`), the
/// batched trigonometry (`sin_q`, `cos_q`, `sin_cos_n`), and `Params::from_array`'s argument `v`.
pub const RESERVED_LOCALS: &[&str] = &[
    "lanes",
    "p",
    "_p",
    "pc",
    "_pc",
    "q",
    "u",
    "ud",
    "m",
    "out",
    "s",
    "c",
    "r",
    "sin_q",
    "cos_q",
    "sin_cos_n",
    "v",
    "rot",
    "pos",
    "frame",
];

/// Items of a generated module, and the prelude names its code uses: a model name equal to one
/// of them would shadow it or be read as a pattern (`let None = …`).
pub const RESERVED_ITEMS: &[&str] = &[
    "F64x2",
    "DOF",
    "SPEED_NAMES",
    "COORDINATE_NAMES",
    "PARAM_COUNT",
    "Params",
    "Precomputed",
    "DerivativesWorkspace",
    "UnknownParameter",
    "SetParameterError",
    "Frame",
    "SMatrix",
    "SVector",
    "Some",
    "None",
    "Ok",
    "Err",
    "Option",
    "Result",
    "Default",
    "Clone",
    "Copy",
    "Debug",
    "PartialEq",
    "Eq",
];

/// Prefixes of the statement locals that lowering names `k1`, `d1`, `t1`, `pc1`.
pub const LOCAL_PREFIXES: &[&str] = &["k", "d", "t", "pc"];

/// Name of the acceleration of a speed: `qd_imu` → `qdd_imu`, `xd` → `xdd`, `psid` → `psidd`.
pub fn accel(speed: &str) -> String {
    match speed.strip_prefix("qd") {
        Some(rest) => format!("qdd{rest}"),
        None => format!("{speed}d"),
    }
}

/// Name of the sine of a coordinate: `q_imu` → `s_q_imu`.
pub fn sin(coordinate: &str) -> String {
    format!("s_{coordinate}")
}

/// Name of the cosine of a coordinate: `q_imu` → `c_q_imu`.
pub fn cos(coordinate: &str) -> String {
    format!("c_{coordinate}")
}

/// Name of the index constant of a coordinate: `q_imu` → `Q_IMU`, `q_ψ` → `Q_Ψ` (Unicode upper
/// case; letters without case, such as `肘`, stay).
pub fn index_constant(coordinate: &str) -> String {
    coordinate.to_uppercase()
}

/// The wrapper type of a model: `krang-fixed-wheels` → `KrangFixedWheels` (`Model…` if the
/// name does not start with a letter).
pub fn type_name(model: &str) -> String {
    let mut out = String::new();
    let mut up = true;
    for ch in model.chars() {
        if ch.is_ascii_alphanumeric() {
            if up {
                out.push(ch.to_ascii_uppercase());
            } else {
                out.push(ch);
            }
            up = false;
        } else {
            up = true;
        }
    }
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert_str(0, "Model");
    }
    out
}

/// Whether `name` has the shape of a statement local of generated code: one of
/// [`LOCAL_PREFIXES`] followed by digits only (`k12`, `d3`, `t4`, `pc7`), or two of them
/// joined by `_` (`d5_d90`: a pair of statements computed in two lanes).
pub fn is_generated_local(name: &str) -> bool {
    let single = |name: &str| {
        LOCAL_PREFIXES.iter().any(|p| {
            name.strip_prefix(p)
                .is_some_and(|rest| !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()))
        })
    };
    single(name)
        || name
            .split_once('_')
            .is_some_and(|(a, b)| single(a) && single(b))
}

/// Whether generated code binds or uses `name` itself, whatever the model
/// ([`is_generated_local`], [`RESERVED_LOCALS`], [`RESERVED_ITEMS`]).
pub fn is_reserved(name: &str) -> bool {
    is_generated_local(name) || RESERVED_LOCALS.contains(&name) || RESERVED_ITEMS.contains(&name)
}

/// The typed error for name `name` of `item`.
fn bad(item: String, name: &str, problem: String, fix: String) -> K {
    K::BadName(Box::new(BadName {
        item,
        name: name.to_owned(),
        problem,
        fix,
    }))
}

/// `name` is an identifier as written and no keyword; otherwise the error, proposing the
/// sanitised spelling (made free of `taken` and of reserved names).
fn check_identifier(item: &str, name: &str, taken: &dyn Fn(&str) -> bool) -> Result<(), K> {
    let base = sanitize_identifier(name);
    if base == name {
        return Ok(());
    }
    let mut fix = base.clone();
    let mut n = 2;
    while taken(&fix) || is_reserved(&fix) {
        fix = format!("{base}_{n}");
        n += 1;
    }
    let problem = if is_keyword(name) {
        "is a Rust keyword"
    } else if crate::ident::is_identifier(&crate::ident::nfc(name)) {
        "is not in Unicode normalisation form C (rustc normalises identifiers to NFC)"
    } else {
        "is not a Rust identifier (letters of any script, digits and `_`, not starting with a \
         digit)"
    };
    Err(bad(
        item.to_owned(),
        name,
        problem.to_owned(),
        format!("rename it, e.g. `{fix}`"),
    ))
}

/// `name` is not reserved (nor the wrapper type `ty`).
fn check_not_reserved(item: &str, name: &str, ty: &str) -> Result<(), K> {
    let problem = if is_generated_local(name) {
        "has the shape of a local variable of generated code (`k<n>`, `d<n>`, `t<n>`, `pc<n>` \
         hold intermediate values)"
    } else if RESERVED_LOCALS.contains(&name) {
        "is a local variable of every generated function"
    } else if RESERVED_ITEMS.contains(&name) {
        "is an item of the generated module or of the Rust prelude"
    } else if name == ty {
        "is the model's generated wrapper type"
    } else {
        return Ok(());
    };
    Err(bad(
        item.to_owned(),
        name,
        problem.to_owned(),
        format!("rename it, e.g. `{name}_`"),
    ))
}

/// One name of a generated function body: what it is (for messages) and its spelling.
struct Local {
    /// `speed`, `coordinate of joint `a``, `sine of coordinate `q_w``, ...
    item: String,
    name: String,
    /// Whether the model gives the name as written (coordinates, speeds) rather than deriving it.
    written: bool,
}

/// The local names of generated function bodies: per speed its coordinate, the speed, its
/// acceleration, and the sine and cosine of the coordinate.
fn locals(model: &Model) -> Vec<Local> {
    let mut driver: Vec<Option<&str>> = vec![None; model.speeds.len()];
    for (_, _, m) in model.mounted_links() {
        if let JointKind::Revolute { speed } | JointKind::Prismatic { speed } = m.joint.kind {
            driver[speed] = Some(&m.joint.name);
        }
    }
    let mut out = Vec::new();
    for (s, sp) in model.speeds.iter().zip(&driver) {
        let of = match sp {
            Some(j) => format!(" of joint `{j}`"),
            None if model.is_floating() => " of the floating base".to_owned(),
            None => " of the wheeled base".to_owned(),
        };
        let c = &s.coordinate;
        let mut push = |item: String, name: String, written: bool| {
            out.push(Local {
                item,
                name,
                written,
            })
        };
        push(format!("coordinate{of}"), c.clone(), true);
        push(format!("speed{of}"), s.name.clone(), true);
        push(
            format!("acceleration of speed `{}`", s.name),
            accel(&s.name),
            false,
        );
        push(format!("sine of coordinate `{c}`"), sin(c), false);
        push(format!("cosine of coordinate `{c}`"), cos(c), false);
    }
    if model.is_floating() {
        out.push(Local {
            item: "coordinate of the floating base".to_owned(),
            name: crate::ir::FLOATING_BASE_COORDINATES[6].to_owned(),
            written: true,
        });
    }
    out
}

/// The model name: printable, and its wrapper type free.
fn check_model_name(model: &Model) -> Result<String, K> {
    let item = "model name".to_owned();
    if let Some(c) = model.name.chars().find(|&c| is_unprintable(c)) {
        return Err(bad(
            item,
            &escape_unprintable(&model.name),
            format!(
                "contains the character {:?}, which generated comments and documentation cannot carry",
                c
            ),
            "choose a name without control characters ([model] name in TOML; \
             UrdfOptions::name or `--name` for a URDF)"
                .into(),
        ));
    }
    let ty = type_name(&model.name);
    if is_keyword(&ty) || RESERVED_ITEMS.contains(&ty.as_str()) {
        return Err(bad(
            item,
            &model.name,
            format!("gives the wrapper type `{ty}`, a name generated code already uses"),
            "choose another model name ([model] name in TOML; UrdfOptions::name or `--name` \
             for a URDF)"
                .into(),
        ));
    }
    Ok(ty)
}

/// The parameters: identifiers, not reserved, distinct. A body's parameters name its link.
fn check_params(model: &Model, ty: &str) -> Result<(), K> {
    let mut owner: HashMap<usize, &str> = HashMap::new();
    for l in &model.links {
        if let Some(b) = &l.body {
            for i in [b.mass].into_iter().chain(b.first_moment).chain(b.inertia) {
                owner.insert(i, &l.name);
            }
        }
    }
    let item = |i: usize| match owner.get(&i) {
        Some(link) => format!("parameter of the body on frame `{link}`"),
        None => "parameter".to_owned(),
    };
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (i, p) in model.params.iter().enumerate() {
        check_identifier(&item(i), &p.name, &|n| model.param_index(n).is_some())?;
        check_not_reserved(&item(i), &p.name, ty)?;
        if let Some(first) = seen.insert(&p.name, i) {
            return Err(bad(
                item(i),
                &p.name,
                format!("is also the name of a {}", item(first)),
                "rename one of them (for a URDF: one of the links; names are compared after \
                 sanitising to identifiers)"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// The local names of function bodies: identifiers, not reserved, distinct ignoring case (as
/// upper-cased by [`index_constant`]).
fn check_locals(model: &Model, ty: &str) -> Result<(), K> {
    let locals = locals(model);
    let folded: HashMap<String, usize> = locals
        .iter()
        .enumerate()
        .rev()
        .map(|(k, l)| (index_constant(&l.name), k))
        .collect();
    for (k, l) in locals.iter().enumerate() {
        if l.written {
            check_identifier(&l.item, &l.name, &|n| {
                folded.contains_key(&index_constant(n))
            })?;
        }
        check_not_reserved(&l.item, &l.name, ty)?;
        let first = folded[&index_constant(&l.name)];
        if first != k {
            // Report the name the model writes (a derived name follows from it).
            let other = &locals[first];
            let (named, clash) = if l.written { (l, other) } else { (other, l) };
            let problem = if clash.name == named.name {
                format!("is also the name of the {} in generated code", clash.item)
            } else {
                format!(
                    "equals `{}`, the name of the {}, ignoring case (generated index \
                     constants are upper-cased)",
                    clash.name, clash.item
                )
            };
            return Err(bad(
                named.item.clone(),
                &named.name,
                problem,
                "rename one of them".into(),
            ));
        }
    }
    Ok(())
}

/// The names that generated comments, documentation and string literals carry as written
/// (frames, joints, bodies): printable, so that no name can end a comment and start code.
fn check_printable(model: &Model) -> Result<(), K> {
    for link in &model.links {
        let mut names = vec![("frame", &link.name)];
        if let Some(j) = link.joint() {
            names.push(("joint", &j.name));
        }
        if let Some(b) = &link.body {
            names.push(("body", &b.name));
        }
        for (what, name) in names {
            if let Some(c) = name.chars().find(|&c| is_unprintable(c)) {
                return Err(bad(
                    format!("{what} `{}`", escape_unprintable(name)),
                    &escape_unprintable(name),
                    format!(
                        "contains the character {c:?}, which generated comments, documentation \
                         and name strings cannot carry as written"
                    ),
                    "rename it without control or bidirectional-override characters".into(),
                ));
            }
        }
    }
    Ok(())
}

/// The one validation of every name that reaches generated code (see the [module](self)).
pub(crate) fn check(model: &Model) -> Result<(), K> {
    let ty = check_model_name(model)?;
    check_printable(model)?;
    check_params(model, &ty)?;
    check_locals(model, &ty)
}

impl Model {
    /// Checks every name that reaches generated code (coordinates, speeds, parameters, the model
    /// name) against the rule of the [`names`](crate::names) module. Both loaders run it; the
    /// generator runs it on models built in memory.
    pub fn check_names(&self) -> Result<(), ModelError> {
        check(self).map_err(|kind| ModelError::new(&self.source, kind))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statement_local_shapes_are_recognised() {
        // `d5_d90`: a pair of statements in two lanes.
        for n in ["k1", "d12", "t3", "pc40", "d5_d90", "k1_t2"] {
            assert!(is_generated_local(n) && is_reserved(n), "{n}");
        }
        for n in [
            "k", "d1a", "pc", "kd1", "K1", "qd1", "t_1", "d5_", "d5_x1", "d5_d6_d7",
        ] {
            assert!(!is_generated_local(n), "{n}");
        }
    }

    #[test]
    fn derived_names() {
        assert_eq!(accel("qd_imu"), "qdd_imu");
        assert_eq!(accel("psid"), "psidd");
        assert_eq!(sin("q_w"), "s_q_w");
        assert_eq!(cos("q_w"), "c_q_w");
        assert_eq!(index_constant("q_imu"), "Q_IMU");
        assert_eq!(type_name("krang-fixed-wheels"), "KrangFixedWheels");
        assert_eq!(type_name("2link"), "Model2link");
        assert_eq!(type_name("self"), "Self");
    }
}
