//! The reference recursion with a **free-flyer root**: the model's root link (frame 0) floats
//! in the world with six degrees of freedom, in the layout of Pinocchio's `JointModelFreeFlyer`,
//! written independently of the generator (the test oracle of generated floating-base code and of
//! the Pinocchio comparison).
//!
//! * coordinates `q = [x, y, z, qx, qy, qz, qw, joint coordinates]`: the base origin in the world
//!   and the unit quaternion base → world (normalized before use); `NQ = DOF + 1`;
//! * speeds `u = [v, ω, joint speeds]`: the base origin's linear velocity and the base's angular
//!   velocity, both in the base frame, then the joints' speeds in the order of
//!   [`kanegen_model::Model::speeds`]; `u̇` is the time derivative of `u` (so the base origin's
//!   classical acceleration in the base frame is `v̇ + ω × v`);
//! * gravity `−g ẑ` in the world, `g` the model's gravity parameter (the model's own gravity
//!   direction, relative to a fixed root, is not used).
//!
//! Kane's equations are evaluated as in [`crate::Reference`]: the base frame's motion is
//! `(ω₀, α₀, v₀, a₀) = (ω, ω̇, v, v̇ + ω × v)`, its partial velocities are the unit vectors of
//! the base frame (`(v₀)_r = e_r` for `r < 3`, `(ω₀)_r = e_{r−3}` for `3 ≤ r < 6`), and gravity
//! enters each body through `Rₖᵀ g` with `Rₖ` the body's rotation in the world. Generalized
//! forces `τ = M(q) u̇ + c(q, u) + g(q)` are conjugate to `u`: the first six are the force and
//! moment on the base in the base frame (Pinocchio's `rnea` of a free-flyer model).
//!
//! Kinematics follow the generated functions' conventions (docs/kinematics.md) with the world
//! in place of frame 0: poses in the world, Jacobian rows 0–2 the frame origin's linear velocity
//! and rows 3–5 its angular velocity in world axes (Pinocchio's `LOCAL_WORLD_ALIGNED`), bias
//! accelerations classical. Centroidal quantities (`crate::free_flyer_centroidal`) and the
//! tangent-space derivatives (`crate::free_flyer_derivatives`) are in their own files.

use std::fmt;

use kanegen_model::{Base, JointKind, Model};
use nalgebra::{DMatrix, DVector, Matrix3, RealField, Vector3, Vector6};

use crate::se3::quaternion_to_rotation;
use crate::{BodyData, FrameState, axis_rotation, cst, joint_placement};

/// Why a [`FreeFlyer`] could not be built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FreeFlyerError {
    /// The model has a two-wheeled base: its root is constrained to the floor (rolling without
    /// slipping), not free. Load the robot with a fixed (or floating) base instead.
    WheeledBase {
        /// The model's name.
        model: String,
    },
    /// `params` does not have one value per model parameter.
    ParamCount {
        /// The model's name.
        model: String,
        /// `model.params.len()`.
        expected: usize,
        /// Values given.
        given: usize,
    },
}

impl fmt::Display for FreeFlyerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::WheeledBase { model } => write!(
                f,
                "model `{model}` has a two-wheeled base, which is not a free flyer; load it with a fixed or floating base to evaluate it with a free-flyer root"
            ),
            Self::ParamCount {
                model,
                expected,
                given,
            } => write!(
                f,
                "model `{model}`: {given} parameter values given, the model has {expected}; pass one value per `Model::params` entry"
            ),
        }
    }
}

impl std::error::Error for FreeFlyerError {}

/// How a joint moves its child frame, with the index of its speed in the free-flyer `u`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Revolute(usize),
    Prismatic(usize),
    Fixed,
}

#[derive(Debug, Clone)]
struct Joint<T> {
    parent: usize,
    motion: Motion,
    axis: Vector3<T>,
    rotation0: Matrix3<T>,
    translation: Vector3<T>,
}

/// The partial velocities `((ω_k)_r, (v_k)_r)` of every frame, `[r][k]`, in frame `k`.
pub(crate) type Partials<T> = Vec<Vec<(Vector3<T>, Vector3<T>)>>;

/// Reference dynamics of a model whose root link is a free flyer (see the module docs).
///
/// ```
/// use kanegen_reference::FreeFlyer;
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/two-link.toml");
/// let model = kanegen_model::Model::from_toml_file(path).unwrap();
/// let ff = FreeFlyer::<f64>::new(&model).unwrap();
/// assert_eq!((ff.nq(), ff.dof()), (9, 8));
/// let q = ff.neutral();
/// let h = ff.nonlinear_effects(&q, &[0.0; 8]);
/// // At rest the base carries the weight: the force on the base is m g up (base axes = world).
/// assert!((h[2] - ff.total_mass() * 9.81).abs() < 1e-9);
/// ```
#[derive(Debug, Clone)]
pub struct FreeFlyer<T: RealField + Copy> {
    model: Model,
    dof: usize,
    joints: Vec<Option<Joint<T>>>,
    pub(crate) bodies: Vec<Option<BodyData<T>>>,
    /// `−g ẑ`, in the world.
    gravity: Vector3<T>,
    params: Vec<T>,
}

impl<T: RealField + Copy> FreeFlyer<T> {
    /// The model with a free-flyer root and its default parameter values.
    pub fn new(model: &Model) -> Result<Self, FreeFlyerError> {
        let params: Vec<T> = model.params.iter().map(|p| cst(p.value)).collect();
        Self::with_params(model, &params)
    }

    /// The model with a free-flyer root and parameter values `params` (indexed by
    /// [`kanegen_model::ParamId`]). A wheeled base is refused ([`FreeFlyerError::WheeledBase`]);
    /// any other base kind is replaced by the free flyer.
    pub fn with_params(model: &Model, params: &[T]) -> Result<Self, FreeFlyerError> {
        if matches!(model.base, Base::Wheeled(_)) {
            return Err(FreeFlyerError::WheeledBase {
                model: model.name.clone(),
            });
        }
        if params.len() != model.params.len() {
            return Err(FreeFlyerError::ParamCount {
                model: model.name.clone(),
                expected: model.params.len(),
                given: params.len(),
            });
        }
        // The joints' speeds, in the model's order, become u[6..].
        let mut driven: Vec<usize> = model
            .links
            .iter()
            .filter_map(|l| match l.mount.as_ref()?.joint.kind {
                JointKind::Revolute { speed } | JointKind::Prismatic { speed } => Some(speed),
                JointKind::Fixed => None,
            })
            .collect();
        driven.sort_unstable();
        driven.dedup();
        let slot = |speed: usize| 6 + driven.binary_search(&speed).unwrap_or(0);
        let p = |i: usize| params[i];
        let joints = model
            .links
            .iter()
            .map(|link| {
                let mount = link.mount.as_ref()?;
                let (axis, rotation0, translation) = joint_placement(&mount.joint, params);
                Some(Joint {
                    parent: mount.parent,
                    motion: match mount.joint.kind {
                        JointKind::Revolute { speed } => Motion::Revolute(slot(speed)),
                        JointKind::Prismatic { speed } => Motion::Prismatic(slot(speed)),
                        JointKind::Fixed => Motion::Fixed,
                    },
                    axis,
                    rotation0,
                    translation,
                })
            })
            .collect();
        let bodies = BodyData::per_link(model, params);
        let g = p(model.gravity.symbol);
        Ok(Self {
            model: model.clone(),
            dof: 6 + driven.len(),
            joints,
            bodies,
            gravity: Vector3::new(T::zero(), T::zero(), -g),
            params: params.to_vec(),
        })
    }

    /// The model this was built from.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The parameter values in use.
    pub fn params(&self) -> &[T] {
        &self.params
    }

    /// Number of speeds: 6 + the joints' speeds.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Number of coordinates, `dof + 1`.
    pub fn nq(&self) -> usize {
        self.dof + 1
    }

    /// Gravity in the world, `[0, 0, −g]`.
    pub fn gravity_vector(&self) -> Vector3<T> {
        self.gravity
    }

    /// The neutral configuration: base at the origin, identity orientation, joints at 0.
    pub fn neutral(&self) -> Vec<T> {
        let mut q = vec![T::zero(); self.nq()];
        q[6] = T::one();
        q
    }

    /// Total mass of the robot.
    pub fn total_mass(&self) -> T {
        self.bodies
            .iter()
            .flatten()
            .fold(T::zero(), |s, b| s + b.mass)
    }

    fn check(&self, q: &[T], u: &[T], ud: &[T]) {
        assert_eq!(q.len(), self.nq(), "`q` has {} entries, not NQ", q.len());
        assert_eq!(u.len(), self.dof, "`u` has {} entries, not DOF", u.len());
        assert_eq!(ud.len(), self.dof, "`ud` has {} entries, not DOF", ud.len());
    }

    /// The base's rotation (base → world) and position.
    pub fn base_pose(&self, q: &[T]) -> (Matrix3<T>, Vector3<T>) {
        (
            quaternion_to_rotation([q[3], q[4], q[5], q[6]]),
            Vector3::new(q[0], q[1], q[2]),
        )
    }

    /// `iAj(q)`, `iPj(q)` of link `k`'s joint.
    fn joint_transform(&self, j: &Joint<T>, q: &[T]) -> (Matrix3<T>, Vector3<T>) {
        match j.motion {
            // Coordinate of speed slot s is q[s + 1].
            Motion::Revolute(s) => (
                j.rotation0 * axis_rotation(&j.axis, q[s + 1]),
                j.translation,
            ),
            Motion::Prismatic(s) => (j.rotation0, j.translation + j.rotation0 * j.axis * q[s + 1]),
            Motion::Fixed => (j.rotation0, j.translation),
        }
    }

    /// Every frame's pose in the world (`rotation`, `position`) and its velocities and
    /// accelerations relative to the world, expressed in the frame itself (as
    /// [`crate::Reference::frame_states`], with the base's motion given by `u`, `u̇`).
    ///
    /// # Panics
    /// If `q` does not have [`FreeFlyer::nq`] entries or `u`, `ud` [`FreeFlyer::dof`].
    pub fn frame_states(&self, q: &[T], u: &[T], ud: &[T]) -> Vec<FrameState<T>> {
        self.check(q, u, ud);
        let (r0, p0) = self.base_pose(q);
        let v = Vector3::new(u[0], u[1], u[2]);
        let w = Vector3::new(u[3], u[4], u[5]);
        let base = FrameState {
            rotation: r0,
            position: p0,
            omega: w,
            alpha: Vector3::new(ud[3], ud[4], ud[5]),
            velocity: v,
            acceleration: Vector3::new(ud[0], ud[1], ud[2]) + w.cross(&v),
        };
        let mut states: Vec<FrameState<T>> = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let Some(j) = joint else {
                states.push(base);
                continue;
            };
            let parent = states[j.parent];
            let (a, p) = self.joint_transform(j, q);
            let at = a.transpose();
            let e = j.axis;
            let w_parent = at * parent.omega;
            let mut omega = w_parent;
            let mut alpha = at * parent.alpha;
            let mut velocity = at * (parent.velocity + parent.omega.cross(&p));
            let mut acceleration = at
                * (parent.acceleration
                    + parent.alpha.cross(&p)
                    + parent.omega.cross(&parent.omega.cross(&p)));
            match j.motion {
                Motion::Revolute(s) => {
                    omega += e * u[s];
                    alpha += e * ud[s] + w_parent.cross(&e) * u[s];
                }
                Motion::Prismatic(s) => {
                    velocity += e * u[s];
                    acceleration += e * ud[s] + w_parent.cross(&e) * (cst::<T>(2.0) * u[s]);
                }
                Motion::Fixed => {}
            }
            states.push(FrameState {
                rotation: parent.rotation * a,
                position: parent.position + parent.rotation * p,
                omega,
                alpha,
                velocity,
                acceleration,
            });
        }
        states
    }

    /// The partial velocities of every frame with respect to every speed.
    pub(crate) fn partials(&self, q: &[T]) -> Partials<T> {
        let tf: Vec<(Matrix3<T>, Vector3<T>)> = self
            .joints
            .iter()
            .map(|j| match j {
                Some(j) => self.joint_transform(j, q),
                None => (Matrix3::identity(), Vector3::zeros()),
            })
            .collect();
        (0..self.dof)
            .map(|r| {
                let mut out: Vec<(Vector3<T>, Vector3<T>)> = Vec::with_capacity(tf.len());
                for (k, joint) in self.joints.iter().enumerate() {
                    let Some(j) = joint else {
                        let mut wv = (Vector3::zeros(), Vector3::zeros());
                        if r < 3 {
                            wv.1[r] = T::one();
                        } else if r < 6 {
                            wv.0[r - 3] = T::one();
                        }
                        out.push(wv);
                        continue;
                    };
                    let (wi, vi) = out[j.parent];
                    let at = tf[k].0.transpose();
                    let mut w = at * wi;
                    let mut v = at * (vi + wi.cross(&tf[k].1));
                    match j.motion {
                        Motion::Revolute(s) if s == r => w += j.axis,
                        Motion::Prismatic(s) if s == r => v += j.axis,
                        _ => {}
                    }
                    out.push((w, v));
                }
                out
            })
            .collect()
    }

    /// Per body, the inertia force and moment about the frame origin (frame axes) of the
    /// motion `states`, with gravity subtracted when `with_gravity`.
    pub(crate) fn loads(
        &self,
        states: &[FrameState<T>],
        with_gravity: bool,
    ) -> Vec<Option<(Vector3<T>, Vector3<T>)>> {
        self.bodies
            .iter()
            .zip(states)
            .map(|(b, s)| {
                b.as_ref().map(|b| {
                    let ms = b.first_moment;
                    let (w, al, a) = (s.omega, s.alpha, s.acceleration);
                    let force = a * b.mass + al.cross(&ms) + w.cross(&w.cross(&ms));
                    let moment = b.inertia * al + w.cross(&(b.inertia * w)) + ms.cross(&a);
                    if with_gravity {
                        let gk = s.rotation.transpose() * self.gravity;
                        (force - gk * b.mass, moment - ms.cross(&gk))
                    } else {
                        (force, moment)
                    }
                })
            })
            .collect()
    }

    fn kane(&self, partials: &Partials<T>, q: &[T], u: &[T], ud: &[T]) -> DVector<T> {
        let loads = self.loads(&self.frame_states(q, u, ud), true);
        DVector::from_fn(self.dof, |r, _| {
            let mut sum = T::zero();
            for (load, (wr, vr)) in loads.iter().zip(&partials[r]) {
                if let Some((f, n)) = load {
                    sum += f.dot(vr) + n.dot(wr);
                }
            }
            sum
        })
    }

    /// Generalized forces `τ = M(q) u̇ + c(q, u) + g(q)` (the base's six first: force and
    /// moment on the base, base axes).
    ///
    /// # Panics
    /// If a slice has the wrong length.
    pub fn inverse_dynamics(&self, q: &[T], u: &[T], ud: &[T]) -> DVector<T> {
        self.check(q, u, ud);
        self.kane(&self.partials(q), q, u, ud)
    }

    /// The mass matrix, by columns `M[:, i] = τ(q, 0, e_i) − τ(q, 0, 0)`.
    pub fn mass_matrix(&self, q: &[T]) -> DMatrix<T> {
        let zero = vec![T::zero(); self.dof];
        self.check(q, &zero, &zero);
        let partials = self.partials(q);
        let g = self.kane(&partials, q, &zero, &zero);
        let mut m = DMatrix::zeros(self.dof, self.dof);
        let mut e = zero.clone();
        for i in 0..self.dof {
            e[i] = T::one();
            m.set_column(i, &(self.kane(&partials, q, &zero, &e) - &g));
            e[i] = T::zero();
        }
        m
    }

    /// `c(q, u) = τ(q, u, 0) − τ(q, 0, 0)`.
    pub fn coriolis(&self, q: &[T], u: &[T]) -> DVector<T> {
        let zero = vec![T::zero(); self.dof];
        self.check(q, u, &zero);
        let partials = self.partials(q);
        self.kane(&partials, q, u, &zero) - self.kane(&partials, q, &zero, &zero)
    }

    /// `g(q) = τ(q, 0, 0)`.
    pub fn gravity(&self, q: &[T]) -> DVector<T> {
        let zero = vec![T::zero(); self.dof];
        self.inverse_dynamics(q, &zero, &zero)
    }

    /// `h(q, u) = c + g = τ(q, u, 0)` (Pinocchio's `nonLinearEffects`).
    pub fn nonlinear_effects(&self, q: &[T], u: &[T]) -> DVector<T> {
        let zero = vec![T::zero(); self.dof];
        self.inverse_dynamics(q, u, &zero)
    }

    /// Kinetic energy `Σ ½(ωᵀJω + m vᵀv + 2 MS·(v × ω))`.
    pub fn kinetic_energy(&self, q: &[T], u: &[T]) -> T {
        let zero = vec![T::zero(); self.dof];
        let states = self.frame_states(q, u, &zero);
        let (half, two) = (cst::<T>(0.5), cst::<T>(2.0));
        let mut e = T::zero();
        for (b, s) in self.bodies.iter().zip(&states) {
            let Some(b) = b else { continue };
            let (w, v) = (s.omega, s.velocity);
            e += half
                * (w.dot(&(b.inertia * w))
                    + b.mass * v.dot(&v)
                    + two * b.first_moment.dot(&v.cross(&w)));
        }
        e
    }

    /// Potential energy `V = −Σ g·(m pₖ + Rₖ MSₖ)` in the world (zero at height 0).
    pub fn potential_energy(&self, q: &[T]) -> T {
        let zero = vec![T::zero(); self.dof];
        let states = self.frame_states(q, &zero, &zero);
        let mut e = T::zero();
        for (b, s) in self.bodies.iter().zip(&states) {
            let Some(b) = b else { continue };
            e -= self
                .gravity
                .dot(&(s.position * b.mass + s.rotation * b.first_moment));
        }
        e
    }

    /// Centre of mass in the world.
    pub fn center_of_mass(&self, q: &[T]) -> Vector3<T> {
        let zero = vec![T::zero(); self.dof];
        let states = self.frame_states(q, &zero, &zero);
        let mut ms = Vector3::zeros();
        for (b, s) in self.bodies.iter().zip(&states) {
            let Some(b) = b else { continue };
            ms += s.position * b.mass + s.rotation * b.first_moment;
        }
        ms / self.total_mass()
    }

    /// Pose of frame `frame` (an index into `model.links`) in the world: `(rotation, position)`.
    ///
    /// # Panics
    /// If `frame` is out of range or `q` has the wrong length.
    pub fn frame_pose(&self, q: &[T], frame: usize) -> (Matrix3<T>, Vector3<T>) {
        let zero = vec![T::zero(); self.dof];
        let s = self.frame_states(q, &zero, &zero)[frame];
        (s.rotation, s.position)
    }

    /// Jacobian of frame `frame` (6 × DOF): rows 0–2 the velocity of its origin, rows 3–5 its
    /// angular velocity, world axes; column `r` is Kane's partial velocity of speed `r`.
    pub fn frame_jacobian(&self, q: &[T], frame: usize) -> DMatrix<T> {
        let zero = vec![T::zero(); self.dof];
        let r = self.frame_states(q, &zero, &zero)[frame].rotation;
        let partials = self.partials(q);
        let mut j = DMatrix::zeros(6, self.dof);
        for (c, p) in partials.iter().enumerate() {
            let (w, v) = p[frame];
            j.fixed_view_mut::<3, 1>(0, c).copy_from(&(r * v));
            j.fixed_view_mut::<3, 1>(3, c).copy_from(&(r * w));
        }
        j
    }

    /// Classical acceleration of frame `frame` at `u̇ = 0` (`d/dt(J u) = J u̇ + bias`): rows
    /// 0–2 its origin's, rows 3–5 its angular acceleration, world axes.
    pub fn frame_bias_acceleration(&self, q: &[T], u: &[T], frame: usize) -> Vector6<T> {
        let zero = vec![T::zero(); self.dof];
        let s = self.frame_states(q, u, &zero)[frame];
        let (a, al) = (s.rotation * s.acceleration, s.rotation * s.alpha);
        Vector6::new(a.x, a.y, a.z, al.x, al.y, al.z)
    }
}
