//! The function registry: one typed list of the functions a generated module can have.
//!
//! Every stage reads this list instead of keeping its own: [`kane`](crate::kane) derives the
//! functions of a [`FunctionSet`] (one derivation step per [`FunctionId`]),
//! [`lower`](crate::lower) turns each into a straight-line program, [`emit`](crate::emit)
//! writes the free function, the wrapper method and the `kanegen-runtime` trait implementations
//! from its [`FunctionSpec`], and `kanegen stats` prints one row per entry.
//!
//! Adding a function: add a variant to [`FunctionId`], its entry to [`FUNCTIONS`] (name, doc,
//! inputs, result shape, whether it is in the default set), and its derivation step in
//! `kane/mod.rs` (`Ctx::derive_function`). Emission, the wrapper method, `stats`, the CLI's
//! `--functions` and `Builder::functions` follow from the entry.

use std::fmt;

/// Identifies one function of the registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FunctionId {
    /// Mass matrix M(q).
    MassMatrix,
    /// Coriolis and centrifugal vector c(q, u).
    Coriolis,
    /// Gravity vector g(q).
    Gravity,
    /// Inverse dynamics τ = M u̇ + c + g.
    InverseDynamics,
    /// Coriolis matrix C(q, u).
    CoriolisMatrix,
    /// Centre of mass of the whole robot in frame 0.
    CenterOfMass,
    /// Jacobian of the centre of mass (its partial velocities).
    ComJacobian,
    /// Acceleration of the centre of mass at `u̇ = 0`.
    ComBiasAcceleration,
    /// Kinetic energy T(q, u).
    KineticEnergy,
    /// Potential energy V(q).
    PotentialEnergy,
    /// Pose of a body frame relative to frame 0.
    FramePose,
    /// Jacobian of a body frame (linear velocity of its origin, angular velocity).
    FrameJacobian,
    /// Acceleration of a body frame at `u̇ = 0`.
    FrameBiasAcceleration,
    /// Derivatives of inverse dynamics `[∂τ/∂q | ∂τ/∂u]` (∂τ/∂u̇ = M).
    InverseDynamicsDerivatives,
    /// Inverse-dynamics regressor Y(q, u, u̇) with τ = Y π (π: the inertial parameters).
    InverseDynamicsRegressor,
    /// Gravity regressor Y_g(q) with g = Y_g β (β: mass and first moments per body).
    GravityRegressor,
    /// Base regressor: the identifiable columns of Y, τ = Y_b π_b.
    BaseRegressor,
    /// Base gravity regressor: the identifiable columns of Y_g, g = Y_gb β_b.
    BaseGravityRegressor,
    /// Nonlinear effects `h(q, u) = c(q, u) + g(q)` in one pass (inverse dynamics at `u̇ = 0`).
    NonlinearEffects,
    /// Centroidal momentum matrix `A_G(q)`: linear momentum, then angular momentum about the
    /// centre of mass, in world axes, as `A_G u`.
    CentroidalMomentumMatrix,
    /// Centroidal momentum bias `Ȧ_G u`: the momentum's rate at `u̇ = 0` without gravity.
    CentroidalMomentumBias,
    /// Centroidal composite inertia `I_G = [[m 1, 0], [0, J_G]]` (world axes).
    CentroidalInertia,
}

/// One dimension of a [`Shape::Dense`] result: the number of speeds N, or a constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// The model's number of speeds.
    N,
    /// A fixed size (3 for a point, 6 for a twist).
    Fixed(usize),
    /// Twice the number of speeds: two N-column blocks side by side (`[∂τ/∂q | ∂τ/∂u]`).
    TwoN,
    /// The number P of inertial parameters π (`INERTIAL_NAMES`).
    Inertial,
    /// The number of gravity parameters β (4 per body: m, MX, MY, MZ).
    Beta,
    /// The number B of base parameters (`BASE_PARAMETER_NAMES`).
    Base,
    /// The number of base gravity parameters (`BASE_BETA_NAMES`).
    BaseBeta,
}

/// The sizes a [`Dim`] can name for one model: the speeds and the regressors' parameter counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sizes {
    /// Number of speeds N.
    pub dof: usize,
    /// Number of inertial parameters P.
    pub inertial: usize,
    /// Number of gravity parameters (4 per body).
    pub beta: usize,
    /// Number of base parameters B (0 unless derived).
    pub base: usize,
    /// Number of base gravity parameters (0 unless derived).
    pub base_beta: usize,
}

impl Sizes {
    /// Sizes of a model with `n` speeds and no regressor parameters.
    pub fn dof(n: usize) -> Self {
        Sizes {
            dof: n,
            ..Sizes::default()
        }
    }
}

impl Sizes {
    /// The number of columns of function `id`'s result (1 for a vector or scalar).
    pub fn size_of(&self, id: FunctionId) -> usize {
        id.spec().shape.size_in(self).1
    }
}

impl Dim {
    /// The size for a model with `n` speeds (the regressors' parameter counts are 0 here: use
    /// [`Dim::size_in`] for them).
    pub fn size(self, n: usize) -> usize {
        self.size_in(&Sizes::dof(n))
    }

    /// The size for a model of sizes `s`.
    pub fn size_in(self, s: &Sizes) -> usize {
        match self {
            Dim::N => s.dof,
            Dim::Fixed(k) => k,
            Dim::TwoN => 2 * s.dof,
            Dim::Inertial => s.inertial,
            Dim::Beta => s.beta,
            Dim::Base => s.base,
            Dim::BaseBeta => s.base_beta,
        }
    }
}

/// Shape of a generated function's result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Symmetric N×N matrix; entries are the upper triangle `(row ≤ col)`.
    SymmetricMatrix,
    /// N-vector; entries are `(row, 0)`.
    Vector,
    /// General (non-symmetric) N×N matrix; entries are `(row, col)`, absent entries are zero.
    Matrix,
    /// A `rows × cols` matrix (`SMatrix`; `SVector` when `cols` is 1); entries are
    /// `(row, col)`, absent entries are zero.
    Dense {
        /// Number of rows.
        rows: Dim,
        /// Number of columns.
        cols: Dim,
    },
    /// A scalar; its one entry is `(0, 0)`.
    Scalar,
    /// A rigid transform (`Isometry3`): entries `(r, c)` of the rotation for `c < 3` and the
    /// translation as `(r, 3)`; its dense value is the row-major 3×4 matrix `[R | p]`.
    Isometry,
}

/// Which state inputs a function takes (besides the parameters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inputs {
    /// `f(q)`.
    Q,
    /// `f(q, u)`.
    QU,
    /// `f(q, u, u̇)`.
    QUUd,
}

impl Shape {
    /// `(rows, cols)` of a result of this shape with `n` speeds (a vector is one column; the
    /// regressors' parameter dimensions count 0 here, see [`Shape::size_in`]).
    pub fn size(self, n: usize) -> (usize, usize) {
        self.size_in(&Sizes::dof(n))
    }

    /// `(rows, cols)` of a result of this shape for a model of sizes `s`.
    pub fn size_in(self, s: &Sizes) -> (usize, usize) {
        let n = s.dof;
        match self {
            Shape::SymmetricMatrix | Shape::Matrix => (n, n),
            Shape::Vector => (n, 1),
            Shape::Dense { rows, cols } => (rows.size_in(s), cols.size_in(s)),
            Shape::Scalar => (1, 1),
            Shape::Isometry => (3, 4),
        }
    }

    /// The dense value of a result of this shape with `n` speeds from its entries: its
    /// row-major `rows × cols` matrix (both triangles of a symmetric one; an `n`-vector, a
    /// 3-vector or a scalar for one column).
    pub fn dense(
        self,
        n: usize,
        entries: impl IntoIterator<Item = (usize, usize, f64)>,
    ) -> Vec<f64> {
        self.dense_in(&Sizes::dof(n), entries)
    }

    /// [`Shape::dense`] for a model of sizes `s` (regressors).
    pub fn dense_in(
        self,
        s: &Sizes,
        entries: impl IntoIterator<Item = (usize, usize, f64)>,
    ) -> Vec<f64> {
        let (rows, cols) = self.size_in(s);
        let mut out = vec![0.0; rows * cols];
        for (r, c, v) in entries {
            out[r * cols + c] = v;
            if self == Shape::SymmetricMatrix {
                out[c * cols + r] = v;
            }
        }
        out
    }
}

impl Inputs {
    /// Whether the function reads the speeds `u`.
    pub fn needs_u(self) -> bool {
        !matches!(self, Inputs::Q)
    }

    /// Whether the function reads the accelerations `u̇`.
    pub fn needs_ud(self) -> bool {
        matches!(self, Inputs::QUUd)
    }
}

/// The `kanegen-runtime` trait a function belongs to: generated robots implement a trait when
/// their module has all of its functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RuntimeTrait {
    /// `kanegen_runtime::RobotDynamics` (M, c, g, τ).
    RobotDynamics,
    /// `kanegen_runtime::CoriolisMatrix` (C; requires `RobotDynamics`).
    CoriolisMatrix,
    /// `kanegen_runtime::InverseDynamicsDerivatives` (∂τ/∂q, ∂τ/∂u as two square blocks;
    /// requires `RobotDynamics`).
    InverseDynamicsDerivatives,
}

impl RuntimeTrait {
    /// The traits in implementation order (a trait's supertraits first).
    pub const ALL: [RuntimeTrait; 3] = [
        RuntimeTrait::RobotDynamics,
        RuntimeTrait::CoriolisMatrix,
        RuntimeTrait::InverseDynamicsDerivatives,
    ];

    /// The trait's name in `kanegen_runtime`.
    pub fn name(self) -> &'static str {
        match self {
            RuntimeTrait::RobotDynamics => "RobotDynamics",
            RuntimeTrait::CoriolisMatrix => "CoriolisMatrix",
            RuntimeTrait::InverseDynamicsDerivatives => "InverseDynamicsDerivatives",
        }
    }
}

/// Everything the stages need to know about one function.
#[derive(Clone, Copy, Debug)]
pub struct FunctionSpec {
    /// Which function.
    pub id: FunctionId,
    /// The Rust name of the free function and the wrapper method (`mass_matrix`).
    pub name: &'static str,
    /// The symbol of its result in listings (`M`, `c`, `τ`).
    pub symbol: &'static str,
    /// One-line documentation of the generated function.
    pub doc: &'static str,
    /// State inputs.
    pub inputs: Inputs,
    /// Result shape.
    pub shape: Shape,
    /// Whether [`FunctionSet::default`] includes it.
    pub default: bool,
    /// The runtime trait it implements, if any.
    pub runtime_trait: Option<RuntimeTrait>,
    /// Whether it takes a body frame (`frame: Frame`): one straight-line program per frame of
    /// the model and a dispatcher.
    pub per_frame: bool,
}

/// The registry, in the order generated modules define the functions.
pub const FUNCTIONS: [FunctionSpec; 22] = [
    FunctionSpec {
        id: FunctionId::MassMatrix,
        name: "mass_matrix",
        symbol: "M",
        doc: "Mass matrix M(q) (symmetric positive definite).",
        inputs: Inputs::Q,
        shape: Shape::SymmetricMatrix,
        default: true,
        runtime_trait: Some(RuntimeTrait::RobotDynamics),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::Coriolis,
        name: "coriolis",
        symbol: "c",
        doc: "Coriolis and centrifugal vector c(q, u) (velocity-product terms).",
        inputs: Inputs::QU,
        shape: Shape::Vector,
        default: true,
        runtime_trait: Some(RuntimeTrait::RobotDynamics),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::Gravity,
        name: "gravity",
        symbol: "g",
        doc: "Gravity vector g(q).",
        inputs: Inputs::Q,
        shape: Shape::Vector,
        default: true,
        runtime_trait: Some(RuntimeTrait::RobotDynamics),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::InverseDynamics,
        name: "inverse_dynamics",
        symbol: "tau",
        doc: "Inverse dynamics τ = M(q) u̇ + c(q, u) + g(q), in one pass.",
        inputs: Inputs::QUUd,
        shape: Shape::Vector,
        default: true,
        runtime_trait: Some(RuntimeTrait::RobotDynamics),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::CoriolisMatrix,
        name: "coriolis_matrix",
        symbol: "C",
        doc: "Coriolis matrix C(q, u): c(q, u) = C(q, u) u, and Ṁ − 2C is skew-symmetric.",
        inputs: Inputs::QU,
        shape: Shape::Matrix,
        default: true,
        runtime_trait: Some(RuntimeTrait::CoriolisMatrix),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::CenterOfMass,
        name: "center_of_mass",
        symbol: "rG",
        doc: "Centre of mass of the whole robot (wheels included) in frame 0 (for a wheeled base: the heading frame at the axle midpoint).",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::Fixed(3),
            cols: Dim::Fixed(1),
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::ComJacobian,
        name: "com_jacobian",
        symbol: "JG",
        doc: "Jacobian of the centre of mass: its velocity relative to the ground, in frame 0's axes, is `J u`.",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::Fixed(3),
            cols: Dim::N,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::ComBiasAcceleration,
        name: "com_bias_acceleration",
        symbol: "aG0",
        doc: "Acceleration of the centre of mass at `u̇ = 0` (relative to the ground, in frame 0's axes): the acceleration is `J u̇ + bias`.",
        inputs: Inputs::QU,
        shape: Shape::Dense {
            rows: Dim::Fixed(3),
            cols: Dim::Fixed(1),
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::KineticEnergy,
        name: "kinetic_energy",
        symbol: "T",
        doc: "Kinetic energy `T = ½ uᵀ M(q) u` (wheels included).",
        inputs: Inputs::QU,
        shape: Shape::Scalar,
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::PotentialEnergy,
        name: "potential_energy",
        symbol: "V",
        doc: "Potential energy of gravity, zero with the centre of mass at the height of frame 0's origin: `∂V/∂q = g(q)`.",
        inputs: Inputs::Q,
        shape: Shape::Scalar,
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::FramePose,
        name: "frame_pose",
        symbol: "T0",
        doc: "Pose of a body frame relative to frame 0 (for a wheeled base: the heading frame at the axle midpoint; x and ψ do not enter).",
        inputs: Inputs::Q,
        shape: Shape::Isometry,
        default: false,
        runtime_trait: None,
        per_frame: true,
    },
    FunctionSpec {
        id: FunctionId::FrameJacobian,
        name: "frame_jacobian",
        symbol: "J",
        doc: "Jacobian of a body frame: rows 0–2 the velocity of its origin, rows 3–5 its angular velocity, relative to the ground, in frame 0's axes, as `J u`.",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::Fixed(6),
            cols: Dim::N,
        },
        default: false,
        runtime_trait: None,
        per_frame: true,
    },
    FunctionSpec {
        id: FunctionId::FrameBiasAcceleration,
        name: "frame_bias_acceleration",
        symbol: "a0",
        doc: "Classical acceleration of a body frame's origin (rows 0–2) and its angular acceleration (rows 3–5) at `u̇ = 0`, relative to the ground, in frame 0's axes: the acceleration is `J u̇ + bias`.",
        inputs: Inputs::QU,
        shape: Shape::Dense {
            rows: Dim::Fixed(6),
            cols: Dim::Fixed(1),
        },
        default: false,
        runtime_trait: None,
        per_frame: true,
    },
    FunctionSpec {
        id: FunctionId::InverseDynamicsDerivatives,
        name: "inverse_dynamics_derivatives",
        symbol: "dtau",
        doc: "Derivatives of inverse dynamics τ(q, u, u̇) = M u̇ + c + g: columns `0..N` are ∂τ/∂q (column j: ∂τ/∂q_j), columns `N..2N` are ∂τ/∂u (∂τ/∂u̇ is M). Exact (symbolic), structural zeros omitted.",
        inputs: Inputs::QUUd,
        shape: Shape::Dense {
            rows: Dim::N,
            cols: Dim::TwoN,
        },
        default: false,
        runtime_trait: Some(RuntimeTrait::InverseDynamicsDerivatives),
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::InverseDynamicsRegressor,
        name: "inverse_dynamics_regressor",
        symbol: "Y",
        doc: "Inverse-dynamics regressor Y(q, u, u̇): τ = Y π with π the inertial parameters in the order of `INERTIAL_NAMES` (`Params::inertial_vector`); exact derivatives ∂τ/∂π, independent of π.",
        inputs: Inputs::QUUd,
        shape: Shape::Dense {
            rows: Dim::N,
            cols: Dim::Inertial,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::GravityRegressor,
        name: "gravity_regressor",
        symbol: "Yg",
        doc: "Gravity regressor Y_g(q): g = Y_g β with β the masses and first moments (m, MX, MY, MZ per body, in the body frames) in the order of `BETA_NAMES` (`Params::beta_vector`).",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::N,
            cols: Dim::Beta,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::BaseRegressor,
        name: "base_regressor",
        symbol: "Yb",
        doc: "Base regressor Y_b(q, u, u̇): the identifiable columns of the inverse-dynamics regressor, τ = Y_b π_b with π_b = `base_parameters(&Params)` in the order of `BASE_PARAMETER_NAMES` (full column rank on generic trajectories).",
        inputs: Inputs::QUUd,
        shape: Shape::Dense {
            rows: Dim::N,
            cols: Dim::Base,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::BaseGravityRegressor,
        name: "base_gravity_regressor",
        symbol: "Ygb",
        doc: "Base gravity regressor: the identifiable columns of the gravity regressor, g = Y_gb β_b with β_b = `base_beta(&Params)` in the order of `BASE_BETA_NAMES`.",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::N,
            cols: Dim::BaseBeta,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::NonlinearEffects,
        name: "nonlinear_effects",
        symbol: "h",
        doc: "Nonlinear effects h(q, u) = c(q, u) + g(q) in one pass (inverse dynamics at `u̇ = 0`; Pinocchio's `nonLinearEffects`): `τ = M u̇ + h`.",
        inputs: Inputs::QU,
        shape: Shape::Vector,
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::CentroidalMomentumMatrix,
        name: "centroidal_momentum_matrix",
        symbol: "AG",
        doc: "Centroidal momentum matrix A_G(q) (Pinocchio's `ccrba` Ag): `A_G u` is the whole robot's linear momentum (rows 0–2) and its angular momentum about the centre of mass (rows 3–5), in world axes (frame 0's for a fixed or wheeled base).",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::Fixed(6),
            cols: Dim::N,
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::CentroidalMomentumBias,
        name: "centroidal_momentum_bias",
        symbol: "dAGu",
        doc: "Centroidal momentum bias `Ȧ_G u`: the rate of the centroidal momentum at `u̇ = 0` without gravity (world axes), so that its rate is `A_G u̇ + Ȧ_G u`.",
        inputs: Inputs::QU,
        shape: Shape::Dense {
            rows: Dim::Fixed(6),
            cols: Dim::Fixed(1),
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
    FunctionSpec {
        id: FunctionId::CentroidalInertia,
        name: "centroidal_inertia",
        symbol: "IG",
        doc: "Centroidal composite inertia `I_G = [[m 1, 0], [0, J_G]]` (Pinocchio's `ccrba` Ig): the total mass and the whole robot's inertia about its centre of mass, in world axes.",
        inputs: Inputs::Q,
        shape: Shape::Dense {
            rows: Dim::Fixed(6),
            cols: Dim::Fixed(6),
        },
        default: false,
        runtime_trait: None,
        per_frame: false,
    },
];

impl FunctionId {
    /// Every function, in registry order (the order of [`FUNCTIONS`]).
    pub fn all() -> impl Iterator<Item = FunctionId> {
        FUNCTIONS.iter().map(|s| s.id)
    }

    /// The registry entry.
    pub fn spec(self) -> &'static FunctionSpec {
        &FUNCTIONS[self as usize]
    }

    /// The Rust name (`mass_matrix`).
    pub fn name(self) -> &'static str {
        self.spec().name
    }

    /// The function whose Rust name is `name`.
    pub fn from_name(name: &str) -> Option<FunctionId> {
        FunctionId::all().find(|f| f.name() == name)
    }
}

impl fmt::Display for FunctionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of registry functions: which functions a generated module gets.
///
/// ```
/// use kanegen::{FunctionId, FunctionSet};
/// let set = FunctionSet::default().without(FunctionId::CoriolisMatrix);
/// assert!(set.contains(FunctionId::MassMatrix) && !set.contains(FunctionId::CoriolisMatrix));
/// assert_eq!("mass_matrix,gravity".parse::<FunctionSet>().unwrap().len(), 2);
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct FunctionSet(u32);

impl FunctionSet {
    /// No function.
    pub const EMPTY: FunctionSet = FunctionSet(0);

    /// Every registry function.
    pub fn all() -> Self {
        FunctionId::all().collect()
    }

    /// This set and `f`.
    #[must_use]
    pub fn with(self, f: FunctionId) -> Self {
        FunctionSet(self.0 | 1 << f as u32)
    }

    /// This set without `f`.
    #[must_use]
    pub fn without(self, f: FunctionId) -> Self {
        FunctionSet(self.0 & !(1 << f as u32))
    }

    /// Whether `f` is in the set.
    pub fn contains(self, f: FunctionId) -> bool {
        self.0 & (1 << f as u32) != 0
    }

    /// The functions of the set, in registry order.
    pub fn iter(self) -> impl Iterator<Item = FunctionId> {
        FunctionId::all().filter(move |&f| self.contains(f))
    }

    /// Number of functions.
    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

impl Default for FunctionSet {
    /// The functions whose registry entry says `default`: the dynamics (M, c, g, τ, C); the
    /// kinematics and energies are opt-in.
    fn default() -> Self {
        FUNCTIONS
            .iter()
            .filter(|s| s.default)
            .map(|s| s.id)
            .collect()
    }
}

impl FromIterator<FunctionId> for FunctionSet {
    fn from_iter<I: IntoIterator<Item = FunctionId>>(iter: I) -> Self {
        iter.into_iter().fold(FunctionSet::EMPTY, FunctionSet::with)
    }
}

impl fmt::Debug for FunctionSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

impl fmt::Display for FunctionSet {
    /// Comma-separated Rust names, in registry order (the form [`str::parse`] reads).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(FunctionId::name).collect();
        f.write_str(&names.join(","))
    }
}

/// A function name that is not in the registry.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown function `{name}`; the generated functions are: {}",
    known_names()
)]
pub struct UnknownFunction {
    /// The name that was asked for.
    pub name: String,
}

fn known_names() -> String {
    FunctionSet::all().to_string().replace(',', ", ")
}

impl std::str::FromStr for FunctionSet {
    type Err = UnknownFunction;

    /// Comma-separated Rust names (`mass_matrix,gravity`); `all` for every function, `default`
    /// for the default set, `kinematics` for [`FunctionSet::kinematics`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut set = FunctionSet::EMPTY;
        for name in s.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            set = match name {
                "all" => set.union(FunctionSet::all()),
                "default" => set.union(FunctionSet::default()),
                "kinematics" => set.union(FunctionSet::kinematics()),
                "regressors" => set.union(FunctionSet::regressors()),
                "centroidal" => set.union(FunctionSet::centroidal()),
                _ => set.with(FunctionId::from_name(name).ok_or_else(|| UnknownFunction {
                    name: name.to_owned(),
                })?),
            };
        }
        Ok(set)
    }
}

impl FunctionSet {
    /// Both sets' functions.
    #[must_use]
    pub fn union(self, other: FunctionSet) -> Self {
        FunctionSet(self.0 | other.0)
    }

    /// The kinematics and energies: centre of mass, its Jacobian and bias acceleration, kinetic
    /// and potential energy, and the per-frame pose, Jacobian and bias acceleration.
    pub fn kinematics() -> Self {
        [
            FunctionId::CenterOfMass,
            FunctionId::ComJacobian,
            FunctionId::ComBiasAcceleration,
            FunctionId::KineticEnergy,
            FunctionId::PotentialEnergy,
            FunctionId::FramePose,
            FunctionId::FrameJacobian,
            FunctionId::FrameBiasAcceleration,
        ]
        .into_iter()
        .collect()
    }

    /// The centroidal functions: the centroidal momentum matrix, its bias and the centroidal
    /// composite inertia.
    pub fn centroidal() -> Self {
        [
            FunctionId::CentroidalMomentumMatrix,
            FunctionId::CentroidalMomentumBias,
            FunctionId::CentroidalInertia,
        ]
        .into_iter()
        .collect()
    }

    /// The regressors: inverse dynamics and gravity, full and base.
    pub fn regressors() -> Self {
        [
            FunctionId::InverseDynamicsRegressor,
            FunctionId::GravityRegressor,
            FunctionId::BaseRegressor,
            FunctionId::BaseGravityRegressor,
        ]
        .into_iter()
        .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_entries_are_in_id_order() {
        for (i, s) in FUNCTIONS.iter().enumerate() {
            assert_eq!(s.id as usize, i, "{}", s.name);
            assert_eq!(FunctionId::from_name(s.name), Some(s.id));
        }
    }

    #[test]
    fn function_sets_parse_and_print_in_registry_order() {
        let set: FunctionSet = "gravity, mass_matrix".parse().unwrap();
        assert_eq!(set.to_string(), "mass_matrix,gravity");
        assert_eq!("all".parse::<FunctionSet>().unwrap(), FunctionSet::all());
        let err = "mass_matrix,jacobian".parse::<FunctionSet>().unwrap_err();
        assert_eq!(err.name, "jacobian");
        assert!(err.to_string().contains("coriolis_matrix"));
    }
}
