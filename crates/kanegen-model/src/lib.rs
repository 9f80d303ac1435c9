//! Robot description IR shared by the kanegen generator and the numeric reference recursion.
//!
//! A [`Model`] is a tree of frames rooted at the base frame (`"0"` in the Krang reports). Every
//! non-root frame is attached to its parent by a [`Joint`] whose transform is
//! `iTj(q) = iTj(0) · Rot(e_j, q_j)` (revolute), `iTj(0) · Trans(e_j q_j)` (prismatic) or the
//! constant `iTj(0)` (fixed), with the axis `e_j` expressed in the child frame, as in the fixed-wheels report (Zafar 2014) §2.1.
//! Bodies carry Khalil's standard inertial parameters (mass, first moments `MS = m·S`, inertia about
//! the frame origin) as named, symbolic [`Param`]s with default values, so that the generator can
//! keep them as runtime inputs and the reference recursion can evaluate them.
//!
//! Models are loaded from TOML ([`Model::from_toml_file`]) or imported from URDF
//! ([`Model::from_urdf_file`], module [`urdf`]) and validated; every failure is a typed
//! [`ModelError`] naming the file, the item and the fix.
#![forbid(unsafe_code)]

mod error;
mod frames;
mod ident;
mod ir;
mod limits;
mod mass_matrix;
mod mimic;
pub mod names;
mod toml_format;
pub mod urdf;
mod validate;

pub use error::{BadName, ModelError, ModelErrorKind};
pub use frames::OperationalFrame;
pub use ident::{
    escape_unprintable, is_identifier, is_keyword, is_unprintable, nfc, sanitize_identifier,
};
pub use ir::*;
pub use limits::{MAX_DESCRIPTION_BYTES, MAX_PARAMETER_MAGNITUDE, MAX_URDF_DEPTH};
pub use mass_matrix::kinetic_energy_mass_matrix;
pub use mimic::{Mimic, MimicMode};
pub use urdf::{
    AbsurdInertia, AngleSnap, NonPhysicalInertia, UrdfBase, UrdfImport, UrdfOptions,
    WheeledBaseSpec, ZeroMassInertia,
};
