//! Numeric reference of the rigid-body dynamics of a [`kanegen_model::Model`]: the test oracle
//! of the generated code and the "naive recursion" benchmark baseline.
//!
//! It is written from the fixed-wheels report (Zafar 2014) (frames, eqs. 3–6) and Kane's equations, independently of any
//! symbolic code, and deliberately *naively*: for every generalized speed `r` the partial
//! velocities `(v_k)_r`, `(ω_k)_r` of every frame are computed by their own forward recursion,
//! and the generalized inertia and gravity forces are summed body by body,
//!
//! ```text
//! τ_r = Σ_k [ F_k·(v_k)_r + N_k·(ω_k)_r ] − Σ_k [ m_k g_k·(v_k)_r + (MS_k × g_k)·(ω_k)_r ]
//! F_k = m a_k + α_k × MS + ω_k × (ω_k × MS)
//! N_k = J α_k + ω_k × (J ω_k) + MS × a_k
//! ```
//!
//! (all vectors of frame `k` in frame `k`; `J` about the frame origin; Khalil's standard
//! parameters `m`, `MS = m·S`, `XX … ZZ`). This is `O(n·dof)` and has none of the backward
//! force accumulation of the recursive Newton–Euler algorithm used by the generator.
//!
//! The equation form is `τ = M(q) u̇ + c(q, u) + g(q)`; [`Reference::mass_matrix`],
//! [`Reference::coriolis`] and [`Reference::gravity`] are obtained from
//! [`Reference::inverse_dynamics`] by `M[:, i] = τ(q, 0, e_i) − τ(q, 0, 0)`, `g = τ(q, 0, 0)`,
//! `c = τ(q, u, 0) − g`.
//!
//! For the two-wheeled base (DynamicModeling.tex) the base frame moves with
//! `ω0 = [0, 0, ψ̇]`, `v0 = [ẋ, 0, 0]`, `α0 = [0, 0, ψ̈]`, `a0 = [ẍ, ẋψ̇, 0]` (the centripetal
//! term `ẋψ̇`; the MATLAB behind the efficient-computation report (Zafar 2015) wrongly used `ψ̇`), and the axisymmetric wheels add
//! `(2 mw + 2 YYw/R²) ẍ` to the `ẋ` row and `(mw L²/2 + YYw L²/(2R²) + 2 ZZw) ψ̈` to the `ψ̇` row.
//!
//! [`FreeFlyer`] evaluates the same recursion with the root link floating in the world (a
//! free-flyer base in Pinocchio's layout; [`se3`] its configuration space), with centroidal
//! momentum and tangent-space derivatives.
//!
//! The scalar type is generic (`f64`, `f32`, or any [`RealField`] + [`Copy`]).
//!
//! ```
//! use kanegen_reference::Reference;
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/two-link.toml");
//! let model = kanegen_model::Model::from_toml_file(path).unwrap();
//! let r = Reference::<f64>::new(&model);
//! let m = r.mass_matrix(&[0.1, -0.2]);
//! assert!((m[(0, 1)] - m[(1, 0)]).abs() < 1e-12);
//! ```
#![forbid(unsafe_code)]

use kanegen_model::{Base, JointKind, Model};
use nalgebra::{DMatrix, DVector, Matrix3, RealField, Vector3};

mod free_flyer;
mod free_flyer_centroidal;
mod free_flyer_derivatives;
pub mod random;
pub mod se3;

pub use free_flyer::{FreeFlyer, FreeFlyerError};

/// Converts an `f64` constant of the model to the scalar type.
fn cst<T: RealField + Copy>(x: f64) -> T {
    nalgebra::convert(x)
}

/// The joint of a non-root frame, with its constant data converted to `T`.
#[derive(Debug, Clone)]
struct JointData<T> {
    parent: usize,
    kind: JointKind,
    /// `e_j`, in the child frame.
    axis: Vector3<T>,
    /// `iAj(0)`.
    rotation0: Matrix3<T>,
    /// Constant part of `iPj`.
    translation: Vector3<T>,
}

/// A joint's constant placement with the parameter values `params`: its axis `e_j` (child
/// frame), `iAj(0)` and the constant part of `iPj` (the fixed/wheeled and the free-flyer
/// recursions' joints share it).
fn joint_placement<T: RealField + Copy>(
    j: &kanegen_model::Joint,
    params: &[T],
) -> (Vector3<T>, Matrix3<T>, Vector3<T>) {
    let translation = Vector3::from_fn(|r, _| {
        let s = j.translation[r];
        match s.symbol {
            Some(id) => cst::<T>(s.coef) * params[id],
            None => cst(s.coef),
        }
    });
    (
        Vector3::from_fn(|r, _| cst(j.axis[r])),
        Matrix3::from_fn(|r, c| cst(j.rotation[r][c])),
        translation,
    )
}

/// Khalil's standard inertial parameters of one body, converted to `T`.
#[derive(Debug, Clone)]
struct BodyData<T> {
    mass: T,
    /// `MS = m·S`.
    first_moment: Vector3<T>,
    /// Inertia about the frame origin.
    inertia: Matrix3<T>,
}

impl<T: RealField + Copy> BodyData<T> {
    /// Every link's body (`None` for a link without one) with the parameter values `params`,
    /// indexed by [`kanegen_model::ParamId`].
    fn per_link(model: &Model, params: &[T]) -> Vec<Option<Self>> {
        let p = |i: usize| params[i];
        model
            .links
            .iter()
            .map(|link| {
                link.body.as_ref().map(|b| {
                    let [xx, xy, xz, yy, yz, zz] = b.inertia.map(p);
                    BodyData {
                        mass: p(b.mass),
                        first_moment: Vector3::from_fn(|r, _| p(b.first_moment[r])),
                        inertia: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
                    }
                })
            })
            .collect()
    }
}

/// The wheeled base's speed indices and the wheels' inertia on those rows.
#[derive(Debug, Clone)]
struct WheelData<T> {
    x_speed: usize,
    psi_speed: usize,
    /// `2 mw + 2 YYw/R²`, added to `M[ẋ, ẋ]`.
    x_inertia: T,
    /// `mw L²/2 + YYw L²/(2R²) + 2 ZZw`, added to `M[ψ̇, ψ̇]`.
    psi_inertia: T,
}

/// Position, orientation, velocities and accelerations of one frame.
///
/// `rotation` and `position` are relative to the base frame (frame 0) and expressed in it; the
/// velocities and accelerations are absolute (relative to the ground) and expressed in the frame
/// itself, as in the fixed-wheels report (Zafar 2014) eqs. 3–6.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameState<T: RealField + Copy> {
    /// `0A_k`: the frame's unit vectors (columns) in frame 0.
    pub rotation: Matrix3<T>,
    /// `0P_k`: the frame origin in frame 0.
    pub position: Vector3<T>,
    /// Angular velocity `ω_k`.
    pub omega: Vector3<T>,
    /// Angular acceleration `α_k`.
    pub alpha: Vector3<T>,
    /// Linear velocity `v_k` of the frame origin.
    pub velocity: Vector3<T>,
    /// Linear acceleration `a_k` of the frame origin.
    pub acceleration: Vector3<T>,
}

/// The joint transform `iAj(q)`, `iPj(q)` of one frame.
#[derive(Debug, Clone, Copy)]
struct Transform<T: RealField + Copy> {
    rotation: Matrix3<T>,
    translation: Vector3<T>,
}

/// The numeric reference dynamics of one model with fixed parameter values.
///
/// Construct it with [`Reference::new`] (the model's default parameters) or
/// [`Reference::with_params`]; all methods take `q`, `u`, `u̇` in the order of
/// [`Model::speeds`] (coordinate `i` is the one whose rate is speed `i`; for the wheeled base
/// the coordinates `x`, `ψ` are accepted and ignored) and panic if a slice does not have
/// [`Reference::dof`] entries.
#[derive(Debug, Clone)]
pub struct Reference<T: RealField + Copy> {
    dof: usize,
    /// Per link; `None` for the base frame (link 0).
    joints: Vec<Option<JointData<T>>>,
    /// Per link.
    bodies: Vec<Option<BodyData<T>>>,
    wheels: Option<WheelData<T>>,
    /// Gravity vector `g · direction` in frame 0.
    gravity: Vector3<T>,
    params: Vec<T>,
}

impl<T: RealField + Copy> Reference<T> {
    /// The reference dynamics with the model's default parameter values.
    pub fn new(model: &Model) -> Self {
        let params: Vec<T> = model.params.iter().map(|p| cst(p.value)).collect();
        Self::with_params(model, &params)
    }

    /// The reference dynamics with parameter values `params`, indexed by
    /// [`kanegen_model::ParamId`].
    ///
    /// # Panics
    /// If `params.len()` differs from the number of model parameters.
    pub fn with_params(model: &Model, params: &[T]) -> Self {
        assert_eq!(
            params.len(),
            model.params.len(),
            "{} parameter values given, model `{}` has {}",
            params.len(),
            model.name,
            model.params.len()
        );
        let p = |i: usize| params[i];
        let joints = model
            .links
            .iter()
            .map(|link| {
                let mount = link.mount.as_ref()?;
                let (axis, rotation0, translation) = joint_placement(&mount.joint, params);
                Some(JointData {
                    parent: mount.parent,
                    kind: mount.joint.kind,
                    axis,
                    rotation0,
                    translation,
                })
            })
            .collect();
        let bodies = BodyData::per_link(model, params);
        let wheels = match &model.base {
            // A floating base's six speeds drive no joint of this recursion: it holds the base
            // frame still (the free-flyer recursion is a separate entry point).
            Base::Fixed | Base::Floating => None,
            Base::Wheeled(w) => {
                let (r, l) = (p(w.radius), p(w.track));
                let (mw, yy, zz) = (
                    p(w.wheel_mass),
                    p(w.wheel_axle_inertia),
                    p(w.wheel_diametral_inertia),
                );
                let two: T = cst(2.0);
                // YYw/R², taken as 0 when YYw = 0 so that wheels can be removed entirely
                // (R = 0 included) without producing 0/0.
                let yy_over_r2 = if yy == T::zero() { yy } else { yy / (r * r) };
                Some(WheelData {
                    x_speed: w.x_speed,
                    psi_speed: w.psi_speed,
                    x_inertia: two * mw + two * yy_over_r2,
                    psi_inertia: mw * l * l / two + yy_over_r2 * l * l / two + two * zz,
                })
            }
        };
        let g = p(model.gravity.symbol);
        let gravity = Vector3::from_fn(|r, _| g * cst(model.gravity.direction[r]));
        Self {
            dof: model.dof(),
            joints,
            bodies,
            wheels,
            gravity,
            params: params.to_vec(),
        }
    }

    /// Number of generalized speeds (length of `q`, `u`, `u̇` and `τ`).
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The parameter values in use, indexed by [`kanegen_model::ParamId`].
    pub fn params(&self) -> &[T] {
        &self.params
    }

    /// The gravity vector `g · direction` in frame 0.
    pub fn gravity_vector(&self) -> Vector3<T> {
        self.gravity
    }

    fn check_len(&self, what: &str, x: &[T]) {
        assert_eq!(
            x.len(),
            self.dof,
            "`{what}` has {} entries, the model has {} speeds",
            x.len(),
            self.dof
        );
    }

    /// `iAj(q)` and `iPj(q)` for every link (identity/zero for the base frame).
    fn transforms(&self, q: &[T]) -> Vec<Transform<T>> {
        self.joints
            .iter()
            .map(|j| match j {
                None => Transform {
                    rotation: Matrix3::identity(),
                    translation: Vector3::zeros(),
                },
                Some(j) => match j.kind {
                    JointKind::Revolute { speed } => Transform {
                        rotation: j.rotation0 * axis_rotation(&j.axis, q[speed]),
                        translation: j.translation,
                    },
                    JointKind::Prismatic { speed } => Transform {
                        rotation: j.rotation0,
                        translation: j.translation + j.rotation0 * j.axis * q[speed],
                    },
                    JointKind::Fixed => Transform {
                        rotation: j.rotation0,
                        translation: j.translation,
                    },
                },
            })
            .collect()
    }

    /// Velocity and acceleration of the base frame (frame 0), in frame 0:
    /// `(ω0, α0, v0, a0)`.
    fn base_motion(&self, u: &[T], ud: &[T]) -> [Vector3<T>; 4] {
        let z = T::zero();
        match &self.wheels {
            None => [Vector3::zeros(); 4],
            Some(w) => {
                let (xd, psid) = (u[w.x_speed], u[w.psi_speed]);
                let (xdd, psidd) = (ud[w.x_speed], ud[w.psi_speed]);
                [
                    Vector3::new(z, z, psid),
                    Vector3::new(z, z, psidd),
                    Vector3::new(xd, z, z),
                    // The centripetal term ẋψ̇ along y0 (not ψ̇ as in the efficient-computation report (Zafar 2015)).
                    Vector3::new(xdd, xd * psid, z),
                ]
            }
        }
    }

    /// Positions, velocities and accelerations of every frame (indexed like
    /// [`Model::links`]), by the fixed-wheels report (Zafar 2014) eqs. 3–6.
    ///
    /// # Panics
    /// If a slice does not have [`Reference::dof`] entries.
    pub fn frame_states(&self, q: &[T], u: &[T], ud: &[T]) -> Vec<FrameState<T>> {
        self.check_len("q", q);
        self.check_len("u", u);
        self.check_len("ud", ud);
        let tf = self.transforms(q);
        let [omega, alpha, velocity, acceleration] = self.base_motion(u, ud);
        let mut states: Vec<FrameState<T>> = Vec::with_capacity(self.joints.len());
        for (k, joint) in self.joints.iter().enumerate() {
            let Some(j) = joint else {
                states.push(FrameState {
                    rotation: Matrix3::identity(),
                    position: Vector3::zeros(),
                    omega,
                    alpha,
                    velocity,
                    acceleration,
                });
                continue;
            };
            let parent = states[j.parent];
            let Transform {
                rotation: a,
                translation: p,
            } = tf[k];
            let at = a.transpose(); // jAi
            let e = j.axis;
            // The parent's angular velocity, in frame j.
            let w_parent = at * parent.omega;
            let mut omega = w_parent;
            let mut alpha = at * parent.alpha;
            let mut velocity = at * (parent.velocity + parent.omega.cross(&p));
            let mut acceleration = at
                * (parent.acceleration
                    + parent.alpha.cross(&p)
                    + parent.omega.cross(&parent.omega.cross(&p)));
            match j.kind {
                JointKind::Revolute { speed } => {
                    let (uj, udj) = (u[speed], ud[speed]);
                    // Eqs. 3 and 4.
                    omega += e * uj;
                    alpha += e * udj + w_parent.cross(&e) * uj;
                }
                JointKind::Prismatic { speed } => {
                    let (uj, udj) = (u[speed], ud[speed]);
                    // The child origin slides along e_j at rate u_j relative to the parent:
                    // relative velocity u e, relative acceleration u̇ e, Coriolis 2 ω × (u e).
                    let two: T = cst(2.0);
                    velocity += e * uj;
                    acceleration += e * udj + w_parent.cross(&e) * (two * uj);
                }
                JointKind::Fixed => {}
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

    /// Partial velocities `((ω_k)_r, (v_k)_r)` of every frame origin with respect to speed `r`:
    /// the velocity recursion run with `u = e_r`.
    fn partial_velocities(&self, tf: &[Transform<T>], r: usize) -> Vec<(Vector3<T>, Vector3<T>)> {
        let mut out: Vec<(Vector3<T>, Vector3<T>)> = Vec::with_capacity(self.joints.len());
        for (k, joint) in self.joints.iter().enumerate() {
            let Some(j) = joint else {
                let (mut w, mut v) = (Vector3::zeros(), Vector3::zeros());
                if let Some(wh) = &self.wheels {
                    if r == wh.x_speed {
                        v = Vector3::x();
                    }
                    if r == wh.psi_speed {
                        w = Vector3::z();
                    }
                }
                out.push((w, v));
                continue;
            };
            let (wi, vi) = out[j.parent];
            let at = tf[k].rotation.transpose();
            let mut w = at * wi;
            let mut v = at * (vi + wi.cross(&tf[k].translation));
            match j.kind {
                JointKind::Revolute { speed } if speed == r => w += j.axis,
                JointKind::Prismatic { speed } if speed == r => v += j.axis,
                _ => {}
            }
            out.push((w, v));
        }
        out
    }

    /// The partial velocities of every frame with respect to every speed, `[r][k]`.
    fn partial_velocity_table(&self, q: &[T]) -> Vec<Vec<(Vector3<T>, Vector3<T>)>> {
        let tf = self.transforms(q);
        (0..self.dof)
            .map(|r| self.partial_velocities(&tf, r))
            .collect()
    }

    /// Kane's `τ_r = Σ_k [F_k·(v_k)_r + N_k·(ω_k)_r] − (generalized gravity force)_r` plus the
    /// wheel terms, for the motion `(q, u, u̇)` and the partial velocities of `q`.
    fn kane(
        &self,
        partials: &[Vec<(Vector3<T>, Vector3<T>)>],
        q: &[T],
        u: &[T],
        ud: &[T],
    ) -> DVector<T> {
        let states = self.frame_states(q, u, ud);
        // Per body: the resultant of inertia forces minus gravity, reduced to the frame origin.
        let loads: Vec<Option<(Vector3<T>, Vector3<T>)>> = self
            .bodies
            .iter()
            .zip(&states)
            .map(|(b, s)| {
                b.as_ref().map(|b| {
                    let ms = b.first_moment;
                    let (w, al, a) = (s.omega, s.alpha, s.acceleration);
                    let force = a * b.mass + al.cross(&ms) + w.cross(&w.cross(&ms));
                    let moment = b.inertia * al + w.cross(&(b.inertia * w)) + ms.cross(&a);
                    // Gravity in frame k; its force m g_k acts at the centre of mass.
                    let gk = s.rotation.transpose() * self.gravity;
                    (force - gk * b.mass, moment - ms.cross(&gk))
                })
            })
            .collect();
        let mut tau = DVector::from_fn(self.dof, |r, _| {
            let mut sum = T::zero();
            for (load, (wr, vr)) in loads.iter().zip(&partials[r]) {
                if let Some((f, n)) = load {
                    sum += f.dot(vr) + n.dot(wr);
                }
            }
            sum
        });
        if let Some(w) = &self.wheels {
            tau[w.x_speed] += w.x_inertia * ud[w.x_speed];
            tau[w.psi_speed] += w.psi_inertia * ud[w.psi_speed];
        }
        tau
    }

    /// Generalized forces `τ = M(q) u̇ + c(q, u) + g(q)` needed for the motion `(q, u, u̇)`
    /// (Kane's equations, evaluated naively; see the crate documentation).
    ///
    /// # Panics
    /// If a slice does not have [`Reference::dof`] entries.
    pub fn inverse_dynamics(&self, q: &[T], u: &[T], ud: &[T]) -> DVector<T> {
        self.check_len("q", q);
        let partials = self.partial_velocity_table(q);
        self.kane(&partials, q, u, ud)
    }

    /// The mass matrix, by columns `M[:, i] = τ(q, 0, e_i) − τ(q, 0, 0)` (the partial
    /// velocities, which depend on `q` only, are computed once).
    ///
    /// # Panics
    /// If `q` does not have [`Reference::dof`] entries.
    pub fn mass_matrix(&self, q: &[T]) -> DMatrix<T> {
        self.check_len("q", q);
        let partials = self.partial_velocity_table(q);
        let zero = vec![T::zero(); self.dof];
        let g = self.kane(&partials, q, &zero, &zero);
        let mut m = DMatrix::zeros(self.dof, self.dof);
        let mut e = zero.clone();
        for i in 0..self.dof {
            e[i] = T::one();
            let col = self.kane(&partials, q, &zero, &e) - &g;
            m.set_column(i, &col);
            e[i] = T::zero();
        }
        m
    }

    /// The velocity-product terms `c(q, u) = τ(q, u, 0) − τ(q, 0, 0)`.
    ///
    /// # Panics
    /// If a slice does not have [`Reference::dof`] entries.
    pub fn coriolis(&self, q: &[T], u: &[T]) -> DVector<T> {
        self.check_len("q", q);
        let partials = self.partial_velocity_table(q);
        let zero = vec![T::zero(); self.dof];
        self.kane(&partials, q, u, &zero) - self.kane(&partials, q, &zero, &zero)
    }

    /// The gravity terms `g(q) = τ(q, 0, 0)` (the gradient of the potential energy for the
    /// holonomic coordinates, zero on the wheeled base's rows).
    ///
    /// # Panics
    /// If `q` does not have [`Reference::dof`] entries.
    pub fn gravity(&self, q: &[T]) -> DVector<T> {
        let zero = vec![T::zero(); self.dof];
        self.inverse_dynamics(q, &zero, &zero)
    }

    /// Kinetic energy `Σ ½(ωᵀJω + m vᵀv + 2 MS·(v × ω))` plus the wheels'
    /// `½(2mw + 2YYw/R²)ẋ² + ½(mw L²/2 + YYw L²/(2R²) + 2ZZw)ψ̇²`.
    ///
    /// # Panics
    /// If a slice does not have [`Reference::dof`] entries.
    pub fn kinetic_energy(&self, q: &[T], u: &[T]) -> T {
        let zero = vec![T::zero(); self.dof];
        let states = self.frame_states(q, u, &zero);
        let half: T = cst(0.5);
        let two: T = cst(2.0);
        let mut e = T::zero();
        for (b, s) in self.bodies.iter().zip(&states) {
            let Some(b) = b else { continue };
            let (w, v) = (s.omega, s.velocity);
            e += half
                * (w.dot(&(b.inertia * w))
                    + b.mass * v.dot(&v)
                    + two * b.first_moment.dot(&v.cross(&w)));
        }
        if let Some(wh) = &self.wheels {
            let (xd, psid) = (u[wh.x_speed], u[wh.psi_speed]);
            e += half * (wh.x_inertia * xd * xd + wh.psi_inertia * psid * psid);
        }
        e
    }

    /// Potential energy `V = −Σ g0·(m ⁰P_k + ⁰A_k MS_k)`, relative to frame 0 (which, for the
    /// wheeled base, moves horizontally only).
    ///
    /// # Panics
    /// If `q` does not have [`Reference::dof`] entries.
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
}

/// `Rot(e, θ)` for a unit axis `e` (Rodrigues: `1 + sin θ [e]× + (1 − cos θ) [e]×²`).
fn axis_rotation<T: RealField + Copy>(e: &Vector3<T>, theta: T) -> Matrix3<T> {
    let k = e.cross_matrix();
    Matrix3::identity() + k * theta.sin() + k * k * (T::one() - theta.cos())
}
