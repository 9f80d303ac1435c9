//! Derivatives of inverse dynamics by forward-mode dual numbers (feature `dual`): the same
//! recursions run in [`num_dual::Dual64`], one pass per input, as the generic baseline of the
//! generated `inverse_dynamics_derivatives`.

use kanegen_model::Model;
use nalgebra::{SMatrix, SVector};
use num_dual::{Dual64, DualNum};

use crate::{Rbd, RbdError, Scalar};

impl Scalar for Dual64 {
    /// `(sin x, cos x)` with their derivatives (`num-dual`'s, through `f64::sin_cos`).
    #[inline(always)]
    fn sin_cos_joint(self) -> (Self, Self) {
        self.sin_cos()
    }
}

/// `∂τ/∂q` and `∂τ/∂u` of [`Rbd::inverse_dynamics`] by forward-mode dual numbers: `2N` passes
/// of the recursion in [`Dual64`], each seeding one input's derivative with 1. Exact (no step
/// size), allocation-free after [`DualDerivatives::new`], and generic over any model `Rbd` runs.
#[derive(Debug, Clone)]
pub struct DualDerivatives<const N: usize> {
    rbd: Rbd<N, Dual64>,
}

impl<const N: usize> DualDerivatives<N> {
    /// The recursions for `model` with parameter values `params` (indexed by
    /// [`kanegen_model::ParamId`]); fails like [`Rbd::new`].
    pub fn new(model: &Model, params: &[f64]) -> Result<Self, RbdError> {
        let p: Vec<Dual64> = params.iter().map(|&x| Dual64::from_re(x)).collect();
        Ok(Self {
            rbd: Rbd::new(model, &p)?,
        })
    }

    /// `(∂τ/∂q, ∂τ/∂u)` at `(q, u, u̇)`: column j is the derivative in `q_j` (`u_j`). The
    /// wheeled base's x and ψ do not enter τ, so their q-columns are zero.
    pub fn inverse_dynamics_derivatives(
        &self,
        q: &SVector<f64, N>,
        u: &SVector<f64, N>,
        ud: &SVector<f64, N>,
    ) -> (SMatrix<f64, N, N>, SMatrix<f64, N, N>) {
        let lift = |v: &SVector<f64, N>| v.map(Dual64::from_re);
        let (qd, ud_, udd) = (lift(q), lift(u), lift(ud));
        let mut dq = SMatrix::<f64, N, N>::zeros();
        let mut du = SMatrix::<f64, N, N>::zeros();
        for j in 0..N {
            let mut qj = qd;
            qj[j] = qj[j].derivative();
            let t = self.rbd.inverse_dynamics(&qj, &ud_, &udd);
            dq.set_column(j, &t.map(|x| x.eps));
            let mut uj = ud_;
            uj[j] = uj[j].derivative();
            let t = self.rbd.inverse_dynamics(&qd, &uj, &udd);
            du.set_column(j, &t.map(|x| x.eps));
        }
        (dq, du)
    }
}
