//! URDF import: [`Model::from_urdf_file`], [`Model::from_urdf_str`] and [`UrdfImport`] (which also
//! returns the import notes).
//!
//! The file is parsed with `urdf-rs` (meshes are never opened) and converted to the IR:
//!
//! * **Joints.** `revolute` and `continuous` → [`JointKind::Revolute`], `prismatic` →
//!   [`JointKind::Prismatic`]. URDF's child link frame is the joint frame, so
//!   `iTj(q) = T(origin) · Rot(axis, q)` is exactly the IR's `iTj(0) · Rot(e_j, q)`: the origin's
//!   rpy gives `iAj(0)` with URDF's convention `R = Rz(yaw) · Ry(pitch) · Rx(roll)`, its xyz gives
//!   `iPj` (numeric constants, no length symbols), and the `<axis>` (normalised) is `e_j`.
//! * **Fixed joints** merge the child link into its parent: the child's inertia is rotated and
//!   shifted into the parent frame (Huygens–Steiner) and its children are re-attached with the
//!   composed transform. The merged link keeps a body-less frame at its pose in the merged frame
//!   ([`UrdfOptions::link_frames`], appended after the moving frames), so every link is
//!   addressable by the kinematics; tool frames are added by [`UrdfOptions::frames`].
//!   `floating`, `planar`, `spherical` joints are typed errors
//!   ([`ModelErrorKind::UrdfUnsupportedJoint`](crate::ModelErrorKind::UrdfUnsupportedJoint)) unless the base declaration replaces them.
//! * **Mimic joints** (`<mimic joint multiplier offset>`): by default exact constraints
//!   `q = a·q_master + b` in reduced coordinates (the joint has no speed of its own in generated
//!   code; [`Model::mimics`], module `mimic`); [`UrdfOptions::mimic`] makes them independent
//!   coordinates (Pinocchio's behaviour) or fixed at their offset ([`MimicMode`](crate::MimicMode)).
//! * **Inertia.** With the `<inertial><origin>` xyz = S and rpy = R, and the URDF inertia I about
//!   the centre of mass in that frame: `I_G = R I Rᵀ`, `[MX, MY, MZ] = m·S`,
//!   `J = I_G + m(|S|²·1 − S Sᵀ)` about the link origin (Khalil's standard parameters). A link with
//!   zero or no `<inertial>` mass is no body.
//! * **Names.** A body on link `L1` has the parameters `m_L1`, `MX_L1`, `MY_L1`, `MZ_L1`, `XX_L1`,
//!   `XY_L1`, `XZ_L1`, `YY_L1`, `YZ_L1`, `ZZ_L1` (also the field names of the generated `Params`);
//!   the gravity magnitude is `g`; a moving joint `LJ1` has the coordinate `q_LJ1` and the speed
//!   `qd_LJ1` (generated index constant `Q_LJ1`). Each of these names, and the body name, is made
//!   an identifier by [`sanitize_identifier`](crate::sanitize_identifier) (letters of every
//!   script are kept, ASCII punctuation becomes `_`, other symbols their escaped code point: link
//!   `base-link` gives `m_base_link`, `肘` gives `m_肘`, `a→b` gives `m_a_u2192_b`), then
//!   checked by [`Model::check_names`] like the names of a TOML model (names that are equal once
//!   sanitised or ignoring case, or a `<robot name>` that cannot name the wrapper type, are
//!   typed errors).
//! * **Order of u**: depth-first from the root, children in the order their joints appear in the
//!   file (for a wheeled base `xd`, `psid` and the pitch speed come first).
//! * **What is read**: links, joints and their `<inertial>`s. `<visual>`, `<collision>` and
//!   `<material>` elements are removed before parsing (never read, so malformed visual content
//!   never aborts an import); meshes are never opened.
//! * **Real-world data** ([`UrdfOptions`]): rotation angles written as the rounded decimal of a
//!   multiple of π/2 (`3.1416`, `1.5708`, `3.14`) are snapped to it ([`AngleSnap::Rounded`], the
//!   default; everything else is kept exactly), so that the rotations are exactly sparse
//!   (smaller generated code). A link's inertia about its centre of mass may be positive
//!   semi-definite (point masses, rods); a non-physical one (by any amount, as the reference
//!   libraries load it; [`UrdfOptions::inertia_tolerance`] can bound it) loads as written with
//!   a note, or is an error or repaired ([`NonPhysicalInertia`]); one zero to rounding
//!   ([`UrdfOptions::inertia_floor`]) is zero; a zero-mass link keeps its rotational inertia (a body with
//!   `m = 0`) unless [`ZeroMassInertia::Drop`]. Links whose inertia has a radius of gyration
//!   above [`UrdfOptions::max_radius_of_gyration`] (default 5 m; Krang's gripper plates: 0.1 g
//!   with 0.09 kg·m², ~30 m) are an error by default, or dropped/kept ([`AbsurdInertia`]);
//!   [`UrdfOptions::drop_links`] removes links (with their subtrees) by name. Every snap, merge,
//!   drop and inertia decision is reported in [`UrdfImport::notes`].
//! * **Base** ([`UrdfBase`]): fixed (the root link's frame is inertial, z up: gravity
//!   `[0, 0, −g]`), or the two-wheeled inverted pendulum of [`WheeledBaseSpec`].
//!
//! The result passes the same validation as a TOML model (names, unit axes, proper rotations,
//! physical masses and inertias, a positive definite mass matrix).

mod convert;
mod cut;
mod diagnose;
mod inertia;
mod mimic;
mod options;
mod resolved;
mod transform;
mod tree;
mod wheeled;

use std::path::Path;

pub use options::{
    AbsurdInertia, AngleSnap, DEFAULT_INERTIA_FLOOR, DEFAULT_INERTIA_TOLERANCE,
    DEFAULT_MAX_RADIUS_OF_GYRATION, NonPhysicalInertia, UrdfBase, UrdfOptions, WheeledBaseSpec,
    ZeroMassInertia,
};

use crate::error::{ModelError, ModelErrorKind as K};
use crate::ir::*;

/// A converted URDF: the model and what the conversion did (snapped angles, merged, dropped and
/// ignored links, wheel constants), one line each.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfImport {
    /// The validated model.
    pub model: Model,
    /// Human-readable notes.
    pub notes: Vec<String>,
}

impl UrdfImport {
    /// Read, convert and validate a URDF file.
    pub fn read(path: impl AsRef<Path>, options: &UrdfOptions) -> Result<Self, ModelError> {
        let path = path.as_ref();
        let label = path.display().to_string();
        let text = crate::limits::read_description(path)?;
        Self::parse(&text, &label, options)
    }

    /// Convert and validate a URDF held in memory; `label` names it in errors and in
    /// [`Model::source`].
    pub fn parse(text: &str, label: &str, options: &UrdfOptions) -> Result<Self, ModelError> {
        let err = |kind| ModelError::new(label, kind);
        // Limits first: nothing below reads a text that is too large or too deep.
        crate::limits::check_size(text.len() as u64).map_err(err)?;
        crate::limits::check_urdf_depth(text).map_err(err)?;
        let text = diagnose::without_unused_elements(text);
        if let Some(kind) = diagnose::diagnose(&text) {
            return Err(err(kind));
        }
        let robot = urdf_rs::read_from_string(&text).map_err(|e| {
            err(K::UrdfParse {
                detail: e.to_string(),
            })
        })?;
        convert::convert(&robot, label, options)
            .map(|(model, notes)| UrdfImport { model, notes })
            .map_err(err)
    }
}

impl Model {
    /// Load, convert and validate a URDF file (see the [`urdf`](crate::urdf) module).
    pub fn from_urdf_file(
        path: impl AsRef<Path>,
        options: &UrdfOptions,
    ) -> Result<Model, ModelError> {
        UrdfImport::read(path, options).map(|i| i.model)
    }

    /// Convert and validate a URDF held in memory; `label` names it in errors.
    pub fn from_urdf_str(
        text: &str,
        label: &str,
        options: &UrdfOptions,
    ) -> Result<Model, ModelError> {
        UrdfImport::parse(text, label, options).map(|i| i.model)
    }
}
