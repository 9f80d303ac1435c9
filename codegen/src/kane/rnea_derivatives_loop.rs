//! The looped form of `inverse_dynamics_derivatives`: the same analytic recursion as
//! `rnea_derivatives.rs`, split into a straight-line part and a loop.
//!
//! The straight-line part (generated statements, as every function's) computes what is per
//! link or per column into a workspace: each link's transform to its parent (`R`, `P`), each
//! speed's `S`, `Ψ̇`, `Ψ̈`, and each column's four forces `Φ`, `Ξ`, `H`, `G` in its own frame
//! (τ's pass, composite inertias, subtree momenta and inertia rates come first, as in the
//! straight-line form). The O(columns × ancestors) part, carrying the four forces of each column
//! up to the root and reading them with every ancestor speed, is
//! `kanegen_runtime::derivative_steps::run` over the generated [`DerivativeLoop`] tables: one
//! small loop instead of Krang's ~100 unrolled steps (233 KB of code, beyond the instruction
//! cache).
//!
//! Models with mimic joints keep the straight-line form (their columns and rows are sums over
//! the constraint's joints; the tables do not express them).

use super::Ctx;
use super::rnea_derivatives::Setup;
use crate::expr::ExprId;

/// The tables of the looped derivatives (mirrors of `kanegen_runtime::derivative_steps`'s
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
    /// A joint's speed (`true`) or one of the wheeled base's.
    pub joint: bool,
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

/// One step of a column's walk in the flat tables (`kanegen_runtime::derivative_steps::Step`):
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
    /// and the column's speed `i`.
    pub entries: [Option<usize>; 4],
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

    /// Floating-point operations of the loop per call, as `derivative_steps::run` performs
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
            let reads = if self.speeds[s.speed].joint {
                3 * dots + 3
            } else {
                2 * dots + 1
            };
            s.transform.map_or(0, |_| step) + reads
        };
        columns
            .iter()
            .map(|c| {
                (c.own - c.first) * dots + steps[c.own..c.end].iter().map(ancestor).sum::<usize>()
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
                let ai = self.speeds[a].index;
                steps.push(FlatStep {
                    transform: None,
                    speed: a,
                    entries: [
                        this.joint.then_some(ai + n * ci),
                        Some(ai + n * (n + ci)),
                        None,
                        None,
                    ],
                });
            }
            let own = steps.len();
            let mut l = c.link;
            while let Some(p) = self.links[l].parent {
                let mut transform = Some(self.links[l].transform);
                for a in self.links[p].speeds.clone() {
                    let s = self.speeds[a];
                    let ai = s.index;
                    steps.push(FlatStep {
                        transform: transform.take(),
                        speed: a,
                        entries: [
                            this.joint.then_some(ai + n * ci),
                            Some(ai + n * (n + ci)),
                            s.joint.then_some(ci + n * ai),
                            Some(ci + n * (n + ai)),
                        ],
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
                m.extend_from_slice(&col.psidd.unwrap_or([zero; 6]));
                let motion = push(&mut ws, &m);
                plan.speeds.push(LoopSpeed {
                    index: col.speed,
                    motion,
                    joint: col.psidd.is_some(),
                    axis: self.rotation_axis(&col.s),
                });
            }
            plan.links.push(DerivativeLink {
                parent: mount.map(|m| m.parent),
                transform,
                speeds: first..plan.speeds.len(),
            });
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

#[cfg(test)]
mod tests {
    //! The looped form (the workspace evaluated from the generator's expressions, then the
    //! runtime's loop) against the straight-line form, on random parameters and states, for
    //! every kind of joint and base the models have (mimic joints keep the straight-line form).

    use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
    use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
    use kanegen_runtime::derivative_steps::{Column, NO_ENTRY, NO_TRANSFORM, Plan, Step};

    use crate::expr::Values;
    use crate::options::{Options, ParamMode};
    use crate::registry::{FunctionId, FunctionSet};

    fn models_dir() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models")
    }

    /// Worst `max |looped − straight| / max(max |straight|, 1)` over `draws` random draws.
    fn compare(label: &str, model: &Model, params: ParamMode, draws: usize, seed: u64) {
        let options = Options {
            params,
            functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
        };
        let d = super::super::derive(model, options);
        let looped = d
            .derivative_loop
            .as_ref()
            .expect("no mimic joints: looped form derived");
        let plan = &looped.plan;
        let u16_of = |x: usize| u16::try_from(x).expect("fits");
        let u32_of = |x: usize| u32::try_from(x).expect("fits");
        let (flat_columns, flat_steps) = plan.flatten();
        let steps: Vec<Step> = flat_steps
            .iter()
            .map(|s| {
                let speed = plan.speeds[s.speed];
                Step {
                    transform: s.transform.map_or(NO_TRANSFORM, u16_of),
                    motion: u16_of(speed.motion),
                    axis: speed
                        .axis
                        .unwrap_or(kanegen_runtime::derivative_steps::DENSE),
                    joint: speed.joint,
                    entries: s.entries.map(|e| e.map_or(NO_ENTRY, u32_of)),
                }
            })
            .collect();
        let columns: Vec<Column> = flat_columns
            .iter()
            .map(|c| Column {
                forces: u16_of(c.forces),
                first: u32_of(c.first),
                own: u32_of(c.own),
                end: u32_of(c.end),
            })
            .collect();
        let tables = Plan {
            dof: plan.dof,
            columns: &columns,
            steps: &steps,
        };
        let n = model.independent_dof();
        let mut rng = SplitMix64::new(seed);
        let mut uni = move || rng.next_f64();
        let pi = std::f64::consts::PI;
        let mut worst = 0.0f64;
        for draw in 0..draws {
            let p = if draw == 0 || params == ParamMode::Baked {
                model.param_values()
            } else {
                random_physical_params(model, &mut uni)
            };
            let q = uniform_vec(&mut uni, model.dof(), -pi, pi);
            let u = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
            let ud = uniform_vec(&mut uni, model.dof(), -2.0, 2.0);
            // Row-major N × 2N.
            let straight = d.evaluate(FunctionId::InverseDynamicsDerivatives, &p, &q, &u, &ud);
            let x = Values {
                params: &p,
                q: &q,
                u: &u,
                ud: &ud,
            };
            let v = d.arena.eval(&x);
            let mut w = vec![0.0; plan.workspace];
            for &(k, _, e) in &looped.entries {
                w[k] = v[e.index()];
            }
            // Column-major N × 2N: the dispatched kernel (the AVX2 copy on x86-64-v3 CPUs)
            // and the portable one.
            let mut out = vec![0.0; n * 2 * n];
            kanegen_runtime::derivative_steps::run(&tables, &w, &mut out);
            let mut portable = vec![0.0; n * 2 * n];
            kanegen_runtime::derivative_steps::run_generic(&tables, &w, &mut portable);
            let scale = straight.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            for r in 0..n {
                for c in 0..2 * n {
                    let b = straight[r * 2 * n + c];
                    for (kernel, a) in [("run", out[r + n * c]), ("portable", portable[r + n * c])]
                    {
                        let e = (a - b).abs() / scale;
                        assert!(
                            e < 1e-12,
                            "{label}: draw {draw}, entry [{r}, {c}]: looped ({kernel}) {a} vs straight-line {b}"
                        );
                        worst = worst.max(e);
                    }
                }
            }
        }
        eprintln!("{label}: {draws} draws, worst relative difference {worst:.1e}");
    }

    #[test]
    fn looped_derivatives_equal_the_straight_line_form_on_trees_and_wheeled_bases() {
        let toml = |name: &str| Model::from_toml_file(models_dir().join(name)).expect("loads");
        compare("krang", &toml("krang.toml"), ParamMode::Runtime, 20, 11);
        compare("krang, baked", &toml("krang.toml"), ParamMode::Baked, 2, 12);
        compare(
            "fixed wheels",
            &toml("krang-fixed-wheels.toml"),
            ParamMode::Runtime,
            20,
            13,
        );
        compare(
            "two-link",
            &toml("two-link.toml"),
            ParamMode::Runtime,
            50,
            14,
        );
        let arm =
            Model::from_urdf_file(models_dir().join("singlearm.urdf"), &UrdfOptions::default())
                .expect("imports");
        compare("arm", &arm, ParamMode::Runtime, 20, 15);
        let spec = WheeledBaseSpec::new(
            "left_wheel_joint",
            "right_wheel_joint",
            "chassis",
            [0.0, 0.0, 1.0],
            0.2,
        );
        let lift = Model::from_urdf_str(
            include_str!("../../tests/data/lift.urdf"),
            "lift.urdf",
            &UrdfOptions::wheeled(spec),
        )
        .expect("imports");
        compare("lift on a wheeled base", &lift, ParamMode::Runtime, 50, 16);
    }

    #[test]
    fn flat_tables_write_every_entry_once_and_move_once_per_ancestor_link() {
        let krang = Model::from_toml_file(models_dir().join("krang.toml")).expect("loads");
        let options = Options {
            params: ParamMode::Runtime,
            functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
        };
        let d = super::super::derive(&krang, options);
        let plan = &d
            .derivative_loop
            .as_ref()
            .expect("looped form derived")
            .plan;
        let (columns, steps) = plan.flatten();
        assert!(plan.fits_tables());
        // Each result entry has one writer, so the loop may run the columns in any order.
        let n = plan.dof;
        let mut writers = vec![0usize; 2 * n * n];
        for s in &steps {
            for e in s.entries.into_iter().flatten() {
                writers[e] += 1;
            }
        }
        assert!(writers.iter().all(|&w| w <= 1), "an entry written twice");
        // The columns' runs tile the steps; a run moves the forces once per ancestor link.
        assert_eq!(columns.last().map(|c| c.end), Some(steps.len()));
        let mut moves = 0;
        for (k, c) in columns.iter().enumerate() {
            assert_eq!(c.first, k.checked_sub(1).map_or(0, |j| columns[j].end));
            assert!(c.first <= c.own && c.own <= c.end);
            assert!(steps[c.first..c.own].iter().all(|s| s.transform.is_none()));
            moves += steps[c.own..c.end]
                .iter()
                .filter(|s| s.transform.is_some())
                .count();
        }
        assert_eq!(moves, plan.steps(), "one transform per step up");
    }

    #[test]
    fn models_with_mimic_joints_keep_the_straight_line_form() {
        let gripper = Model::from_urdf_file(
            models_dir().join("mimic_gripper.urdf"),
            &UrdfOptions::default(),
        )
        .expect("imports");
        let options = Options {
            params: ParamMode::Runtime,
            functions: FunctionSet::default().with(FunctionId::InverseDynamicsDerivatives),
        };
        assert!(
            super::super::derive(&gripper, options)
                .derivative_loop
                .is_none()
        );
    }
}
