//! Recursive Kane's-method derivation with K/D substitution.
//!
//! Kane's equations for a tree of rigid bodies read, for every generalized speed r,
//! `τ_r = Σ_k [F_k · (v_k)_r + N_k · (ω_k)_r] − (generalized gravity force)_r`, where F_k and N_k
//! are body k's inertia force and moment about its frame origin and (v_k)_r, (ω_k)_r its partial
//! velocities. In a tree, the partial angular velocity of every descendant of a revolute joint j
//! is the joint axis e_j and the partial linear velocity is `e_j × (p_k − p_j)`, so the sum over
//! bodies collapses into `e_j · n_j`, with n_j the moment about O_j of the inertia forces of the
//! subtree of j. These subtree sums are accumulated backward, so the generated code grows with
//! the number of bodies plus the sum of depths instead of their product.
//!
//! * ω, α and the origin acceleration a of every frame follow the fixed-wheels report (Zafar 2014) eqs. 3–6 (K variables);
//!   for the wheeled base `ω0 = [0,0,ψ̇]`, `α0 = [0,0,ψ̈]`, `a0 = [ẍ, ẋψ̇, 0]` (the report's
//!   `[ẍ, ψ̇, 0]` is a known error). Gravity enters as the base acceleration `a0 − g0`.
//! * inverse dynamics and c: body inertia forces and moments (D variables), accumulated backward;
//! * M: the same generalized inertia forces for a unit acceleration of one speed at rest, i.e.
//!   composite (subtree) mass, first moment and inertia carried backward, one column per speed,
//!   only the upper triangle;
//! * g: composite first moments against the gravity acceleration of each frame;
//! * wheel terms of DynamicModeling.tex on the ẋ and ψ̇ rows;
//! * the Coriolis matrix C (c = C u, Ṁ − 2C skew-symmetric): spatial vectors in body
//!   coordinates, composite inertia, subtree momentum and subtree inertia rate, three force
//!   vectors carried backward per (speed, ancestor speed) pair (see `Ctx::coriolis_matrix` in
//!   `kane/coriolis_matrix.rs`).
//!
//! Every compound component is replaced by a substitution variable as soon as it is formed.
//!
//! The derivation is one `Ctx` (arena, model, per-link caches) whose methods are split by
//! concern, one file each:
//!
//! | file | what |
//! |---|---|
//! | `mod.rs` | public types, [`derive()`] (one arena phase per function), [`Derivation::evaluate`] |
//! | `ctx.rs` | the derivation's state `Ctx` and its vector and matrix types |
//! | `algebra.rs` | 3-vector and 3×3 algebra, spatial motion/force algebra |
//! | `leaves.rs` | leaves, model data: parameters, `iAj(q)`, `iPj(q)`, bodies, axes, wheels |
//! | `composite.rs` | composite (subtree) mass, first moment and inertia; rotation of inertias |
//! | `mass_matrix.rs` | M, one column per joint, formed inside the composite pass |
//! | `gravity.rs` | g |
//! | `rnea.rs` | c and τ: forward motion pass, body inertia forces, backward accumulation |
//! | `coriolis_matrix.rs` | C: frame velocities, subtree momenta and inertia rates, columns |
//! | `rnea_derivatives.rs` | ∂τ/∂q, ∂τ/∂u: the analytic recursion (four forces per column carried up; `derivatives.rs` keeps forward mode as its test oracle) |
//! | `derivatives_loop.rs` | the looped form of the same: per-link and per-column quantities into a workspace, tables for `kanegen_runtime::derivatives_loop` |
//! | `kinematics.rs` | frames in frame 0 (`⁰A`, `⁰p`), centre of mass, its Jacobian and bias acceleration, energies |
//! | `centroidal.rs` | the centroidal momentum matrix `A_G`, its bias `Ȧ_G u`, the centroidal inertia |
//! | `regressor.rs` | regressors `∂τ/∂π`, `∂g/∂β` (by [`Arena::diff`]) and their base parameters |
//! | `regressor_sample.rs` | the regressor evaluated at random states, what the base parameters are found from |
//! | `regressor_loop.rs` | the loop form of Y and the base regressor: per-link motion and joint transforms, the (speed, body) tables of `kanegen_runtime::regressor` |
//! | `grouping.rs` | the base parameters' groupings as exact expressions of the geometry (fitted, then verified in exact modular arithmetic) |
//! | `mimic.rs`, `mirror.rs` | mimic joints' projection; the mirrored subtrees that `lower::mirrored_lanes` pairs |
//!
//! The files depend on `ctx.rs` and on each other one way; `mod.rs` drives them and re-exports
//! what later stages use.
//!
//! The arena records the order in which each phase first asks for a node and the lowering
//! schedules statements in that order: moving arena calls around changes the generated code.

// Index loops over links mirror the recursions of the reports (parent indices, per-link tables).
#![allow(clippy::needless_range_loop)]

mod algebra;
mod centroidal;
mod composite;
mod coriolis_matrix;
mod ctx;
mod derivatives;
mod derivatives_loop;
#[cfg(test)]
mod derivatives_loop_tests;
mod gravity;
mod grouping;
mod kinematics;
mod leaves;
mod mass_matrix;
mod mimic;
mod mirror;
mod regressor;
mod regressor_loop;
mod regressor_sample;
mod rnea;
mod rnea_derivatives;
#[cfg(test)]
mod rnea_derivatives_tests;

use kanegen_model::{Model, ParamKind};

use crate::combined::ResolvedCombined;
use crate::expr::{Arena, ExprId, Names};
use crate::options::{Options, RegressorForm};
use crate::registry::{FunctionId, Sizes};

use composite::Composite;
use ctx::Ctx;
pub use derivatives_loop::{DerivativeLink, DerivativeLoop, LoopColumn, LoopSpeed};
pub use grouping::{Coefficient, Exactness, SymbolicGroup, symbolic_group_text};
pub use mirror::Mirror;
pub use regressor::{BaseParameters, Regressors, group_text};
pub use regressor_loop::{
    CarryFrom, JointShape, KIN, LANES, LOOP_MIN_PAIRS, LoopLink, LoopPlan, LoopStep, PlanStep,
    RegressorLoop, first_row,
};

/// One derived registry function: its output entries as expressions in the arena (its name,
/// inputs and result shape are in the registry).
#[derive(Clone, Debug)]
pub struct Function {
    /// Which function.
    pub id: FunctionId,
    /// The body frame (link index) of a per-frame function
    /// ([`FunctionSpec::per_frame`](crate::registry::FunctionSpec::per_frame)), else `None`.
    pub frame: Option<usize>,
    /// `(row, col, expr)` in the layout of the function's [`Shape`](crate::registry::Shape); col = 0 for vectors.
    pub entries: Vec<(usize, usize, ExprId)>,
    /// The arena nodes this function's derivation asked for, in the order it first asked for
    /// them: the statement order the lowering follows (see [`Arena::begin_phase`]).
    pub order: Vec<ExprId>,
    /// The loop form of a regressor (`inverse_dynamics_regressor`, `base_regressor`) when
    /// `regressor_form` chooses it; `entries` are the same function straight-line
    /// (for evaluation and the base parameters).
    pub looped: Option<RegressorLoop>,
}

/// A function's `(row, col, expression)` entries.
type Entries = Vec<(usize, usize, ExprId)>;

/// The symbolic dynamics of a model.
#[derive(Clone, Debug)]
pub struct Derivation {
    /// All expressions and substitution variables.
    pub arena: Arena,
    /// The functions of [`Options::functions`], in registry order.
    pub functions: Vec<Function>,
    /// Number of speeds.
    pub dof: usize,
    /// Number of coordinates (the length of `q`): `dof`, or `dof + 1` for a floating base.
    pub nq: usize,
    /// Whether the base is floating ([`kanegen_model::Base::Floating`]).
    pub floating: bool,
    /// Options used.
    pub options: Options,
    /// The body frames' names (the model's links, in order): the frames of the per-frame
    /// functions.
    pub frame_names: Vec<String>,
    /// The regressors' parameters (π, β) and, when a base regressor is derived, the base
    /// parameters.
    pub regressors: Regressors,
    /// The result sizes (speeds, regressor columns).
    pub sizes: Sizes,
    /// The combined functions (one arena phase each; see [`crate::combined`]).
    pub combined: Vec<CombinedFunction>,
    /// The looped form of `inverse_dynamics_derivatives` (its own arena phase, after every
    /// other): derived when the module has the derivatives and the model has no mimic joints.
    pub derivative_loop: Option<LoopedDerivatives>,
    /// The model's mirrored subtrees, if it has any (see [`Mirror`]): what the lowering pairs
    /// into two-lane statements.
    pub mirror: Option<Mirror>,
}

/// The looped form of `inverse_dynamics_derivatives` (`kane/derivatives_loop.rs`): the
/// workspace the generated statements fill and the tables the runtime loop runs over.
#[derive(Clone, Debug)]
pub struct LoopedDerivatives {
    /// `(offset, 0, expr)`: the workspace entries.
    pub entries: Vec<(usize, usize, ExprId)>,
    /// The statement order of its phase (see [`Function::order`]).
    pub order: Vec<ExprId>,
    /// The tables.
    pub plan: DerivativeLoop,
}

/// One derived combined function: its parts' entries and the statement order of its phase.
#[derive(Clone, Debug)]
pub struct CombinedFunction {
    /// What was asked for, resolved against the model.
    pub spec: ResolvedCombined,
    /// Per part (in the order of `spec.parts`), its `(row, col, expr)` entries in the layout of
    /// the part's [`Shape`](crate::registry::Shape).
    pub parts: Vec<Vec<(usize, usize, ExprId)>>,
    /// The arena nodes the combined function's phase asked for, in the order it first asked
    /// for them (see [`Function::order`]).
    pub order: Vec<ExprId>,
}

impl Derivation {
    /// The derived function `id`, if [`Options::functions`] asked for it (frame 0's program of
    /// a per-frame function).
    pub fn function(&self, id: FunctionId) -> Option<&Function> {
        self.functions.iter().find(|f| f.id == id)
    }

    /// The derived function `id` for body frame `frame` (`None` for a function without frames).
    pub fn function_at(&self, id: FunctionId, frame: Option<usize>) -> Option<&Function> {
        self.functions
            .iter()
            .find(|f| f.id == id && (frame.is_none() || f.frame == frame))
    }
}

/// Names for the arena's printer, from the model.
pub fn names_of(model: &Model) -> Names {
    Names {
        params: model.params.iter().map(|p| p.name.clone()).collect(),
        speeds: model.speeds.iter().map(|s| s.name.clone()).collect(),
        coords: model.speeds.iter().map(|s| s.coordinate.clone()).collect(),
        lengths: model
            .params
            .iter()
            .map(|p| p.kind == ParamKind::Length)
            .collect(),
    }
}

/// The order in which functions are derived. M comes first: its columns are formed inside the
/// backward composite pass, each right after its subtree's composite is complete, so that the
/// generated code uses values soon after it computes them (short live ranges, fewer register
/// spills); g and C reuse those composites. The order fixes the arena's numbering and with it the
/// generated code, so it is part of the output's definition. The opt-in kinematics come last, so
/// that they do not change the dynamics' code.
const DERIVATION_ORDER: [FunctionId; 22] = [
    FunctionId::MassMatrix,
    FunctionId::Gravity,
    FunctionId::Coriolis,
    FunctionId::InverseDynamics,
    FunctionId::CoriolisMatrix,
    FunctionId::CenterOfMass,
    FunctionId::ComJacobian,
    FunctionId::ComBiasAcceleration,
    FunctionId::KineticEnergy,
    FunctionId::PotentialEnergy,
    FunctionId::FramePose,
    FunctionId::FrameJacobian,
    FunctionId::FrameBiasAcceleration,
    FunctionId::InverseDynamicsDerivatives,
    FunctionId::InverseDynamicsRegressor,
    FunctionId::GravityRegressor,
    FunctionId::BaseRegressor,
    FunctionId::BaseGravityRegressor,
    FunctionId::NonlinearEffects,
    FunctionId::CentroidalMomentumMatrix,
    FunctionId::CentroidalMomentumBias,
    FunctionId::CentroidalInertia,
];

/// Derive the functions of `options.functions` for `model` (M as its upper triangle).
pub fn derive(model: &Model, options: Options) -> Derivation {
    derive_with(model, options, &[])
}

/// [`derive()`], and the combined functions `combined` (resolved against `model` by
/// [`crate::combined::resolve`]), each one arena phase after the module's functions.
pub fn derive_with(model: &Model, options: Options, combined: &[ResolvedCombined]) -> Derivation {
    derive_shaped(model, options, combined, RegressorForm::Auto)
}

/// [`derive_with`], with the regressors' code shape `regressor_form` (the loop form's tables in
/// [`Function::looped`] when it is chosen).
pub fn derive_shaped(
    model: &Model,
    options: Options,
    combined: &[ResolvedCombined],
    regressor_form: RegressorForm,
) -> Derivation {
    let mut arena = Arena::new(names_of(model));
    arena.hoist_params = options.params.is_runtime();
    if model.is_floating() {
        arena.set_floating();
    }
    mimic::declare(&mut arena, model);
    let mut cx = Ctx {
        ar: &mut arena,
        model,
        options,
        rot: vec![None; model.links.len()],
        pos: vec![None; model.links.len()],
        root_rot: vec![None; model.links.len()],
        root_pos: vec![None; model.links.len()],
        keep_inertial: false,
    };
    // Results have the independent speeds (the derivation runs on all speeds of the tree and
    // `mimic::project` reduces them).
    let n = model.independent_dof();
    let mut composites = None;
    let mut functions = Vec::new();
    let mut regressors = regressor::layout(model);
    let mut full: [Option<Entries>; 2] = [None, None];
    for id in DERIVATION_ORDER {
        if !options.has(id) {
            continue;
        }
        // Each function (each frame of a per-frame function) is one arena phase: its statements
        // are later scheduled in the order its own recursion forms them.
        let frames: Vec<Option<usize>> = if id.spec().per_frame {
            (0..model.links.len()).map(Some).collect()
        } else {
            vec![None]
        };
        for frame in frames {
            cx.ar.begin_phase();
            let entries = match (frame, id) {
                (Some(l), _) => cx.derive_frame_function(id, l),
                (
                    None,
                    FunctionId::InverseDynamicsRegressor
                    | FunctionId::GravityRegressor
                    | FunctionId::BaseRegressor
                    | FunctionId::BaseGravityRegressor,
                ) => cx.derive_regressor(id, &mut regressors, &mut full),
                (None, _) => cx.derive_function(id, &mut composites),
            };
            let looped = cx.looped_regressor(id, &regressors, &entries, regressor_form);
            let entries = mimic::project(cx.ar, model, id.spec().shape, entries);
            let order = cx.ar.phase_order();
            functions.push(Function {
                id,
                frame,
                entries,
                order,
                looped,
            });
        }
    }
    // Each combined function is one phase: its parts are derived again (the arena's hash-consing
    // and variable cache give the very nodes of the separate functions), so that the one program
    // computes every shared sine, cosine and variable once.
    let mut combined_out = Vec::with_capacity(combined.len());
    for c in combined {
        cx.ar.begin_phase();
        let mut parts = Vec::with_capacity(c.parts.len());
        for part in &c.parts {
            let id = part.function;
            let entries = match part.frame {
                Some(l) => cx.derive_frame_function(id, l),
                None => cx.derive_function(id, &mut composites),
            };
            parts.push(mimic::project(cx.ar, model, id.spec().shape, entries));
        }
        combined_out.push(CombinedFunction {
            spec: c.clone(),
            parts,
            order: cx.ar.phase_order(),
        });
    }
    // The looped derivatives: one more phase, after every other (the other functions' code is
    // unchanged).
    let derivative_loop = (options.has(FunctionId::InverseDynamicsDerivatives)
        && model.mimics.is_empty())
    .then(|| {
        cx.ar.begin_phase();
        let (entries, plan) = cx.inverse_dynamics_derivatives_looped();
        LoopedDerivatives {
            entries,
            order: cx.ar.phase_order(),
            plan,
        }
    });
    functions.sort_by_key(|f| (f.id, f.frame));
    let sizes = Sizes {
        dof: n,
        inertial: regressors.inertial.len(),
        beta: regressors.beta.len(),
        base: regressors.base.as_ref().map_or(0, |b| b.names.len()),
        base_beta: regressors.base_beta.as_ref().map_or(0, |b| b.names.len()),
    };
    debug_assert!(functions.iter().all(|f| {
        let (rows, cols) = f.id.spec().shape.size_in(&sizes);
        f.entries.iter().all(|e| e.0 < rows && e.1 < cols)
    }));
    Derivation {
        arena,
        functions,
        dof: n,
        nq: model.nq(),
        floating: model.is_floating(),
        options,
        frame_names: model.links.iter().map(|l| l.name.clone()).collect(),
        regressors,
        sizes,
        combined: combined_out,
        derivative_loop,
        // A floating base's coordinates are not indexed like its speeds, which the pairing of
        // mirrored subtrees assumes.
        mirror: Mirror::of(model).filter(|_| !model.is_floating()),
    }
}

impl Ctx<'_> {
    /// The entries of registry function `id`. `composites`: the subtree inertias, formed by the
    /// first function that needs them (M forms its columns on the way).
    fn derive_function(
        &mut self,
        id: FunctionId,
        composites: &mut Option<Vec<Composite>>,
    ) -> Vec<(usize, usize, ExprId)> {
        let vector = |v: Vec<ExprId>| v.into_iter().enumerate().map(|(i, e)| (i, 0, e)).collect();
        match id {
            FunctionId::MassMatrix => {
                let mut columns = Vec::new();
                let comp = self.composites(true, Some(&mut columns));
                let m = self.mass_matrix(&comp, columns);
                *composites = Some(comp);
                m
            }
            FunctionId::Gravity => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                vector(self.gravity(comp))
            }
            FunctionId::Coriolis => vector(self.rnea(false, false)),
            FunctionId::InverseDynamics => vector(self.rnea(true, true)),
            FunctionId::NonlinearEffects => vector(self.rnea(false, true)),
            FunctionId::CoriolisMatrix => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                self.coriolis_matrix(comp)
            }
            FunctionId::CenterOfMass => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                vector(self.center_of_mass(comp).to_vec())
            }
            FunctionId::ComJacobian => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                self.com_jacobian(comp)
            }
            FunctionId::ComBiasAcceleration => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                vector(self.com_bias_acceleration(comp).to_vec())
            }
            FunctionId::KineticEnergy => vec![(0, 0, self.kinetic_energy())],
            FunctionId::PotentialEnergy => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                vec![(0, 0, self.potential_energy(comp))]
            }
            FunctionId::InverseDynamicsDerivatives => self.inverse_dynamics_derivatives(),
            FunctionId::CentroidalMomentumMatrix => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                self.centroidal_momentum_matrix(comp)
            }
            FunctionId::CentroidalMomentumBias => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                let [f, n] = self.centroidal_momentum_bias(comp);
                vector(f.into_iter().chain(n).collect())
            }
            FunctionId::CentroidalInertia => {
                let comp = composites.get_or_insert_with(|| self.composites(true, None));
                self.centroidal_inertia(comp)
            }
            FunctionId::FramePose
            | FunctionId::FrameJacobian
            | FunctionId::FrameBiasAcceleration => {
                unreachable!("per-frame functions are derived by `derive_frame_function`")
            }
            FunctionId::InverseDynamicsRegressor
            | FunctionId::GravityRegressor
            | FunctionId::BaseRegressor
            | FunctionId::BaseGravityRegressor => {
                unreachable!("regressors are derived by `derive_regressor`")
            }
        }
    }

    /// The entries of a regressor function. `full`: Y and Y_g once derived (the base
    /// regressors are their identifiable columns).
    fn derive_regressor(
        &mut self,
        id: FunctionId,
        reg: &mut Regressors,
        full: &mut [Option<Entries>; 2],
    ) -> Entries {
        let gravity = matches!(
            id,
            FunctionId::GravityRegressor | FunctionId::BaseGravityRegressor
        );
        let k = usize::from(gravity);
        let entries = match full[k].clone() {
            Some(e) => {
                // Ask for the nodes again in this phase, for its statement order.
                for &(_, _, x) in &e {
                    self.ar.touch_tree(x);
                }
                e
            }
            None => {
                let e = if gravity {
                    self.gravity_regressor(&reg.beta.clone())
                } else {
                    self.inertial_regressor(&reg.inertial.clone())
                };
                full[k] = Some(e.clone());
                e
            }
        };
        if matches!(
            id,
            FunctionId::InverseDynamicsRegressor | FunctionId::GravityRegressor
        ) {
            return entries;
        }
        let params = if gravity { &reg.beta } else { &reg.inertial };
        let baked = !matches!(self.options.params, crate::options::ParamMode::Runtime);
        let base = regressor::base_parameters(self.ar, self.model, &entries, params, baked);
        let column: std::collections::HashMap<usize, usize> = base
            .groups
            .iter()
            .enumerate()
            .map(|(b, g)| (g[0].0, b))
            .collect();
        let out = entries
            .iter()
            .filter_map(|&(r, c, e)| column.get(&c).map(|&b| (r, b, e)))
            .collect();
        if gravity {
            reg.base_beta = Some(base);
        } else {
            reg.base = Some(base);
        }
        out
    }

    /// The loop form of regressor `id` with straight-line `entries`, if it is
    /// `inverse_dynamics_regressor` or `base_regressor` and `regressor_form` chooses
    /// the loop for the model (`form`).
    fn looped_regressor(
        &mut self,
        id: FunctionId,
        reg: &Regressors,
        entries: &[(usize, usize, ExprId)],
        form: RegressorForm,
    ) -> Option<RegressorLoop> {
        let model = self.model;
        let pairs = regressor_loop::steps(model)
            .iter()
            .filter(|s| model.links[s.link].body.is_some())
            .count();
        if !regressor_loop::use_loop(form, model, pairs) {
            return None;
        }
        match id {
            FunctionId::InverseDynamicsRegressor => {
                let full: Vec<(usize, usize, ExprId)> = entries.to_vec();
                Some(self.regressor_loop(&Some, &full))
            }
            FunctionId::BaseRegressor => {
                let base = reg.base.as_ref()?;
                let column: std::collections::HashMap<usize, usize> = base
                    .groups
                    .iter()
                    .enumerate()
                    .map(|(b, g)| (g[0].0, b))
                    .collect();
                // `entries` are already in the base columns: the straight-line extras are
                // picked from them by their base column.
                let inverse: std::collections::HashMap<usize, usize> =
                    column.iter().map(|(&c, &b)| (b, c)).collect();
                let full: Vec<(usize, usize, ExprId)> = entries
                    .iter()
                    .filter_map(|&(r, b, e)| inverse.get(&b).map(|&c| (r, c, e)))
                    .collect();
                Some(self.regressor_loop(&|c| column.get(&c).copied(), &full))
            }
            _ => None,
        }
    }

    /// The entries of per-frame registry function `id` for body frame `l`.
    fn derive_frame_function(&mut self, id: FunctionId, l: usize) -> Vec<(usize, usize, ExprId)> {
        match id {
            FunctionId::FramePose => self.frame_pose(l),
            FunctionId::FrameJacobian => self.frame_jacobian(l),
            FunctionId::FrameBiasAcceleration => self.frame_bias_acceleration(l),
            _ => unreachable!("`{id}` is not a per-frame function"),
        }
    }
}

impl Derivation {
    /// Evaluate function `id` numerically from the symbolic expressions (no code generation):
    /// the row-major dense value of its [`Shape`](crate::registry::Shape) (an `n × n` matrix
    /// with both triangles, an `n`-vector, a `3 × n` Jacobian, a scalar, …). Parameter values are
    /// used in [`ParamMode::Runtime`](crate::options::ParamMode::Runtime); in baked mode the model's values are already folded in.
    pub fn evaluate(
        &self,
        id: FunctionId,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        self.evaluate_at(id, None, params, q, u, ud)
    }

    /// [`Derivation::evaluate`] for body frame `frame` (a link index) of a per-frame function
    /// (`None`: frame 0, or a function without frames).
    pub fn evaluate_at(
        &self,
        id: FunctionId,
        frame: Option<usize>,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        let f = self
            .function_at(id, frame)
            .unwrap_or_else(|| panic!("the derivation has no function `{id}`"));
        // Sines and cosines of dependent (mimic) angles are formed from `q` by the arena.
        let vals = self.arena.eval(&crate::expr::Values { params, q, u, ud });
        let entries = f.entries.iter().map(|&(r, c, e)| (r, c, vals[e.index()]));
        id.spec().shape.dense_in(&self.sizes, entries)
    }
}
