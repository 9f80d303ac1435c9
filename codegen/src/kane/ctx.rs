//! The derivation's state ([`Ctx`]) and its vocabulary: 3-vectors, 3×3 matrices and spatial
//! 6-vectors of expressions.

use kanegen_model::Model;

use crate::expr::{Arena, ExprId};
use crate::options::Options;

pub(super) type V3 = [ExprId; 3];
pub(super) type M3 = [[ExprId; 3]; 3];
/// A spatial vector: motion `(ω; v)` or force `(n; f)`.
pub(super) type V6 = [ExprId; 6];

pub(super) fn split3(x: &V6) -> (V3, V3) {
    ([x[0], x[1], x[2]], [x[3], x[4], x[5]])
}

pub(super) fn join3(a: &V3, b: &V3) -> V6 {
    [a[0], a[1], a[2], b[0], b[1], b[2]]
}

/// Component suffixes of substitution labels.
pub(super) const AXES: [&str; 3] = ["x", "y", "z"];

/// The derivation's state: the arena, the model, and the per-link caches of `iAj(q)` and
/// `iPj(q)`. Its methods are spread over the files of `kane`, one concern each.
pub(super) struct Ctx<'a> {
    pub(super) ar: &'a mut Arena,
    pub(super) model: &'a Model,
    pub(super) options: Options,
    pub(super) rot: Vec<Option<M3>>,
    pub(super) pos: Vec<Option<V3>>,
    /// `⁰A_l(q)`: the rotation of frame l relative to frame 0, cached.
    pub(super) root_rot: Vec<Option<M3>>,
    /// `⁰p_l(q)`: the origin of frame l in frame 0, cached.
    pub(super) root_pos: Vec<Option<V3>>,
    /// Keep the regressor parameters (inertial, wheel mass and inertias) as symbols even with
    /// baked parameters: set while a regressor's dynamics are derived.
    pub(super) keep_inertial: bool,
}
