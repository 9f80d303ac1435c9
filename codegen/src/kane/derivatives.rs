//! Derivatives of inverse dynamics: `∂τ/∂q` and `∂τ/∂u`, exact, on the expression DAG.
//!
//! Generated code uses the analytic recursion of `rnea_derivatives.rs` (four forces carried
//! per (speed, ancestor speed) pair) on every base, a floating base's orientation columns
//! included. The forward mode kept here for its tests is the first
//! derivation: τ is derived by the recursion of `rnea.rs`, then every entry is differentiated
//! with [`Arena::diff`](crate::expr::Arena::diff), forward mode over the K/D substitution
//! variables (one pass per input over everything that depends on it; Krang: 35,959 flops
//! against the analytic recursion's 14,728; Solo 12 on a floating base, with its base's
//! orientation columns from M: 13,474 against 7,768). Both are exact, so they agree to rounding.

#[cfg(test)]
use std::collections::HashMap;

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

    /// A floating base's `[∂τ/∂q | ∂τ/∂u]` by forward mode, `∂τ/∂q` in the tangent space
    /// (`q ⊕ δ`, as Pinocchio's `computeRNEADerivatives`): the base position does not enter τ
    /// (columns `δv` zero); its orientation enters only through `g_b = Rᵀ g`, and τ depends on
    /// `g_b` exactly as on `−v̇`, so with `∂g_b/∂δω = [g_b]×` the `δω` columns are
    /// `−M[:, v] [g_b]×`; the joints' columns and `∂τ/∂u` are forward-mode derivatives of τ.
    #[cfg(test)]
    fn floating_inverse_dynamics_derivatives_forward_mode(
        &mut self,
    ) -> Vec<(usize, usize, ExprId)> {
        let tau = self.rnea(true, true);
        let n = self.model.independent_dof();
        let mut columns = Vec::new();
        let comp = self.composites(true, Some(&mut columns));
        let m: HashMap<(usize, usize), ExprId> = self
            .mass_matrix(&comp, columns)
            .into_iter()
            .flat_map(|(a, b, e)| [((a, b), e), ((b, a), e)])
            .collect();
        let gb = self.gravity_vector();
        let zero = self.ar.zero();
        let mut out = Vec::new();
        // g_b × e_k for k = x, y, z.
        let gx = [
            [zero, gb[2], self.ar.neg(gb[1])],
            [self.ar.neg(gb[2]), zero, gb[0]],
            [gb[1], self.ar.neg(gb[0]), zero],
        ];
        for (k, g) in gx.iter().enumerate() {
            for row in 0..n {
                let terms: Vec<ExprId> = (0..3)
                    .filter_map(|i| m.get(&(row, i)).map(|&mi| self.ar.mul(mi, g[i])))
                    .collect();
                let s = self.ar.sum(terms);
                let d = self.ar.neg(s);
                if !self.ar.is_zero(d) {
                    out.push((row, 3 + k, d));
                }
            }
        }
        let columns = (6..n as u32)
            .map(|s| (s as usize, Wrt::Coord(s)))
            .chain((0..n as u32).map(|s| (n + s as usize, Wrt::Speed(s))));
        for (col, wrt) in columns {
            for (row, &t) in tau.iter().enumerate() {
                let d = self.ar.diff(t, wrt);
                if !self.ar.is_zero(d) {
                    out.push((row, col, d));
                }
            }
        }
        out
    }

    /// The same by forward mode over τ's recursion (the test oracle of the analytic one).
    #[cfg(test)]
    pub(super) fn inverse_dynamics_derivatives_forward_mode(
        &mut self,
    ) -> Vec<(usize, usize, ExprId)> {
        if self.model.is_floating() {
            return self.floating_inverse_dynamics_derivatives_forward_mode();
        }
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
