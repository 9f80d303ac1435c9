//! Hash-consed expression arena with construction-time exact simplification.
//!
//! Every node is interned once (identical subexpressions are shared) and children are always
//! created before their parents, so arena order is a topological order. Expressions are kept in
//! a canonical form:
//!
//! * a [`Node::Sum`] is `c₀ + Σ cᵢ·tᵢ` with distinct, sorted, non-constant, non-sum terms `tᵢ`
//!   and non-zero coefficients (like terms collected, numeric factors pulled into `cᵢ`);
//! * a [`Node::Prod`] is `Π bᵢ^nᵢ` with distinct, sorted bases that are atoms or sums, and non-zero
//!   integer powers (numeric factors live in the enclosing sum);
//! * constants are folded; `0·x = 0`, `1·x = x`, `x + 0 = x`.
//!
//! No trigonometric identity is applied, so simplification is exact (only f64 rounding of
//! constants). Substitution variables ([`Atom::Var`]) name compound subexpressions: the reports'
//! K (kinematic) and D (inertial/gravity) variables. [`Arena::diff`] (`diff.rs`) differentiates
//! exactly, variable by variable.
//!
//! Files: `arena.rs` (the arena, its node types and canonicalising constructors), `subst.rs`
//! (substitution variables, hoisting), `diff.rs` (differentiation), `partial.rs` (evaluating only what some roots need), `eval.rs`
//! (numeric evaluation), `display.rs` (printing), `modular.rs` (exact modular arithmetic).

mod arena;
mod diff;
mod display;
mod eval;
pub mod modular;
mod partial;
mod subst;

pub use arena::{Arena, Atom, ExprId, MimicLeaf, Names, Node, Num, Values, VarInfo, VarKind, Wrt};
pub use display::fmt_num;
