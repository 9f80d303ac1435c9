//! The state the conversion passes between its steps: the URDF resolved against the options
//! ([`Resolved`]) and the IR under construction ([`Ir`]).

use std::collections::HashMap;

use super::cut::BaseCut;
use super::inertia::{Clusters, Inertial};
use super::transform::Tf;
use super::tree::Tree;
use crate::ir::*;

/// The URDF with the options applied: what is kept, where the base is, the joint origins, the
/// link inertials and the rigid clusters.
pub(super) struct Resolved<'a> {
    /// The URDF's link/joint graph.
    pub(super) tree: Tree<'a>,
    /// Per link: removed by [`UrdfOptions::drop_links`].
    pub(super) dropped: Vec<bool>,
    /// The top of the kept tree, the body link and the wheels.
    pub(super) cut: BaseCut,
    /// The kept links, depth first from the top (wheel subtrees included, dropped links not).
    pub(super) kept: Vec<usize>,
    /// Per joint: its origin, for the joints above the kept links other than the top.
    pub(super) origin: Vec<Option<Tf>>,
    /// Per kept link: its inertial data (`None` without mass or when dropped as absurd).
    pub(super) inertial: Vec<Option<Inertial>>,
    /// The rigid clusters (links joined by fixed joints).
    pub(super) clusters: Clusters,
}

/// The IR under construction.
pub(super) struct Ir {
    /// Parameters; the first is the gravity magnitude `g`.
    pub(super) params: Vec<Param>,
    /// Generalized speeds in the order of `u`.
    pub(super) speeds: Vec<Speed>,
    /// Frames, parents first.
    pub(super) links: Vec<Link>,
    /// The IR frame of each URDF link that is one (the representatives of the rigid clusters).
    pub(super) ir_index: HashMap<usize, usize>,
    /// The gravity magnitude `g`.
    pub(super) gravity: ParamId,
}

impl Ir {
    /// No frames or speeds yet; the parameter `g` with the default value `gravity`.
    pub(super) fn new(gravity: f64) -> Self {
        let mut ir = Self {
            params: Vec::new(),
            speeds: Vec::new(),
            links: Vec::new(),
            ir_index: HashMap::new(),
            gravity: 0,
        };
        ir.gravity = ir.param("g".into(), gravity, ParamKind::Gravity);
        ir
    }

    /// Adds a parameter (`-0.0` stored as `0.0`) and returns its index.
    pub(super) fn param(&mut self, name: String, value: f64, kind: ParamKind) -> ParamId {
        self.params.push(Param {
            name,
            value: if value == 0.0 { 0.0 } else { value },
            kind,
        });
        self.params.len() - 1
    }
}
