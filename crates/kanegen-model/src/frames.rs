//! Operational frames: frames fixed to a body frame at a constant offset (a tool, a hand, a
//! sensor), declared in a TOML description (`[[frame]]`), as URDF tool frames
//! ([`UrdfOptions::frames`](crate::UrdfOptions::frames)) or added to a loaded model
//! ([`Model::add_frame`]).
//!
//! An operational frame becomes a link of the IR without a body, mounted on its parent by a
//! [`JointKind::Fixed`] joint whose `iAj(0)` and `iPj` are the frame's rotation and translation.
//! It is appended after the frames already there (the indices of the body frames do not change),
//! so it joins every per-frame function (`frame_pose`, `frame_jacobian`,
//! `frame_bias_acceleration`) and the generated `Frame` type, and adds nothing to the dynamics.

use crate::error::{ModelError, ModelErrorKind as K};
use crate::ir::*;
use crate::validate;

/// A frame fixed to a body frame of the model (or to another operational frame) at a constant
/// offset: `rotation` is `parentAframe` by rows (its columns are the frame's unit vectors in the
/// parent frame), `translation` the frame's origin in the parent frame (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct OperationalFrame {
    /// The frame's name (`left_hand`, `tool0`); unique among the model's frames.
    pub name: String,
    /// The name of the frame it is fixed to.
    pub parent: String,
    /// `parentAframe`, by rows: a proper rotation.
    pub rotation: [[f64; 3]; 3],
    /// The frame's origin in the parent frame.
    pub translation: [f64; 3],
}

impl OperationalFrame {
    /// A frame at `translation` in `parent`, with the parent's axes (identity rotation).
    pub fn new(name: impl Into<String>, parent: impl Into<String>, translation: [f64; 3]) -> Self {
        Self {
            name: name.into(),
            parent: parent.into(),
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation,
        }
    }

    /// The same frame with the rotation `parentAframe` (by rows).
    pub fn with_rotation(mut self, rotation: [[f64; 3]; 3]) -> Self {
        self.rotation = rotation;
        self
    }
}

impl Model {
    /// Adds an operational frame (validated: a new, printable name, an existing parent, a proper
    /// rotation and a finite translation) and returns its link index. The error names
    /// [`Model::source`] as the file.
    pub fn add_frame(&mut self, frame: &OperationalFrame) -> Result<usize, ModelError> {
        let translation = frame.translation.map(Length::number);
        if let Some(x) = frame.translation.iter().find(|x| !x.is_finite()) {
            return Err(ModelError::new(
                &self.source,
                K::BadFrame {
                    frame: frame.name.clone(),
                    detail: format!("translation entry {x} is not a finite number (metres)"),
                },
            ));
        }
        add_fixed_frame(
            self,
            &frame.name,
            &frame.parent,
            frame.rotation,
            translation,
            &frame.name,
        )
        .map_err(|k| ModelError::new(&self.source, k))
    }
}

/// Appends a body-less link `name` mounted on `parent` by a fixed joint called `joint`, after
/// checking the name (non-empty, printable, new), the parent and the rotation. Its index.
pub(crate) fn add_fixed_frame(
    model: &mut Model,
    name: &str,
    parent: &str,
    rotation: [[f64; 3]; 3],
    translation: [Length; 3],
    joint: &str,
) -> Result<usize, K> {
    let bad = |detail: String| K::BadFrame {
        frame: name.to_owned(),
        detail,
    };
    if name.trim().is_empty() || name.chars().any(|c| c.is_control()) {
        return Err(bad(
            "a frame needs a non-empty name without control characters".into(),
        ));
    }
    if model.link_index(name).is_some() {
        return Err(K::Duplicate {
            what: "frame",
            name: name.to_owned(),
        });
    }
    let Some(p) = model.link_index(parent) else {
        let names: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
        return Err(bad(format!(
            "parent frame `{parent}` is not defined; name one of the model's frames ({})",
            names.join(", ")
        )));
    };
    validate::check_rotation(joint, &rotation).map_err(|e| bad(e.to_string()))?;
    model.links.push(Link {
        name: name.to_owned(),
        mount: Some(Mount {
            parent: p,
            joint: Joint {
                name: joint.to_owned(),
                kind: JointKind::Fixed,
                axis: [0.0, 0.0, 1.0],
                rotation,
                translation,
            },
        }),
        body: None,
    });
    Ok(model.links.len() - 1)
}
