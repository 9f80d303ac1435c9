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
//! * ω, α and the origin acceleration a of every frame follow seed 002 eqs. 3–6 (K variables);
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
//! | `algebra.rs` | 3-vector and 3×3 algebra, spatial motion/force algebra |
//! | `frames.rs` | leaves, model data: parameters, `iAj(q)`, `iPj(q)`, bodies, axes, wheels |
//! | `composite.rs` | composite (subtree) mass, first moment and inertia; rotation of inertias |
//! | `mass_matrix.rs` | M, one column per joint, formed inside the composite pass |
//! | `gravity.rs` | g |
//! | `rnea.rs` | c and τ: forward motion pass, body inertia forces, backward accumulation |
//! | `coriolis_matrix.rs` | C: frame velocities, subtree momenta and inertia rates, columns |
//!
//! The arena records the order in which each phase first asks for a node and the lowering
//! schedules statements in that order: moving arena calls around changes the generated code.

// Index loops over links mirror the recursions of the reports (parent indices, per-link tables).
#![allow(clippy::needless_range_loop)]

mod algebra;
mod composite;
mod coriolis_matrix;
mod frames;
mod gravity;
mod mass_matrix;
mod rnea;

use kanegen_model::Model;

use crate::expr::{Arena, ExprId, Names};

use algebra::{M3, V3};

/// How model parameters enter the generated code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ParamMode {
    /// Parameters are runtime inputs (a `Params` value); parameter-only subexpressions are
    /// computed once per parameter set, outside the hot path.
    #[default]
    Runtime,
    /// The model file's values are folded in as constants; terms of zero parameters vanish.
    Baked,
}

/// Generator options.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// How parameters enter.
    pub params: ParamMode,
    /// Also derive `coriolis_matrix`, the Coriolis matrix C(q, u) (default `true`). It costs
    /// about four times the operations of `coriolis` (Krang: ≈ 9,500 flops) and roughly doubles
    /// the compile time of a large model's generated module; turn it off when only M, c, g and
    /// τ are needed.
    pub coriolis_matrix: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            params: ParamMode::default(),
            coriolis_matrix: true,
        }
    }
}

/// Shape of a generated function's result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Symmetric matrix; entries are the upper triangle `(row ≤ col)`.
    SymmetricMatrix,
    /// Vector; entries are `(row, 0)`.
    Vector,
    /// General (non-symmetric) matrix; entries are `(row, col)`, absent entries are zero.
    Matrix,
}

/// Which inputs a function takes besides the parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signature {
    /// `f(q)`.
    Q,
    /// `f(q, u)`.
    QU,
    /// `f(q, u, u̇)`.
    QUUd,
}

/// One derived function: its name and output entries as expressions in the arena.
#[derive(Clone, Debug)]
pub struct Function {
    /// Rust name (`mass_matrix`).
    pub name: &'static str,
    /// What it computes, for docs.
    pub doc: &'static str,
    /// Result shape.
    pub shape: Shape,
    /// Inputs.
    pub signature: Signature,
    /// `(row, col, expr)`; col = 0 for vectors.
    pub entries: Vec<(usize, usize, ExprId)>,
    /// Per arena node, when this function's derivation first asked for it (`u32::MAX`: never):
    /// the statement order the lowering follows (see [`Arena::begin_phase`]).
    pub order: Vec<u32>,
}

/// The symbolic dynamics of a model.
#[derive(Clone, Debug)]
pub struct Derivation {
    /// All expressions and substitution variables.
    pub arena: Arena,
    /// `mass_matrix`, `coriolis`, `gravity`, `inverse_dynamics`, and `coriolis_matrix` if
    /// [`Options::coriolis_matrix`].
    pub functions: Vec<Function>,
    /// Number of speeds.
    pub dof: usize,
    /// Options used.
    pub options: Options,
}

impl Derivation {
    /// The function called `name`.
    pub fn function(&self, name: &str) -> Option<&Function> {
        self.functions.iter().find(|f| f.name == name)
    }
}

/// Names for the arena's printer, from the model.
pub fn names_of(model: &Model) -> Names {
    Names {
        params: model.params.iter().map(|p| p.name.clone()).collect(),
        speeds: model.speeds.iter().map(|s| s.name.clone()).collect(),
        coords: model.speeds.iter().map(|s| s.coordinate.clone()).collect(),
    }
}

/// Derive M (upper triangle), c, g, τ and the Coriolis matrix C for `model`.
pub fn derive(model: &Model, options: Options) -> Derivation {
    let mut arena = Arena::new(names_of(model));
    arena.hoist_params = options.params == ParamMode::Runtime;
    let mut cx = Ctx {
        ar: &mut arena,
        model,
        options,
        rot: vec![None; model.links.len()],
        pos: vec![None; model.links.len()],
    };
    let n = model.dof();
    // The columns of M are formed inside the backward composite pass, each right after its
    // subtree's composite is complete, so that the generated code uses values soon after it
    // computes them (short live ranges, fewer register spills). Each function is one arena
    // phase: its statements are later scheduled in the order its own recursion forms them.
    cx.ar.begin_phase();
    let mut columns = Vec::new();
    let composites = cx.composites(true, Some(&mut columns));
    let m = cx.mass_matrix(&composites, columns);
    let m_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let g = cx.gravity(&composites);
    let g_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let c = cx.rnea(false, false);
    let c_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let tau = cx.rnea(true, true);
    let tau_order = cx.ar.phase_order();
    let cm = options.coriolis_matrix.then(|| {
        cx.ar.begin_phase();
        let cm = cx.coriolis_matrix(&composites);
        (cm, cx.ar.phase_order())
    });
    let vector = |v: Vec<ExprId>| v.into_iter().enumerate().map(|(i, e)| (i, 0, e)).collect();
    let mut functions = vec![
        Function {
            name: "mass_matrix",
            doc: "Mass matrix M(q) (symmetric positive definite).",
            shape: Shape::SymmetricMatrix,
            signature: Signature::Q,
            entries: m,
            order: m_order,
        },
        Function {
            name: "coriolis",
            doc: "Coriolis and centrifugal vector c(q, u) (velocity-product terms).",
            shape: Shape::Vector,
            signature: Signature::QU,
            entries: vector(c),
            order: c_order,
        },
        Function {
            name: "gravity",
            doc: "Gravity vector g(q).",
            shape: Shape::Vector,
            signature: Signature::Q,
            entries: vector(g),
            order: g_order,
        },
        Function {
            name: "inverse_dynamics",
            doc: "Inverse dynamics τ = M(q) u̇ + c(q, u) + g(q), in one pass.",
            shape: Shape::Vector,
            signature: Signature::QUUd,
            entries: vector(tau),
            order: tau_order,
        },
    ];
    if let Some((cm, cm_order)) = cm {
        functions.push(Function {
            name: "coriolis_matrix",
            doc: "Coriolis matrix C(q, u): c(q, u) = C(q, u) u, and Ṁ − 2C is skew-symmetric.",
            shape: Shape::Matrix,
            signature: Signature::QU,
            entries: cm,
            order: cm_order,
        });
    }
    debug_assert!(functions.iter().all(|f| f.entries.iter().all(|e| e.0 < n)));
    Derivation {
        arena,
        functions,
        dof: n,
        options,
    }
}

/// The derivation's state: the arena, the model, and the per-link caches of `iAj(q)` and
/// `iPj(q)`. Its methods are spread over this module's files, one concern each.
struct Ctx<'a> {
    ar: &'a mut Arena,
    model: &'a Model,
    options: Options,
    rot: Vec<Option<M3>>,
    pos: Vec<Option<V3>>,
}

impl Derivation {
    /// Evaluate function `name` numerically from the symbolic expressions (no code generation):
    /// a dense row-major `n × n` matrix (both triangles) or an `n`-vector. Parameter values are
    /// used in [`ParamMode::Runtime`]; in baked mode the model's values are already folded in.
    pub fn evaluate(
        &self,
        name: &str,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        let f = self
            .function(name)
            .unwrap_or_else(|| panic!("no function `{name}`"));
        let vals = self.arena.eval(&crate::expr::Values { params, q, u, ud });
        let n = self.dof;
        match f.shape {
            Shape::SymmetricMatrix => {
                let mut m = vec![0.0; n * n];
                for &(r, c, e) in &f.entries {
                    m[r * n + c] = vals[e.index()];
                    m[c * n + r] = vals[e.index()];
                }
                m
            }
            Shape::Matrix => {
                let mut m = vec![0.0; n * n];
                for &(r, c, e) in &f.entries {
                    m[r * n + c] = vals[e.index()];
                }
                m
            }
            Shape::Vector => {
                let mut v = vec![0.0; n];
                for &(r, _, e) in &f.entries {
                    v[r] = vals[e.index()];
                }
                v
            }
        }
    }
}
