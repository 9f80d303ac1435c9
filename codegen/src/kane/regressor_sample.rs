//! The regressor evaluated numerically at random states (a small deterministic generator, so
//! that what is found from the samples depends on the model alone): what the base parameters
//! and the symbolic groups are found from.

use kanegen_model::Model;

use crate::expr::{Arena, ExprId, Values};

/// A small deterministic generator (xorshift64*): the base parameters, and with them the
/// generated code, must not depend on anything but the model.
pub(super) struct Rng(pub(super) u64);

impl Rng {
    /// Uniform in `[0, 1)`.
    pub(super) fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (x >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[-a, a]`.
    pub(super) fn sym(&mut self, a: f64) -> f64 {
        a * (2.0 * self.next() - 1.0)
    }
}

/// The dense regressor (`independent_dof × cols`, row-major) of `entries` at one random state,
/// with the model parameter values `params`. `entries` are the whole tree's rows; a mimic model's are projected by the constraint map
/// (`Tᵀ Y`, as the generated function is), so that the base parameters are those of the reduced
/// model.
pub(super) fn regressor_at(
    ar: &Arena,
    entries: &[(usize, usize, ExprId)],
    model: &Model,
    params: &[f64],
    needed: &[bool],
    cols: usize,
    rng: &mut Rng,
) -> Vec<f64> {
    let n = model.dof();
    // A floating base's q has one entry more: its quaternion, scaled to unit norm.
    let nq = n + usize::from(model.is_floating());
    let mut q: Vec<f64> = (0..nq).map(|_| rng.sym(std::f64::consts::PI)).collect();
    if model.is_floating() {
        let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
        q[3..7].iter_mut().for_each(|x| *x /= norm);
    }
    let u: Vec<f64> = (0..n).map(|_| rng.sym(2.0)).collect();
    let ud: Vec<f64> = (0..n).map(|_| rng.sym(2.0)).collect();
    let vals = ar.eval_needed(
        &Values {
            params,
            q: &q,
            u: &u,
            ud: &ud,
        },
        needed,
    );
    let map = model.constraint_map();
    let mut y = vec![0.0; model.independent_dof() * cols];
    for &(r, c, e) in entries {
        let (row, factor) = map[r];
        y[row * cols + c] += factor * vals[e.index()];
    }
    y
}
