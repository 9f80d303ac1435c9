//! Optimized numeric recursive rigid-body dynamics for kanegen robot models.
//!
//! [`Rbd`] evaluates, for any loaded [`Model`], the terms of `τ = M(q) u̇ + c(q, u) + g(q)` with the
//! standard recursive algorithms, written for speed: it is the honest "optimized numeric" baseline
//! the generated code is benchmarked against.
//!
//! * [`Rbd::mass_matrix`]: the composite-rigid-body algorithm (CRBA);
//! * [`Rbd::inverse_dynamics`]: the recursive Newton–Euler algorithm (RNEA), `τ(q, u, u̇)`;
//! * [`Rbd::coriolis`]: RNEA with `u̇ = 0` and no gravity, `c(q, u)`;
//! * [`Rbd::gravity`]: a gravity-only pass `g(q)` using composite masses and first moments;
//! * [`Rbd::kinetic_energy`]: `½ uᵀ M u` from the link velocities;
//! * [`Rbd::frame_pose`], [`Rbd::frame_jacobian`], [`Rbd::frame_bias_acceleration`]: one frame's
//!   kinematics ([`RbdFrame`]), a pass down its path only;
//! * [`Rbd::center_of_mass`], [`Rbd::com_jacobian`]: the whole robot's centre of mass and its
//!   Jacobian, one forward and one backward pass (subtree first moments).
//!
//! # Formulation
//!
//! Classical 3-vectors expressed in each link frame, as in the fixed-wheels report (Zafar 2014) (eqs. 3–6): angular velocity
//! `ω`, angular acceleration `α`, linear acceleration `a` of the frame origin; bodies carry
//! Khalil's standard parameters (mass `m`, first moment `h = m·S`, inertia `J` about the frame
//! origin). Joint `j` moves by `iAj(q) = iAj(0)·Rot(e_j, q_j)` (revolute) or adds `iAj(0) e_j q_j`
//! to the translation (prismatic); gravity is folded in as a base acceleration `a0 − g0`.
//!
//! # What is precomputed ([`Rbd::new`])
//!
//! * **Fixed joints are merged**: a rigidly attached frame's body is moved into its moving
//!   ancestor, and its children's joint transforms are composed with the fixed transform.
//! * **Every joint axis becomes `+z`**: each moving frame `j` is replaced by a constant rotation of
//!   it, `C_j`, whose third axis is `e_j` (a signed permutation when `e_j` is `±x`, `±y` or `±z`,
//!   see [`Axis`]); body parameters are re-expressed in that frame and the constant rotations are
//!   folded into `A'_j = C_iᵀ·iAj(0)·C_j`. Every joint rotation is then `A'_j Rot_z(q_j)`, a
//!   joint's motion subspace is the unit `z` of its own frame, `τ_j` is a single component
//!   (`n_z` or `f_z`) and `ω_j = … + u_j ẑ` costs one addition, with no branch on the axis in the
//!   hot loops. The change of frame is exact for axis-aligned axes (it only permutes and negates
//!   numbers), and `M`, `c`, `g`, `τ` do not depend on the choice of link frames.
//! * **Constant rotations as signed permutations**: when `A'_j` is one (all of Krang), row `i`
//!   of `Rot_z(q)` lands, times a sign, in a fixed row of `R = A' Rot_z(q)`; the six possible
//!   row assignments are compile-time constants (a per-link kind selects one), so
//!   `R x`, `Rᵀ x`, `W R` and `R J Rᵀ` cost 5 multiplications and 2 additions per vector (and
//!   `A' (Rot_z J Rot_zᵀ) A'ᵀ` for inertias) with no data-dependent indexing. Other rotations
//!   fall back to 3×3 products. `R` is never formed.
//! * Flat fixed-size per-link arrays: parent index, speed index, joint kind, `A'`, translation,
//!   mass, first moment, inertia, subtree (composite) mass and `m_c·p'`, and for the CRBA each
//!   link's list of ancestors with the flat indices of the entries of `M` they fill.
//!
//! # Hot paths
//!
//! No allocation, no dynamic dispatch, `[T; N]` stack arrays. The sines and cosines of all joint
//! angles are computed first, in one independent batch (for `f64` the branch-free polynomial
//! kernel of generated code, [`kanegen_runtime::trig::sin_cos_n`], that the compiler vectorizes;
//! within one ulp of the standard library; [`sin_cos_f64`] is its scalar form). Along a
//! chain (`parent = j − 1`) the parent's state is passed in registers rather than through memory.
//! The CRBA accumulates composite inertias in the link frames, takes each `F_j = I_j^c S_j` to
//! frame 0 once and fills column `j` of `M` with 6-term dot products `S_k · F_j` against the
//! precomputed ancestor list (each entry computed once and mirrored). The gravity pass rotates
//! only the gravity vector down the tree and accumulates composite first moments back up (subtree
//! masses are constants).
//!
//! # Wheeled base
//!
//! For [`kanegen_model::Base::Wheeled`] frame 0 is the heading frame with quasi-velocities `ẋ`, `ψ̇`:
//! `ω0 = [0, 0, ψ̇]`, `v0 = [ẋ, 0, 0]`, `α0 = [0, 0, ψ̈]`, `a0 = [ẍ, ẋψ̇, 0]`. The generalized force of
//! `ẋ` is `x̂0 ·` (total force on the tree) and that of `ψ̇` is `ẑ0 ·` (total moment about the origin
//! of frame 0); the wheels add `(2 mw + 2 YYw/R²)` to `M[ẋ,ẋ]` and
//! `(mw L²/2 + YYw L²/(2R²) + 2 ZZw)` to `M[ψ̇,ψ̇]` (inertia only).
//!
//! ```no_run
//! use kanegen_model::Model;
//! use kanegen_rbd::Rbd;
//! use nalgebra::SVector;
//!
//! let model = Model::from_toml_file("models/krang.toml").unwrap();
//! let rbd = Rbd::<19>::new(&model, &model.param_values()).unwrap();
//! let q = SVector::<f64, 19>::zeros();
//! let m = rbd.mass_matrix(&q);
//! let tau = rbd.inverse_dynamics(&q, &q, &q);
//! assert_eq!(m.nrows(), tau.len());
//! ```
#![forbid(unsafe_code)]

mod algorithms;
mod build;
mod com;
#[cfg(feature = "dual")]
mod dual;
mod frames;
mod rot;
mod scalar;

use std::fmt;

use kanegen_model::Model;

#[cfg(feature = "dual")]
pub use dual::DualDerivatives;
pub use frames::RbdFrame;
use scalar::{M3, S3, V3};
pub use scalar::{Scalar, sin_cos_f64};

/// `parent` value of a link attached to the base frame.
const ROOT: usize = usize::MAX;

/// Why an [`Rbd`] could not be built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RbdError {
    /// The const generic `N` is not the model's number of generalized speeds.
    DofMismatch {
        /// The model's name.
        model: String,
        /// `model.dof()`.
        model_dof: usize,
        /// The `N` requested.
        requested: usize,
    },
    /// `params` does not have one value per model parameter.
    ParamCount {
        /// `model.params.len()`.
        expected: usize,
        /// `params.len()`.
        given: usize,
    },
    /// The frame tree is malformed (a hand-built [`Model`] that skipped validation).
    BadTree {
        /// The offending link.
        link: String,
        /// What is wrong.
        detail: String,
    },
    /// The speeds are not driven exactly once each.
    BadSpeeds {
        /// What is wrong.
        detail: String,
    },
}

impl fmt::Display for RbdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DofMismatch {
                model,
                model_dof,
                requested,
            } => write!(
                f,
                "model `{model}` has {model_dof} generalized speeds but Rbd::<{requested}> was requested; use Rbd::<{model_dof}>"
            ),
            Self::ParamCount { expected, given } => write!(
                f,
                "expected {expected} parameter values (one per model parameter, indexed by ParamId), got {given}"
            ),
            Self::BadTree { link, detail } => write!(f, "link `{link}`: {detail}"),
            Self::BadSpeeds { detail } => write!(f, "speeds: {detail}"),
        }
    }
}

impl std::error::Error for RbdError {}

/// How a joint axis `e_j` (in the child frame) is aligned; decides the constant change of frame
/// `C_j` (third column `e_j`) that makes the joint a rotation about `+z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// `+x`: `C = [ŷ, ẑ, x̂]`.
    PosX,
    /// `−x`: `C = [ẑ, ŷ, −x̂]`.
    NegX,
    /// `+y`: `C = [ẑ, x̂, ŷ]`.
    PosY,
    /// `−y`: `C = [x̂, ẑ, −ŷ]`.
    NegY,
    /// `+z`: `C = 1`.
    PosZ,
    /// `−z`: `C = [ŷ, x̂, −ẑ]`.
    NegZ,
    /// Not axis-aligned: `C` is an orthonormal frame completing `e_j`.
    General,
}

/// Everything parameter-dependent about one moving link, in its `+z`-axis frame.
#[derive(Debug, Clone, Copy)]
struct LinkData<T> {
    /// Index of the parent moving link, or [`ROOT`].
    parent: usize,
    /// The parent is the previous link (`parent == j − 1`): its state is still in registers.
    chain: bool,
    /// Index of the joint's speed in `u`.
    speed: usize,
    /// Prismatic (else revolute).
    prismatic: bool,
    /// `A'`: constant rotation child → parent, by columns.
    a: M3<T>,
    /// How `A'` acts: a compile-time signed permutation or a general rotation.
    kind: rot::RotKind,
    /// Signs `g_i` of the signed permutation (see [`rot`]); 1 for a general rotation.
    g: [T; 3],
    /// Signs `g_{I[a]} g_{I[b]}` of the entries of `R J Rᵀ`.
    sym_sign: [T; 6],
    /// Constant translation `p'` (parent frame).
    p: V3<T>,
    /// `p' ≠ 0` or prismatic.
    offset: bool,
    /// Mass.
    m: T,
    /// First moment `m·S`.
    h: V3<T>,
    /// Inertia about the origin.
    j: S3<T>,
    /// Mass of the subtree rooted here.
    mc: T,
    /// `mc · p'`.
    mc_p: V3<T>,
    /// `mc/2 · p'`.
    half_mc_p: V3<T>,
}

/// The wheel terms and base speeds of a wheeled base.
#[derive(Debug, Clone, Copy)]
struct Wheels<T> {
    x: usize,
    psi: usize,
    /// `2 mw + 2 YYw/R²`.
    m_xx: T,
    /// `mw L²/2 + YYw L²/(2R²) + 2 ZZw`.
    m_psipsi: T,
    /// `2 mw`: both wheels' mass (point masses on the axle, for the centre of mass).
    mass: T,
}

/// The base frame: the bodies rigidly attached to it, gravity and the wheels.
#[derive(Debug, Clone, Copy)]
struct RootData<T> {
    m: T,
    h: V3<T>,
    j: S3<T>,
    /// Total mass of the tree (base bodies included).
    mc: T,
    /// `−g0` in frame 0 (gravity folded in as a base acceleration).
    grav: V3<T>,
    wheels: Option<Wheels<T>>,
}

/// Optimized recursive dynamics of a [`Model`] with `N` generalized speeds, in scalar `T`.
///
/// Build once per parameter vector with [`Rbd::new`]; every evaluation is then allocation-free.
/// `q`, `u`, `u̇` and all results are in `model.speeds` order; the coordinate of joint `j` is
/// `q[joint.speed()]` (the wheeled base's `x`, `ψ` do not enter).
#[derive(Debug, Clone)]
pub struct Rbd<const N: usize, T = f64> {
    /// Number of moving links.
    nl: usize,
    links: [LinkData<T>; N],
    root: RootData<T>,
    axes: [Axis; N],
    /// For moving link `j`, the off-diagonal entries of column `j` of `M` that the CRBA fills
    /// from `F_j`: one per ancestor (and, for a wheeled base, per base speed).
    anc: [[AncEntry; N]; N],
    /// Number of valid entries in each `anc[j]`.
    anc_len: [usize; N],
}

/// One off-diagonal CRBA entry `M[k, j] = M[j, k] = S_k · F_j`.
#[derive(Debug, Clone, Copy, Default)]
struct AncEntry {
    /// Index of `S_k` in the world motion-subspace array (a link, or `nl`/`nl + 1` for the
    /// wheeled base's `ẋ`/`ψ̇`).
    k: usize,
    /// Flat (column-major) index of `M[k, j]`.
    upper: usize,
    /// Flat index of `M[j, k]`.
    lower: usize,
}

impl<const N: usize, T: Scalar> Rbd<N, T> {
    /// Precomputes everything parameter-dependent. `params` holds one value per model parameter,
    /// indexed by [`kanegen_model::ParamId`] (e.g. `model.param_values()`).
    ///
    /// Fails if `N != model.dof()`, if `params` has the wrong length, or if the model's tree or
    /// speeds are malformed.
    pub fn new(model: &Model, params: &[T]) -> Result<Self, RbdError> {
        build::build(model, params)
    }

    /// [`Rbd::new`] with the model's default parameter values.
    pub fn with_default_params(model: &Model) -> Result<Self, RbdError> {
        let p: Vec<T> = model
            .param_values()
            .into_iter()
            .map(nalgebra::convert)
            .collect();
        Self::new(model, &p)
    }

    /// Number of generalized speeds (`N`).
    pub fn dof(&self) -> usize {
        N
    }

    /// Number of moving links after merging fixed joints.
    pub fn moving_links(&self) -> usize {
        self.nl
    }

    /// The classified axis of each moving link, in link order (the model's, fixed links removed).
    pub fn axes(&self) -> &[Axis] {
        &self.axes[..self.nl]
    }

    /// Does the model have a wheeled base?
    pub fn is_wheeled(&self) -> bool {
        self.root.wheels.is_some()
    }
}
