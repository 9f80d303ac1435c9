//! The loop form of the inverse-dynamics regressor and its base regressor.
//!
//! The straight-line Y is one derivative chain per parameter column (`regressor.rs`): for
//! Krang 9,950 flops in 135 KB of machine code, which runs from L2 (the L1 instruction cache
//! holds 32 KB). The loop form computes straight-line only what is per link — every link's
//! `ω`, `α`, origin acceleration minus gravity (τ's own motion pass, the same K variables),
//! its joint rotation and origin — into a small table, and runs the per (speed, body) work as a
//! loop over a generated constant table calling `kanegen_runtime::regressor` (Kane's
//! `τ_r = Σ_k φ_kr · W_k π_k`: the partial velocity of each body for each speed, carried one
//! joint down the tree, dotted with the body's 6×10 motion matrix). Entries that are not a
//! body's (a wheeled base's wheel columns) stay straight-line.
//!
//! The rule ([`RegressorForm::Auto`]): the loop form for models without mimic joints with at
//! least [`LOOP_MIN_PAIRS`] (speed, body) pairs, the straight line otherwise.

use kanegen_model::{JointKind, Model};

use super::ctx::Ctx;
use crate::expr::ExprId;
use crate::options::RegressorForm;

/// Values per link of the loop form's table (`kanegen_runtime::regressor::KIN`): `ω`, `α`,
/// `a − g`, the joint rotation `R` (row-major) and origin `P`, then the body's coefficients
/// `K = [α]× + [ω]×[ω]×` (row-major), `−(a − g)` and `−ω`.
pub const KIN: usize = 36;

/// Rows per chunk of the loop (`kanegen_runtime::regressor::LANES`).
pub const LANES: usize = 4;

/// The fewest (speed, body) pairs for which [`RegressorForm::Auto`] chooses the loop form.
/// Below it the straight line fits the instruction cache: it costs about 70 flops per pair at
/// 11–14 bytes of machine code per flop, so 40 pairs are ≈ 35 KB, the size of a 32 KB L1
/// instruction cache (the 7-DOF arm: 28 pairs, 1,617 flops, straight-line; Krang: 138).
pub const LOOP_MIN_PAIRS: usize = 40;

/// A regressor in loop form: what the generated function computes straight-line and the
/// tables of its loop (see `kanegen_runtime::regressor`).
#[derive(Clone, Debug, PartialEq)]
pub struct RegressorLoop {
    /// [`KIN`] expressions per link, in link order.
    pub kin: Vec<ExprId>,
    /// Per link: its parent and the result columns of its body's ten parameters.
    pub links: Vec<LoopLink>,
    /// The (row, link) pairs in loop order.
    pub steps: Vec<LoopStep>,
    /// Result entries outside the bodies' columns (a wheeled base's wheel parameters),
    /// straight-line: `(row, column, expression)`.
    pub extra: Vec<(usize, usize, ExprId)>,
    /// Per link, the structure of its joint transform (what the runtime kernel's carry is
    /// specialised for).
    pub joints: Vec<JointShape>,
}

/// The structure of a link's joint transform in the loop form's `kin` table, found from its
/// expressions: which entry of the rotation `R` is the constant ±1 (a rotation about a
/// coordinate axis after a constant signed permutation: Krang's joints) and whether the
/// origin `P` can be non-zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JointShape {
    /// `(row, column)` of the constant ±1 entry of `R` whose row and column are otherwise
    /// constant zeros, or `None` (dense).
    pub axis: Option<(usize, usize)>,
    /// Whether some component of `P` is not the constant zero.
    pub offset: bool,
}

/// One (link, row chunk) step of the loop form's plan (`kanegen_runtime::regressor::Step`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanStep {
    /// The link.
    pub link: usize,
    /// The row chunk (rows from [`first_row`]`(chunk, rows)`).
    pub chunk: usize,
    /// Scratch slot written (the link's depth), or `None` when no step but the next one (which
    /// takes the value from the previous step directly) reads it.
    pub slot: Option<usize>,
    /// Where the parent's partial velocities of these rows are, if it has any.
    pub from: Option<CarryFrom>,
    /// Index of the chunk of the link's own joints' partial velocities in
    /// [`LoopPlan::seeds`], if its joints move some of these rows.
    pub seed: Option<usize>,
    /// Whether the link's body has result columns.
    pub body: bool,
}

/// Where a [`PlanStep`] finds its parent's partial velocities.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CarryFrom {
    /// The step just before (kept in registers by the kernel).
    Previous,
    /// A scratch slot.
    Slot(usize),
}

/// The loop form's tables as the runtime kernel `kanegen_runtime::regressor::inverse_dynamics_regressor`
/// runs them: chunk by chunk, each chunk's links depth-first, only the (link, chunk) pairs some
/// ancestor speed moves; the others' body entries are stored as zeros.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopPlan {
    /// The steps, in order.
    pub steps: Vec<PlanStep>,
    /// Seed chunks: per lane (row [`first_row`]`(chunk, rows) + lane`), `(ω; v)` component by
    /// component.
    pub seeds: Vec<[[f64; LANES]; 6]>,
    /// (link, chunk) pairs of bodies with columns whose rows no speed moves.
    pub zeros: Vec<(usize, usize)>,
    /// Scratch slots (the deepest step's depth plus one).
    pub slots: usize,
    /// Lane flops of the steps per call, as the kernel runs them (a multiply-add counts 2, as
    /// in the straight-line counts; the links' coefficients are in the straight-line part): per
    /// step and lane 26 to
    /// carry through an axis-aligned joint with an offset, 14 without, 42 and 30 dense, none
    /// from zero; 71 for a body's entries; 6 to add a seed chunk.
    pub flops: usize,
}

/// One link of a [`RegressorLoop`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopLink {
    /// Parent link (the root's own index).
    pub parent: usize,
    /// Result column of each of the body's parameters `m, MX, MY, MZ, XX, XY, XZ, YY, YZ, ZZ`.
    pub columns: [Option<usize>; 10],
}

/// One (row, link) pair of a [`RegressorLoop`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopStep {
    /// Speed (result row).
    pub row: usize,
    /// Link.
    pub link: usize,
    /// The link's own joint's partial velocity `(ω; v)` in its frame, or `None`: carried from
    /// the parent's.
    pub seed: Option<[f64; 6]>,
}

impl LoopLink {
    /// Whether the link's body has a column in the result.
    pub fn writes(&self) -> bool {
        self.columns.iter().any(Option::is_some)
    }
}

impl RegressorLoop {
    /// The (row, body) pairs whose entries the loop writes.
    pub fn pairs(&self) -> usize {
        self.steps
            .iter()
            .filter(|s| self.links[s.link].writes())
            .count()
    }

    /// Per link, the number of row chunks of [`LANES`] rows (from row 0) that cover every
    /// speed that moves it, and the index of its first chunk in the scratch; and the total.
    pub fn chunks(&self) -> (Vec<(usize, usize)>, usize) {
        let mut hi = vec![0; self.links.len()];
        for s in &self.steps {
            hi[s.link] = hi[s.link].max(s.row + 1);
        }
        let mut slot = 0;
        let out = hi
            .iter()
            .map(|&h| {
                let n = h.div_ceil(LANES);
                slot += n;
                (n, slot - n)
            })
            .collect();
        (out, slot)
    }

    /// The seeds (`row`, `link`, partial velocity), sorted by link.
    pub fn seeds(&self) -> Vec<(usize, usize, [f64; 6])> {
        let mut s: Vec<_> = self
            .steps
            .iter()
            .filter_map(|s| s.seed.map(|x| (s.row, s.link, x)))
            .collect();
        s.sort_by_key(|&(r, l, _)| (l, r));
        s
    }

    /// The plan of the runtime kernel: per chunk of [`LANES`] rows, the links some speed in
    /// those rows moves, depth-first (children after their parent, a subtree before the next
    /// sibling), each carried from its parent's chunk (when the parent has it) and seeded with
    /// its own joints' partial velocities.
    pub fn plan(&self, rows: usize) -> LoopPlan {
        let nl = self.links.len();
        let n_chunks = rows.div_ceil(LANES);
        // Which chunks each link's partial velocities can be non-zero in.
        let mut has = vec![vec![false; n_chunks]; nl];
        // Chunk c covers the rows from `first_row(c)`: the last one ends at the last row (it
        // overlaps the one before when the rows are not a multiple of LANES, so that every store
        // is a whole vector; the overlapping rows are computed twice, identically).
        let windows = |r: usize| {
            (0..n_chunks).filter(move |&c| {
                let r0 = first_row(c, rows);
                r0 <= r && r < r0 + LANES
            })
        };
        for s in &self.steps {
            if s.row < rows {
                for c in windows(s.row) {
                    has[s.link][c] = true;
                }
            }
        }
        // Children lists and depths (links are in topological order).
        let mut children = vec![Vec::new(); nl];
        let mut depth = vec![0; nl];
        for (l, link) in self.links.iter().enumerate() {
            if link.parent != l {
                children[link.parent].push(l);
                depth[l] = depth[link.parent] + 1;
            }
        }
        let mut preorder = Vec::with_capacity(nl);
        let mut stack: Vec<usize> = (0..nl)
            .rev()
            .filter(|&l| self.links[l].parent == l)
            .collect();
        while let Some(l) = stack.pop() {
            preorder.push(l);
            stack.extend(children[l].iter().rev());
        }
        let mut seeds = Vec::new();
        let mut seed_of = std::collections::BTreeMap::new();
        for (row, link, phi) in self.seeds() {
            if row >= rows {
                continue;
            }
            for c in windows(row) {
                let i = *seed_of.entry((link, c)).or_insert_with(|| {
                    seeds.push([[0.0; LANES]; 6]);
                    seeds.len() - 1
                });
                for (d, x) in seeds[i].iter_mut().zip(phi) {
                    d[row - first_row(c, rows)] = x;
                }
            }
        }
        let mut steps = Vec::new();
        let mut flops = 0;
        for chunk in 0..n_chunks {
            for &l in &preorder {
                if !has[l][chunk] {
                    continue;
                }
                let link = &self.links[l];
                let p = link.parent;
                let from = (p != l && has[p][chunk]).then(|| {
                    let prev = steps.last().filter(|s: &&PlanStep| s.chunk == chunk);
                    if prev.is_some_and(|s| s.link == p) {
                        CarryFrom::Previous
                    } else {
                        CarryFrom::Slot(depth[p])
                    }
                });
                let seed = seed_of.get(&(l, chunk)).copied();
                let body = link.writes();
                if from.is_some() {
                    let j = self.joints[l];
                    flops += LANES
                        * match (j.axis.is_some(), j.offset) {
                            (true, true) => 26,
                            (true, false) => 14,
                            (false, true) => 42,
                            (false, false) => 30,
                        };
                }
                if seed.is_some() {
                    flops += 6 * LANES;
                }
                if body {
                    flops += 71 * LANES;
                }
                steps.push(PlanStep {
                    link: l,
                    chunk,
                    slot: Some(depth[l]),
                    from,
                    seed,
                    body,
                });
            }
        }
        let zeros = (0..n_chunks)
            .flat_map(|c| (0..nl).map(move |l| (l, c)))
            .filter(|&(l, c)| self.links[l].writes() && !has[l][c])
            .collect();
        // A step's slot is needed only by a later step reading it from the scratch.
        let mut read = vec![false; steps.len()];
        for (i, s) in steps.iter().enumerate() {
            if let Some(CarryFrom::Slot(d)) = s.from {
                // The last earlier step of the same chunk at that depth wrote it.
                if let Some(j) = (0..i)
                    .rev()
                    .find(|&j| steps[j].chunk == s.chunk && steps[j].slot == Some(d))
                {
                    read[j] = true;
                }
            }
        }
        for (s, r) in steps.iter_mut().zip(read) {
            if !r {
                s.slot = None;
            }
        }
        let slots = steps
            .iter()
            .filter_map(|s| s.slot.map(|d| d + 1))
            .max()
            .unwrap_or(0);
        LoopPlan {
            steps,
            seeds,
            zeros,
            slots,
            flops,
        }
    }

    /// Lane flops of the loop per call, as the generated code's runtime kernel runs them: the
    /// flops of its [`RegressorLoop::plan`] (a multiply-add counts once; every lane of a step
    /// is counted, also rows that do not move the link).
    pub fn flops(&self) -> usize {
        let rows = self.steps.iter().map(|s| s.row + 1).max().unwrap_or(0);
        self.plan(rows).flops
    }

    /// Flops of the loop per call as the plain kernel (`inverse_dynamics_regressor_with`) runs
    /// them (every lane of a chunk, rows that are not a link's ancestors' included): 23 per
    /// link with a body, and per chunk of [`LANES`] rows 42 per lane to carry it from the
    /// parent and 71 per lane for the body's entries.
    pub fn plain_flops(&self) -> usize {
        let (chunks, _) = self.chunks();
        let mut flops = 0;
        for (l, link) in self.links.iter().enumerate() {
            let (n, _) = chunks[l];
            let inherited = if link.parent == l {
                0
            } else {
                chunks[link.parent].0.min(n)
            };
            flops += 42 * LANES * inherited;
            if link.writes() && n > 0 {
                flops += 23 + 71 * LANES * n;
            }
        }
        flops
    }
}

/// The first row of chunk `c` of a result of `rows` rows
/// (`kanegen_runtime::regressor::first_row`): `LANES · c`, but the last chunk ends at the last
/// row (overlapping the one before) when there are at least [`LANES`] rows.
pub fn first_row(c: usize, rows: usize) -> usize {
    (LANES * c).min(rows.saturating_sub(LANES))
}

/// Whether `form` asks for the loop form of `model`'s regressor with `pairs` (speed, body)
/// pairs.
pub(super) fn use_loop(form: RegressorForm, model: &Model, pairs: usize) -> bool {
    // A floating base's root rows are not in the loop's (speed, body) tables.
    model.mimics.is_empty()
        && !model.is_floating()
        && match form {
            RegressorForm::Auto => pairs >= LOOP_MIN_PAIRS,
            RegressorForm::Loop => true,
            RegressorForm::StraightLine => false,
        }
}

/// The (row, link) steps of `model`'s tree (no mimic joints): per speed, the link its joint
/// moves with the joint's partial velocity, then that link's descendants in link order; links
/// whose subtree has no body are left out.
pub(super) fn steps(model: &Model) -> Vec<LoopStep> {
    let nl = model.links.len();
    // Whether link l's subtree has a body (links are in topological order).
    let mut needed: Vec<bool> = model.links.iter().map(|l| l.body.is_some()).collect();
    for l in (1..nl).rev() {
        if let (Some(p), true) = (model.links[l].parent(), needed[l]) {
            needed[p] = true;
        }
    }
    let descends = |k: usize, l: usize| k == l || model.path_to_base(k).any(|(_, m)| m.parent == l);
    let mut seeds: Vec<(usize, usize, [f64; 6])> = Vec::new();
    if let Some(w) = model.wheeled_base() {
        seeds.push((w.x_speed, 0, [0.0, 0.0, 0.0, 1.0, 0.0, 0.0]));
        seeds.push((w.psi_speed, 0, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]));
    }
    for (l, _, mount) in model.mounted_links() {
        let e = mount.joint.axis;
        match mount.joint.kind {
            JointKind::Revolute { speed } => {
                seeds.push((speed, l, [e[0], e[1], e[2], 0.0, 0.0, 0.0]));
            }
            JointKind::Prismatic { speed } => {
                seeds.push((speed, l, [0.0, 0.0, 0.0, e[0], e[1], e[2]]));
            }
            JointKind::Fixed => {}
        }
    }
    seeds.sort_by_key(|s| s.0);
    let mut out = Vec::new();
    for (row, l, seed) in seeds {
        if !needed[l] {
            continue;
        }
        out.push(LoopStep {
            row,
            link: l,
            seed: Some(seed),
        });
        for k in l + 1..nl {
            if needed[k] && descends(k, l) {
                out.push(LoopStep {
                    row,
                    link: k,
                    seed: None,
                });
            }
        }
    }
    out
}

impl Ctx<'_> {
    /// The loop form of a regressor whose parameter column `c` of π is result column
    /// `column(c)` (`None`: left out), with the straight-line `entries` (in π's columns) for
    /// the entries that are not a body's.
    pub(super) fn regressor_loop(
        &mut self,
        column: &dyn Fn(usize) -> Option<usize>,
        entries: &[(usize, usize, ExprId)],
    ) -> RegressorLoop {
        let model = self.model;
        let motion = self.full_motion();
        let zero = self.ar.zero();
        let one = self.ar.one();
        let mut kin = Vec::with_capacity(KIN * model.links.len());
        let mut links = Vec::with_capacity(model.links.len());
        let mut joints = Vec::with_capacity(model.links.len());
        let mut body = 0;
        for (l, link) in model.links.iter().enumerate() {
            kin.extend(motion.w[l]);
            kin.extend(motion.wd[l]);
            kin.extend(motion.a[l]);
            match &link.mount {
                Some(mount) => {
                    let r = self.rotation(l, &mount.joint);
                    let p = self.position(l, &mount.joint);
                    kin.extend(r.iter().flatten());
                    kin.extend(p);
                }
                None => {
                    let eye = [[one, zero, zero], [zero, one, zero], [zero, zero, one]];
                    kin.extend(eye.iter().flatten());
                    kin.extend([zero; 3]);
                }
            }
            // The coefficients of the body's entries: K = ω ωᵀ − |ω|² I + [α]×, −a, −ω.
            let (w, al, acc) = (motion.w[l], motion.wd[l], motion.a[l]);
            for i in 0..3 {
                for j in 0..3 {
                    let e = if i == j {
                        let (a, b) = ((i + 1) % 3, (i + 2) % 3);
                        let wa = self.ar.mul(w[a], w[a]);
                        let wb = self.ar.mul(w[b], w[b]);
                        let s = self.ar.add(wa, wb);
                        self.ar.neg(s)
                    } else {
                        // [α]×: (i, j) = −ε_ijk α_k.
                        let k = 3 - i - j;
                        let ww = self.ar.mul(w[i], w[j]);
                        if (j + 3 - i) % 3 == 1 {
                            self.ar.sub(ww, al[k])
                        } else {
                            self.ar.add(ww, al[k])
                        }
                    };
                    kin.push(e);
                }
            }
            for x in acc.into_iter().chain(w) {
                let e = self.ar.neg(x);
                kin.push(e);
            }
            // The transform's structure: a constant ±1 entry of R with zeros in its row and
            // column (an axis-aligned joint), and whether P can be non-zero.
            let at = kin.len() - 27;
            let is = |e: ExprId, v: f64| self.ar.as_const(e) == Some(v);
            let axis = (0..9).map(|i| (i / 3, i % 3)).find(|&(r, c)| {
                let e = kin[at + 3 * r + c];
                (is(e, 1.0) || is(e, -1.0))
                    && (0..3).all(|k| {
                        (k == c || is(kin[at + 3 * r + k], 0.0))
                            && (k == r || is(kin[at + 3 * k + c], 0.0))
                    })
            });
            let offset = !kin[at + 9..at + 12].iter().all(|&e| is(e, 0.0));
            joints.push(JointShape { axis, offset });
            let mut columns = [None; 10];
            if link.body.is_some() {
                for (t, c) in columns.iter_mut().enumerate() {
                    *c = column(10 * body + t);
                }
                body += 1;
            }
            links.push(LoopLink {
                parent: link.parent().unwrap_or(l),
                columns,
            });
        }
        let bodies = 10 * body;
        let extra = entries
            .iter()
            .filter(|&&(_, c, _)| c >= bodies)
            .filter_map(|&(r, c, e)| column(c).map(|b| (r, b, e)))
            .collect();
        RegressorLoop {
            kin,
            links,
            steps: steps(model),
            extra,
            joints,
        }
    }
}

#[cfg(test)]
mod tests {
    /// `RegressorForm::Auto`'s documentation (`codegen/src/options.rs`) states this threshold.
    #[test]
    fn the_loop_threshold_is_the_documented_40_pairs() {
        assert_eq!(super::LOOP_MIN_PAIRS, 40);
        let doc = include_str!("../options.rs");
        assert!(
            doc.contains("40 (speed, body) pairs"),
            "RegressorForm::Auto's doc names 40 pairs"
        );
    }
}
