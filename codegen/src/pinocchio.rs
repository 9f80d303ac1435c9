//! Export of a model to [Pinocchio](https://github.com/stack-of-tasks/pinocchio), for
//! side-by-side checks and timings (`benches/pinocchio/run.sh`).
//!
//! [`export`] turns a validated [`Model`] and a parameter set into a Pinocchio kinematic tree
//! with numbers ([`PinocchioModel`]), and [`PinocchioModel::to_text`] writes it in a small
//! line-oriented text format that the C++ harness `benches/pinocchio/harness.cpp` reads to build a
//! `pinocchio::Model` with `addJoint`, `appendBodyToJoint` and `armature` (format below).
//!
//! # The mapping
//!
//! * **Joints.** A revolute (prismatic) joint about (along) a coordinate axis `±x`, `±y`, `±z`
//!   becomes Pinocchio's specialised `JointModelRX`/`RY`/`RZ` (`PX`/`PY`/`PZ`): a rotation by `q`
//!   about `−x` is a rotation by `−q` about `+x`, so such a coordinate and its speed enter
//!   Pinocchio with the sign `−1` ([`SpeedMap::sign`], [`CoordinateMap::Joint`]); every other
//!   axis becomes `JointModelRevoluteUnaligned` (`PrismaticUnaligned`). The joint placement is
//!   `iTj(0)` (`iAj(0)`, `iPj`), Pinocchio's convention `oMi = oMparent · placement · joint(q)`
//!   is the model's `iTj(q) = iTj(0) · Rot(e_j, q_j)`. Pinocchio's URDF parser would make a `−x`
//!   axis unaligned (slower); the aligned form is Pinocchio's best case.
//! * **Fixed joints** add no Pinocchio joint: the bodies of such frames are appended to the
//!   nearest moving ancestor's joint with the composed placement.
//! * **Bodies.** Khalil's standard parameters `m`, `MS`, `J` (about the frame origin) become
//!   `Inertia(m, c, I_c)` with `c = MS/m` and `I_c = J − m(|c|²·1 − c cᵀ)`. A massless body
//!   with a non-zero first moment cannot be expressed ([`ExportError::MasslessFirstMoment`]).
//! * **The two-wheeled base** (quasi-velocities ẋ, ψ̇ of DynamicModeling.tex) becomes a
//!   `JointModelPlanar` at the root: configuration `(x, y, cos ψ, sin ψ)`, velocity `(v_x, v_y,
//!   ω_z)` in the joint's own (heading) frame. With `v_y = 0` (rolling without side slip) and
//!   `v_x = ẋ`, `ω_z = ψ̇` its frame moves exactly like the heading frame: `ω0 = [0, 0, ψ̇]`,
//!   `v0 = [ẋ, 0, 0]` and classical acceleration `d/dt(v) + ω × v = [ẍ, ẋψ̇, 0]` (`a0`).
//!   Kane's equations in the quasi-velocities `u` with `v = S u` (constant selection `S`) are
//!   `Sᵀ(M_pin S u̇ + nle(q, S u)) = Sᵀ τ_pin`, so `M = Sᵀ M_pin S`, `c + g = Sᵀ nle`,
//!   `τ = Sᵀ rnea(q, S u, S u̇)`, `C = Sᵀ C_pin(q, S u) S`: the rows and columns of the speeds
//!   ([`PinocchioModel::speeds`]); the `v_y` row of Pinocchio's results is the lateral constraint
//!   force, which the model does not need. The wheels' masses and diametral moments are a body on
//!   the planar joint (`2 mw` at the axle midpoint; its moment about `z` is `mw L²/2 + 2 ZZw`),
//!   their spin about the axle (`θ̇ = ẋ/R ∓ (L/2R) ψ̇`) is Pinocchio's `armature` on `v_x`
//!   (`2 YYw/R²`) and `ω_z` (`YYw L²/(2R²)`): exactly the wheel terms of DynamicModeling.tex
//!   (axisymmetric wheels whose axle is fixed in the heading frame have no velocity-product
//!   terms). Gravity must be along the heading frame's `z` (`ExportError::GravityNotVertical`).
//!   A revolute `ψ` joint about `z` followed by a prismatic `x` joint is *not* equivalent: its
//!   slider has the acceleration `[ẍ, 2ẋψ̇, 0]` (polar coordinates), not `a0`.
//!   The coordinate `x` (distance travelled) is not a position in the plane; it enters neither
//!   model, and [`CoordinateMap::PlanarX`] puts it in Pinocchio's `x` with `y = 0`.
//! * **A free-flyer root** ([`export_free_flyer`]): the root link on a `JointModelFreeFlyer`,
//!   whose configuration `(x, y, z, qx, qy, qz, qw)` and velocity `(v, ω)` (base frame) are
//!   those of `kanegen_reference::FreeFlyer` and of generated floating-base modules, mapped one
//!   to one; gravity `(0, 0, −g)` in the world.
//!
//! # Text format (version 1)
//!
//! Whitespace-separated tokens, one record per line, numbers with Rust's shortest round-trip
//! formatting (`{:?}`, exact in both directions), whitespace inside names replaced by `_`;
//! rotations by rows:
//!
//! ```text
//! kanegen-pinocchio 1
//! model <name> nq <nq> nv <nv> dof <dof>
//! gravity <gx> <gy> <gz>
//! joints <n>
//! joint <name> <parent: 0 = universe> <RX|RY|RZ|PX|PY|PZ|RU|PU|PLANAR|FREEFLYER> <ax> <ay> <az> <R: 9> <p: 3>
//! bodies <n>
//! body <name> <joint> <R: 9> <p: 3> <m> <c: 3> <I_c by rows: 9>
//! armature <nv values>
//! speeds <dof>
//! speed <name> <v index> <sign>
//! coordinates <dof, or dof + 1 with a free flyer>
//! coordinate <name> <joint|planar_x|planar_psi> <q index> <sign>
//! end
//! ```

use std::fmt::Write as _;

use crate::model::{Base, JointKind, Model};

/// Why a model cannot be exported to Pinocchio.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExportError {
    /// The parameter vector does not fit the model.
    #[error(
        "model `{model}` ({file}): {given} parameter values given, the model has {expected}; pass one value per `Model::params` entry (e.g. `Model::param_values()`)"
    )]
    ParamCount {
        /// The model name.
        model: String,
        /// The description file.
        file: String,
        /// Values given.
        given: usize,
        /// Parameters of the model.
        expected: usize,
    },
    /// A wheeled base whose gravity is not along the heading frame's z axis (Pinocchio's planar
    /// joint rotates about z, so gravity would turn with ψ).
    #[error(
        "model `{model}` ({file}): gravity direction {direction:?} of the wheeled base is not along the heading frame's z axis; Pinocchio's planar joint needs it along ±z (write `direction = [0, 0, -1]` in [gravity])"
    )]
    GravityNotVertical {
        /// The model name.
        model: String,
        /// The description file.
        file: String,
        /// The direction in the model.
        direction: [f64; 3],
    },
    /// [`export_free_flyer`] of a wheeled base: its root is not free.
    #[error(
        "model `{model}` ({file}): a two-wheeled base cannot be exported with a free-flyer root; load the robot with a fixed base (UrdfOptions::base) to export it as a free flyer"
    )]
    WheeledFreeFlyer {
        /// The model name.
        model: String,
        /// The description file.
        file: String,
    },
    /// A body with zero mass and a non-zero first moment has no centre of mass.
    #[error(
        "model `{model}` ({file}): body `{body}` has zero mass but first moment {first_moment:?}; Pinocchio needs a centre of mass (give the body a mass or a zero first moment)"
    )]
    MasslessFirstMoment {
        /// The model name.
        model: String,
        /// The description file.
        file: String,
        /// The body.
        body: String,
        /// Its first moment `[MX, MY, MZ]`.
        first_moment: [f64; 3],
    },
}

/// The Pinocchio joint model of a [`PinJoint`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PinJointType {
    /// `JointModelRX` (0), `RY` (1) or `RZ` (2): revolute about a coordinate axis.
    Revolute(usize),
    /// `JointModelPX` (0), `PY` (1) or `PZ` (2): prismatic along a coordinate axis.
    Prismatic(usize),
    /// `JointModelRevoluteUnaligned` about a unit axis.
    RevoluteUnaligned([f64; 3]),
    /// `JointModelPrismaticUnaligned` along a unit axis.
    PrismaticUnaligned([f64; 3]),
    /// `JointModelPlanar` (the two-wheeled base: x, y, rotation about z).
    Planar,
    /// `JointModelFreeFlyer` (a free-flyer root, [`export_free_flyer`]): position and unit
    /// quaternion `(x, y, z, qx, qy, qz, qw)`, velocity `(v, ω)` in the joint's frame.
    FreeFlyer,
}

impl PinJointType {
    /// The text format's tag and axis.
    fn tag_axis(self) -> (&'static str, [f64; 3]) {
        let unit = |i: usize| {
            let mut a = [0.0; 3];
            a[i] = 1.0;
            a
        };
        match self {
            PinJointType::Revolute(i) => (["RX", "RY", "RZ"][i], unit(i)),
            PinJointType::Prismatic(i) => (["PX", "PY", "PZ"][i], unit(i)),
            PinJointType::RevoluteUnaligned(a) => ("RU", a),
            PinJointType::PrismaticUnaligned(a) => ("PU", a),
            PinJointType::Planar => ("PLANAR", [0.0, 0.0, 1.0]),
            PinJointType::FreeFlyer => ("FREEFLYER", [0.0, 0.0, 0.0]),
        }
    }

    /// Configuration and velocity sizes `(nq, nv)`.
    pub fn sizes(self) -> (usize, usize) {
        match self {
            PinJointType::Planar => (4, 3),
            PinJointType::FreeFlyer => (7, 6),
            _ => (1, 1),
        }
    }
}

/// One Pinocchio joint (`model.addJoint(parent, joint, placement, name)`).
#[derive(Debug, Clone, PartialEq)]
pub struct PinJoint {
    /// Name: the model's joint name (the wheeled base: `base`).
    pub name: String,
    /// Parent joint id: 0 is Pinocchio's universe, `k` the `k`-th entry of
    /// [`PinocchioModel::joints`] counted from 1.
    pub parent: usize,
    /// The joint model.
    pub kind: PinJointType,
    /// Placement rotation in the parent joint's frame, by rows.
    pub rotation: [[f64; 3]; 3],
    /// Placement translation in the parent joint's frame.
    pub translation: [f64; 3],
    /// First index of its configuration in Pinocchio's `q`.
    pub idx_q: usize,
    /// First index of its velocity in Pinocchio's `v`.
    pub idx_v: usize,
}

/// A body appended to a joint (`model.appendBodyToJoint(joint, inertia, placement)`).
#[derive(Debug, Clone, PartialEq)]
pub struct PinBody {
    /// The model's body name (the wheels: `wheels`).
    pub name: String,
    /// The joint id it moves with (1-based, as [`PinJoint::parent`]).
    pub joint: usize,
    /// Rotation of the body frame in the joint frame, by rows.
    pub rotation: [[f64; 3]; 3],
    /// Origin of the body frame in the joint frame.
    pub translation: [f64; 3],
    /// Mass.
    pub mass: f64,
    /// Centre of mass in the body frame.
    pub com: [f64; 3],
    /// Inertia about the centre of mass, body axes, by rows.
    pub inertia_com: [[f64; 3]; 3],
}

/// Where a frame of the model (a link, a merged link or an operational frame) sits in the
/// exported tree: Pinocchio's `Frame(name, joint, placement)`.
#[derive(Debug, Clone, PartialEq)]
pub struct PinFrame {
    /// The model's link name.
    pub name: String,
    /// The joint id it moves with (0: the universe).
    pub joint: usize,
    /// Rotation of the frame in the joint frame, by rows.
    pub rotation: [[f64; 3]; 3],
    /// Origin of the frame in the joint frame.
    pub translation: [f64; 3],
}

/// Where one of the model's speeds is in Pinocchio's velocity `v`.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedMap {
    /// The model's speed name.
    pub name: String,
    /// Index in Pinocchio's `v` (and `a`, `τ`, the rows and columns of M and C).
    pub v: usize,
    /// `v[v] = sign · u[i]` (−1 for a joint about a negative coordinate axis).
    pub sign: f64,
}

/// How one of the model's coordinates enters Pinocchio's configuration `q`.
#[derive(Debug, Clone, PartialEq)]
pub enum CoordinateMap {
    /// `q_pin[q] = sign · q_i`.
    Joint {
        /// Index in Pinocchio's `q`.
        q: usize,
        /// ±1.
        sign: f64,
    },
    /// The wheeled base's `x`: `q_pin[q] = x`, `q_pin[q + 1] = 0` (planar position; enters no
    /// dynamics).
    PlanarX {
        /// Index of the planar joint's `x` in Pinocchio's `q`.
        q: usize,
    },
    /// The wheeled base's `ψ`: `q_pin[q] = cos ψ`, `q_pin[q + 1] = sin ψ`.
    PlanarPsi {
        /// Index of the planar joint's `cos ψ` in Pinocchio's `q`.
        q: usize,
    },
}

/// A model as a Pinocchio kinematic tree with numeric parameters (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PinocchioModel {
    /// The model name.
    pub name: String,
    /// Joints in Pinocchio order (parents first); joint id = position + 1.
    pub joints: Vec<PinJoint>,
    /// Bodies, each appended to one joint.
    pub bodies: Vec<PinBody>,
    /// Pinocchio's `model.armature` (one entry per velocity; the wheels' spin).
    pub armature: Vec<f64>,
    /// Gravity in Pinocchio's world frame.
    pub gravity: [f64; 3],
    /// Pinocchio's configuration size.
    pub nq: usize,
    /// Pinocchio's velocity size.
    pub nv: usize,
    /// Per speed of the model (in the order of `u`): its place in Pinocchio's `v`.
    pub speeds: Vec<SpeedMap>,
    /// Per coordinate of the model (in the order of `q`): its place in Pinocchio's `q`.
    pub coordinates: Vec<CoordinateMap>,
    /// The model's coordinate names, in the order of `q`.
    pub coordinate_names: Vec<String>,
    /// Every frame of the model (indexed like `Model::links`) in the tree; not part of the
    /// text format.
    pub frames: Vec<PinFrame>,
}

type M3 = [[f64; 3]; 3];

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

fn mat_vec(a: &M3, v: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

/// `Some((axis index, sign))` if `axis` is `±` a coordinate axis exactly.
fn cartesian(axis: [f64; 3]) -> Option<(usize, f64)> {
    let nonzero: Vec<usize> = (0..3).filter(|&i| axis[i] != 0.0).collect();
    match nonzero[..] {
        [i] if axis[i].abs() == 1.0 => Some((i, axis[i])),
        _ => None,
    }
}

/// Exports `model` with parameter values `params` (indexed like [`Model::params`]) as a
/// Pinocchio tree; see the module documentation for the mapping. A model with a floating base
/// ([`Base::Floating`]) is exported through [`export_free_flyer`]: its base is the free flyer, its
/// `q`, `u` and gravity those of its generated module, one to one.
pub fn export(model: &Model, params: &[f64]) -> Result<PinocchioModel, ExportError> {
    export_tree(model, params, model.is_floating())
}

/// Exports `model` with its root link on a `JointModelFreeFlyer` (joint 1), in the layout of
/// `kanegen_reference::FreeFlyer` and of generated floating-base modules: the first seven
/// coordinates are the free flyer's `(x, y, z, qx, qy, qz, qw)` (names `base_x` … `base_qw`),
/// the first six speeds its `(v, ω)` in the base frame (`base_vx` … `base_wz`), both mapped one
/// to one; the joints follow as in [`export`]. Gravity is `(0, 0, −g)` in the world for a
/// fixed model made free, the model's own gravity direction for a floating one. A wheeled
/// base is an error ([`ExportError::WheeledFreeFlyer`]); a fixed base's root becomes free.
pub fn export_free_flyer(model: &Model, params: &[f64]) -> Result<PinocchioModel, ExportError> {
    export_tree(model, params, true)
}

fn export_tree(
    model: &Model,
    params: &[f64],
    free_flyer: bool,
) -> Result<PinocchioModel, ExportError> {
    if params.len() != model.params.len() {
        return Err(ExportError::ParamCount {
            model: model.name.clone(),
            file: model.source.clone(),
            given: params.len(),
            expected: model.params.len(),
        });
    }
    let dof = model.dof();
    let g = params[model.gravity.symbol];
    let gravity = model.gravity.direction.map(|d| g * d);
    let mut joints: Vec<PinJoint> = Vec::new();
    let mut bodies: Vec<PinBody> = Vec::new();
    let mut armature: Vec<f64> = Vec::new();
    let mut speeds: Vec<Option<SpeedMap>> = vec![None; dof];
    let mut coordinates: Vec<Option<CoordinateMap>> = vec![None; dof];
    let (mut nq, mut nv) = (0usize, 0usize);
    // Per link: the Pinocchio joint id it moves with and its placement in that joint's frame.
    let mut attach: Vec<(usize, M3, [f64; 3])> = Vec::with_capacity(model.links.len());

    let mut base_speeds: Vec<SpeedMap> = Vec::new();
    let mut base_coordinates: Vec<(CoordinateMap, String)> = Vec::new();
    let gravity = if free_flyer {
        if matches!(model.base, Base::Wheeled(_)) {
            return Err(ExportError::WheeledFreeFlyer {
                model: model.name.clone(),
                file: model.source.clone(),
            });
        }
        joints.push(PinJoint {
            name: "root_joint".into(),
            parent: 0,
            kind: PinJointType::FreeFlyer,
            rotation: IDENTITY,
            translation: [0.0; 3],
            idx_q: 0,
            idx_v: 0,
        });
        for (v, name) in ["vx", "vy", "vz", "wx", "wy", "wz"].iter().enumerate() {
            base_speeds.push(SpeedMap {
                name: format!("base_{name}"),
                v,
                sign: 1.0,
            });
        }
        for (q, name) in ["x", "y", "z", "qx", "qy", "qz", "qw"].iter().enumerate() {
            base_coordinates.push((
                CoordinateMap::Joint { q, sign: 1.0 },
                format!("base_{name}"),
            ));
        }
        armature.extend([0.0; 6]);
        (nq, nv) = (7, 6);
        attach.push((1, IDENTITY, [0.0; 3]));
        // A floating model keeps its own gravity direction (in the world), as its generated
        // code does; a fixed model made free falls along −z, as `kanegen_reference::FreeFlyer`.
        if model.is_floating() {
            gravity
        } else {
            [0.0, 0.0, -g]
        }
    } else {
        gravity
    };
    match &model.base {
        _ if free_flyer => {}
        Base::Fixed => attach.push((0, IDENTITY, [0.0; 3])),
        // `export` sends a floating model through the free-flyer path.
        Base::Floating => unreachable!("a floating base is exported with its free flyer"),
        Base::Wheeled(w) => {
            let dir = model.gravity.direction;
            if dir[0] != 0.0 || dir[1] != 0.0 {
                return Err(ExportError::GravityNotVertical {
                    model: model.name.clone(),
                    file: model.source.clone(),
                    direction: dir,
                });
            }
            joints.push(PinJoint {
                name: "base".into(),
                parent: 0,
                kind: PinJointType::Planar,
                rotation: IDENTITY,
                translation: [0.0; 3],
                idx_q: 0,
                idx_v: 0,
            });
            let (r, l) = (params[w.radius], params[w.track]);
            let (mw, yy, zz) = (
                params[w.wheel_mass],
                params[w.wheel_axle_inertia],
                params[w.wheel_diametral_inertia],
            );
            // YYw/R², 0 when YYw = 0 (wheels removed, R possibly 0), as the reference does.
            let yy_r2 = if yy == 0.0 { 0.0 } else { yy / (r * r) };
            armature.extend([2.0 * yy_r2, 0.0, yy_r2 * l * l / 2.0]);
            speeds[w.x_speed] = Some(SpeedMap {
                name: model.speeds[w.x_speed].name.clone(),
                v: 0,
                sign: 1.0,
            });
            speeds[w.psi_speed] = Some(SpeedMap {
                name: model.speeds[w.psi_speed].name.clone(),
                v: 2,
                sign: 1.0,
            });
            coordinates[w.x_speed] = Some(CoordinateMap::PlanarX { q: 0 });
            coordinates[w.psi_speed] = Some(CoordinateMap::PlanarPsi { q: 2 });
            // The two wheels as one body fixed in the heading frame: point masses mw at
            // (0, ±L/2, 0), each axisymmetric about y (YYw about the axle, ZZw about a diameter).
            // Only the moment about z matters; x and y are given their physical values.
            let lateral = 2.0 * mw * (l / 2.0) * (l / 2.0);
            if mw != 0.0 || yy != 0.0 || zz != 0.0 {
                bodies.push(PinBody {
                    name: "wheels".into(),
                    joint: 1,
                    rotation: IDENTITY,
                    translation: [0.0; 3],
                    mass: 2.0 * mw,
                    com: [0.0; 3],
                    inertia_com: [
                        [2.0 * zz + lateral, 0.0, 0.0],
                        [0.0, 2.0 * yy, 0.0],
                        [0.0, 0.0, 2.0 * zz + lateral],
                    ],
                });
            }
            nq = 4;
            nv = 3;
            attach.push((1, IDENTITY, [0.0; 3]));
        }
    }

    for (i, link) in model.links.iter().enumerate().skip(1) {
        let Some(mount) = &link.mount else {
            // Only link 0 has no mount (validated IR).
            attach.push((0, IDENTITY, [0.0; 3]));
            continue;
        };
        let j = &mount.joint;
        let (pj, prot, ptr) = attach[mount.parent];
        // The joint's placement in the frame of the Pinocchio joint its parent moves with.
        let local_t = j.translation.map(|s| s.eval(params));
        let rotation = mat_mul(&prot, &j.rotation);
        let t = mat_vec(&prot, &local_t);
        let translation = [ptr[0] + t[0], ptr[1] + t[1], ptr[2] + t[2]];
        match j.kind {
            JointKind::Fixed => attach.push((pj, rotation, translation)),
            JointKind::Revolute { speed } | JointKind::Prismatic { speed } => {
                let revolute = matches!(j.kind, JointKind::Revolute { .. });
                let (kind, sign) = match (cartesian(j.axis), revolute) {
                    (Some((a, s)), true) => (PinJointType::Revolute(a), s),
                    (Some((a, s)), false) => (PinJointType::Prismatic(a), s),
                    (None, true) => (PinJointType::RevoluteUnaligned(j.axis), 1.0),
                    (None, false) => (PinJointType::PrismaticUnaligned(j.axis), 1.0),
                };
                joints.push(PinJoint {
                    name: j.name.clone(),
                    parent: pj,
                    kind,
                    rotation,
                    translation,
                    idx_q: nq,
                    idx_v: nv,
                });
                speeds[speed] = Some(SpeedMap {
                    name: model.speeds[speed].name.clone(),
                    v: nv,
                    sign,
                });
                coordinates[speed] = Some(CoordinateMap::Joint { q: nq, sign });
                armature.push(0.0);
                nq += 1;
                nv += 1;
                attach.push((joints.len(), IDENTITY, [0.0; 3]));
            }
        }
        debug_assert_eq!(attach.len(), i + 1);
    }

    for (i, link) in model.links.iter().enumerate() {
        let Some(b) = &link.body else { continue };
        let m = params[b.mass];
        let ms = b.first_moment.map(|p| params[p]);
        let [xx, xy, xz, yy, yz, zz] = b.inertia.map(|p| params[p]);
        let com = if m == 0.0 {
            if ms != [0.0; 3] {
                return Err(ExportError::MasslessFirstMoment {
                    model: model.name.clone(),
                    file: model.source.clone(),
                    body: b.name.clone(),
                    first_moment: ms,
                });
            }
            [0.0; 3]
        } else {
            ms.map(|x| x / m)
        };
        // I_c = J − m(|c|²·1 − c cᵀ) (Huygens–Steiner back to the centre of mass).
        let c2 = com.iter().map(|x| x * x).sum::<f64>();
        let j = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]];
        let mut inertia_com = [[0.0; 3]; 3];
        for r in 0..3 {
            for c in 0..3 {
                let shift = m * (if r == c { c2 } else { 0.0 } - com[r] * com[c]);
                inertia_com[r][c] = j[r][c] - shift;
            }
        }
        let (joint, rotation, translation) = attach[i];
        bodies.push(PinBody {
            name: b.name.clone(),
            joint,
            rotation,
            translation,
            mass: m,
            com,
            inertia_com,
        });
    }

    let frames = model
        .links
        .iter()
        .zip(&attach)
        .map(|(link, &(joint, rotation, translation))| PinFrame {
            name: link.name.clone(),
            joint,
            rotation,
            translation,
        })
        .collect();
    Ok(PinocchioModel {
        frames,
        name: model.name.clone(),
        joints,
        bodies,
        armature,
        gravity,
        nq,
        nv,
        // Every speed is driven by exactly one joint or the base (validated IR).
        speeds: base_speeds
            .into_iter()
            .chain(speeds.into_iter().flatten())
            .collect(),
        coordinates: base_coordinates
            .iter()
            .map(|(c, _)| c.clone())
            .chain(coordinates.into_iter().flatten())
            .collect(),
        coordinate_names: base_coordinates
            .into_iter()
            .map(|(_, n)| n)
            .chain(
                // A floating model's own base speeds are the free flyer's, named above.
                model
                    .speeds
                    .iter()
                    .skip(if model.is_floating() { 6 } else { 0 })
                    .map(|s| s.coordinate.clone()),
            )
            .collect(),
    })
}

/// A name as one token of the text format: whitespace replaced by `_`, never empty.
fn token(name: &str) -> String {
    let t: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if t.is_empty() { "_".into() } else { t }
}

fn push_numbers(out: &mut String, xs: impl IntoIterator<Item = f64>) {
    for x in xs {
        let _ = write!(out, " {x:?}");
    }
}

impl PinocchioModel {
    /// The model in the text format of the module documentation (read by
    /// `benches/pinocchio/harness.cpp`).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "kanegen-pinocchio 1");
        let _ = writeln!(
            s,
            "model {} nq {} nv {} dof {}",
            token(&self.name),
            self.nq,
            self.nv,
            self.speeds.len()
        );
        s.push_str("gravity");
        push_numbers(&mut s, self.gravity);
        let _ = writeln!(s, "\njoints {}", self.joints.len());
        for j in &self.joints {
            let (tag, axis) = j.kind.tag_axis();
            let _ = write!(s, "joint {} {} {tag}", token(&j.name), j.parent);
            push_numbers(&mut s, axis);
            push_numbers(&mut s, j.rotation.into_iter().flatten());
            push_numbers(&mut s, j.translation);
            s.push('\n');
        }
        let _ = writeln!(s, "bodies {}", self.bodies.len());
        for b in &self.bodies {
            let _ = write!(s, "body {} {}", token(&b.name), b.joint);
            push_numbers(&mut s, b.rotation.into_iter().flatten());
            push_numbers(&mut s, b.translation);
            push_numbers(&mut s, [b.mass]);
            push_numbers(&mut s, b.com);
            push_numbers(&mut s, b.inertia_com.into_iter().flatten());
            s.push('\n');
        }
        s.push_str("armature");
        push_numbers(&mut s, self.armature.iter().copied());
        let _ = writeln!(s, "\nspeeds {}", self.speeds.len());
        for m in &self.speeds {
            let _ = writeln!(s, "speed {} {} {:?}", token(&m.name), m.v, m.sign);
        }
        let _ = writeln!(s, "coordinates {}", self.coordinates.len());
        for (c, name) in self.coordinates.iter().zip(&self.coordinate_names) {
            let (kind, q, sign) = match *c {
                CoordinateMap::Joint { q, sign } => ("joint", q, sign),
                CoordinateMap::PlanarX { q } => ("planar_x", q, 1.0),
                CoordinateMap::PlanarPsi { q } => ("planar_psi", q, 1.0),
            };
            let _ = writeln!(s, "coordinate {} {kind} {q} {sign:?}", token(name));
        }
        s.push_str("end\n");
        s
    }

    /// Pinocchio's configuration for the model's coordinates `q` (in the order of
    /// [`Model::speeds`]).
    pub fn configuration(&self, q: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.nq];
        for (c, &x) in self.coordinates.iter().zip(q) {
            match *c {
                CoordinateMap::Joint { q, sign } => out[q] = sign * x,
                CoordinateMap::PlanarX { q } => out[q] = x,
                CoordinateMap::PlanarPsi { q } => {
                    out[q] = x.cos();
                    out[q + 1] = x.sin();
                }
            }
        }
        out
    }

    /// Pinocchio's velocity (or acceleration) `S u` for the model's speeds `u`; entries no
    /// speed maps to (the planar base's lateral `v_y`) are zero.
    pub fn velocity(&self, u: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.nv];
        for (m, &x) in self.speeds.iter().zip(u) {
            out[m.v] = m.sign * x;
        }
        out
    }
}
