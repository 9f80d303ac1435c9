//! The looped form of `inverse_dynamics_derivatives`: the same analytic recursion as
//! `rnea_derivatives.rs`, split into a straight-line part and a loop.
//!
//! The straight-line part (generated statements, as every function's) computes what is per
//! link or per column into a workspace: each link's transform to its parent (`R`, `P`), each
//! speed's `S`, `Ψ̇`, `Ψ̈`, and each column's four forces `Φ`, `Ξ`, `H`, `G` in its own frame
//! (τ's pass, composite inertias, subtree momenta and inertia rates come first, as in the
//! straight-line form). The O(columns × ancestors) part, carrying the four forces of each column
//! up to the root and reading them with every ancestor speed, is
//! `kanegen_runtime::derivatives_loop::run` over the generated [`DerivativeLoop`] tables: one
//! small loop instead of Krang's ~100 unrolled steps (233 KB of code, beyond the instruction
//! cache).
//!
//! Models with mimic joints keep the straight-line form (their columns and rows are sums over
//! the constraint's joints; the tables do not express them).

use super::ctx::Ctx;
use super::rnea_derivatives::Setup;
use crate::expr::ExprId;

/// The tables of the looped derivatives (mirrors of `kanegen_runtime::derivatives_loop`'s
/// `Link`, `Speed`, `Column`, emitted as a `const`), and the size of the workspace the
/// generated statements fill.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DerivativeLoop {
    /// Number of speeds N (the result is N × 2N).
    pub dof: usize,
    /// Workspace length.
    pub workspace: usize,
    /// Per link: parent link (`None` for the root), workspace offset of `R` (by rows) and `P`,
    /// and its range of [`DerivativeLoop::speeds`].
    pub links: Vec<DerivativeLink>,
    /// The speeds, grouped by link: result index, workspace offset of `S`, `Ψ̇`, `Ψ̈`, and
    /// whether it is a joint's speed (else the wheeled base's).
    pub speeds: Vec<LoopSpeed>,
    /// The columns in run order: link, index in `speeds`, workspace offset of the forces.
    pub columns: Vec<LoopColumn>,
    /// A floating base: workspace offset of its twist `V_0 = (ω; v)` and gravity `g_b` (9
    /// values), which its root step reads instead of one step per base speed (see
    /// [`FlatStep::root`]); `None` for other bases.
    pub floating_root: Option<usize>,
}

/// One link of a [`DerivativeLoop`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DerivativeLink {
    /// The parent link; `None` for the root.
    pub parent: Option<usize>,
    /// Workspace offset of the transform to the parent (`R` by rows, then `P`).
    pub transform: usize,
    /// The link's speeds, a range of [`DerivativeLoop::speeds`].
    pub speeds: std::ops::Range<usize>,
}

/// One speed of a [`DerivativeLoop`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopSpeed {
    /// Result row (and column) index.
    pub index: usize,
    /// Workspace offset of `S`, `Ψ̇`, `Ψ̈` (6 each).
    pub motion: usize,
    /// A joint's speed (`true`) or one of the wheeled or floating base's.
    pub joint: bool,
    /// A floating base's rotation speed: its `Ψ̈` slot holds `(0; e_k × g_b)` and its column of
    /// `∂τ/∂q` is `Φ · Ψ̈` (see `rnea_derivatives.rs`), read by every column, the base's own
    /// included.
    pub rotation: bool,
    /// `Some(k)` when `S = ±(e_k; 0)` (a rotation about a coordinate axis of the link's frame,
    /// `k < 3`): `Ψ̇ = V_λ × S` vanishes in components `k` and `3 + k`.
    pub axis: Option<u8>,
}

/// One column of a [`DerivativeLoop`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopColumn {
    /// The link of the speed.
    pub link: usize,
    /// Index in [`DerivativeLoop::speeds`].
    pub speed: usize,
    /// Workspace offset of `Φ`, `Ξ`, `H`, `G`, component-major (24 entries).
    pub forces: usize,
}

/// One step of a column's walk in the flat tables (`kanegen_runtime::derivatives_loop::Step`):
/// the forces moved up one link (unless `transform` is `None`), then one speed's reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FlatStep {
    /// Workspace offset of the transform from the link below; `None` for the rows of the
    /// column's own link and for a second speed of the same link.
    pub transform: Option<usize>,
    /// The speed read, index in [`DerivativeLoop::speeds`].
    pub speed: usize,
    /// The four result offsets (column-major `N × 2N`) the step writes, `None` where it writes
    /// nothing: `∂τ_a/∂q_i`, `∂τ_a/∂u_i`, `∂τ_i/∂q_a`, `∂τ_i/∂u_a` for the step's speed `a`
    /// and the column's speed `i`. For a [`root`](Self::root) step, the first offset of each
    /// of the four runs it writes instead: `∂τ_a/∂q_i` and `∂τ_a/∂u_i` for the six base
    /// speeds `a` (consecutive), `∂τ_i/∂q_a` for the three rotations and `∂τ_i/∂u_a` for the
    /// six speeds (every `N` entries).
    pub entries: [Option<usize>; 4],
    /// A floating base's root step (`kanegen_runtime::derivatives_loop::FLOATING_ROOT`): the
    /// six base speeds read at once from `V_0` and `g_b`, their `S` being unit vectors: `S_a ·
    /// G`, `S_a · H` and `Ξ · S_a` are components, `Φ · (V_0 × S_a)` the components of
    /// `−V_0 ×* Φ`, and `Φ · (0; e_k × g_b)` those of `g_b × f_Φ`.
    pub root: bool,
}

impl FlatStep {
    /// The result offsets the step writes (for a table of `n` speeds).
    pub fn writes(&self, n: usize) -> Vec<usize> {
        if !self.root {
            return self.entries.into_iter().flatten().collect();
        }
        let runs = [(6, 1), (6, 1), (3, n), (6, n)];
        self.entries
            .iter()
            .zip(runs)
            .filter_map(|(e, run)| e.map(|e| (e, run)))
            .flat_map(|(e, (len, stride))| (0..len).map(move |k| e + k * stride))
            .collect()
    }
}

/// One column of the flat tables: its forces and its range of steps, the own link's rows
/// first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FlatColumn {
    /// Workspace offset of the column's four forces.
    pub forces: usize,
    /// First step.
    pub first: usize,
    /// End of the own link's rows.
    pub own: usize,
    /// End of the column's steps.
    pub end: usize,
}

impl DerivativeLoop {
    /// Number of steps up (one force transform of the four forces each).
    pub fn steps(&self) -> usize {
        self.columns
            .iter()
            .map(|c| {
                let mut n = 0;
                let mut l = c.link;
                while let Some(p) = self.links[l].parent {
                    n += 1;
                    l = p;
                }
                n
            })
            .sum()
    }

    /// Floating-point operations of the loop per call, as `derivatives_loop::run` performs
    /// them on the [`flatten`](Self::flatten)ed tables (dense: the loop does not skip the zeros
    /// of axis-aligned joints).
    pub fn flops(&self) -> usize {
        // A step: 4 forces × (R f, R n: 2 × 15; P × f: 9; the sum: 3).
        let step = 4 * 42;
        // A dot product of a motion with the four forces: 4 × 11.
        let dots = 44;
        let (columns, steps) = self.flatten();
        let ancestor = |s: &FlatStep| {
            // S, Ψ̇ (and Ψ̈) dots, then the sums of the two column entries.
            let speed = self.speeds[s.speed];
            let reads = if speed.joint {
                3 * dots + 3
            } else if speed.rotation {
                3 * dots + 1
            } else {
                2 * dots + 1
            };
            // The root step: −V_0 ×* Φ on one lane (30), g_b × f_Φ (9), Ξ · S_a − (…)_a (6).
            let reads = if s.root { 45 } else { reads };
            s.transform.map_or(0, |_| step) + reads
        };
        // A row of the own link: the S dots (and a floating base's rotation's Ψ̈ dots).
        let own = |s: &FlatStep| {
            if s.entries[2].is_some() {
                2 * dots
            } else {
                dots
            }
        };
        columns
            .iter()
            .map(|c| {
                steps[c.first..c.own].iter().map(own).sum::<usize>()
                    + steps[c.own..c.end].iter().map(ancestor).sum::<usize>()
            })
            .sum()
    }

    /// Every column's walk to the root as one run of steps (the runtime's flat tables): the
    /// rows of its own link, then one step per speed of each ancestor link, from the parent up.
    pub fn flatten(&self) -> (Vec<FlatColumn>, Vec<FlatStep>) {
        let n = self.dof;
        let mut columns = Vec::with_capacity(self.columns.len());
        let mut steps = Vec::new();
        for c in &self.columns {
            let this = self.speeds[c.speed];
            let ci = this.index;
            let first = steps.len();
            for a in self.links[c.link].speeds.clone() {
                let s = self.speeds[a];
                let ai = s.index;
                steps.push(FlatStep {
                    transform: None,
                    speed: a,
                    entries: [
                        this.joint.then_some(ai + n * ci),
                        Some(ai + n * (n + ci)),
                        s.rotation.then_some(ci + n * ai),
                        None,
                    ],
                    root: false,
                });
            }
            let own = steps.len();
            let mut l = c.link;
            while let Some(p) = self.links[l].parent {
                let mut transform = Some(self.links[l].transform);
                if p == 0 && self.floating_root.is_some() {
                    // The base speeds are the first six, on the root.
                    debug_assert!((0..6).all(|a| self.speeds[a].index == a));
                    steps.push(FlatStep {
                        transform,
                        speed: self.links[0].speeds.start,
                        entries: [
                            this.joint.then_some(n * ci),
                            Some(n * (n + ci)),
                            Some(ci + 3 * n),
                            Some(ci + n * n),
                        ],
                        root: true,
                    });
                    l = p;
                    continue;
                }
                for a in self.links[p].speeds.clone() {
                    let s = self.speeds[a];
                    let ai = s.index;
                    steps.push(FlatStep {
                        transform: transform.take(),
                        speed: a,
                        entries: [
                            this.joint.then_some(ai + n * ci),
                            Some(ai + n * (n + ci)),
                            (s.joint || s.rotation).then_some(ci + n * ai),
                            Some(ci + n * (n + ai)),
                        ],
                        root: false,
                    });
                }
                l = p;
            }
            columns.push(FlatColumn {
                forces: c.forces,
                first,
                own,
                end: steps.len(),
            });
        }
        (columns, steps)
    }

    /// Whether every offset and index fits the runtime tables: workspace offsets in `u16`,
    /// result offsets and step indices in `u32` (the largest value of each marks a step
    /// without a transform or an entry not written).
    pub fn fits_tables(&self) -> bool {
        let max16 = usize::from(u16::MAX - 1);
        let max32 = usize::try_from(u32::MAX - 1).unwrap_or(usize::MAX);
        let flat_steps = self.flatten().1.len();
        self.workspace <= max16
            && self.dof.saturating_mul(2 * self.dof) <= max32
            && flat_steps <= max32
    }
}

impl Ctx<'_> {
    /// `Some(k)` when `s` is `±(e_k; 0)` exactly (constants), else `None`.
    fn rotation_axis(&self, s: &[ExprId; 6]) -> Option<u8> {
        let value = |e: ExprId| self.ar.as_const(e);
        let mut axis = None;
        for (k, &e) in s.iter().enumerate() {
            match value(e) {
                Some(0.0) => {}
                Some(v) if k < 3 && v.abs() == 1.0 && axis.is_none() => axis = Some(k as u8),
                _ => return None,
            }
        }
        axis
    }

    /// The workspace entries `(offset, 0, expr)` and the tables of the looped derivatives (see
    /// the module documentation). Only for models without mimic joints.
    pub(super) fn inverse_dynamics_derivatives_looped(
        &mut self,
    ) -> (Vec<(usize, usize, ExprId)>, DerivativeLoop) {
        let model = self.model;
        debug_assert!(model.mimics.is_empty());
        let links = model.links.len();
        let Setup {
            columns,
            comp,
            hc,
            dc,
            f,
            n,
        } = self.derivative_setup();
        let zero = self.ar.zero();
        // Links that a column is carried up from.
        let mut stepped = vec![false; links];
        for l in 0..links {
            if !columns[l].is_empty() {
                for (child, _) in model.path_to_base(l) {
                    stepped[child] = true;
                }
            }
        }
        let mut ws: Vec<ExprId> = Vec::new();
        let push = |ws: &mut Vec<ExprId>, xs: &[ExprId]| {
            let at = ws.len();
            ws.extend_from_slice(xs);
            at
        };
        let mut plan = DerivativeLoop {
            dof: model.independent_dof(),
            workspace: 0,
            links: Vec::with_capacity(links),
            speeds: Vec::new(),
            columns: Vec::new(),
            floating_root: None,
        };
        // Transforms and motions.
        for l in 0..links {
            let mount = model.links[l].mount.as_ref();
            let transform = match mount {
                Some(m) if stepped[l] => {
                    let r = self.rotation(l, &m.joint);
                    let p = self.position(l, &m.joint);
                    let mut t = r.concat().to_vec();
                    t.extend_from_slice(&p);
                    push(&mut ws, &t)
                }
                _ => 0,
            };
            let first = plan.speeds.len();
            for col in &columns[l] {
                let mut m = col.s.to_vec();
                m.extend_from_slice(&col.psid);
                m.extend_from_slice(&col.psidd.or(col.rotation).unwrap_or([zero; 6]));
                let motion = push(&mut ws, &m);
                plan.speeds.push(LoopSpeed {
                    index: col.speed,
                    motion,
                    joint: col.psidd.is_some(),
                    rotation: col.rotation.is_some(),
                    axis: self.rotation_axis(&col.s),
                });
            }
            plan.links.push(DerivativeLink {
                parent: mount.map(|m| m.parent),
                transform,
                speeds: first..plan.speeds.len(),
            });
        }
        // A floating base's twist (ω; v) and gravity, for its root step.
        if model.is_floating() {
            let mut x: Vec<ExprId> = [3u32, 4, 5, 0, 1, 2]
                .map(|s| self.ar.atom(crate::expr::Atom::Speed(s)))
                .to_vec();
            x.extend_from_slice(&self.gravity_vector());
            plan.floating_root = Some(push(&mut ws, &x));
        }
        // The columns' forces, leaves first (the straight-line form's order).
        for l in (0..links).rev() {
            for (k, col) in columns[l].iter().enumerate() {
                let c = self.derivative_forces(l, col, &comp, &hc, &dc, &f, &n);
                let g = c.g.unwrap_or([zero; 6]);
                let x: Vec<ExprId> = (0..6)
                    .flat_map(|i| [c.phi[i], c.xi[i], c.h[i], g[i]])
                    .collect();
                let forces = push(&mut ws, &x);
                plan.columns.push(LoopColumn {
                    link: l,
                    speed: plan.links[l].speeds.start + k,
                    forces,
                });
            }
        }
        plan.workspace = ws.len();
        // Schedule: transforms and motions, then the columns from the leaves, each right after
        // what it reads.
        self.ar.begin_phase();
        for &e in &ws {
            self.ar.touch_tree(e);
        }
        let entries = ws.into_iter().enumerate().map(|(i, e)| (i, 0, e)).collect();
        (entries, plan)
    }
}
