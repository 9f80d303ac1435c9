//! The import options ([`UrdfOptions`]: base, angle snapping, inertia policies, dropped links,
//! gravity) and their checks.

use crate::error::ModelErrorKind as K;
use crate::frames::OperationalFrame;
use crate::mimic::MimicMode;
use crate::validate;

/// Default of [`UrdfOptions::max_radius_of_gyration`], in metres.
pub const DEFAULT_MAX_RADIUS_OF_GYRATION: f64 = 5.0;
/// Default of [`UrdfOptions::inertia_tolerance`]: no limit. A link's inertia about its centre of
/// mass may break positive semi-definiteness or the triangle inequality by any amount and still
/// load as [`UrdfOptions::non_physical_inertia`] says (by default as written, with a warning), as
/// the reference libraries load such files; the model must still have a positive definite mass
/// matrix.
pub const DEFAULT_INERTIA_TOLERANCE: f64 = f64::INFINITY;
/// Default of [`UrdfOptions::inertia_floor`], in kg·m²: a link inertia whose principal moments
/// are all at most this in magnitude is zero to rounding (a millimetre-sized gram part has
/// about 10⁻⁹ kg·m²; exports write 10⁻²⁰ for "none").
pub const DEFAULT_INERTIA_FLOOR: f64 = 1e-12;

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

/// What to do with a link inertia (about its centre of mass) that is non-physical: not positive
/// semi-definite, or breaking the triangle inequality, by at most
/// [`UrdfOptions::inertia_tolerance`] of its largest principal moment (by default by any
/// amount). Larger violations are always errors. Inertias zero to rounding
/// ([`UrdfOptions::inertia_floor`]) are zero, whatever the policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NonPhysicalInertia {
    /// Load it as written, with a note (a build prints one warning line per link; the default:
    /// the reference libraries load such files). The model is still refused if its mass matrix
    /// is not positive definite.
    #[default]
    Note,
    /// Fail with [`ModelErrorKind::UrdfNonPhysicalInertial`](crate::ModelErrorKind::UrdfNonPhysicalInertial),
    /// whatever the amount.
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
    /// The two-wheeled inverted-pendulum base ([`WheeledBase`](crate::WheeledBase)).
    Wheeled(WheeledBaseSpec),
    /// A free-flying base ([`Base::Floating`](crate::Base::Floating)): the URDF root link is the
    /// base frame and its inertia counts (a root link named `world`, without inertia, whose one
    /// joint is `floating` is cut off, and its child is the base frame; that happens with
    /// [`UrdfBase::Fixed`] too). Gravity's direction is in the world frame.
    Floating,
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
/// `0A1(0) = [[0, 0, −1], [−1, 0, 0], [0, 1, 0]]` and the pitch axis `e1 = [−1, 0, 0]` of the fixed-wheels report (Zafar 2014).
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
/// inertias an error, non-physical ones loaded as written with a note (by any amount),
/// inertias below 10⁻¹² kg·m² zero, zero-mass inertias kept, g = 9.81 along −z of the root
/// frame.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfOptions {
    /// Fixed, floating or two-wheeled base.
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
    /// What to do with a non-physical link inertia (default: load it as written, with a note).
    pub non_physical_inertia: NonPhysicalInertia,
    /// How far (relative to the largest principal moment) a link inertia may be non-physical
    /// and still load as [`UrdfOptions::non_physical_inertia`] says; beyond it the inertia is an
    /// error ([`DEFAULT_INERTIA_TOLERANCE`]: no limit; `0.05` refuses violations above 5 %).
    pub inertia_tolerance: f64,
    /// Largest magnitude (kg·m²) of the principal moments of a link inertia that is zero to
    /// rounding: such an inertia is imported as zero, silently ([`DEFAULT_INERTIA_FLOOR`]).
    pub inertia_floor: f64,
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
            inertia_floor: DEFAULT_INERTIA_FLOOR,
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
    /// Default options with a floating base.
    pub fn floating() -> Self {
        Self {
            base: UrdfBase::Floating,
            ..Self::default()
        }
    }

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

/// The typed error for an import option that is inconsistent with the file.
pub(super) fn bad_option(option: &str, detail: String) -> K {
    K::UrdfBadOption {
        option: option.to_owned(),
        detail,
    }
}

impl UrdfOptions {
    /// Checks the options on their own (before the file is looked at).
    pub(super) fn check(&self) -> Result<(), K> {
        let opts = self;
        if let AngleSnap::Within(t) = opts.snap_angles
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(bad_option(
                "snap_angles",
                format!("tolerance {t} must be a finite angle ≥ 0 (radians)"),
            ));
        }
        if opts.inertia_tolerance.is_nan() || opts.inertia_tolerance < 0.0 {
            return Err(bad_option(
                "inertia_tolerance",
                format!(
                    "{} must be a fraction ≥ 0 (f64::INFINITY: no limit)",
                    opts.inertia_tolerance
                ),
            ));
        }
        if !(opts.inertia_floor.is_finite() && opts.inertia_floor >= 0.0) {
            return Err(bad_option(
                "inertia_floor",
                format!(
                    "{} must be a finite inertia ≥ 0 (kg·m²)",
                    opts.inertia_floor
                ),
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
