//! The validated robot IR.

use std::fmt;

/// Index of a parameter in [`Model::params`].
pub type ParamId = usize;

/// What a parameter is; used for documentation and grouping only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamKind {
    /// A length appearing in a joint translation (`L1`, `L2`, ...).
    Length,
    /// The gravity magnitude `g`.
    Gravity,
    /// A body inertial parameter (`m1`, `MX1`, ..., `ZZ1`).
    Inertial,
    /// A wheel constant (`R`, `L`, `mw`, `YYw`, `ZZw`).
    Wheel,
}

/// A named, symbolic model parameter with its default value.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// The symbol, as in the reports (`MX4l`, `L1`, `g`, `R`).
    pub name: String,
    /// The default value from the description file (SI units).
    pub value: f64,
    /// What the parameter is.
    pub kind: ParamKind,
}

/// A generalized speed `u_i` and the coordinate it is the rate of.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Speed {
    /// Name of the speed (`qd_imu`, `xd`).
    pub name: String,
    /// Name of the coordinate (`q_imu`, `x`); for the wheeled base's quasi-velocities a
    /// coordinate that does not enter M, c or g.
    pub coordinate: String,
}

/// A length in a joint translation: a number, or `coef · symbol` (such as `L1` or `-L2`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Length {
    /// The factor (±1 for `L1`/`-L2`, or the value itself when `symbol` is `None`).
    pub coef: f64,
    /// The parameter multiplied by `coef`, if any.
    pub symbol: Option<ParamId>,
}

impl Length {
    /// A plain number.
    pub fn number(v: f64) -> Self {
        Self {
            coef: v,
            symbol: None,
        }
    }

    /// Is this the constant zero?
    pub fn is_zero(&self) -> bool {
        self.coef == 0.0
    }

    /// The value given parameter values indexed by [`ParamId`].
    pub fn eval(&self, params: &[f64]) -> f64 {
        match self.symbol {
            Some(p) => self.coef * params[p],
            None => self.coef,
        }
    }
}

/// How a joint moves; a moving joint drives one generalized speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// Rotation about the axis by the coordinate of `speed`.
    Revolute {
        /// Index into [`Model::speeds`] of the speed this joint drives.
        speed: usize,
    },
    /// Translation along the axis by the coordinate of `speed`.
    Prismatic {
        /// Index into [`Model::speeds`] of the speed this joint drives.
        speed: usize,
    },
    /// No motion; the child frame is rigidly attached.
    Fixed,
}

impl JointKind {
    /// The speed a moving joint drives; `None` for a fixed joint.
    pub fn speed(self) -> Option<usize> {
        match self {
            JointKind::Revolute { speed } | JointKind::Prismatic { speed } => Some(speed),
            JointKind::Fixed => None,
        }
    }

    /// `Revolute`, `Prismatic` or `Fixed`.
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "Revolute",
            JointKind::Prismatic { .. } => "Prismatic",
            JointKind::Fixed => "Fixed",
        }
    }
}

/// The joint that attaches a frame to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Joint name; for moving joints the name of its coordinate (`q1l`).
    pub name: String,
    /// Revolute or prismatic (with the speed it drives), or fixed.
    pub kind: JointKind,
    /// Unit axis `e_j` in the child frame.
    pub axis: [f64; 3],
    /// `iAj(0)`: columns are the child's unit vectors in the parent frame; stored by rows.
    pub rotation: [[f64; 3]; 3],
    /// `iPj`: the child origin in the parent frame.
    pub translation: [Length; 3],
}

impl Joint {
    /// The speed the joint drives; `None` for a fixed joint.
    pub fn speed(&self) -> Option<usize> {
        self.kind.speed()
    }
}

/// Khalil's standard inertial parameters of one body, as parameter indices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Body {
    /// Body name (`1`, `4l`); also the suffix of its symbols (`m4l`, `MX4l`, ...).
    pub name: String,
    /// Mass `m`.
    pub mass: ParamId,
    /// First moments `[MX, MY, MZ] = m·S` in the body frame.
    pub first_moment: [ParamId; 3],
    /// Inertia about the frame origin `[XX, XY, XZ, YY, YZ, ZZ]`.
    pub inertia: [ParamId; 6],
}

/// How a frame other than the base frame hangs from its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Mount {
    /// Index of the parent link (always smaller than the index of the link it mounts).
    pub parent: usize,
    /// The joint to the parent.
    pub joint: Joint,
}

/// A frame of the tree. `links[0]` is the base frame, the only one without a [`Mount`].
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Frame name (`0`, `1`, `4l`).
    pub name: String,
    /// The parent and the joint to it; `None` for the base frame.
    pub mount: Option<Mount>,
    /// The rigid body fixed in this frame, if any.
    pub body: Option<Body>,
}

impl Link {
    /// Index of the parent link; `None` for the base frame.
    pub fn parent(&self) -> Option<usize> {
        self.mount.as_ref().map(|m| m.parent)
    }

    /// The joint to the parent; `None` for the base frame.
    pub fn joint(&self) -> Option<&Joint> {
        self.mount.as_ref().map(|m| &m.joint)
    }
}

/// The two-wheeled inverted-pendulum base of DynamicModeling.tex.
///
/// The base frame is the heading frame at the axle midpoint (z up); its motion is given by the
/// quasi-velocities ẋ (forward speed of the axle midpoint) and ψ̇ (yaw rate):
/// `ω0 = [0, 0, ψ̇]`, `v0 = [ẋ, 0, 0]`, `α0 = [0, 0, ψ̈]`, `a0 = [ẍ, ẋψ̇, 0]`. The axisymmetric
/// wheels add inertia only: `(2 mw + 2 YYw/R²)` to `M[ẋ,ẋ]` and
/// `(mw L²/2 + YYw L²/(2R²) + 2 ZZw)` to `M[ψ̇,ψ̇]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WheeledBase {
    /// Index of ẋ in [`Model::speeds`].
    pub x_speed: usize,
    /// Index of ψ̇ in [`Model::speeds`].
    pub psi_speed: usize,
    /// Wheel radius `R`.
    pub radius: ParamId,
    /// Track width `L` (distance between the wheel contact points).
    pub track: ParamId,
    /// Mass of one wheel `mw`.
    pub wheel_mass: ParamId,
    /// Moment of inertia of one wheel about its axle `YYw`.
    pub wheel_axle_inertia: ParamId,
    /// Moment of inertia of one wheel about a diameter `ZZw`.
    pub wheel_diametral_inertia: ParamId,
}

/// How the base frame moves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Base {
    /// The base frame is inertial.
    Fixed,
    /// Two-wheeled inverted-pendulum base with quasi-velocities ẋ, ψ̇.
    Wheeled(WheeledBase),
    /// A free-flying base frame (legged robots, humanoids), laid out as Pinocchio's free-flyer
    /// joint. The first six speeds of [`Model::speeds`] are the base's: the base origin's
    /// velocity `v` and the base's angular velocity `ω`, both in the base frame
    /// ([`FLOATING_BASE_SPEEDS`]). Its seven coordinates come first in `q`: the base origin in
    /// the world, then the unit quaternion `(qx, qy, qz, qw)` that rotates base vectors into the
    /// world ([`FLOATING_BASE_COORDINATES`]); the first six are the coordinates of the six base
    /// speeds and `base_qw` has no speed, so a model has [`Model::nq`] = [`Model::dof`] + 1
    /// coordinates. Gravity's direction is in the world frame.
    Floating,
}

/// The coordinates of a floating base, first in `q`: position of the base origin in the world,
/// then the quaternion (vector part first, as Pinocchio and Eigen store it).
pub const FLOATING_BASE_COORDINATES: [&str; 7] = [
    "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw",
];

/// The speeds of a floating base, first in `u`: the base origin's linear velocity and the base's
/// angular velocity, both in the base frame.
pub const FLOATING_BASE_SPEEDS: [&str; 6] = [
    "base_vx", "base_vy", "base_vz", "base_wx", "base_wy", "base_wz",
];

/// The floating base's six speeds (named [`FLOATING_BASE_SPEEDS`], the rates of the first six
/// [`FLOATING_BASE_COORDINATES`]), to put first in [`Model::speeds`].
pub fn floating_base_speeds() -> Vec<Speed> {
    FLOATING_BASE_SPEEDS
        .iter()
        .zip(FLOATING_BASE_COORDINATES)
        .map(|(s, c)| Speed {
            name: (*s).to_owned(),
            coordinate: c.to_owned(),
        })
        .collect()
}

/// Uniform gravity `g · direction` in the base frame (in the world frame for a floating base).
#[derive(Debug, Clone, PartialEq)]
pub struct Gravity {
    /// The magnitude parameter (`g`).
    pub symbol: ParamId,
    /// Unit direction in the base frame (`[0, 0, -1]` for z up); in the world frame for a
    /// floating base.
    pub direction: [f64; 3],
}

/// A validated robot description.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Short name (`krang`), used in generated headers.
    pub name: String,
    /// One-line description.
    pub description: String,
    /// The file the model came from (for messages and generated headers).
    pub source: String,
    /// All symbols with default values.
    pub params: Vec<Param>,
    /// Generalized speeds in the order of `u`.
    pub speeds: Vec<Speed>,
    /// Frames in topological order (parents first); `links[0]` is the base frame.
    pub links: Vec<Link>,
    /// The base.
    pub base: Base,
    /// Gravity.
    pub gravity: Gravity,
    /// Mimic constraints (URDF `<mimic>`): each makes one speed of [`Model::speeds`] dependent,
    /// `q_dep = multiplier · q_master + offset`. The dependent speeds are the last
    /// `mimics.len()` entries of `speeds`, in the order of this list; without constraints (the
    /// usual case) the model is an ordinary tree. Read without the constraints, the model is the
    /// unconstrained tree with an independent coordinate per joint (what Pinocchio builds).
    pub mimics: Vec<crate::Mimic>,
}

impl Model {
    /// Number of generalized speeds of the tree, the dependent speeds of mimic joints included
    /// (see [`Model::mimics`]; [`Model::independent_dof`] without them).
    pub fn dof(&self) -> usize {
        self.speeds.len()
    }

    /// Number of independent generalized speeds: [`Model::dof`] minus the mimic constraints.
    /// Generated code has this many speeds.
    pub fn independent_dof(&self) -> usize {
        self.speeds.len() - self.mimics.len()
    }

    /// Index of the parameter called `name`.
    pub fn param_index(&self, name: &str) -> Option<ParamId> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Default parameter values, indexed by [`ParamId`].
    pub fn param_values(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.value).collect()
    }

    /// Whether the base is floating ([`Base::Floating`]).
    pub fn is_floating(&self) -> bool {
        matches!(self.base, Base::Floating)
    }

    /// Number of coordinates of generated code (the length of `q`): [`Model::independent_dof`],
    /// plus one for a floating base (its quaternion has four entries for three speeds).
    pub fn nq(&self) -> usize {
        self.independent_dof() + usize::from(self.is_floating())
    }

    /// Index in `q` of the coordinate of speed `s`: `s`, or `s + 1` for a joint speed of a
    /// floating base (after the base's seven coordinates).
    pub fn coordinate_index(&self, s: usize) -> usize {
        if self.is_floating() && s >= 6 {
            s + 1
        } else {
            s
        }
    }

    /// The coordinate names of generated code, in the order of `q` ([`Model::nq`] of them): the
    /// coordinates of the independent speeds, with `base_qw` after the floating base's first six.
    pub fn coordinate_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.speeds[..self.independent_dof()]
            .iter()
            .map(|s| s.coordinate.as_str())
            .collect();
        if self.is_floating() {
            names.insert(6, FLOATING_BASE_COORDINATES[6]);
        }
        names
    }

    /// Index of the speed called `name`.
    pub fn speed_index(&self, name: &str) -> Option<usize> {
        self.speeds.iter().position(|s| s.name == name)
    }

    /// Index of the link called `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Indices of the children of link `i`, in order.
    pub fn children(&self, i: usize) -> Vec<usize> {
        (0..self.links.len())
            .filter(|&c| self.links[c].parent() == Some(i))
            .collect()
    }

    /// The frames other than the base frame, parents first, each with its index and its mount.
    pub fn mounted_links(&self) -> impl DoubleEndedIterator<Item = (usize, &Link, &Mount)> {
        self.links
            .iter()
            .enumerate()
            .filter_map(|(i, l)| l.mount.as_ref().map(|m| (i, l, m)))
    }

    /// The mounts on the path from link `l` up to the base frame, each with the index of the
    /// link it mounts: `(l, mount of l)`, then its parent's, ...; empty for the base frame.
    pub fn path_to_base(&self, l: usize) -> impl Iterator<Item = (usize, &Mount)> {
        let mut at = Some(l);
        std::iter::from_fn(move || {
            let k = at?;
            let m = self.links[k].mount.as_ref()?;
            at = Some(m.parent);
            Some((k, m))
        })
    }

    /// The link indices depth first from the base frame, children in index order: frames
    /// appended after their parents' siblings (operational frames, merged URDF links) come right
    /// after their parents' other children (for listings).
    pub fn preorder(&self) -> Vec<usize> {
        let mut order = Vec::with_capacity(self.links.len());
        let mut stack = vec![0];
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(self.children(i).into_iter().rev());
        }
        order
    }

    /// The wheeled base, if the model has one.
    pub fn wheeled_base(&self) -> Option<&WheeledBase> {
        match &self.base {
            Base::Wheeled(w) => Some(w),
            Base::Fixed | Base::Floating => None,
        }
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.links.iter().filter(|l| l.body.is_some()).count()
    }
}

fn fmt_length(s: &Length, m: &Model) -> String {
    match s.symbol {
        None => format!("{}", s.coef),
        Some(p) if s.coef == 1.0 => m.params[p].name.clone(),
        Some(p) if s.coef == -1.0 => format!("-{}", m.params[p].name),
        Some(p) => format!("{}*{}", s.coef, m.params[p].name),
    }
}

impl fmt::Display for Model {
    /// A human-readable dump: the frame tree, speeds and parameters.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "model {} ({})", self.name, self.source)?;
        if !self.description.is_empty() {
            writeln!(f, "  {}", self.description)?;
        }
        match &self.base {
            Base::Fixed => writeln!(f, "base: fixed frame `{}`", self.links[0].name)?,
            Base::Floating => writeln!(
                f,
                "base: floating frame `{}`; coordinates {}; speeds {}",
                self.links[0].name,
                FLOATING_BASE_COORDINATES.join(", "),
                FLOATING_BASE_SPEEDS.join(", ")
            )?,
            Base::Wheeled(w) => writeln!(
                f,
                "base: two-wheeled heading frame `{}`; speeds {} and {}; R = {}, L = {}, mw = {}, YYw = {}, ZZw = {}",
                self.links[0].name,
                self.speeds[w.x_speed].name,
                self.speeds[w.psi_speed].name,
                self.params[w.radius].name,
                self.params[w.track].name,
                self.params[w.wheel_mass].name,
                self.params[w.wheel_axle_inertia].name,
                self.params[w.wheel_diametral_inertia].name,
            )?,
        }
        let g = &self.gravity;
        let frame = if self.is_floating() { "world" } else { "base" };
        writeln!(
            f,
            "gravity: {} * {:?} in the {frame} frame",
            self.params[g.symbol].name, g.direction
        )?;
        writeln!(f, "frames ({}):", self.links.len())?;
        for i in self.preorder() {
            let l = &self.links[i];
            let indent = "  ".repeat(self.path_to_base(i).count() + 1);
            match l.joint() {
                None => write!(f, "{indent}{}", l.name)?,
                Some(j) => {
                    let t: Vec<String> =
                        j.translation.iter().map(|s| fmt_length(s, self)).collect();
                    write!(
                        f,
                        "{indent}{} <- {} joint `{}` axis {:?} P [{}]",
                        l.name,
                        j.kind.name(),
                        j.name,
                        j.axis,
                        t.join(", ")
                    )?;
                    if let Some(s) = j.speed() {
                        write!(f, " speed {}", self.speeds[s].name)?;
                    }
                }
            }
            if let Some(b) = &l.body {
                write!(f, "  [body {}: m = {}]", b.name, self.params[b.mass].value)?;
            }
            writeln!(f)?;
        }
        writeln!(f, "speeds ({}):", self.speeds.len())?;
        for (i, s) in self.speeds.iter().enumerate() {
            writeln!(f, "  u[{i:2}] = {} (rate of {})", s.name, s.coordinate)?;
        }
        writeln!(f, "parameters ({}):", self.params.len())?;
        for p in &self.params {
            writeln!(f, "  {:<6} = {:<22} ({:?})", p.name, p.value, p.kind)?;
        }
        Ok(())
    }
}
