//! Combined functions: several registry functions (and frames of per-frame functions) emitted as
//! **one** straight-line program with one result struct, for a controller that needs them at the
//! same state every tick.
//!
//! A controller built on operational-space or task-priority control calls `M`, `c + g`, the
//! hands' poses, Jacobians and bias accelerations and the CoM Jacobian at the same `(q, u)`.
//! Called one by one, every function computes its own sines and cosines and its own rotations,
//! angular velocities and positions. A combined function is the union of the parts' expression
//! DAGs in the one hash-consed arena, lowered as one program: sines and cosines are computed once
//! (one batched `sin_cos_n`), and so is every substitution variable two parts share (`⁰A_l`,
//! `⁰p_l`, `ω`, `α`, the composite inertias that `M`, `g` and the CoM Jacobian read, …). Every
//! part's values are those of its separate function, bit for bit (the same expressions; tested).
//!
//! ```no_run
//! use kanegen::FunctionId as F;
//! use kanegen::Combined;
//! kanegen::Builder::new("krang.toml")
//!     .combined(
//!         Combined::new("whole_body_terms")
//!             .with(F::MassMatrix)
//!             .with(F::NonlinearEffects)
//!             .with(F::ComJacobian)
//!             .with_frame(F::FrameJacobian, "right_hand")
//!             .with_frame(F::FrameBiasAcceleration, "right_hand"),
//!     )
//!     .run();
//! // generated: `pub struct WholeBodyTerms { pub mass_matrix, pub nonlinear_effects,
//! //   pub com_jacobian, pub frame_jacobian_right_hand, pub frame_bias_acceleration_right_hand }`,
//! // `fn whole_body_terms(p, pc, q, u) -> WholeBodyTerms` and the wrapper method
//! // `k.whole_body_terms(&q, &u)`.
//! ```
//!
//! The parts' registry functions need not be in the module's [`FunctionSet`](crate::FunctionSet)
//! (the separate functions are only generated if they are). The combined function takes the
//! inputs of its most demanding part (`q`; `q, u`; `q, u, u̇`). The regressors cannot be parts
//! (their columns depend on the module's base-parameter analysis).

use kanegen_model::Model;

use crate::registry::{FunctionId, Inputs};

/// One part of a combined function: a registry function, and the frame for a per-frame one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// The registry function.
    pub function: FunctionId,
    /// The frame's name in the model (`"right_hand"`, `"10l"`) for a per-frame function, else
    /// `None`.
    pub frame: Option<String>,
}

/// A combined function as asked for: a name and its parts (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Combined {
    name: String,
    parts: Vec<Part>,
}

impl Combined {
    /// A combined function named `name` (a Rust identifier in snake case, e.g.
    /// `whole_body_terms`; its result struct is the name in CamelCase, `WholeBodyTerms`),
    /// without parts yet.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            parts: Vec::new(),
        }
    }

    /// Adds registry function `function` (one without a frame argument) as a part; its field is
    /// the function's name (`mass_matrix`).
    #[must_use]
    pub fn with(mut self, function: FunctionId) -> Self {
        self.parts.push(Part {
            function,
            frame: None,
        });
        self
    }

    /// Adds per-frame registry function `function` for the frame named `frame` as a part; its
    /// field is the function's name, `_`, and the frame's name in snake case
    /// (`frame_jacobian_right_hand`, `frame_pose_10l`).
    #[must_use]
    pub fn with_frame(mut self, function: FunctionId, frame: impl Into<String>) -> Self {
        self.parts.push(Part {
            function,
            frame: Some(frame.into()),
        });
        self
    }

    /// The function's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The parts, in the order of the result struct's fields.
    pub fn parts(&self) -> &[Part] {
        &self.parts
    }
}

/// A part resolved against a model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ResolvedPart {
    /// The registry function.
    pub function: FunctionId,
    /// The frame (link index) of a per-frame function.
    pub frame: Option<usize>,
    /// The result struct's field.
    pub field: String,
}

/// A combined function resolved against a model: frames by index, field and type names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ResolvedCombined {
    /// The function's name (`whole_body_terms`).
    pub name: String,
    /// The result struct's name (`WholeBodyTerms`).
    pub type_name: String,
    /// The parts, in field order.
    pub parts: Vec<ResolvedPart>,
    /// The state inputs: those of the most demanding part.
    pub inputs: Inputs,
}

/// A combined function that cannot be generated: its name, the problem and the fix.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{model}: combined function `{function}`: {problem}; fix: {fix}")]
pub struct CombinedError {
    /// The model's description file.
    pub model: String,
    /// The combined function's name.
    pub function: String,
    /// What is wrong.
    pub problem: String,
    /// How to fix it.
    pub fix: String,
}

/// Names a combined function cannot take: the wrapper's own methods and the items of a module.
const RESERVED: &[&str] = &["new", "params", "set_params", "default", "index"];

/// `frame`'s name as the tail of a field name: ASCII alphanumerics in lower case, every other
/// run of characters one `_`.
fn snake(frame: &str) -> String {
    let mut out = String::new();
    for ch in frame.chars() {
        if ch.is_ascii_alphanumeric() {
            out.push(ch.to_ascii_lowercase());
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_matches('_').to_owned()
}

fn is_identifier(name: &str) -> bool {
    name.starts_with(|c: char| c.is_ascii_lowercase() || c == '_')
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && syn::parse_str::<syn::Ident>(name).is_ok()
}

/// Resolve `combined` against `model`: frame names to link indices, field and type names, the
/// inputs; every problem is a typed error naming the function and the fix.
pub fn resolve(
    model: &Model,
    combined: &[Combined],
) -> Result<Vec<ResolvedCombined>, CombinedError> {
    let mut out: Vec<ResolvedCombined> = Vec::new();
    for c in combined {
        let err = |problem: String, fix: String| CombinedError {
            model: model.source.clone(),
            function: c.name.clone(),
            problem,
            fix,
        };
        let name = c.name.as_str();
        if !is_identifier(name) {
            return Err(err(
                "the name is not a snake-case Rust identifier".into(),
                "use lower-case ASCII letters, digits and `_`, starting with a letter (e.g. `whole_body_terms`)".into(),
            ));
        }
        let per_frame_prefix = FunctionId::all()
            .filter(|f| f.spec().per_frame)
            .any(|f| name.starts_with(&format!("{}_", f.name())));
        if FunctionId::from_name(name).is_some()
            || per_frame_prefix
            || name.ends_with("_batch")
            || RESERVED.contains(&name)
            || kanegen_model::names::is_reserved(name)
        {
            return Err(err(
                "the name is taken by a generated function, a wrapper method or a local of generated code".into(),
                "choose another name (e.g. `whole_body_terms`)".into(),
            ));
        }
        if out.iter().any(|o| o.name == name) {
            return Err(err(
                "two combined functions have this name".into(),
                "give each combined function its own name".into(),
            ));
        }
        let type_name = crate::naming::type_name(name);
        if type_name == crate::naming::type_name(&model.name)
            || kanegen_model::names::RESERVED_ITEMS.contains(&type_name.as_str())
            || out.iter().any(|o| o.type_name == type_name)
        {
            return Err(err(
                format!("its result type `{type_name}` is taken by another item of the module"),
                "choose another name".into(),
            ));
        }
        if c.parts.is_empty() {
            return Err(err(
                "it has no parts".into(),
                "add parts with `Combined::with` and `Combined::with_frame`".into(),
            ));
        }
        let mut parts: Vec<ResolvedPart> = Vec::new();
        let mut inputs = Inputs::Q;
        for part in &c.parts {
            let spec = part.function.spec();
            if crate::registry::FunctionSet::regressors().contains(part.function) {
                return Err(err(
                    format!("`{}` cannot be a part of a combined function", spec.name),
                    "call the regressor on its own".into(),
                ));
            }
            let (frame, field) = match (&part.frame, spec.per_frame) {
                (None, false) => (None, spec.name.to_owned()),
                (Some(f), true) => {
                    let l = model.link_index(f).ok_or_else(|| {
                        err(
                            format!("the model has no frame `{f}` (part `{}`)", spec.name),
                            format!(
                                "use one of the model's frames: {}",
                                model
                                    .links
                                    .iter()
                                    .map(|l| l.name.as_str())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                    (Some(l), format!("{}_{}", spec.name, snake(f)))
                }
                (None, true) => {
                    return Err(err(
                        format!("`{}` takes a frame", spec.name),
                        format!(
                            "add it with `with_frame(FunctionId::{:?}, \"FRAME\")`",
                            spec.id
                        ),
                    ));
                }
                (Some(f), false) => {
                    return Err(err(
                        format!("`{}` takes no frame (asked for `{f}`)", spec.name),
                        format!("add it with `with(FunctionId::{:?})`", spec.id),
                    ));
                }
            };
            if parts.iter().any(|p| p.field == field) {
                return Err(err(
                    format!(
                        "the part `{field}` appears twice (or two frames' names differ only in punctuation or case)"
                    ),
                    "list each part once".into(),
                ));
            }
            inputs = match (inputs, spec.inputs) {
                (Inputs::QUUd, _) | (_, Inputs::QUUd) => Inputs::QUUd,
                (Inputs::QU, _) | (_, Inputs::QU) => Inputs::QU,
                _ => Inputs::Q,
            };
            parts.push(ResolvedPart {
                function: part.function,
                frame,
                field,
            });
        }
        out.push(ResolvedCombined {
            name: name.to_owned(),
            type_name,
            parts,
            inputs,
        });
    }
    Ok(out)
}
