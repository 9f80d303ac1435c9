//! Derivatives of inverse dynamics: `∂τ/∂q` and `∂τ/∂u`, exact, on the expression DAG.
//!
//! τ is derived by the recursion of `rnea.rs` (the same nodes as the `inverse_dynamics`
//! function: the arena is hash-consed), then every entry is differentiated with
//! [`Arena::diff`](crate::expr::Arena::diff), forward mode over the K/D substitution variables:
//! the derivative of a variable is a variable of its own, so the derivative program is itself
//! a recursion sharing τ's statements, and an entry that does not depend on an input is the
//! constant zero at generation time (never computed, never stored).

use super::Ctx;
use crate::expr::{ExprId, Wrt};

impl Ctx<'_> {
    /// `[∂τ/∂q | ∂τ/∂u]` as `(row, col, expr)`: column `j` is ∂τ/∂q_j, column `N + j` is ∂τ/∂u_j.
    ///
    /// Rows are the tree's speeds (a mimic model's rows are projected afterwards, like τ's);
    /// columns are the `N` independent speeds only: the arena writes a mimic joint's leaves in
    /// terms of its master, so the derivative in the master's coordinate already carries the
    /// chain rule, and the dependent speeds (numbered last) are not inputs.
    pub(super) fn inverse_dynamics_derivatives(&mut self) -> Vec<(usize, usize, ExprId)> {
        let tau = self.rnea(true, true);
        let n = self.model.independent_dof();
        let mut out = Vec::new();
        for (col, wrt) in (0..n as u32)
            .map(Wrt::Coord)
            .chain((0..n as u32).map(Wrt::Speed))
            .enumerate()
        {
            for (row, &t) in tau.iter().enumerate() {
                let d = self.ar.diff(t, wrt);
                if !self.ar.is_zero(d) {
                    out.push((row, col, d));
                }
            }
        }
        out
    }
}
