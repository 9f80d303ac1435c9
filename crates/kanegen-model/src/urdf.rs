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
//!   composed transform. `floating`, `planar`, `spherical` joints and `<mimic>` are typed errors
//!   ([`ModelErrorKind::UrdfUnsupportedJoint`](crate::ModelErrorKind::UrdfUnsupportedJoint)) unless the base declaration replaces them.
//! * **Inertia.** With the `<inertial><origin>` xyz = S and rpy = R, and the URDF inertia I about
//!   the centre of mass in that frame: `I_G = R I Rᵀ`, `[MX, MY, MZ] = m·S`,
//!   `J = I_G + m(|S|²·1 − S Sᵀ)` about the link origin (Khalil's standard parameters). A link with
//!   zero or no `<inertial>` mass is no body.
//! * **Names.** Link and joint names are sanitised to identifiers ([`sanitize`]: every character
//!   other than ASCII letters, digits and `_` becomes `_`). A body on link `L1` has the parameters
//!   `m_L1`, `MX_L1`, `MY_L1`, `MZ_L1`, `XX_L1`, `XY_L1`, `XZ_L1`, `YY_L1`, `YZ_L1`, `ZZ_L1` (also
//!   the field names of the generated `Params`); the gravity magnitude is `g`; a moving joint
//!   `LJ1` has the coordinate `q_LJ1` and the speed `qd_LJ1` (generated index constant `Q_LJ1`).
//! * **Order of u**: depth-first from the root, children in the order their joints appear in the
//!   file (for a wheeled base `xd`, `psid` and the pitch speed come first).
//! * **Real-world data** ([`UrdfOptions`]): rotation angles within
//!   [`UrdfOptions::snap_angles`] (default 2·10⁻³ rad) of a multiple of π/2 are snapped to it, so
//!   that `3.1416`, `1.5708` and `3.14` become exact and the rotations exactly sparse (smaller
//!   generated code). Links whose inertia has a radius of gyration above
//!   [`UrdfOptions::max_radius_of_gyration`] (default 5 m; Krang's gripper plates: 0.1 g with
//!   0.09 kg·m², ~30 m) are an error by default, or dropped/kept ([`AbsurdInertia`]);
//!   [`UrdfOptions::drop_links`] removes links (with their subtrees) by name. Every snap, merge and
//!   drop is reported in [`UrdfImport::notes`].
//! * **Base** ([`UrdfBase`]): fixed (the root link's frame is inertial, z up: gravity
//!   `[0, 0, −g]`), or the two-wheeled inverted pendulum of [`WheeledBaseSpec`].
//!
//! The result passes the same validation as a TOML model (unit axes, proper rotations, positive
//! masses, physical inertias).

use std::collections::{HashMap, HashSet};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::error::{ModelError, ModelErrorKind as K};
use crate::ir::*;
use crate::validate;

/// Default of [`UrdfOptions::snap_angles`]: 2·10⁻³ rad (catches `3.14` for π, 1.6·10⁻³ off).
pub const DEFAULT_SNAP_TOLERANCE: f64 = 2e-3;
/// Default of [`UrdfOptions::max_radius_of_gyration`], in metres.
pub const DEFAULT_MAX_RADIUS_OF_GYRATION: f64 = 5.0;

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

/// Options of the URDF import. `UrdfOptions::default()` is a fixed base, angles snapped within
/// 2·10⁻³ rad, nothing dropped, absurd inertias an error, g = 9.81 along −z of the root frame.
#[derive(Debug, Clone, PartialEq)]
pub struct UrdfOptions {
    /// Fixed or two-wheeled base.
    pub base: UrdfBase,
    /// Model name (default: the `<robot name>`); the generated wrapper type is named after it.
    pub name: Option<String>,
    /// Snap rotation angles (joint and inertial rpy) within this many radians of a multiple of
    /// π/2 to it; `None` keeps them as written.
    pub snap_angles: Option<f64>,
    /// Links to remove, each with its joint and its whole subtree.
    pub drop_links: Vec<String>,
    /// Largest plausible radius of gyration about the centre of mass (m), checked per URDF link
    /// before fixed links are merged.
    pub max_radius_of_gyration: f64,
    /// What to do with a link above [`UrdfOptions::max_radius_of_gyration`].
    pub absurd_inertia: AbsurdInertia,
    /// Default value of the gravity parameter `g` (m/s²).
    pub gravity: f64,
    /// Unit direction of gravity in the root frame (fixed base only; the wheeled base's heading
    /// frame has z up, so it must stay `[0, 0, −1]` there).
    pub gravity_direction: [f64; 3],
}

impl Default for UrdfOptions {
    fn default() -> Self {
        Self {
            base: UrdfBase::Fixed,
            name: None,
            snap_angles: Some(DEFAULT_SNAP_TOLERANCE),
            drop_links: Vec::new(),
            max_radius_of_gyration: DEFAULT_MAX_RADIUS_OF_GYRATION,
            absurd_inertia: AbsurdInertia::Error,
            gravity: 9.81,
            gravity_direction: [0.0, 0.0, -1.0],
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
        let text = std::fs::read_to_string(path)
            .map_err(|e| ModelError::new(&label, K::Io(e.to_string())))?;
        Self::parse(&text, &label, options)
    }

    /// Convert and validate a URDF held in memory; `label` names it in errors and in
    /// [`Model::source`].
    pub fn parse(text: &str, label: &str, options: &UrdfOptions) -> Result<Self, ModelError> {
        let err = |kind| ModelError::new(label, kind);
        if let Some(kind) = diagnose(text) {
            return Err(err(kind));
        }
        let robot = urdf_rs::read_from_string(text).map_err(|e| {
            err(K::UrdfParse {
                detail: e.to_string(),
            })
        })?;
        convert(&robot, label, options).map_err(err)
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

/// A URDF name as an identifier fragment: every character other than ASCII letters, digits and
/// `_` becomes `_` (`base-link` → `base_link`).
pub fn sanitize(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "_".into() } else { s }
}

// ---- rigid transforms and inertia ---------------------------------------------------------------

#[derive(Debug, Clone, Copy)]
struct Tf {
    r: Matrix3<f64>,
    p: Vector3<f64>,
}

impl Tf {
    fn identity() -> Self {
        Self {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self ∘ b`: b's pose given in this frame.
    fn then(&self, b: &Tf) -> Tf {
        Tf {
            r: self.r * b.r,
            p: self.r * b.p + self.p,
        }
    }

    fn inverse(&self) -> Tf {
        let rt = self.r.transpose();
        Tf {
            r: rt,
            p: -(rt * self.p),
        }
    }
}

/// A link's own inertial data in its frame: mass, centre of mass, inertia about the COM.
#[derive(Debug, Clone, Copy)]
struct Inertial {
    m: f64,
    c: Vector3<f64>,
    ig: Matrix3<f64>,
}

/// Mass, first moment and inertia about the frame origin of a set of inertials given with their
/// poses in that frame.
fn merge(items: &[(Tf, Inertial)]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let mut m = 0.0;
    let mut ms = Vector3::zeros();
    let mut j = Matrix3::zeros();
    for (t, i) in items {
        let c = t.r * i.c + t.p;
        m += i.m;
        ms += c * i.m;
        j += t.r * i.ig * t.r.transpose()
            + (Matrix3::identity() * c.norm_squared() - c * c.transpose()) * i.m;
    }
    (m, ms, j)
}

/// Removes floating-point dust from composed rotations and translations.
fn clean(x: f64) -> f64 {
    const EPS: f64 = 1e-15;
    if x.abs() < EPS {
        0.0
    } else if (x - 1.0).abs() < EPS {
        1.0
    } else if (x + 1.0).abs() < EPS {
        -1.0
    } else {
        x
    }
}

/// Snaps up to this size are counted in one note rather than listed (`3.1416` is 7.3·10⁻⁶ off π).
const SMALL_SNAP: f64 = 1e-4;

/// Import notes under construction.
#[derive(Default)]
struct Notes {
    lines: Vec<String>,
    small_snaps: usize,
}

impl Notes {
    fn push(&mut self, line: String) {
        self.lines.push(line);
    }

    fn finish(mut self) -> Vec<String> {
        if self.small_snaps > 0 {
            self.lines.insert(
                0,
                format!(
                    "{} rotation angles within {SMALL_SNAP:e} rad of a multiple of π/2 (such as 3.1416 or 1.5708) snapped to it",
                    self.small_snaps
                ),
            );
        }
        self.lines
    }
}

fn fmt_half_pi(k: i64) -> String {
    match k {
        0 => "0".into(),
        _ if k % 2 == 0 => match k / 2 {
            1 => "π".into(),
            -1 => "-π".into(),
            n => format!("{n}π"),
        },
        1 => "π/2".into(),
        -1 => "-π/2".into(),
        _ => format!("{k}π/2"),
    }
}

/// `(cos a, sin a)`, exact for multiples of π/2 and for angles snapped to them.
fn cos_sin(a: f64, snap: Option<f64>, what: &str, notes: &mut Notes) -> (f64, f64) {
    let k = (a / FRAC_PI_2).round();
    let exact = k * FRAC_PI_2;
    let delta = a - exact;
    if delta == 0.0 || snap.is_some_and(|t| delta.abs() <= t) {
        let k = k as i64;
        if delta.abs() > SMALL_SNAP {
            notes.push(format!(
                "{what}: {a} snapped to {} (by {delta:.2e} rad)",
                fmt_half_pi(k)
            ));
        } else if delta != 0.0 {
            notes.small_snaps += 1;
        }
        return match k.rem_euclid(4) {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 0.0),
            _ => (0.0, -1.0),
        };
    }
    (a.cos(), a.sin())
}

/// URDF rpy: `R = Rz(y) · Ry(p) · Rx(r)`.
fn rpy_matrix(rpy: [f64; 3], snap: Option<f64>, what: &str, notes: &mut Notes) -> Matrix3<f64> {
    let names = ["roll", "pitch", "yaw"];
    let cs: Vec<(f64, f64)> = (0..3)
        .map(|i| cos_sin(rpy[i], snap, &format!("{what} rpy {}", names[i]), notes))
        .collect();
    let (cr, sr) = cs[0];
    let (cp, sp) = cs[1];
    let (cy, sy) = cs[2];
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    (rz * ry * rx).map(clean)
}

fn pose_tf(pose: &urdf_rs::Pose, snap: Option<f64>, what: &str, notes: &mut Notes) -> Tf {
    Tf {
        r: rpy_matrix(pose.rpy.0, snap, what, notes),
        p: Vector3::from(pose.xyz.0),
    }
}

fn finite3(v: [f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

// ---- conversion ---------------------------------------------------------------------------------

fn bad_option(option: &str, detail: String) -> K {
    K::UrdfBadOption {
        option: option.to_owned(),
        detail,
    }
}

fn type_name(t: &urdf_rs::JointType) -> &'static str {
    use urdf_rs::JointType as J;
    match t {
        J::Revolute => "revolute",
        J::Continuous => "continuous",
        J::Prismatic => "prismatic",
        J::Fixed => "fixed",
        J::Floating => "floating",
        J::Planar => "planar",
        J::Spherical => "spherical",
    }
}

fn is_moving(t: &urdf_rs::JointType) -> bool {
    use urdf_rs::JointType as J;
    matches!(t, J::Revolute | J::Continuous | J::Prismatic)
}

/// The URDF as a tree of indices.
struct Tree<'a> {
    robot: &'a urdf_rs::Robot,
    index: HashMap<&'a str, usize>,
    /// Per link: the joint whose child it is.
    parent_joint: Vec<Option<usize>>,
    /// Per link: the joints whose parent it is, in file order.
    child_joints: Vec<Vec<usize>>,
}

impl<'a> Tree<'a> {
    fn new(robot: &'a urdf_rs::Robot) -> Result<Self, K> {
        let n = robot.links.len();
        let mut index = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if index.insert(l.name.as_str(), i).is_some() {
                return Err(K::Duplicate {
                    what: "URDF link",
                    name: l.name.clone(),
                });
            }
        }
        let mut names = HashSet::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; n];
        let mut child_joints = vec![Vec::new(); n];
        for (k, j) in robot.joints.iter().enumerate() {
            if !names.insert(j.name.as_str()) {
                return Err(K::Duplicate {
                    what: "URDF joint",
                    name: j.name.clone(),
                });
            }
            let &p = index
                .get(j.parent.link.as_str())
                .ok_or_else(|| K::UrdfMissingParentLink {
                    joint: j.name.clone(),
                    parent: j.parent.link.clone(),
                })?;
            let &c = index
                .get(j.child.link.as_str())
                .ok_or_else(|| K::UrdfMissingChildLink {
                    joint: j.name.clone(),
                    child: j.child.link.clone(),
                })?;
            if let Some(first) = parent_joint[c] {
                return Err(K::UrdfTwoParents {
                    link: j.child.link.clone(),
                    first: robot.joints[first].name.clone(),
                    second: j.name.clone(),
                });
            }
            parent_joint[c] = Some(k);
            child_joints[p].push(k);
        }
        Ok(Self {
            robot,
            index,
            parent_joint,
            child_joints,
        })
    }

    fn link(&self, i: usize) -> &'a urdf_rs::Link {
        &self.robot.links[i]
    }

    fn joint(&self, k: usize) -> &'a urdf_rs::Joint {
        &self.robot.joints[k]
    }

    fn parent_of(&self, k: usize) -> usize {
        self.index[self.joint(k).parent.link.as_str()]
    }

    fn child_of(&self, k: usize) -> usize {
        self.index[self.joint(k).child.link.as_str()]
    }

    /// The unique root, or a typed error (no links, several roots, a cycle).
    fn root(&self) -> Result<usize, K> {
        let roots: Vec<usize> = (0..self.robot.links.len())
            .filter(|&i| self.parent_joint[i].is_none())
            .collect();
        match roots.len() {
            0 if self.robot.links.is_empty() => Err(K::UrdfParse {
                detail: "the <robot> has no <link>".into(),
            }),
            0 => Err(self.cycle_from(0)),
            1 => {
                let root = roots[0];
                let reached = self.preorder(root, &|_| true);
                if reached.len() < self.robot.links.len() {
                    let lost = (0..self.robot.links.len())
                        .find(|i| !reached.contains(i))
                        .expect("an unreached link");
                    return Err(self.cycle_from(lost));
                }
                Ok(root)
            }
            _ => Err(K::UrdfTwoRoots {
                roots: roots.iter().map(|&i| self.link(i).name.clone()).collect(),
            }),
        }
    }

    /// Walks up from a link that is not reachable from the root to a joint on its cycle.
    fn cycle_from(&self, link: usize) -> K {
        let mut seen = vec![false; self.robot.links.len()];
        let mut l = link;
        while !seen[l] {
            seen[l] = true;
            l = self.parent_of(self.parent_joint[l].expect("every link on a cycle has a parent"));
        }
        let k = self.parent_joint[l].expect("on the cycle");
        K::Cycle {
            joint: self.joint(k).name.clone(),
            frame: self.joint(k).child.link.clone(),
        }
    }

    /// Links of the subtree of `top` in depth-first preorder (children in joint file order),
    /// descending only through joints `k` with `keep(k)`.
    fn preorder(&self, top: usize, keep: &dyn Fn(usize) -> bool) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![top];
        while let Some(l) = stack.pop() {
            out.push(l);
            for &k in self.child_joints[l].iter().rev() {
                if keep(k) {
                    stack.push(self.child_of(k));
                }
            }
        }
        out
    }
}

/// A link's inertial data (`None` for zero mass), after the checks of the options.
fn link_inertial(
    link: &urdf_rs::Link,
    opts: &UrdfOptions,
    notes: &mut Notes,
) -> Result<Option<Inertial>, K> {
    let inertial = &link.inertial;
    let m = inertial.mass.value;
    let t = &inertial.inertia;
    let nums = [m, t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    let element = format!("link `{}` <inertial>", link.name);
    if !nums.iter().all(|x| x.is_finite())
        || !finite3(inertial.origin.xyz.0)
        || !finite3(inertial.origin.rpy.0)
    {
        return Err(K::UrdfBadNumber {
            element,
            attribute: "mass/inertia/origin".into(),
            text: format!(
                "m {m}, I {nums:?}, xyz {:?}, rpy {:?}",
                inertial.origin.xyz.0, inertial.origin.rpy.0
            ),
            expected: "finite numbers".into(),
        });
    }
    if m < 0.0 {
        return Err(K::NonPositiveMass {
            body: link.name.clone(),
            symbol: "<mass value>".into(),
            value: m,
        });
    }
    let ic = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    if m == 0.0 {
        if ic != Matrix3::zeros() {
            notes.push(format!(
                "link `{}`: zero mass with a nonzero inertia; the inertia is ignored",
                link.name
            ));
        }
        return Ok(None);
    }
    let rot = rpy_matrix(
        inertial.origin.rpy.0,
        opts.snap_angles,
        &format!("link `{}` <inertial><origin>", link.name),
        notes,
    );
    let ig = rot * ic * rot.transpose();
    let lmax = SymmetricEigen::new(ig).eigenvalues.max();
    if lmax > 0.0 {
        let radius = (lmax / m).sqrt();
        if radius > opts.max_radius_of_gyration {
            let what = format!(
                "link `{}`: radius of gyration {radius:.3} m (mass {m} kg, largest principal moment {lmax:.4e} kg·m²) exceeds {} m",
                link.name, opts.max_radius_of_gyration
            );
            match opts.absurd_inertia {
                AbsurdInertia::Error => {
                    return Err(K::UrdfAbsurdInertia {
                        link: link.name.clone(),
                        mass: m,
                        moment: lmax,
                        radius,
                        limit: opts.max_radius_of_gyration,
                    });
                }
                AbsurdInertia::Drop => {
                    notes.push(format!("{what}: inertia dropped"));
                    return Ok(None);
                }
                AbsurdInertia::Keep => notes.push(format!("{what}: kept as written")),
            }
        }
    }
    Ok(Some(Inertial {
        m,
        c: Vector3::from(inertial.origin.xyz.0),
        ig,
    }))
}

fn check_options(opts: &UrdfOptions) -> Result<(), K> {
    if let Some(t) = opts.snap_angles
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(bad_option(
            "snap_angles",
            format!("tolerance {t} must be a finite angle ≥ 0 (radians), or None"),
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
    let d = Vector3::from(opts.gravity_direction);
    if !finite3(opts.gravity_direction) || (d.norm() - 1.0).abs() > validate::TOLERANCE {
        return Err(bad_option(
            "gravity_direction",
            format!(
                "{:?} is not a unit vector; normalise it",
                opts.gravity_direction
            ),
        ));
    }
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

/// The wheeled base, resolved against the tree.
struct WheelGeometry {
    /// `0A1(0)`: the heading frame's axes (rows) in the body frame.
    a01: Matrix3<f64>,
    /// `0P1`: the body origin in the heading frame.
    p01: Vector3<f64>,
    /// Pitch axis in the body frame.
    axis: Vector3<f64>,
    track: f64,
    mass: f64,
    axle: f64,
    diametral: f64,
}

fn convert(robot: &urdf_rs::Robot, file: &str, opts: &UrdfOptions) -> Result<UrdfImport, K> {
    check_options(opts)?;
    let mut notes = Notes::default();
    let tree = Tree::new(robot)?;
    let n = robot.links.len();
    let root = tree.root()?;

    // Dropped subtrees.
    let mut dropped = vec![false; n];
    for name in &opts.drop_links {
        let Some(&i) = tree.index.get(name.as_str()) else {
            return Err(bad_option(
                "drop_links",
                format!("the URDF has no link `{name}`; list existing link names"),
            ));
        };
        if i == root {
            return Err(bad_option(
                "drop_links",
                format!("`{name}` is the root link and cannot be dropped"),
            ));
        }
        let sub = tree.preorder(i, &|_| true);
        let names: Vec<&str> = sub.iter().map(|&l| tree.link(l).name.as_str()).collect();
        let mass: f64 = sub.iter().map(|&l| tree.link(l).inertial.mass.value).sum();
        notes.push(format!(
            "dropped (drop_links): {} ({mass} kg in all)",
            names.join(", ")
        ));
        for l in sub {
            dropped[l] = true;
        }
    }

    // The wheeled base: body link, the cut above it, the wheel subtrees.
    let spec = match &opts.base {
        UrdfBase::Wheeled(w) => Some(w),
        UrdfBase::Fixed => None,
    };
    let mut top = root;
    let mut body = root;
    let mut wheel_joints: Vec<usize> = Vec::new();
    let mut wheel_part = vec![false; n];
    if let Some(w) = spec {
        let &b = tree.index.get(w.body_link.as_str()).ok_or_else(|| {
            bad_option(
                "base.body_link",
                format!("the URDF has no link `{}`", w.body_link),
            )
        })?;
        if dropped[b] {
            return Err(bad_option(
                "base.body_link",
                format!("`{}` is dropped by drop_links", w.body_link),
            ));
        }
        body = b;
        let mut l = b;
        while let Some(k) = tree.parent_joint[l] {
            let j = tree.joint(k);
            use urdf_rs::JointType as J;
            match j.joint_type {
                J::Fixed => l = tree.parent_of(k),
                J::Floating | J::Planar => {
                    top = l;
                    let above: Vec<&str> = (0..n)
                        .filter(|i| !tree.preorder(l, &|_| true).contains(i))
                        .map(|i| tree.link(i).name.as_str())
                        .collect();
                    notes.push(format!(
                        "{} joint `{}` replaced by the wheeled base; links above it discarded: {}",
                        type_name(&j.joint_type),
                        j.name,
                        above.join(", ")
                    ));
                    break;
                }
                _ => {
                    return Err(bad_option(
                        "base.body_link",
                        format!(
                            "`{}` hangs from the {} joint `{}`; the body of a two-wheeled base must be fixed to the URDF root (fixed joints only) or hang from a floating or planar joint, which the base replaces",
                            w.body_link,
                            type_name(&j.joint_type),
                            j.name
                        ),
                    ));
                }
            }
        }
        for (option, name) in [
            ("base.left_wheel_joint", &w.left_wheel_joint),
            ("base.right_wheel_joint", &w.right_wheel_joint),
        ] {
            let Some(k) = robot.joints.iter().position(|j| &j.name == name) else {
                return Err(bad_option(
                    option,
                    format!("the URDF has no joint `{name}`"),
                ));
            };
            let j = tree.joint(k);
            if !matches!(
                j.joint_type,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
            ) {
                return Err(bad_option(
                    option,
                    format!(
                        "`{name}` is a {} joint; a wheel joint is revolute or continuous",
                        type_name(&j.joint_type)
                    ),
                ));
            }
            let c = tree.child_of(k);
            if dropped[c] {
                return Err(bad_option(
                    option,
                    format!("the wheel link of `{name}` is dropped by drop_links"),
                ));
            }
            if wheel_joints.contains(&k) {
                return Err(bad_option(
                    option,
                    "the left and right wheel joints must differ".into(),
                ));
            }
            for l in tree.preorder(c, &|_| true) {
                wheel_part[l] = true;
                for &kk in &tree.child_joints[l] {
                    let jj = tree.joint(kk);
                    if jj.joint_type != urdf_rs::JointType::Fixed && !dropped[tree.child_of(kk)] {
                        return Err(bad_option(
                            option,
                            format!(
                                "the {} joint `{}` hangs below the wheel; only fixed joints may (drop its link with drop_links)",
                                type_name(&jj.joint_type),
                                jj.name
                            ),
                        ));
                    }
                }
            }
            wheel_joints.push(k);
        }
        if wheel_part[b] {
            return Err(bad_option(
                "base.body_link",
                format!("`{}` is part of a wheel", w.body_link),
            ));
        }
    }

    // The kept links, depth first from the top (wheel subtrees included, dropped links not).
    let kept = tree.preorder(top, &|k| !dropped[tree.child_of(k)]);
    let is_kept = {
        let mut v = vec![false; n];
        for &l in &kept {
            v[l] = true;
        }
        v
    };

    // Joint checks, in file order.
    for (k, j) in robot.joints.iter().enumerate() {
        let c = tree.child_of(k);
        if !is_kept[c] || c == top || wheel_joints.contains(&k) {
            continue;
        }
        use urdf_rs::JointType as J;
        match j.joint_type {
            J::Floating | J::Planar | J::Spherical => {
                let fix = match (&j.joint_type, spec.is_some()) {
                    (J::Spherical, _) => "model it as three revolute joints with massless links between them, or make it fixed".to_owned(),
                    (_, false) => "the generator has fixed and two-wheeled bases: make it fixed, or declare a wheeled base (UrdfBase::Wheeled) whose body link hangs from it".to_owned(),
                    (_, true) => "only the joint directly above the wheeled base's body link (through fixed joints) is replaced by the base; make this one fixed".to_owned(),
                };
                return Err(K::UrdfUnsupportedJoint {
                    joint: j.name.clone(),
                    kind: type_name(&j.joint_type).into(),
                    fix,
                });
            }
            _ => {}
        }
        if let Some(mimic) = &j.mimic
            && is_moving(&j.joint_type)
        {
            return Err(K::UrdfUnsupportedJoint {
                joint: j.name.clone(),
                kind: "mimic".into(),
                fix: format!(
                    "the joint copies `{}` (<mimic>), a constraint the generator cannot represent; remove <mimic> to make it an independent coordinate, or make it fixed",
                    mimic.joint
                ),
            });
        }
        let axis = j.axis.xyz.0;
        if !finite3(j.origin.xyz.0) || !finite3(j.origin.rpy.0) || !finite3(axis) {
            return Err(K::UrdfBadNumber {
                element: format!("joint `{}` <origin>/<axis>", j.name),
                attribute: "xyz/rpy".into(),
                text: format!("{:?} {:?} {:?}", j.origin.xyz.0, j.origin.rpy.0, axis),
                expected: "finite numbers".into(),
            });
        }
        if is_moving(&j.joint_type) && Vector3::from(axis).norm() == 0.0 {
            return Err(K::Invalid {
                item: format!("URDF joint `{}`", j.name),
                detail: "<axis xyz=\"0 0 0\"> has no direction; give a nonzero axis".into(),
            });
        }
    }

    // Joint origins (snapping noted once per joint).
    let mut origin: Vec<Option<Tf>> = vec![None; robot.joints.len()];
    for &l in &kept {
        if l == top {
            continue;
        }
        let k = tree.parent_joint[l].expect("non-top link has a joint");
        let j = tree.joint(k);
        origin[k] = Some(pose_tf(
            &j.origin,
            opts.snap_angles,
            &format!("joint `{}` <origin>", j.name),
            &mut notes,
        ));
    }

    // Per-link inertials (checks of the options included).
    let mut inertial: Vec<Option<Inertial>> = vec![None; n];
    for &l in &kept {
        inertial[l] = link_inertial(tree.link(l), opts, &mut notes)?;
    }

    // Rigid clusters: each link's cluster top (the link below the nearest moving joint) and its
    // pose in that top's frame; the cluster's frame (its representative) is the top, except
    // for the wheeled body's cluster, whose frame is the body link.
    let mut cl = Clusters {
        top,
        body,
        cluster_top: vec![usize::MAX; n],
        in_top: vec![Tf::identity(); n],
    };
    for &l in &kept {
        match tree.parent_joint[l].filter(|_| l != top) {
            Some(k) if tree.joint(k).joint_type == urdf_rs::JointType::Fixed => {
                let p = tree.parent_of(k);
                cl.cluster_top[l] = cl.cluster_top[p];
                cl.in_top[l] = cl.in_top[p].then(&origin[k].expect("origin"));
            }
            _ => cl.cluster_top[l] = l,
        }
    }

    // Wheel geometry and constants.
    let wheel = match spec {
        None => None,
        Some(w) => Some(wheel_geometry(
            w,
            &tree,
            &wheel_joints,
            &origin,
            &inertial,
            &dropped,
            &cl,
            &mut notes,
        )?),
    };

    // ---- the IR ----
    let mut params: Vec<Param> = Vec::new();
    let add_param = |params: &mut Vec<Param>, name: String, value: f64, kind| {
        params.push(Param {
            name,
            value: if value == 0.0 { 0.0 } else { value },
            kind,
        });
        params.len() - 1
    };
    let g = add_param(&mut params, "g".into(), opts.gravity, ParamKind::Gravity);
    let mut speeds: Vec<Speed> = Vec::new();
    let mut links: Vec<Link> = Vec::new();
    let mut ir_index: HashMap<usize, usize> = HashMap::new();
    let base = match (&wheel, spec) {
        (Some(wg), Some(w)) => {
            let radius = add_param(&mut params, "R".into(), w.radius, ParamKind::Wheel);
            let track = add_param(&mut params, "L".into(), wg.track, ParamKind::Wheel);
            let wheel_mass = add_param(&mut params, "mw".into(), wg.mass, ParamKind::Wheel);
            let axle = add_param(&mut params, "YYw".into(), wg.axle, ParamKind::Wheel);
            let diam = add_param(&mut params, "ZZw".into(), wg.diametral, ParamKind::Wheel);
            if tree.index.contains_key("0") {
                return Err(K::Duplicate {
                    what: "frame (the wheeled base's heading frame is `0`)",
                    name: "0".into(),
                });
            }
            speeds.push(Speed {
                name: "xd".into(),
                coordinate: "x".into(),
            });
            speeds.push(Speed {
                name: "psid".into(),
                coordinate: "psi".into(),
            });
            let pitch = sanitize(&w.pitch_name);
            speeds.push(Speed {
                name: format!("qd_{pitch}"),
                coordinate: format!("q_{pitch}"),
            });
            links.push(Link {
                name: "0".into(),
                parent: None,
                joint: None,
                body: None,
            });
            links.push(Link {
                name: tree.link(body).name.clone(),
                parent: Some(0),
                joint: Some(Joint {
                    name: w.pitch_name.clone(),
                    kind: JointKind::Revolute,
                    axis: [wg.axis.x, wg.axis.y, wg.axis.z],
                    rotation: rows(&wg.a01),
                    translation: numbers(wg.p01),
                    speed: Some(2),
                }),
                body: None,
            });
            ir_index.insert(body, 1);
            Base::Wheeled(WheeledBase {
                x_speed: 0,
                psi_speed: 1,
                radius,
                track,
                wheel_mass,
                wheel_axle_inertia: axle,
                wheel_diametral_inertia: diam,
            })
        }
        _ => {
            links.push(Link {
                name: tree.link(top).name.clone(),
                parent: None,
                joint: None,
                body: None,
            });
            ir_index.insert(top, 0);
            Base::Fixed
        }
    };

    // Moving joints, depth first.
    for &l in &kept {
        if l == top || wheel_part[l] {
            continue;
        }
        let k = tree.parent_joint[l].expect("joint");
        let j = tree.joint(k);
        if !is_moving(&j.joint_type) {
            continue;
        }
        let p = tree.parent_of(k);
        let t = cl.in_rep(p).then(&origin[k].expect("origin"));
        let axis = Vector3::from(j.axis.xyz.0).normalize();
        let s = sanitize(&j.name);
        speeds.push(Speed {
            name: format!("qd_{s}"),
            coordinate: format!("q_{s}"),
        });
        ir_index.insert(l, links.len());
        links.push(Link {
            name: tree.link(l).name.clone(),
            parent: Some(ir_index[&cl.rep(p)]),
            joint: Some(Joint {
                name: j.name.clone(),
                kind: if j.joint_type == urdf_rs::JointType::Prismatic {
                    JointKind::Prismatic
                } else {
                    JointKind::Revolute
                },
                axis: [axis.x, axis.y, axis.z].map(clean),
                rotation: rows(&t.r),
                translation: numbers(t.p),
                speed: Some(speeds.len() - 1),
            }),
            body: None,
        });
    }

    // Bodies: each cluster's merged inertia about its frame.
    let mut members: HashMap<usize, Vec<usize>> = HashMap::new();
    for &l in &kept {
        if !wheel_part[l] {
            members.entry(cl.rep(l)).or_default().push(l);
        }
    }
    let mut body_names: HashSet<String> = HashSet::new();
    let mut rep_of_ir: Vec<Option<usize>> = vec![None; links.len()];
    for (&rep, &i) in &ir_index {
        rep_of_ir[i] = Some(rep);
    }
    for (li, link) in links.iter_mut().enumerate() {
        let Some(rep) = rep_of_ir[li] else {
            continue;
        };
        let group = &members[&rep];
        let items: Vec<(Tf, Inertial)> = group
            .iter()
            .filter_map(|&l| inertial[l].map(|i| (cl.in_rep(l), i)))
            .collect();
        let mass: f64 = items.iter().map(|(_, i)| i.m).sum();
        let others: Vec<&str> = group
            .iter()
            .filter(|&&l| l != rep)
            .map(|&l| tree.link(l).name.as_str())
            .collect();
        if matches!(base, Base::Fixed) && li == 0 {
            if !others.is_empty() || mass > 0.0 {
                notes.push(format!(
                    "fixed to the base frame `{}` (no effect on the dynamics, {mass} kg ignored): {}",
                    tree.link(rep).name,
                    group
                        .iter()
                        .map(|&l| tree.link(l).name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
            continue;
        }
        if !others.is_empty() {
            notes.push(format!(
                "merged into `{}` through fixed joints: {}",
                tree.link(rep).name,
                others.join(", ")
            ));
        }
        if items.is_empty() || mass == 0.0 {
            continue;
        }
        let (m, ms, j) = merge(&items);
        let s = sanitize(&tree.link(rep).name);
        if !body_names.insert(s.clone()) {
            return Err(K::Duplicate {
                what: "body name (link name sanitised to an identifier)",
                name: s,
            });
        }
        let mut sym = |prefix: &str, v: f64| {
            add_param(&mut params, format!("{prefix}_{s}"), v, ParamKind::Inertial)
        };
        let body = Body {
            name: s.clone(),
            mass: sym("m", m),
            first_moment: [sym("MX", ms.x), sym("MY", ms.y), sym("MZ", ms.z)],
            inertia: [
                sym("XX", j[(0, 0)]),
                sym("XY", j[(0, 1)]),
                sym("XZ", j[(0, 2)]),
                sym("YY", j[(1, 1)]),
                sym("YZ", j[(1, 2)]),
                sym("ZZ", j[(2, 2)]),
            ],
        };
        link.body = Some(body);
    }

    // Generated identifiers must be distinct (index constants are the upper-cased coordinates).
    let mut seen: HashMap<String, &str> = HashMap::new();
    for s in &speeds {
        if let Some(first) = seen.insert(s.coordinate.to_uppercase(), &s.coordinate) {
            return Err(K::Duplicate {
                what: "coordinate (joint names sanitised and compared case-insensitively)",
                name: format!("{first} / {}", s.coordinate),
            });
        }
    }

    let name = opts.name.clone().unwrap_or_else(|| robot.name.clone());
    let description = format!(
        "imported from URDF robot `{}`: {} speeds, {} base",
        robot.name,
        speeds.len(),
        match base {
            Base::Fixed => "fixed",
            Base::Wheeled(_) => "two-wheeled",
        }
    );
    let model = Model {
        name,
        description,
        source: file.to_owned(),
        params,
        speeds,
        links,
        base,
        gravity: Gravity {
            symbol: g,
            direction: opts.gravity_direction,
        },
    };
    for l in &model.links {
        if let Some(j) = &l.joint {
            validate::check_axis(&j.name, j.axis)?;
            validate::check_rotation(&j.name, &j.rotation)?;
        }
    }
    validate::check_physics(&model)?;
    Ok(UrdfImport {
        model,
        notes: notes.finish(),
    })
}

fn rows(r: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| clean(r[(i, j)])))
}

fn numbers(v: Vector3<f64>) -> [Scalar; 3] {
    [v.x, v.y, v.z].map(|x| Scalar::number(clean(x)))
}

/// The rigid clusters (links joined by fixed joints) of the kept tree.
struct Clusters {
    /// The kept tree's top link.
    top: usize,
    /// The frame of the top cluster: `top` (fixed base) or the wheeled base's body link.
    body: usize,
    /// Per link: the top link of its cluster.
    cluster_top: Vec<usize>,
    /// Per link: its pose in its cluster top's frame.
    in_top: Vec<Tf>,
}

impl Clusters {
    /// The link whose frame is the frame of `l`'s cluster.
    fn rep(&self, l: usize) -> usize {
        let t = self.cluster_top[l];
        if t == self.top { self.body } else { t }
    }

    /// The pose of link `l` in its cluster's frame.
    fn in_rep(&self, l: usize) -> Tf {
        self.in_top[self.rep(l)].inverse().then(&self.in_top[l])
    }
}

/// Resolves the wheeled base declaration: heading frame, pitch axis and wheel constants.
#[allow(clippy::too_many_arguments)]
fn wheel_geometry(
    w: &WheeledBaseSpec,
    tree: &Tree<'_>,
    wheel_joints: &[usize],
    origin: &[Option<Tf>],
    inertial: &[Option<Inertial>],
    dropped: &[bool],
    cl: &Clusters,
    notes: &mut Notes,
) -> Result<WheelGeometry, K> {
    let body_name = &tree.link(cl.body).name;
    let mut centres = Vec::new();
    let mut axes = Vec::new();
    let mut consts = Vec::new();
    for (&k, option) in wheel_joints
        .iter()
        .zip(["base.left_wheel_joint", "base.right_wheel_joint"])
    {
        let j = tree.joint(k);
        let p = tree.parent_of(k);
        if cl.cluster_top[p] == usize::MAX || cl.rep(p) != cl.body {
            return Err(bad_option(
                option,
                format!(
                    "`{}` hangs from `{}`, which is neither the body link `{body_name}` nor fixed to it",
                    j.name, j.parent.link
                ),
            ));
        }
        let t = cl.in_rep(p).then(&origin[k].expect("origin"));
        let a = Vector3::from(j.axis.xyz.0);
        if !(finite3(j.axis.xyz.0) && a.norm() > 0.0) {
            return Err(bad_option(
                option,
                format!("`{}` has no usable <axis> ({:?})", j.name, j.axis.xyz.0),
            ));
        }
        let a = a.normalize();
        centres.push(t.p);
        axes.push(t.r * a);
        // The wheel and the links fixed to it, merged in the wheel link's frame.
        let c = tree.child_of(k);
        let items: Vec<(Tf, Inertial)> = tree
            .preorder(c, &|kk| !dropped[tree.child_of(kk)])
            .into_iter()
            .filter_map(|l| inertial[l].map(|i| (cl.in_top[l], i)))
            .collect();
        let (m, ms, jo) = merge(&items);
        if m > 0.0 {
            let com = ms / m;
            let ig = jo - (Matrix3::identity() * com.norm_squared() - com * com.transpose()) * m;
            let yy = (a.transpose() * ig * a)[(0, 0)];
            let zz = (ig.trace() - yy) / 2.0;
            // The two diametral principal moments (eigenvalues of I_G restricted to the plane ⟂ a).
            let b = if a.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let b = (b - a * a.dot(&b)).normalize();
            let cc = a.cross(&b);
            let (bb, bc, ccc) = (
                (b.transpose() * ig * b)[(0, 0)],
                (b.transpose() * ig * cc)[(0, 0)],
                (cc.transpose() * ig * cc)[(0, 0)],
            );
            let half = ((bb - ccc) * (bb - ccc) / 4.0 + bc * bc).sqrt();
            let (d1, d2) = ((bb + ccc) / 2.0 - half, (bb + ccc) / 2.0 + half);
            if d2 - d1 > 1e-3 * d2.abs() {
                notes.push(format!(
                    "wheel `{}`: not axisymmetric about its axle (diametral moments {d1:.6} and {d2:.6} kg·m²); their mean {zz:.6} is used as ZZw unless overridden",
                    j.child.link
                ));
            }
            let off = (com - a * com.dot(&a)).norm();
            if off > 1e-6 {
                notes.push(format!(
                    "wheel `{}`: centre of mass {off:.3e} m off the axle (ignored by the wheel terms)",
                    j.child.link
                ));
            }
            consts.push((m, yy, zz));
        } else {
            consts.push((0.0, 0.0, 0.0));
        }
    }
    let (cl_, cr) = (centres[0], centres[1]);
    let (al, ar) = (axes[0], axes[1]);
    if al.cross(&ar).norm() > 1e-6 {
        return Err(bad_option(
            "base.right_wheel_joint",
            format!(
                "the wheel axes are not parallel: left {:?}, right {:?} in the body frame `{body_name}`",
                al.as_slice(),
                ar.as_slice()
            ),
        ));
    }
    let d = cl_ - cr;
    if d.norm() < 1e-9 {
        return Err(bad_option(
            "base.right_wheel_joint",
            "the two wheel joint origins coincide; the track is the distance between them".into(),
        ));
    }
    let e1 = al;
    let lateral = (d - e1 * d.dot(&e1)).norm();
    if lateral > 1e-6 {
        return Err(bad_option(
            "base.right_wheel_joint",
            format!(
                "the wheel centres are not on one axle: the line between them is {lateral:.3e} m off the wheel axis"
            ),
        ));
    }
    let y0 = if d.dot(&e1) > 0.0 { e1 } else { -e1 };
    let up = Vector3::from(w.up);
    if !(finite3(w.up) && up.norm() > 0.0) {
        return Err(bad_option(
            "base.up",
            format!("{:?} is not a direction", w.up),
        ));
    }
    let z0 = up.normalize();
    if z0.dot(&y0).abs() > 1e-9 {
        return Err(bad_option(
            "base.up",
            format!(
                "{:?} is not perpendicular to the wheel axis {:?} (body frame `{body_name}`); give the body axis that points up at zero pitch",
                w.up,
                e1.as_slice()
            ),
        ));
    }
    let x0 = y0.cross(&z0);
    let a01 = Matrix3::from_rows(&[x0.transpose(), y0.transpose(), z0.transpose()]).map(clean);
    let mid = (cl_ + cr) / 2.0;
    let p01 = -(a01 * mid);
    let geometric = d.norm();
    let mean = |i: usize| {
        let (l, r) = (consts[0], consts[1]);
        let v = [l.0, l.1, l.2];
        let u = [r.0, r.1, r.2];
        (v[i] + u[i]) / 2.0
    };
    if (consts[0].0 - consts[1].0).abs() > 1e-9 * consts[0].0.max(consts[1].0) {
        notes.push(format!(
            "wheel masses differ ({} and {} kg); their mean is used",
            consts[0].0, consts[1].0
        ));
    }
    let g = WheelGeometry {
        a01,
        p01,
        axis: e1.map(clean),
        track: w.track.unwrap_or(geometric),
        mass: w.wheel_mass.unwrap_or(mean(0)),
        axle: w.wheel_axle_inertia.unwrap_or(mean(1)),
        diametral: w.wheel_diametral_inertia.unwrap_or(mean(2)),
    };
    let src = |given: bool| if given { "given" } else { "from the URDF" };
    notes.push(format!(
        "wheeled base: body `{body_name}`, heading frame 0 at the wheel centres' midpoint {:?} of `{body_name}`, pitch axis {:?}; R = {} (given), L = {} ({}; wheel joint origins {geometric} apart), mw = {} ({}), YYw = {} ({}), ZZw = {} ({})",
        mid.map(clean).as_slice(),
        g.axis.as_slice(),
        w.radius,
        g.track,
        src(w.track.is_some()),
        g.mass,
        src(w.wheel_mass.is_some()),
        g.axle,
        src(w.wheel_axle_inertia.is_some()),
        g.diametral,
        src(w.wheel_diametral_inertia.is_some()),
    ));
    Ok(g)
}

// ---- diagnosis of malformed text ----------------------------------------------------------------

/// Numeric attributes of URDF elements (inside a top-level `<link>` or `<joint>`) and how many
/// numbers each holds.
const NUMERIC: &[(&str, &[(&str, usize)])] = &[
    ("origin", &[("xyz", 3), ("rpy", 3)]),
    ("axis", &[("xyz", 3)]),
    ("mass", &[("value", 1)]),
    (
        "inertia",
        &[
            ("ixx", 1),
            ("ixy", 1),
            ("ixz", 1),
            ("iyy", 1),
            ("iyz", 1),
            ("izz", 1),
        ],
    ),
    (
        "limit",
        &[("lower", 1), ("upper", 1), ("effort", 1), ("velocity", 1)],
    ),
    ("dynamics", &[("damping", 1), ("friction", 1)]),
    ("mimic", &[("multiplier", 1), ("offset", 1)]),
    ("box", &[("size", 3)]),
    ("cylinder", &[("radius", 1), ("length", 1)]),
    ("sphere", &[("radius", 1)]),
    ("mesh", &[("scale", 3)]),
];

const JOINT_TYPES: &[&str] = &[
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// One start or end tag.
struct Tag<'a> {
    name: &'a str,
    attrs: Vec<(&'a str, &'a str)>,
    closing: bool,
    self_closing: bool,
}

/// The tags of an XML text, skipping comments, declarations and CDATA; `None` where the text is
/// not tag-shaped (the URDF parser then reports it).
fn tags(text: &str) -> Option<Vec<Tag<'_>>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find('<') {
        rest = &rest[i..];
        for (open, close) in [
            ("<!--", "-->"),
            ("<![CDATA[", "]]>"),
            ("<?", "?>"),
            ("<!", ">"),
        ] {
            if rest.starts_with(open) {
                let end = rest.find(close)?;
                rest = &rest[end + close.len()..];
                break;
            }
        }
        if !rest.starts_with('<') || rest.starts_with("<!") || rest.starts_with("<?") {
            continue;
        }
        let closing = rest.starts_with("</");
        let mut s = &rest[if closing { 2 } else { 1 }..];
        let name_end = s.find(|c: char| c.is_whitespace() || c == '>' || c == '/')?;
        let name = &s[..name_end];
        s = &s[name_end..];
        let mut attrs = Vec::new();
        let self_closing;
        loop {
            s = s.trim_start();
            if let Some(r) = s.strip_prefix("/>") {
                self_closing = true;
                s = r;
                break;
            }
            if let Some(r) = s.strip_prefix('>') {
                self_closing = false;
                s = r;
                break;
            }
            let eq = s.find('=')?;
            let key = s[..eq].trim();
            let v = s[eq + 1..].trim_start();
            let quote = v.chars().next().filter(|c| *c == '"' || *c == '\'')?;
            let v = &v[1..];
            let end = v.find(quote)?;
            attrs.push((key, &v[..end]));
            s = &v[end + 1..];
        }
        out.push(Tag {
            name,
            attrs,
            closing,
            self_closing,
        });
        rest = s;
    }
    Some(out)
}

/// A typed error for the malformations that the URDF parser would only report generically: an
/// unknown joint type, a bad number. `None` if none is found (or the text is not tag-shaped).
fn diagnose(text: &str) -> Option<K> {
    let tags = tags(text)?;
    // Open elements; the enclosing top-level link or joint.
    let mut depth = 0usize;
    let mut context: Option<String> = None;
    for t in &tags {
        if t.closing {
            depth = depth.saturating_sub(1);
            if depth <= 1 {
                context = None;
            }
            continue;
        }
        let attr = |k: &str| t.attrs.iter().find(|(a, _)| *a == k).map(|(_, v)| *v);
        if depth == 1 && (t.name == "link" || t.name == "joint") {
            let name = attr("name").unwrap_or("?");
            if t.name == "joint" {
                let kind = attr("type").unwrap_or("");
                if !JOINT_TYPES.contains(&kind) {
                    return Some(K::UrdfUnknownJointType {
                        joint: name.to_owned(),
                        kind: kind.to_owned(),
                    });
                }
            }
            context = Some(format!("{} `{name}`", t.name));
        } else if depth >= 2
            && let Some(ctx) = &context
            && let Some((_, numeric)) = NUMERIC.iter().find(|(e, _)| *e == t.name)
        {
            for &(key, count) in *numeric {
                let Some(v) = attr(key) else { continue };
                let parts: Vec<&str> = v.split_whitespace().collect();
                let ok = parts.len() == count
                    && parts
                        .iter()
                        .all(|p| p.parse::<f64>().is_ok_and(f64::is_finite));
                if !ok {
                    return Some(K::UrdfBadNumber {
                        element: format!("{ctx} <{}>", t.name),
                        attribute: key.to_owned(),
                        text: v.to_owned(),
                        expected: if count == 1 {
                            "a finite number".into()
                        } else {
                            format!("{count} finite numbers separated by spaces")
                        },
                    });
                }
            }
        }
        if !t.self_closing {
            depth += 1;
        }
    }
    None
}
