//! Derivatives of a [`FreeFlyer`]'s inverse dynamics in the tangent space, by forward-mode dual
//! numbers ([`num_dual::Dual64`]): column `i` of `∂τ/∂q` is `d/dε τ(q ⊕ ε eᵢ, u, u̇)` at `ε = 0`,
//! with `⊕` the SE(3) exponential on the base ([`crate::se3::integrate`]), as Pinocchio's
//! `computeRNEADerivatives` (`u`, `u̇` in the base frame held fixed); `∂τ/∂u` is the plain
//! derivative. Exact: no step size.

use nalgebra::DMatrix;
use num_dual::Dual64;

use crate::free_flyer::FreeFlyer;
use crate::se3::integrate;

impl FreeFlyer<f64> {
    /// `(∂τ/∂q, ∂τ/∂u)` at `(q, u, u̇)`, both DOF × DOF, `∂τ/∂q` in the tangent space (see the
    /// module docs).
    ///
    /// # Panics
    /// If a slice has the wrong length.
    pub fn inverse_dynamics_derivatives(
        &self,
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = self.dof();
        assert_eq!(q.len(), self.nq(), "`q` has {} entries, not NQ", q.len());
        let params: Vec<Dual64> = self.params().iter().map(|&p| Dual64::from_re(p)).collect();
        let dual = FreeFlyer::<Dual64>::with_params(self.model(), &params)
            .expect("the model was accepted in f64");
        let lift = |x: &[f64]| x.iter().map(|&v| Dual64::from_re(v)).collect::<Vec<_>>();
        let (ql, ul, udl) = (lift(q), lift(u), lift(ud));
        let mut dq = DMatrix::zeros(n, n);
        let mut du = DMatrix::zeros(n, n);
        for i in 0..n {
            let mut delta = vec![Dual64::from_re(0.0); n];
            delta[i] = Dual64::from_re(0.0).derivative();
            let qi = integrate(&ql, &delta, Dual64::from_re(1.0));
            let t = dual.inverse_dynamics(&qi, &ul, &udl);
            dq.set_column(i, &t.map(|x| x.eps));
            let mut ui = ul.clone();
            ui[i] = ui[i].derivative();
            let t = dual.inverse_dynamics(&ql, &ui, &udl);
            du.set_column(i, &t.map(|x| x.eps));
        }
        (dq, du)
    }
}
