//! Derivatives of inverse dynamics: `∂τ/∂q` and `∂τ/∂u`, exact, on the expression DAG.
//!
//! Generated code uses the analytic recursion of `rnea_derivatives.rs` (four forces carried
//! per (speed, ancestor speed) pair). The forward mode kept here for its tests is the first
//! derivation: τ is derived by the recursion of `rnea.rs`, then every entry is differentiated
//! with [`Arena::diff`](crate::expr::Arena::diff), forward mode over the K/D substitution
//! variables (one pass per input over everything that depends on it; Krang: 35,959 flops
//! against the analytic recursion's 14,728). Both are exact, so they agree to rounding.

use super::ctx::Ctx;
use crate::expr::ExprId;
#[cfg(test)]
use crate::expr::Wrt;

impl Ctx<'_> {
    /// `[∂τ/∂q | ∂τ/∂u]` as `(row, col, expr)`: column `j` is ∂τ/∂q_j, column `N + j` is ∂τ/∂u_j.
    ///
    /// Rows are the tree's speeds (a mimic model's rows are projected afterwards, like τ's);
    /// columns are the `N` independent speeds only: the arena writes a mimic joint's leaves in
    /// terms of its master, so the derivative in the master's coordinate already carries the
    /// chain rule, and the dependent speeds (numbered last) are not inputs.
    pub(super) fn inverse_dynamics_derivatives(&mut self) -> Vec<(usize, usize, ExprId)> {
        self.inverse_dynamics_derivatives_analytic()
    }

    /// The same by forward mode over τ's recursion (the test oracle of the analytic one).
    #[cfg(test)]
    pub(super) fn inverse_dynamics_derivatives_forward_mode(
        &mut self,
    ) -> Vec<(usize, usize, ExprId)> {
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
