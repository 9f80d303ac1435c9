//! Numeric evaluation of lowered programs: an interpreter that tests compare with the
//! reference dynamics and with the unlowered arena.

use super::program::*;
use crate::registry::FunctionId;

/// Numeric evaluation of lowered programs (an interpreter, for testing the lowering).
impl Lowered {
    /// Values of the precompute slots for parameter values `params`.
    pub fn precompute_values(&self, params: &[f64]) -> Vec<f64> {
        let locals = run(&self.precompute, params, &[], &[], &[], &[], &[]);
        self.pre_slots.iter().map(|&i| locals[i]).collect()
    }

    /// Evaluate function `id`; dense row-major matrix (both triangles of a symmetric one) or
    /// vector. Panics if the module does not have the function (a test helper).
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

    /// [`Lowered::evaluate`] for body frame `frame` (a link index) of a per-frame function
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
        let pre = self.precompute_values(params);
        let p = self
            .function_at(id, frame)
            .unwrap_or_else(|| panic!("the lowered model has no function `{id}`"));
        let values = output_values(p, params, &pre, q, &self.expand_angles(q), u, ud);
        let entries = p
            .outputs
            .iter()
            .zip(values)
            .map(|((r, c, _), v)| (*r, *c, v));
        id.spec().shape.dense_in(&self.sizes, entries)
    }
}

impl Lowered {
    /// The straight-line part of function `id`'s loop form at one state, if it has one: the
    /// `kin` table and the directly stored `(row, column, value)` entries (a test helper; the
    /// loop itself is `kanegen_runtime::regressor`).
    #[allow(clippy::type_complexity)]
    pub fn evaluate_loop_inputs(
        &self,
        id: FunctionId,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Option<(Vec<f64>, Vec<(usize, usize, f64)>)> {
        let lp = self
            .functions
            .iter()
            .find(|f| f.id == id)?
            .looped
            .as_ref()?;
        let pre = self.precompute_values(params);
        let p = &lp.program;
        let values = output_values(p, params, &pre, q, &self.expand_angles(q), u, ud);
        let kin = values[..lp.kin_len].to_vec();
        let extra = p.outputs[lp.kin_len..]
            .iter()
            .zip(&values[lp.kin_len..])
            .map(|((r, c, _), v)| (*r, *c, *v))
            .collect();
        Some((kin, extra))
    }
}

impl Lowered {
    /// Evaluate combined function `index` (in the order of [`Lowered::combined`]): per part, the
    /// dense value of its shape as [`Lowered::evaluate`] gives it. Panics if there is no such
    /// combined function (a test helper).
    pub fn evaluate_combined(
        &self,
        index: usize,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<Vec<f64>> {
        let pre = self.precompute_values(params);
        let c = &self.combined[index];
        let p = &c.program;
        let values = output_values(p, params, &pre, q, &self.expand_angles(q), u, ud);
        c.spec
            .parts
            .iter()
            .zip(&c.parts)
            .map(|(part, range)| {
                let entries = p.outputs[range.clone()]
                    .iter()
                    .zip(&values[range.clone()])
                    .map(|((r, col, _), v)| (*r, *col, *v));
                part.function.spec().shape.dense_in(&self.sizes, entries)
            })
            .collect()
    }

    /// The angle of every speed's `sin`/`cos` leaves, by speed index, from the coordinates `q`:
    /// `q` itself (a floating base's joint angles moved down by one, to their speeds' indices)
    /// extended by the angles of the dependent (mimic) speeds at their indices.
    pub fn expand_angles(&self, q: &[f64]) -> Vec<f64> {
        let len = self
            .mimic_angles
            .iter()
            .map(|(s, _)| s + 1)
            .max()
            .unwrap_or(0);
        let coord = |s: usize| if self.floating && s >= 6 { s + 1 } else { s };
        let mut out: Vec<f64> = (0..q.len() - usize::from(self.floating))
            .map(|s| q[coord(s)])
            .collect();
        if out.len() < len {
            out.resize(len, 0.0);
        }
        for (s, m) in &self.mimic_angles {
            out[*s] = m.multiplier * q[coord(m.master as usize)] + m.offset;
        }
        out
    }
}

struct EvalCtx<'a> {
    params: &'a [f64],
    pre: &'a [f64],
    q: &'a [f64],
    angles: &'a [f64],
    u: &'a [f64],
    ud: &'a [f64],
    locals: &'a [f64],
}

impl EvalCtx<'_> {
    fn eval(&self, e: &LExpr) -> f64 {
        match e {
            LExpr::Leaf(l) => match *l {
                Leaf::Const(c) => c,
                Leaf::Param(p) => self.params[p],
                Leaf::Pre(s) => self.pre[s],
                Leaf::Speed(s) => self.u[s],
                Leaf::Accel(s) => self.ud[s],
                Leaf::Sin(s) => self.angles[s].sin(),
                Leaf::Cos(s) => self.angles[s].cos(),
                Leaf::Coord(s) => self.q[s],
                Leaf::Local(i) => self.locals[i],
            },
            LExpr::Sum { constant, terms } => terms
                .iter()
                .fold(*constant, |acc, (k, t)| acc + k * self.eval(t)),
            LExpr::Prod(f) => f
                .iter()
                .fold(1.0, |acc, (b, p)| acc * self.eval(b).powi(*p)),
        }
    }
}

/// The values of `p`'s outputs, in order, at one input point (the coordinates `q` and the
/// angles of the `sin`/`cos` leaves, see [`Lowered::expand_angles`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn output_values(
    p: &Program,
    params: &[f64],
    pre: &[f64],
    q: &[f64],
    angles: &[f64],
    u: &[f64],
    ud: &[f64],
) -> Vec<f64> {
    let locals = run(p, params, pre, q, angles, u, ud);
    let ctx = EvalCtx {
        params,
        pre,
        q,
        angles,
        u,
        ud,
        locals: &locals,
    };
    p.outputs.iter().map(|(_, _, e)| ctx.eval(e)).collect()
}

#[allow(clippy::too_many_arguments)]
pub(super) fn run(
    p: &Program,
    params: &[f64],
    pre: &[f64],
    q: &[f64],
    angles: &[f64],
    u: &[f64],
    ud: &[f64],
) -> Vec<f64> {
    let mut locals: Vec<f64> = Vec::with_capacity(p.stmts.len());
    for s in &p.stmts {
        let v = EvalCtx {
            params,
            pre,
            q,
            angles,
            u,
            ud,
            locals: &locals,
        }
        .eval(&s.expr);
        locals.push(v);
    }
    locals
}
