//! The looped form of `inverse_dynamics_derivatives`: the same analytic recursion as
//! `rnea_derivatives.rs`, split into a straight-line part and a loop.
//!
//! The straight-line part (generated statements, as every function's) computes what is per
//! link or per column into a workspace: each link's pose in frame 0 (`⁰R`, `⁰p`), each speed's
//! `S`, `Ψ̇`, `Ψ̈` moved to frame 0 (`ω₀ = ⁰R ω`, `v₀ = ⁰R v + ⁰p × ω₀`: sparse for
//! axis-aligned joints, whose `S` in frame 0 is a column of `⁰R` and `⁰p ×` that), and each
//! column's four forces `Φ`, `Ξ`, `H`, `G` in its own frame (τ's pass, composite inertias,
//! subtree momenta and inertia rates come first, as in the straight-line form). The
//! O(columns × ancestors) part is `kanegen_runtime::derivative_steps::run` over the generated
//! [`DerivativeLoop`] tables: it moves each column's forces to frame 0 once and reads them with
//! every speed on the column's path to the root — dot products of a motion and a force, the
//! same in any frame, so no transform per (column, ancestor) step.
//!
//! Models with mimic joints keep the straight-line form (their columns and rows are sums over
//! the constraint's joints; the tables do not express them).

use super::Ctx;
use super::algebra::{V6, join3, split3};
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
    /// Per link: parent link (`None` for the root), workspace offset of its pose in frame 0
    /// (`⁰R` by rows and `⁰p`; links with speeds), and its range of [`DerivativeLoop::speeds`].
    pub links: Vec<DerivativeLink>,
    /// The speeds, grouped by link: result index and workspace offset of their motions in
    /// frame 0.
    pub speeds: Vec<LoopSpeed>,
    /// The columns in run order: link, index in `speeds`, workspace offset of the forces.
    pub columns: Vec<LoopColumn>,
}

/// One link of a [`DerivativeLoop`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DerivativeLink {
    /// The parent link; `None` for the root.
    pub parent: Option<usize>,
    /// Workspace offset of the link's pose in frame 0 (`⁰R` by rows, then `⁰p`); 0 for links
    /// without speeds (not read).
    pub transform: usize,
    /// The link's speeds, a range of [`DerivativeLoop::speeds`].
    pub speeds: std::ops::Range<usize>,
}

/// One speed of a [`DerivativeLoop`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopSpeed {
    /// Result row (and column) index.
    pub index: usize,
    /// Workspace offset of its motions in frame 0, `MOTION_LANES` = 6 lanes per component:
    /// `[S, S, S, j Ψ̇, k Ψ̇, j Ψ̈]` (`j` = 1 for a joint, 0 for the wheeled base's speeds; `k` =
    /// 2 for a joint, 1 for the base), see `kanegen_runtime::derivative_steps::Speed::motion`.
    pub motion: usize,
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

impl DerivativeLoop {
    /// Number of (column, ancestor link) steps up.
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

    /// Number of (column, speed) pairs the loop writes entries for: the speeds of the column's
    /// own link and of every ancestor link.
    pub fn pairs(&self) -> usize {
        self.columns
            .iter()
            .map(|c| {
                let mut n = self.links[c.link].speeds.len();
                let mut l = c.link;
                while let Some(p) = self.links[l].parent {
                    n += self.links[p].speeds.len();
                    l = p;
                }
                n
            })
            .sum()
    }

    /// Floating-point operations of the loop per call, as `derivative_steps::run` performs
    /// them (dense lanes: the zeros of axis-aligned joints are the straight-line part's).
    pub fn flops(&self) -> usize {
        // A column's four forces to frame 0: 4 × (R f, R n: 2 × 15; p × f: 9; the sum: 3).
        let column = 4 * 42;
        // Own link: the 4-wide chain of 6 products (4 × 11); an ancestor speed adds the
        // 2-wide chain (2 × 11) and the 2-wide sum.
        let own = 44;
        let ancestor = 44 + 22 + 2;
        let mut total = 0;
        for c in &self.columns {
            total += column + self.links[c.link].speeds.len() * own;
            let mut l = c.link;
            while let Some(p) = self.links[l].parent {
                total += self.links[p].speeds.len() * ancestor;
                l = p;
            }
        }
        total
    }

    /// Whether every offset and index fits the runtime tables' `u16`.
    pub fn fits_u16(&self) -> bool {
        let max = usize::from(u16::MAX - 1);
        self.workspace <= max && self.links.len() <= max && self.speeds.len() <= max
    }
}

impl Ctx<'_> {
    /// A motion `(ω; v)` of frame `l` (v of its origin) in frame 0, about frame 0's origin:
    /// `(⁰R ω; ⁰R v + ⁰p × ⁰R ω)`.
    fn motion_to_frame0(&mut self, l: usize, x: &V6) -> V6 {
        let r = self.root_rotation(l);
        let p = self.root_position(l);
        let (w, v) = split3(x);
        let w0 = self.rot_up(&r, &w);
        let rv = self.rot_up(&r, &v);
        let pxw = self.cross(&p, &w0);
        let v0 = self.add3(&rv, &pxw);
        join3(&w0, &v0)
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
        // Poses in frame 0 and the speeds' motions in frame 0.
        for l in 0..links {
            let transform = if columns[l].is_empty() {
                0
            } else {
                let r = self.root_rotation(l);
                let p = self.root_position(l);
                let mut t = r.concat().to_vec();
                t.extend_from_slice(&p);
                push(&mut ws, &t)
            };
            let first = plan.speeds.len();
            for col in &columns[l] {
                let s = self.motion_to_frame0(l, &col.s);
                let psid = self.motion_to_frame0(l, &col.psid);
                let (joint, psidd) = match col.psidd {
                    Some(x) => (psid, self.motion_to_frame0(l, &x)),
                    None => ([zero; 6], [zero; 6]),
                };
                let k = if col.psidd.is_some() { 2.0 } else { 1.0 };
                let lanes: Vec<ExprId> = (0..6)
                    .flat_map(|c| {
                        let kpsid = self.ar.scale(psid[c], k);
                        [s[c], s[c], s[c], joint[c], kpsid, psidd[c]]
                    })
                    .collect();
                let motion = push(&mut ws, &lanes);
                plan.speeds.push(LoopSpeed {
                    index: col.speed,
                    motion,
                });
            }
            plan.links.push(DerivativeLink {
                parent: model.links[l].mount.as_ref().map(|m| m.parent),
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
        // Schedule: poses and motions, then the columns from the leaves, each right after
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
    use kanegen_runtime::derivative_steps::{Column, Link, NO_PARENT, Plan, Speed};

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
        let links: Vec<Link> = plan
            .links
            .iter()
            .map(|l| Link {
                parent: l.parent.map_or(NO_PARENT, u16_of),
                transform: u16_of(l.transform),
                first: u16_of(l.speeds.start),
                end: u16_of(l.speeds.end),
            })
            .collect();
        let speeds: Vec<Speed> = plan
            .speeds
            .iter()
            .map(|s| Speed {
                index: u16_of(s.index),
                motion: u16_of(s.motion),
            })
            .collect();
        let columns: Vec<Column> = plan
            .columns
            .iter()
            .map(|c| Column {
                link: u16_of(c.link),
                speed: u16_of(c.speed),
                forces: u16_of(c.forces),
            })
            .collect();
        let tables = Plan {
            dof: plan.dof,
            links: &links,
            speeds: &speeds,
            columns: &columns,
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
