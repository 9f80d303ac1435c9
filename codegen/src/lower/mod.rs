//! Lowering: from the derivation's expression DAG to straight-line programs.
//!
//! For every generated function only the statements its outputs need are kept (dead-code
//! elimination through the substitution variables), in topological order. Substitution
//! variables become `let` statements named `k1, k2, …` (kinematic) and `d1, d2, …` (inertial and
//! gravity terms), numbered per function; other subexpressions used more than once become `t1, …`
//! statements (common subexpressions). With runtime parameters, every parameter-only
//! subexpression moves to a separate *precompute* program that runs once per parameter set
//! (its results are `pc1, pc2, …`). Each joint's sin/cos is computed once. Op counts are kept
//! per program. No model name can have these shapes
//! ([`kanegen_model::names::is_generated_local`], checked by
//! [`Model::check_names`](kanegen_model::Model::check_names)), so a local never shadows a speed,
//! coordinate or parameter.
//!
//! Files: `program.rs` (the lowered form and its operation counts), `order.rs` (statement
//! order), `build.rs` (lowering a derivation), `eval.rs` (an interpreter of the programs, for
//! tests), `mirrored_lanes.rs` (the statements of mirrored subtrees paired into two lanes;
//! also reachable as `lower::lanes`).

mod build;
mod eval;
pub mod mirrored_lanes;
mod order;
mod program;

/// [`mirrored_lanes`] under the shorter name the crate root and the reports use.
pub use mirrored_lanes as lanes;

pub use build::{lower, lower_with};
pub use order::{BATCH_SUBTREE_ORDER, SUBTREE_ORDER, batch_program, restrict, subtree_order};
pub use program::{
    CombinedProgram, FunctionProgram, LExpr, Leaf, LoopProgram, LoopedProgram, Lowered, OpCount,
    Program, Stmt, fusable, fused_terms, sum_order,
};
