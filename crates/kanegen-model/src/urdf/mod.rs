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
//!   coordinates (Pinocchio's behaviour) or fixed at their offset ([`MimicMode`]).
//! * **Inertia.** With the `<inertial><origin>` xyz = S and rpy = R, and the URDF inertia I about
//!   the centre of mass in that frame: `I_G = R I Rᵀ`, `[MX, MY, MZ] = m·S`,
//!   `J = I_G + m(|S|²·1 − S Sᵀ)` about the link origin (Khalil's standard parameters). A link with
//!   zero or no `<inertial>` mass is no body.
//! * **Names.** A body on link `L1` has the parameters `m_L1`, `MX_L1`, `MY_L1`, `MZ_L1`, `XX_L1`,
//!   `XY_L1`, `XZ_L1`, `YY_L1`, `YZ_L1`, `ZZ_L1` (also the field names of the generated `Params`);
//!   the gravity magnitude is `g`; a moving joint `LJ1` has the coordinate `q_LJ1` and the speed
//!   `qd_LJ1` (generated index constant `Q_LJ1`). Each of these names, and the body name, is made
//!   an identifier by [`sanitize_identifier`](crate::sanitize_identifier) (every character other
//!   than ASCII letters, digits and `_` becomes `_`: link `base-link` gives `m_base_link`), then
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
//!   semi-definite (point masses, rods); a slightly non-physical one (within
//!   [`UrdfOptions::inertia_tolerance`]) loads with a note, or is an error or repaired
//!   ([`NonPhysicalInertia`]); a zero-mass link keeps its rotational inertia (a body with
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
mod diagnose;
mod inertia;
mod mimic;
mod transform;
mod tree;
mod wheeled;

use std::path::Path;

use crate::error::{ModelError, ModelErrorKind as K};
use crate::frames::OperationalFrame;
use crate::ir::*;
use crate::mimic::MimicMode;
use crate::validate;

/// Default of [`UrdfOptions::max_radius_of_gyration`], in metres.
pub const DEFAULT_MAX_RADIUS_OF_GYRATION: f64 = 5.0;
/// Default of [`UrdfOptions::inertia_tolerance`]: a link's inertia about its centre of mass may
/// break positive semi-definiteness or the triangle inequality by 5 % of its largest principal
/// moment (rounding of CAD exports) and still load, as [`UrdfOptions::non_physical_inertia`] says.
pub const DEFAULT_INERTIA_TOLERANCE: f64 = 0.05;

/// How rotation angles (joint and inertial `rpy`) are snapped to multiples of π/2.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AngleSnap {
    /// Keep every angle exactly as written.
    Off,
    /// Snap an angle only if, as written, it is the correctly rounded decimal of a multiple of
    /// π/2 with at least two decimals: `3.14`, `3.1416`, `1.5708`, `-1.571`, `4.71239` (such a
    /// number says "π/2" at the precision it was written with; `3.1415`, `1.5`, `0.00019` are
    /// kept). "As written" is the shortest decimal that reads back as the parsed number
    /// (trailing zeros do not count). Lossless for real geometry; the default.
    #[default]
    Rounded,
    /// Snap every angle within this many radians of a multiple of π/2 (lossy: a real
    /// 1.9·10⁻⁴ rad offset is lost under `Within(2e-3)`, the default before `Rounded`).
    Within(f64),
}

/// What to do with a link inertia (about its centre of mass) that is slightly non-physical:
/// not positive semi-definite, or breaking the triangle inequality, by at most
/// [`UrdfOptions::inertia_tolerance`] of its largest principal moment. Larger violations are
/// always errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NonPhysicalInertia {
    /// Load it as written, with a note (the default; the reference libraries load such files).
    #[default]
    Note,
    /// Fail with [`ModelErrorKind::UrdfNonPhysicalInertial`](crate::ModelErrorKind::UrdfNonPhysicalInertial).
    Error,
    /// Replace it by the nearest physical inertia (principal moments projected onto
    /// `λ ≥ 0`, `λ_max ≤ λ_a + λ_b` in the least-squares sense, principal axes kept), with a note.
    Repair,
}

/// What to do with the rotational inertia of a link with zero mass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ZeroMassInertia {
    /// Keep it: the link is a body with `m = 0` and its inertia `J` (a flywheel, a rotor, or an
    /// export that lost the mass); noted. The default: dropping it changed M by 14 % on a real
    /// arm.
    #[default]
    Keep,
    /// Drop it (the link is no body), with a note.
    Drop,
}

/// What to do with a link whose radius of gyration `sqrt(λ_max(I_G)/m)` exceeds
/// [`UrdfOptions::max_radius_of_gyration`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AbsurdInertia {
    /// Fail with [`ModelErrorKind::UrdfAbsurdInertia`](crate::ModelErrorKind::UrdfAbsurdInertia) (the default).
    #[default]
    Error,
    /// Drop the link's inertia (the link stays as a frame), with a note.
    Drop,
    /// Keep it, with a note.
    Keep,
}

/// How the URDF root moves.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum UrdfBase {
    /// The root link's frame is the inertial base frame (links fixed to it carry no dynamics).
    #[default]
    Fixed,
    /// The two-wheeled inverted-pendulum base ([`WheeledBase`]).
    Wheeled(WheeledBaseSpec),
}

/// Declaration of a two-wheeled inverted-pendulum base (Krang's base, DynamicModeling.tex).
///
/// The model gets the heading frame `0` at the midpoint of the two wheel centres (z up, x forward,
/// y toward the left wheel) moving with the quasi-velocities `xd` (forward speed) and `psid` (yaw
/// rate) (coordinates `x`, `psi`), and the body link attached to frame 0 by a revolute pitch joint
/// (coordinate `q_<pitch_name>`, speed `qd_<pitch_name>`) whose axis is the left wheel joint's
/// axis, expressed in the body frame (its sign fixes the sign of the pitch). At zero pitch the
/// body axis [`WheeledBaseSpec::up`] points up. The wheel links (and links fixed to them) are not
/// bodies: they enter through `mw` (mean of the two wheel masses), `YYw` (moment about the axle,
/// through the wheel's centre of mass) and `ZZw` (mean of the two diametral moments), each
/// overridable, with the radius `R` (required) and the track `L` (default: the distance between
/// the wheel joint origins). The wheel joints need not have a `<mimic>` removed, and a
/// `floating` or `planar` joint above the body link (e.g. from an `odom` or `world` link) is
/// replaced by the base: links above it are discarded.
///
/// For Krang.urdf: wheels `JLWheel`/`JRWheel`, body `Base`, up `[0, 1, 0]`, which gives
/// `0A1(0) = [[0, 0, −1], [−1, 0, 0], [0, 1, 0]]` and the pitch axis `e1 = [−1, 0, 0]` of seed 002.
#[derive(Debug, Clone, PartialEq)]
pub struct WheeledBaseSpec {
    /// The left wheel's joint (revolute or continuous; its child link is the wheel).
    pub left_wheel_joint: String,
    /// The right wheel's joint.
    pub right_wheel_joint: String,
    /// The body (the pendulum) link; the wheel joints hang from it or from links fixed to it.
    pub body_link: String,
    /// The body-frame axis that points up at zero pitch (must be perpendicular to the axle).
    pub up: [f64; 3],
    /// Wheel radius `R` (m).
    pub radius: f64,
    /// Track `L` (m); `None`: the distance between the two wheel joint origins.
    pub track: Option<f64>,
    /// Mass of one wheel `mw`; `None`: the mean of the two wheel links' masses.
    pub wheel_mass: Option<f64>,
    /// `YYw`, one wheel's moment about its axle; `None`: from the wheel links (mean of the two).
    pub wheel_axle_inertia: Option<f64>,
    /// `ZZw`, one wheel's moment about a diameter; `None`: the mean of the two diametral moments
    /// of each wheel link, averaged over the two wheels.
    pub wheel_diametral_inertia: Option<f64>,
    /// Name of the pitch coordinate's suffix (`pitch` → `q_pitch`, `qd_pitch`).
    pub pitch_name: String,
}

impl WheeledBaseSpec {
    /// A declaration with the wheel constants taken from the URDF (track from the joint origins)
    /// and the pitch named `pitch`.
    pub fn new(
        left_wheel_joint: impl Into<String>,
        right_wheel_joint: impl Into<String>,
        body_link: impl Into<String>,
        up: [f64; 3],
        radius: f64,
    ) -> Self {
        Self {
            left_wheel_joint: left_wheel_joint.into(),
            right_wheel_joint: right_wheel_joint.into(),
            body_link: body_link.into(),
            up,
            radius,
            track: None,
            wheel_mass: None,
            wheel_axle_inertia: None,
            wheel_diametral_inertia: None,
            pitch_name: "pitch".into(),
        }
    }
}

/// Options of the URDF import. `UrdfOptions::default()` is a fixed base, angles snapped only
/// when written as rounded multiples of π/2 ([`AngleSnap::Rounded`]), nothing dropped, absurd
/// inertias an error, slightly non-physical ones noted, zero-mass inertias kept, g = 9.81 along
/// −z of the root frame.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfOptions {
    /// Fixed or two-wheeled base.
    pub base: UrdfBase,
    /// Model name (default: the `<robot name>`); the generated wrapper type is named after it.
    pub name: Option<String>,
    /// How rotation angles (joint and inertial rpy) are snapped to multiples of π/2 (default
    /// [`AngleSnap::Rounded`]); every snap is noted.
    pub snap_angles: AngleSnap,
    /// Links to remove, each with its joint and its whole subtree.
    pub drop_links: Vec<String>,
    /// Largest plausible radius of gyration about the centre of mass (m), checked per URDF link
    /// before fixed links are merged.
    pub max_radius_of_gyration: f64,
    /// What to do with a link above [`UrdfOptions::max_radius_of_gyration`].
    pub absurd_inertia: AbsurdInertia,
    /// What to do with a slightly non-physical link inertia (default: load it, with a note).
    pub non_physical_inertia: NonPhysicalInertia,
    /// How far (relative to the largest principal moment) a link inertia may be non-physical
    /// and count as slightly so ([`DEFAULT_INERTIA_TOLERANCE`]).
    pub inertia_tolerance: f64,
    /// What to do with the rotational inertia of a zero-mass link (default: keep it).
    pub zero_mass_inertia: ZeroMassInertia,
    /// Default value of the gravity parameter `g` (m/s²).
    pub gravity: f64,
    /// Unit direction of gravity in the root frame (fixed base only; the wheeled base's heading
    /// frame has z up, so it must stay `[0, 0, −1]` there).
    pub gravity_direction: [f64; 3],
    /// What to do with `<mimic>` joints (default: exact constraints, [`MimicMode::Exact`]).
    pub mimic: MimicMode,
    /// Keep a frame for every link merged into its parent by fixed joints (default `true`): a
    /// body-less frame fixed to the merged frame at the link's pose, so `frame_pose` etc. reach
    /// it (a sensor or tool link of the URDF). Its inertia is merged either way.
    pub link_frames: bool,
    /// Tool frames to add ([`OperationalFrame`]: name, parent link, rotation, translation),
    /// after the URDF's links, in this order; a parent may be any link of the model (merged ones
    /// included while [`UrdfOptions::link_frames`] is on) or an earlier tool frame.
    pub frames: Vec<OperationalFrame>,
}

impl Default for UrdfOptions {
    fn default() -> Self {
        Self {
            base: UrdfBase::Fixed,
            name: None,
            snap_angles: AngleSnap::Rounded,
            drop_links: Vec::new(),
            max_radius_of_gyration: DEFAULT_MAX_RADIUS_OF_GYRATION,
            absurd_inertia: AbsurdInertia::Error,
            non_physical_inertia: NonPhysicalInertia::Note,
            inertia_tolerance: DEFAULT_INERTIA_TOLERANCE,
            zero_mass_inertia: ZeroMassInertia::Keep,
            gravity: 9.81,
            gravity_direction: [0.0, 0.0, -1.0],
            mimic: MimicMode::Exact,
            link_frames: true,
            frames: Vec::new(),
        }
    }
}

impl UrdfOptions {
    /// Default options with a two-wheeled base.
    pub fn wheeled(spec: WheeledBaseSpec) -> Self {
        Self {
            base: UrdfBase::Wheeled(spec),
            ..Self::default()
        }
    }

    /// These options with the tool frame `frame` added to [`UrdfOptions::frames`].
    pub fn frame(mut self, frame: OperationalFrame) -> Self {
        self.frames.push(frame);
        self
    }

    /// These options with `links` added to [`UrdfOptions::drop_links`].
    pub fn drop_links<S: Into<String>>(mut self, links: impl IntoIterator<Item = S>) -> Self {
        self.drop_links.extend(links.into_iter().map(Into::into));
        self
    }
}

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
        convert::convert(&robot, label, options).map_err(err)
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

/// The typed error for an import option that is inconsistent with the file.
fn bad_option(option: &str, detail: String) -> K {
    K::UrdfBadOption {
        option: option.to_owned(),
        detail,
    }
}

impl UrdfOptions {
    /// Checks the options on their own (before the file is looked at).
    fn check(&self) -> Result<(), K> {
        let opts = self;
        if let AngleSnap::Within(t) = opts.snap_angles
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(bad_option(
                "snap_angles",
                format!("tolerance {t} must be a finite angle ≥ 0 (radians)"),
            ));
        }
        if !(opts.inertia_tolerance.is_finite() && opts.inertia_tolerance >= 0.0) {
            return Err(bad_option(
                "inertia_tolerance",
                format!("{} must be a finite fraction ≥ 0", opts.inertia_tolerance),
            ));
        }
        if opts.max_radius_of_gyration.is_nan() || opts.max_radius_of_gyration <= 0.0 {
            return Err(bad_option(
                "max_radius_of_gyration",
                format!("{} must be positive (metres)", opts.max_radius_of_gyration),
            ));
        }
        if !opts.gravity.is_finite() {
            return Err(bad_option(
                "gravity",
                format!("{} is not finite", opts.gravity),
            ));
        }
        validate::check_gravity_direction(opts.gravity_direction)
            .map_err(|detail| bad_option("gravity_direction", detail))?;
        if let UrdfBase::Wheeled(w) = &opts.base {
            if opts.gravity_direction != [0.0, 0.0, -1.0] {
                return Err(bad_option(
                    "gravity_direction",
                    "the wheeled base's heading frame has z up: leave it [0, 0, -1]".into(),
                ));
            }
            if !(w.radius.is_finite() && w.radius > 0.0) {
                return Err(bad_option(
                    "base.radius",
                    format!("wheel radius {} must be positive", w.radius),
                ));
            }
            for (name, v) in [
                ("base.track", w.track),
                ("base.wheel_mass", w.wheel_mass),
                ("base.wheel_axle_inertia", w.wheel_axle_inertia),
                ("base.wheel_diametral_inertia", w.wheel_diametral_inertia),
            ] {
                if let Some(v) = v
                    && !(v.is_finite() && v >= 0.0)
                {
                    return Err(bad_option(name, format!("{v} must be a finite value ≥ 0")));
                }
            }
            if w.pitch_name.is_empty() {
                return Err(bad_option("base.pitch_name", "must not be empty".into()));
            }
        }
        Ok(())
    }
}
