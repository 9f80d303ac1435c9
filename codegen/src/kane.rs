//! Recursive Kane's-method derivation with K/D substitution.
//!
//! Kane's equations for a tree of rigid bodies read, for every generalized speed r,
//! `τ_r = Σ_k [F_k · (v_k)_r + N_k · (ω_k)_r] − (generalized gravity force)_r`, where F_k and N_k
//! are body k's inertia force and moment about its frame origin and (v_k)_r, (ω_k)_r its partial
//! velocities. In a tree, the partial angular velocity of every descendant of a revolute joint j
//! is the joint axis e_j and the partial linear velocity is `e_j × (p_k − p_j)`, so the sum over
//! bodies collapses into `e_j · n_j`, with n_j the moment about O_j of the inertia forces of the
//! subtree of j. These subtree sums are accumulated backward, so the generated code grows with
//! the number of bodies plus the sum of depths instead of their product.
//!
//! * ω, α and the origin acceleration a of every frame follow seed 002 eqs. 3–6 (K variables);
//!   for the wheeled base `ω0 = [0,0,ψ̇]`, `α0 = [0,0,ψ̈]`, `a0 = [ẍ, ẋψ̇, 0]` (the report's
//!   `[ẍ, ψ̇, 0]` is a known error). Gravity enters as the base acceleration `a0 − g0`.
//! * inverse dynamics and c: body inertia forces and moments (D variables), accumulated backward;
//! * M: the same generalized inertia forces for a unit acceleration of one speed at rest, i.e.
//!   composite (subtree) mass, first moment and inertia carried backward, one column per speed,
//!   only the upper triangle;
//! * g: composite first moments against the gravity acceleration of each frame;
//! * wheel terms of DynamicModeling.tex on the ẋ and ψ̇ rows;
//! * the Coriolis matrix C (c = C u, Ṁ − 2C skew-symmetric): spatial vectors in body
//!   coordinates, composite inertia, subtree momentum and subtree inertia rate, three force
//!   vectors carried backward per (speed, ancestor speed) pair (see `Ctx::coriolis_matrix`).
//!
//! Every compound component is replaced by a substitution variable as soon as it is formed.

// Index loops over links mirror the recursions of the reports (parent indices, per-link tables).
#![allow(clippy::needless_range_loop)]

use std::collections::BTreeMap;

use kanegen_model::{Base, JointKind, Model, Scalar};

use crate::expr::{Arena, Atom, ExprId, Names, VarKind};

/// How model parameters enter the generated code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ParamMode {
    /// Parameters are runtime inputs (a `Params` value); parameter-only subexpressions are
    /// computed once per parameter set, outside the hot path.
    #[default]
    Runtime,
    /// The model file's values are folded in as constants; terms of zero parameters vanish.
    Baked,
}

/// Generator options.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// How parameters enter.
    pub params: ParamMode,
    /// Also derive `coriolis_matrix`, the Coriolis matrix C(q, u) (default `true`). It costs
    /// about four times the operations of `coriolis` (Krang: ≈ 9,500 flops) and roughly doubles
    /// the compile time of a large model's generated module; turn it off when only M, c, g and
    /// τ are needed.
    pub coriolis_matrix: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            params: ParamMode::default(),
            coriolis_matrix: true,
        }
    }
}

/// Shape of a generated function's result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Symmetric matrix; entries are the upper triangle `(row ≤ col)`.
    SymmetricMatrix,
    /// Vector; entries are `(row, 0)`.
    Vector,
    /// General (non-symmetric) matrix; entries are `(row, col)`, absent entries are zero.
    Matrix,
}

/// Which inputs a function takes besides the parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signature {
    /// `f(q)`.
    Q,
    /// `f(q, u)`.
    QU,
    /// `f(q, u, u̇)`.
    QUUd,
}

/// One derived function: its name and output entries as expressions in the arena.
#[derive(Clone, Debug)]
pub struct Function {
    /// Rust name (`mass_matrix`).
    pub name: &'static str,
    /// What it computes, for docs.
    pub doc: &'static str,
    /// Result shape.
    pub shape: Shape,
    /// Inputs.
    pub signature: Signature,
    /// `(row, col, expr)`; col = 0 for vectors.
    pub entries: Vec<(usize, usize, ExprId)>,
    /// Per arena node, when this function's derivation first asked for it (`u32::MAX`: never):
    /// the statement order the lowering follows (see [`Arena::begin_phase`]).
    pub order: Vec<u32>,
}

/// The symbolic dynamics of a model.
#[derive(Clone, Debug)]
pub struct Derivation {
    /// All expressions and substitution variables.
    pub arena: Arena,
    /// `mass_matrix`, `coriolis`, `gravity`, `inverse_dynamics`, and `coriolis_matrix` if
    /// [`Options::coriolis_matrix`].
    pub functions: Vec<Function>,
    /// Number of speeds.
    pub dof: usize,
    /// Options used.
    pub options: Options,
}

impl Derivation {
    /// The function called `name`.
    pub fn function(&self, name: &str) -> Option<&Function> {
        self.functions.iter().find(|f| f.name == name)
    }
}

type V3 = [ExprId; 3];
type M3 = [[ExprId; 3]; 3];
/// A spatial vector: motion `(ω; v)` or force `(n; f)`.
type V6 = [ExprId; 6];

fn split3(x: &V6) -> (V3, V3) {
    ([x[0], x[1], x[2]], [x[3], x[4], x[5]])
}

fn join3(a: &V3, b: &V3) -> V6 {
    [a[0], a[1], a[2], b[0], b[1], b[2]]
}

/// Names for the arena's printer, from the model.
pub fn names_of(model: &Model) -> Names {
    Names {
        params: model.params.iter().map(|p| p.name.clone()).collect(),
        speeds: model.speeds.iter().map(|s| s.name.clone()).collect(),
        coords: model.speeds.iter().map(|s| s.coordinate.clone()).collect(),
    }
}

/// Derive M (upper triangle), c, g, τ and the Coriolis matrix C for `model`.
pub fn derive(model: &Model, options: Options) -> Derivation {
    let mut arena = Arena::new(names_of(model));
    arena.hoist_params = options.params == ParamMode::Runtime;
    let mut cx = Ctx {
        ar: &mut arena,
        model,
        options,
        rot: vec![None; model.links.len()],
        pos: vec![None; model.links.len()],
    };
    let n = model.dof();
    // The columns of M are formed inside the backward composite pass, each right after its
    // subtree's composite is complete, so that the generated code uses values soon after it
    // computes them (short live ranges, fewer register spills). Each function is one arena
    // phase: its statements are later scheduled in the order its own recursion forms them.
    cx.ar.begin_phase();
    let mut columns = Vec::new();
    let composites = cx.composites(true, Some(&mut columns));
    let m = cx.mass_matrix(&composites, columns);
    let m_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let g = cx.gravity(&composites);
    let g_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let c = cx.rnea(false, false);
    let c_order = cx.ar.phase_order();
    cx.ar.begin_phase();
    let tau = cx.rnea(true, true);
    let tau_order = cx.ar.phase_order();
    let cm = options.coriolis_matrix.then(|| {
        cx.ar.begin_phase();
        let cm = cx.coriolis_matrix(&composites);
        (cm, cx.ar.phase_order())
    });
    let vector = |v: Vec<ExprId>| v.into_iter().enumerate().map(|(i, e)| (i, 0, e)).collect();
    let mut functions = vec![
        Function {
            name: "mass_matrix",
            doc: "Mass matrix M(q) (symmetric positive definite).",
            shape: Shape::SymmetricMatrix,
            signature: Signature::Q,
            entries: m,
            order: m_order,
        },
        Function {
            name: "coriolis",
            doc: "Coriolis and centrifugal vector c(q, u) (velocity-product terms).",
            shape: Shape::Vector,
            signature: Signature::QU,
            entries: vector(c),
            order: c_order,
        },
        Function {
            name: "gravity",
            doc: "Gravity vector g(q).",
            shape: Shape::Vector,
            signature: Signature::Q,
            entries: vector(g),
            order: g_order,
        },
        Function {
            name: "inverse_dynamics",
            doc: "Inverse dynamics τ = M(q) u̇ + c(q, u) + g(q), in one pass.",
            shape: Shape::Vector,
            signature: Signature::QUUd,
            entries: vector(tau),
            order: tau_order,
        },
    ];
    if let Some((cm, cm_order)) = cm {
        functions.push(Function {
            name: "coriolis_matrix",
            doc: "Coriolis matrix C(q, u): c(q, u) = C(q, u) u, and Ṁ − 2C is skew-symmetric.",
            shape: Shape::Matrix,
            signature: Signature::QU,
            entries: cm,
            order: cm_order,
        });
    }
    debug_assert!(functions.iter().all(|f| f.entries.iter().all(|e| e.0 < n)));
    Derivation {
        arena,
        functions,
        dof: n,
        options,
    }
}

/// Composite (subtree) inertial quantities of a frame, in that frame.
#[derive(Clone, Debug)]
struct Composite {
    mass: ExprId,
    first_moment: V3,
    /// `[XX, XY, XZ, YY, YZ, ZZ]` about the frame origin (empty if not computed).
    inertia: Option<[ExprId; 6]>,
}

struct Ctx<'a> {
    ar: &'a mut Arena,
    model: &'a Model,
    options: Options,
    rot: Vec<Option<M3>>,
    pos: Vec<Option<V3>>,
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Ctx<'_> {
    // ---- leaves -------------------------------------------------------------------------------

    fn param(&mut self, p: usize) -> ExprId {
        match self.options.params {
            ParamMode::Runtime => self.ar.atom(Atom::Param(p as u32)),
            ParamMode::Baked => self.ar.constant(self.model.params[p].value),
        }
    }

    fn scalar(&mut self, s: &Scalar) -> ExprId {
        let c = self.ar.constant(s.coef);
        match s.symbol {
            None => c,
            Some(p) => {
                let p = self.param(p);
                self.ar.mul(c, p)
            }
        }
    }

    fn consts(&mut self, v: [f64; 3]) -> V3 {
        v.map(|x| self.ar.constant(x))
    }

    fn link_name(&self, l: usize) -> &str {
        &self.model.links[l].name
    }

    /// `iAj(q)` of link `l` (rows), cached.
    fn rotation(&mut self, l: usize) -> M3 {
        if let Some(r) = self.rot[l] {
            return r;
        }
        let j = self.model.links[l]
            .joint
            .as_ref()
            .expect("non-root link has a joint");
        let a0: M3 = j.rotation.map(|row| row.map(|x| self.ar.constant(x)));
        let r = match (j.kind, j.speed) {
            (JointKind::Revolute, Some(s)) => {
                let sn = self.ar.atom(Atom::Sin(s as u32));
                let cs = self.ar.atom(Atom::Cos(s as u32));
                let e = j.axis;
                // Rot(e, q) = c·I + s·[e]× + (1 − c)·e eᵀ
                let one = self.ar.one();
                let omc = self.ar.sub(one, cs);
                let ex = [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]];
                let mut rot = [[self.ar.zero(); 3]; 3];
                for r in 0..3 {
                    for c in 0..3 {
                        let id = if r == c { cs } else { self.ar.zero() };
                        let k1 = self.ar.constant(ex[r][c]);
                        let t1 = self.ar.mul(k1, sn);
                        let k2 = self.ar.constant(e[r] * e[c]);
                        let t2 = self.ar.mul(k2, omc);
                        rot[r][c] = self.ar.sum([id, t1, t2]);
                    }
                }
                self.matmul(&a0, &rot)
            }
            _ => a0,
        };
        let name = self.link_name(l).to_owned();
        let mut out = r;
        for (ri, row) in out.iter_mut().enumerate() {
            for (ci, x) in row.iter_mut().enumerate() {
                *x = self
                    .ar
                    .subst(*x, VarKind::K, &format!("A{name}({},{})", ri + 1, ci + 1));
            }
        }
        self.rot[l] = Some(out);
        out
    }

    /// `iPj(q)` of link `l`, cached.
    fn position(&mut self, l: usize) -> V3 {
        if let Some(p) = self.pos[l] {
            return p;
        }
        let j = self.model.links[l]
            .joint
            .clone()
            .expect("non-root link has a joint");
        let mut p = j.translation.map(|s| self.scalar(&s));
        if let (JointKind::Prismatic, Some(s)) = (j.kind, j.speed) {
            let q = self.ar.atom(Atom::Coord(s as u32));
            let dir = [0, 1, 2].map(|r| (0..3).map(|c| j.rotation[r][c] * j.axis[c]).sum::<f64>());
            for (r, pr) in p.iter_mut().enumerate() {
                let k = self.ar.constant(dir[r]);
                let t = self.ar.mul(k, q);
                *pr = self.ar.add(*pr, t);
            }
        }
        let name = self.link_name(l).to_owned();
        let p = self.subst3(p, VarKind::K, &format!("P{name}"));
        self.pos[l] = Some(p);
        p
    }

    // ---- vector algebra -----------------------------------------------------------------------

    fn matmul(&mut self, a: &M3, b: &M3) -> M3 {
        let mut out = [[self.ar.zero(); 3]; 3];
        for (r, row) in out.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(a[r][k], b[k][c])).collect();
                *x = self.ar.sum(t);
            }
        }
        out
    }

    /// `R x`.
    fn rot_up(&mut self, r: &M3, x: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(r[i][k], x[k])).collect();
            self.ar.sum(t)
        })
    }

    /// `Rᵀ x`.
    fn rot_down(&mut self, r: &M3, x: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let t: Vec<ExprId> = (0..3).map(|k| self.ar.mul(r[k][i], x[k])).collect();
            self.ar.sum(t)
        })
    }

    fn add3(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.add(a[i], b[i]))
    }

    fn sub3(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.sub(a[i], b[i]))
    }

    fn scale3(&mut self, k: ExprId, a: &V3) -> V3 {
        [0, 1, 2].map(|i| self.ar.mul(k, a[i]))
    }

    fn cross(&mut self, a: &V3, b: &V3) -> V3 {
        [0, 1, 2].map(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let p = self.ar.mul(a[j], b[k]);
            let m = self.ar.mul(a[k], b[j]);
            self.ar.sub(p, m)
        })
    }

    fn dot(&mut self, a: &V3, b: &V3) -> ExprId {
        let t: Vec<ExprId> = (0..3).map(|i| self.ar.mul(a[i], b[i])).collect();
        self.ar.sum(t)
    }

    fn subst3(&mut self, v: V3, kind: VarKind, label: &str) -> V3 {
        [0, 1, 2].map(|i| self.ar.subst(v[i], kind, &format!("{label}.{}", AXES[i])))
    }

    /// Symmetric 3×3 from `[XX, XY, XZ, YY, YZ, ZZ]`.
    fn sym(j: &[ExprId; 6]) -> M3 {
        [[j[0], j[1], j[2]], [j[1], j[3], j[4]], [j[2], j[4], j[5]]]
    }

    fn sym_mul(&mut self, j: &[ExprId; 6], x: &V3) -> V3 {
        let m = Self::sym(j);
        self.rot_up(&m, x)
    }

    // ---- model data ---------------------------------------------------------------------------

    fn body(&mut self, l: usize) -> Option<(ExprId, V3, [ExprId; 6])> {
        let b = self.model.links[l].body.clone()?;
        let m = self.param(b.mass);
        let ms = b.first_moment.map(|p| self.param(p));
        let j = b.inertia.map(|p| self.param(p));
        Some((m, ms, j))
    }

    fn gravity_vector(&mut self) -> V3 {
        let g = self.param(self.model.gravity.symbol);
        let d = self.consts(self.model.gravity.direction);
        self.scale3(g, &d)
    }

    fn axis(&mut self, l: usize) -> V3 {
        let e = self.model.links[l]
            .joint
            .as_ref()
            .map(|j| j.axis)
            .unwrap_or([0.0; 3]);
        self.consts(e)
    }

    /// Wheel inertia added to M[ẋ,ẋ] and M[ψ̇,ψ̇].
    fn wheel_terms(&mut self) -> Option<(usize, ExprId, usize, ExprId)> {
        let Base::Wheeled(w) = &self.model.base else {
            return None;
        };
        let w = w.clone();
        let (r, l, mw, yy, zz) = (
            self.param(w.radius),
            self.param(w.track),
            self.param(w.wheel_mass),
            self.param(w.wheel_axle_inertia),
            self.param(w.wheel_diametral_inertia),
        );
        let two = self.ar.constant(2.0);
        let half = self.ar.constant(0.5);
        let r_2 = self.ar.powi(r, -2);
        let l2 = self.ar.powi(l, 2);
        // 2 mw + 2 YYw / R²
        let a = self.ar.mul(two, mw);
        let b = self.ar.product([two, yy, r_2]);
        let kx = self.ar.add(a, b);
        let kx = self.ar.subst(kx, VarKind::D, "wheels: 2 mw + 2 YYw/R^2");
        // mw L²/2 + YYw L²/(2R²) + 2 ZZw
        let a = self.ar.product([half, mw, l2]);
        let b = self.ar.product([half, yy, l2, r_2]);
        let c = self.ar.mul(two, zz);
        let kp = self.ar.sum([a, b, c]);
        let kp = self
            .ar
            .subst(kp, VarKind::D, "wheels: mw L^2/2 + YYw L^2/(2R^2) + 2 ZZw");
        Some((w.x_speed, kx, w.psi_speed, kp))
    }

    // ---- composite bodies -----------------------------------------------------------------------

    /// Composite mass, first moment and (optionally) inertia of every subtree, in its own frame.
    /// With `columns`, the mass-matrix column of every joint is formed as soon as the composite
    /// of its subtree is complete (see [`Ctx::mass_matrix_column`]).
    fn composites(
        &mut self,
        with_inertia: bool,
        mut columns: Option<&mut Vec<(usize, usize, ExprId)>>,
    ) -> Vec<Composite> {
        let links = self.model.links.len();
        let zero = self.ar.zero();
        let mut comp: Vec<Composite> = (0..links)
            .map(|_| Composite {
                mass: zero,
                first_moment: [zero; 3],
                inertia: if with_inertia { Some([zero; 6]) } else { None },
            })
            .collect();
        for l in 0..links {
            if let Some((m, ms, j)) = self.body(l) {
                comp[l] = Composite {
                    mass: m,
                    first_moment: ms,
                    inertia: with_inertia.then_some(j),
                };
            }
        }
        for c in (1..links).rev() {
            let parent = self.model.links[c].parent.expect("non-root");
            let name = self.link_name(c).to_owned();
            let pname = self.link_name(parent).to_owned();
            // Finalise the child's composite as substitution variables.
            let child = comp[c].clone();
            let mass = self.ar.subst(child.mass, VarKind::D, &format!("mC{name}"));
            let msc = self.subst3(child.first_moment, VarKind::D, &format!("MSC{name}"));
            let inertia = child.inertia.map(|j| {
                let labels = ["xx", "xy", "xz", "yy", "yz", "zz"];
                let mut out = j;
                for (k, x) in out.iter_mut().enumerate() {
                    *x = self
                        .ar
                        .subst(*x, VarKind::D, &format!("JC{name}.{}", labels[k]));
                }
                out
            });
            comp[c] = Composite {
                mass,
                first_moment: msc,
                inertia,
            };
            let empty = self.ar.is_zero(mass) && msc.iter().all(|x| self.ar.is_zero(*x));
            let r = self.rotation(c);
            let p = self.position(c);
            // First moment moved to the parent frame: R·MS + m·p. (Formed before the column
            // of M, which may share these terms, so that they carry the composite's label.)
            let u = self.rot_up(&r, &msc);
            let u = self.subst3(u, VarKind::D, &format!("MSC{name} in {pname}"));
            if let Some(entries) = columns.as_deref_mut() {
                let composite = comp[c].clone();
                self.mass_matrix_column(c, &composite, entries);
            }
            if empty {
                continue;
            }
            let mp = self.scale3(mass, &p);
            let add = self.add3(&u, &mp);
            let new_mass = self.ar.add(comp[parent].mass, mass);
            let new_ms = self.add3(&comp[parent].first_moment, &add);
            let mut new_inertia = comp[parent].inertia;
            if let (Some(jc), Some(acc)) = (inertia, new_inertia.as_mut()) {
                self.add_inertia_to_parent(c, &r, &p, mass, &u, &jc, &name, "JC", acc);
            }
            comp[parent] = Composite {
                mass: new_mass,
                first_moment: new_ms,
                inertia: new_inertia,
            };
        }
        let name = self.link_name(0).to_owned();
        let root = comp[0].clone();
        comp[0] = Composite {
            mass: self.ar.subst(root.mass, VarKind::D, &format!("mC{name}")),
            first_moment: self.subst3(root.first_moment, VarKind::D, &format!("MSC{name}")),
            inertia: root
                .inertia
                .map(|j| j.map(|x| self.ar.subst(x, VarKind::D, &format!("JC{name}")))),
        };
        comp
    }

    /// Add to `acc` (`[XX, XY, XZ, YY, YZ, ZZ]` about the parent's origin, in the parent's
    /// frame) the inertia `jc` of a child about its own origin, with mass `mass` and first moment
    /// `u` already rotated into the parent's frame (`u = R·MS`): `R J Rᵀ` (see
    /// [`Ctx::rotate_inertia`]) plus the parallel-axis
    /// terms `−(u pᵀ + p uᵀ) + 2 (p·u) 1 + m (|p|² 1 − p pᵀ)`. Linear in `(m, MS, J)`: with
    /// `mass = 0` it carries any matrix of the form `[[A, [b]×], [−[b]×, 0]]` (inertia rates).
    #[allow(clippy::too_many_arguments)]
    fn add_inertia_to_parent(
        &mut self,
        child: usize,
        r: &M3,
        p: &V3,
        mass: ExprId,
        u: &V3,
        jc: &[ExprId; 6],
        name: &str,
        prefix: &str,
        acc: &mut [ExprId; 6],
    ) {
        let zero = self.ar.zero();
        let rjr = self.rotate_inertia(child, r, jc, &format!("{prefix}{name}"));
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        // −(u pᵀ + p uᵀ) + 2 (p·u) I  and  m (|p|² I − p pᵀ)
        let pu = self.dot(p, u);
        let two_pu = self.ar.scale(pu, 2.0);
        let pp = self.dot(p, p);
        for (k, &(a, b)) in idx.iter().enumerate() {
            let rjr = rjr[k];
            let upa = self.ar.mul(u[a], p[b]);
            let pua = self.ar.mul(p[a], u[b]);
            let cross = self.ar.add(upa, pua);
            let cross = self.ar.neg(cross);
            let ppab = self.ar.mul(p[a], p[b]);
            let mterm = if a == b {
                let d = self.ar.sub(pp, ppab);
                self.ar.mul(mass, d)
            } else {
                let d = self.ar.neg(ppab);
                self.ar.mul(mass, d)
            };
            let diag = if a == b { two_pu } else { zero };
            acc[k] = self.ar.sum([acc[k], rjr, cross, diag, mterm]);
        }
    }

    /// `R J Rᵀ` for the rotation `r = iAj` of link `child` and a symmetric `j`
    /// (`[XX, XY, XZ, YY, YZ, ZZ]`). For a revolute joint about a coordinate axis whose constant
    /// part `iAj(0)` is a signed permutation (every joint of Krang), the rotation about the axis
    /// uses double angles: in the plane `(i, j)` normal to the axis, with `d = Jii − Jjj` and
    /// `w = d sin²q + Jij sin 2q`, `J'ii = Jii − w`, `J'jj = Jjj + w`,
    /// `J'ij = Jij cos 2q + d sin q cos q` (15 operations instead of 33); otherwise it is
    /// computed in two stages, `T = J Rᵀ` (variables `{label}·Aᵀ`) and `R T`.
    fn rotate_inertia(
        &mut self,
        child: usize,
        r: &M3,
        j: &[ExprId; 6],
        label: &str,
    ) -> [ExprId; 6] {
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        let jm = Self::sym(j);
        let joint = self.model.links[child].joint.clone().expect("non-root");
        let signed_permutation = joint.rotation.iter().all(|row| {
            row.iter().filter(|x| **x != 0.0).count() == 1
                && row.iter().all(|x| [-1.0, 0.0, 1.0].contains(x))
        });
        let axis = (0..3).find(|&k| joint.axis[k].abs() == 1.0);
        if let (JointKind::Revolute, Some(s), true, Some(k)) =
            (joint.kind, joint.speed, signed_permutation, axis)
        {
            let sigma = joint.axis[k];
            let (i, jx) = ((k + 1) % 3, (k + 2) % 3);
            let (ss, sc, s2, c2) = self.double_angle(s);
            let s2 = self.ar.scale(s2, sigma);
            let sc = self.ar.scale(sc, sigma);
            let sn = self.ar.atom(Atom::Sin(s as u32));
            let sn = self.ar.scale(sn, sigma);
            let cs = self.ar.atom(Atom::Cos(s as u32));
            // d = Jii − Jjj, w = d s² + Jij sin 2q: J'ii = Jii − w, J'jj = Jjj + w,
            // J'ij = Jij cos 2q + d s c.
            let d = self.ar.sub(jm[i][i], jm[jx][jx]);
            let d = self.ar.subst(
                d,
                VarKind::D,
                &format!("{label}: J{0}{0} − J{1}{1}", AXES[i], AXES[jx]),
            );
            let dss = self.ar.mul(d, ss);
            let js2 = self.ar.mul(jm[i][jx], s2);
            let w = self.ar.add(dss, js2);
            let w = self.ar.subst(
                w,
                VarKind::D,
                &format!(
                    "{label} rotated about {}: J{1}{1} − J'{1}{1}",
                    AXES[k], AXES[i]
                ),
            );
            let mut jp = [[self.ar.zero(); 3]; 3];
            jp[i][i] = self.ar.sub(jm[i][i], w);
            jp[jx][jx] = self.ar.add(jm[jx][jx], w);
            let jc2 = self.ar.mul(jm[i][jx], c2);
            let dsc = self.ar.mul(d, sc);
            jp[i][jx] = self.ar.add(jc2, dsc);
            jp[jx][i] = jp[i][jx];
            // The axis column: J'ik = c Jik − s Jjk, J'jk = s Jik + c Jjk, J'kk = Jkk.
            let t1 = self.ar.mul(cs, jm[i][k]);
            let t2 = self.ar.mul(sn, jm[jx][k]);
            jp[i][k] = self.ar.sub(t1, t2);
            let t1 = self.ar.mul(sn, jm[i][k]);
            let t2 = self.ar.mul(cs, jm[jx][k]);
            jp[jx][k] = self.ar.add(t1, t2);
            jp[k][i] = jp[i][k];
            jp[k][jx] = jp[jx][k];
            jp[k][k] = jm[k][k];
            // The constant signed permutation: exact, no operations.
            let a0: M3 = joint.rotation.map(|row| row.map(|x| self.ar.constant(x)));
            return idx.map(|(ra, rb)| {
                let mut terms = Vec::new();
                for m in 0..3 {
                    for n in 0..3 {
                        let am = self.ar.mul(a0[ra][m], a0[rb][n]);
                        terms.push(self.ar.mul(am, jp[m][n]));
                    }
                }
                self.ar.sum(terms)
            });
        }
        let zero = self.ar.zero();
        let mut t = [[zero; 3]; 3];
        for (a, row) in t.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                let terms: Vec<ExprId> = (0..3).map(|k| self.ar.mul(jm[a][k], r[b][k])).collect();
                let s = self.ar.sum(terms);
                *x = self
                    .ar
                    .subst(s, VarKind::D, &format!("{label}·Aᵀ({},{})", a + 1, b + 1));
            }
        }
        idx.map(|(a, b)| {
            let terms: Vec<ExprId> = (0..3).map(|i| self.ar.mul(r[a][i], t[i][b])).collect();
            self.ar.sum(terms)
        })
    }

    /// `(sin² q, sin q cos q, sin 2q, cos 2q)` of the coordinate of speed `s` as K variables
    /// (`s s`, `s c`, `2 s c`, `1 − 2 s²`).
    fn double_angle(&mut self, s: usize) -> (ExprId, ExprId, ExprId, ExprId) {
        let sn = self.ar.atom(Atom::Sin(s as u32));
        let cs = self.ar.atom(Atom::Cos(s as u32));
        let coord = self.model.speeds[s].coordinate.clone();
        let ss = self.ar.mul(sn, sn);
        let ss = self.ar.subst(ss, VarKind::K, &format!("sin² {coord}"));
        let sc = self.ar.mul(sn, cs);
        let sc = self
            .ar
            .subst(sc, VarKind::K, &format!("sin {coord} cos {coord}"));
        let s2 = self.ar.scale(sc, 2.0);
        let s2 = self.ar.subst(s2, VarKind::K, &format!("sin 2{coord}"));
        let one = self.ar.one();
        let two_ss = self.ar.scale(ss, 2.0);
        let c2 = self.ar.sub(one, two_ss);
        let c2 = self.ar.subst(c2, VarKind::K, &format!("cos 2{coord}"));
        (ss, sc, s2, c2)
    }

    // ---- mass matrix ----------------------------------------------------------------------------

    /// Column `l`'s entries of M (the joint of link `l` against itself and its ancestors): the
    /// inertia force and moment of the subtree of `l` for a unit acceleration of its joint at
    /// rest, carried up to the root.
    fn mass_matrix_column(
        &mut self,
        l: usize,
        c: &Composite,
        entries: &mut Vec<(usize, usize, ExprId)>,
    ) {
        let put = |entries: &mut Vec<(usize, usize, ExprId)>, a: usize, b: usize, e: ExprId| {
            entries.push((a.min(b), a.max(b), e));
        };
        let wheeled = self.model.wheeled_base().cloned();
        let joint = self.model.links[l].joint.clone().expect("non-root");
        let Some(col) = joint.speed else { return };
        let e = self.axis(l);
        let jc = c.inertia.expect("inertia computed");
        let name = self.link_name(l).to_owned();
        // Inertia force and moment about O_l for a unit acceleration of this joint.
        let (mut f, mut n) = match joint.kind {
            JointKind::Prismatic => {
                let f = self.scale3(c.mass, &e);
                let n = self.cross(&c.first_moment, &e);
                (f, n)
            }
            _ => {
                let f = self.cross(&e, &c.first_moment);
                let n = self.sym_mul(&jc, &e);
                (f, n)
            }
        };
        f = self.subst3(f, VarKind::D, &format!("F(M col {name}) at {name}"));
        n = self.subst3(n, VarKind::D, &format!("N(M col {name}) at {name}"));
        let diag = match joint.kind {
            JointKind::Prismatic => self.dot(&e, &f),
            _ => self.dot(&e, &n),
        };
        put(entries, col, col, diag);
        let mut k = l;
        while let Some(parent) = self.model.links[k].parent {
            let r = self.rotation(k);
            let p = self.position(k);
            let fu = self.rot_up(&r, &f);
            let pname = self.link_name(parent).to_owned();
            f = self.subst3(fu, VarKind::D, &format!("F(M col {name}) at {pname}"));
            let nu = self.rot_up(&r, &n);
            let pxf = self.cross(&p, &f);
            let nn = self.add3(&nu, &pxf);
            n = self.subst3(nn, VarKind::D, &format!("N(M col {name}) at {pname}"));
            k = parent;
            match self.model.links[k].joint.as_ref() {
                Some(pj) if pj.speed.is_some() => {
                    let row = pj.speed.expect("checked");
                    let ek = self.axis(k);
                    let v = match pj.kind {
                        JointKind::Prismatic => self.dot(&ek, &f),
                        _ => self.dot(&ek, &n),
                    };
                    put(entries, row, col, v);
                }
                Some(_) => {}
                None => {
                    if let Some(w) = &wheeled {
                        put(entries, w.x_speed, col, f[0]);
                        put(entries, w.psi_speed, col, n[2]);
                    }
                }
            }
        }
    }

    fn mass_matrix(
        &mut self,
        comp: &[Composite],
        mut entries: Vec<(usize, usize, ExprId)>,
    ) -> Vec<(usize, usize, ExprId)> {
        let put = |entries: &mut Vec<(usize, usize, ExprId)>, a: usize, b: usize, e: ExprId| {
            entries.push((a.min(b), a.max(b), e));
        };
        let wheeled = self.model.wheeled_base().cloned();
        // The base quasi-velocities.
        if let Some(w) = &wheeled {
            let c = &comp[0];
            let jc = c.inertia.expect("inertia computed");
            let (_, kx, _, kp) = self.wheel_terms().expect("wheeled");
            let mxx = self.ar.add(c.mass, kx);
            // x̂ · (ẑ × MS) = −MS_y
            let mxp = self.ar.neg(c.first_moment[1]);
            let mpp = self.ar.add(jc[5], kp);
            put(&mut entries, w.x_speed, w.x_speed, mxx);
            put(&mut entries, w.x_speed, w.psi_speed, mxp);
            put(&mut entries, w.psi_speed, w.psi_speed, mpp);
        }
        let mut entries: Vec<(usize, usize, ExprId)> = entries
            .into_iter()
            .map(|(a, b, e)| {
                let e = if self.ar.hoist_params {
                    self.ar.hoist(e, &format!("M[{a},{b}]"))
                } else {
                    e
                };
                (a, b, e)
            })
            .collect();
        entries.sort_by_key(|&(a, b, _)| (a, b));
        entries
    }

    // ---- gravity --------------------------------------------------------------------------------

    fn gravity(&mut self, comp: &[Composite]) -> Vec<ExprId> {
        let n = self.model.dof();
        let zero = self.ar.zero();
        let mut out = vec![zero; n];
        let g0 = self.gravity_vector();
        let mut acc: Vec<V3> = vec![[zero; 3]; self.model.links.len()];
        acc[0] = [0, 1, 2].map(|i| self.ar.neg(g0[i]));
        for l in 1..self.model.links.len() {
            let parent = self.model.links[l].parent.expect("non-root");
            let r = self.rotation(l);
            let a = self.rot_down(&r, &acc[parent]);
            let name = self.link_name(l).to_owned();
            acc[l] = self.subst3(a, VarKind::D, &format!("gravity acceleration in {name}"));
        }
        for l in 1..self.model.links.len() {
            let joint = self.model.links[l].joint.clone().expect("non-root");
            let Some(row) = joint.speed else { continue };
            let e = self.axis(l);
            let c = &comp[l];
            out[row] = match joint.kind {
                JointKind::Prismatic => {
                    let d = self.dot(&e, &acc[l]);
                    self.ar.mul(c.mass, d)
                }
                _ => {
                    let x = self.cross(&c.first_moment, &acc[l]);
                    self.dot(&e, &x)
                }
            };
        }
        if let Some(w) = self.model.wheeled_base().cloned() {
            let c = &comp[0];
            out[w.x_speed] = self.ar.mul(c.mass, acc[0][0]);
            let x = self.cross(&c.first_moment, &acc[0]);
            out[w.psi_speed] = x[2];
        }
        self.finish(out, "g")
    }

    fn finish(&mut self, v: Vec<ExprId>, label: &str) -> Vec<ExprId> {
        v.into_iter()
            .enumerate()
            .map(|(i, e)| {
                if self.ar.hoist_params {
                    self.ar.hoist(e, &format!("{label}[{i}]"))
                } else {
                    e
                }
            })
            .collect()
    }

    // ---- inverse dynamics (backward accumulation of Kane's generalized inertia forces) ------------

    /// Add the force `f[c]` and moment `n[c]` (about `O_c`) of the complete subtree of `c` to
    /// its parent's.
    fn accumulate(&mut self, c: usize, f: &mut [V3], n: &mut [V3], tag: &str) {
        let parent = self.model.links[c].parent.expect("non-root");
        if f[c].iter().chain(n[c].iter()).all(|x| self.ar.is_zero(*x)) {
            return;
        }
        let cname = self.link_name(c).to_owned();
        let pname = self.link_name(parent).to_owned();
        let r = self.rotation(c);
        let p = self.position(c);
        let fu = self.rot_up(&r, &f[c]);
        let fu = self.subst3(fu, VarKind::D, &format!("f{cname} in {pname}{tag}"));
        let nu = self.rot_up(&r, &n[c]);
        let pxf = self.cross(&p, &fu);
        let nf = self.add3(&f[parent], &fu);
        let nn = self.add3(&n[parent], &nu);
        let nn = self.add3(&nn, &pxf);
        f[parent] = self.subst3(nf, VarKind::D, &format!("f{pname}{tag}"));
        n[parent] = self.subst3(nn, VarKind::D, &format!("n{pname}{tag}"));
    }

    /// Inertia force and moment about its frame origin of the body on link `l` (if any), from
    /// the frame's angular velocity `w`, angular acceleration `wd` and origin acceleration `a`.
    fn body_force(&mut self, l: usize, w: &V3, wd: &V3, a: &V3, tag: &str) -> Option<(V3, V3)> {
        let (m, ms, j) = self.body(l)?;
        let name = self.link_name(l).to_owned();
        let wxms = self.cross(w, &ms);
        let wxms = self.subst3(wxms, VarKind::D, &format!("w{name}xMS{name}{tag}"));
        let ma = self.scale3(m, a);
        let t1 = self.cross(wd, &ms);
        let t2 = self.cross(w, &wxms);
        let fl = self.add3(&ma, &t1);
        let fl = self.add3(&fl, &t2);
        let fl = self.subst3(fl, VarKind::D, &format!("F{name}{tag}"));
        let jwd = self.sym_mul(&j, wd);
        let jw = self.sym_mul(&j, w);
        let jw = self.subst3(jw, VarKind::D, &format!("J{name}w{name}{tag}"));
        let wxjw = self.cross(w, &jw);
        let msxa = self.cross(&ms, a);
        let nl = self.add3(&jwd, &wxjw);
        let nl = self.add3(&nl, &msxa);
        let nl = self.subst3(nl, VarKind::D, &format!("N{name}{tag}"));
        Some((fl, nl))
    }

    /// τ with the given inputs: `with_accel` keeps u̇ (else u̇ = 0), `with_gravity` folds gravity in.
    fn rnea(&mut self, with_accel: bool, with_gravity: bool) -> Vec<ExprId> {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let speed = |ar: &mut Arena, s: usize| ar.atom(Atom::Speed(s as u32));
        let accel = |ar: &mut Arena, s: usize| {
            if with_accel {
                ar.atom(Atom::Accel(s as u32))
            } else {
                ar.zero()
            }
        };
        let tag = match (with_accel, with_gravity) {
            (true, true) => "",
            (false, false) => "|ud=0,g=0",
            (true, false) => "|g=0",
            (false, true) => "|ud=0",
        };
        let mut w: Vec<V3> = vec![[zero; 3]; links];
        let mut wd: Vec<V3> = vec![[zero; 3]; links];
        let mut a: Vec<V3> = vec![[zero; 3]; links];
        if let Some(wb) = model.wheeled_base() {
            let xd = speed(self.ar, wb.x_speed);
            let psid = speed(self.ar, wb.psi_speed);
            let xdd = accel(self.ar, wb.x_speed);
            let psidd = accel(self.ar, wb.psi_speed);
            w[0] = [zero, zero, psid];
            wd[0] = [zero, zero, psidd];
            // a0 = [ẍ, ẋψ̇, 0]: the centripetal term ẋψ̇ along y0.
            let xp = self.ar.mul(xd, psid);
            a[0] = [xdd, xp, zero];
        }
        if with_gravity {
            let g0 = self.gravity_vector();
            a[0] = self.sub3(&a[0], &g0);
        }
        let root = self.link_name(0).to_owned();
        a[0] = self.subst3(a[0], VarKind::K, &format!("a{root}{tag}"));
        // Body inertia forces and moments about the frame origins, each formed in the forward
        // pass as soon as its body's motion is known (short live ranges in the generated code).
        let mut f: Vec<V3> = vec![[zero; 3]; links];
        let mut n: Vec<V3> = vec![[zero; 3]; links];
        if let Some((fl, nl)) = self.body_force(0, &w[0], &wd[0], &a[0], tag) {
            (f[0], n[0]) = (fl, nl);
        }
        // Forward: seed 002 eqs. 3, 4, 6. (A depth-first interleaving of the forward and
        // backward passes keeps fewer values live, but measured for Krang it made the compiled
        // functions larger and slower: their speed is bound by code size.)
        for l in 1..links {
            let i = model.links[l].parent.expect("non-root");
            let joint = model.links[l].joint.clone().expect("non-root");
            let name = self.link_name(l).to_owned();
            let r = self.rotation(l);
            let p = self.position(l);
            let e = self.axis(l);
            let wi = self.rot_down(&r, &w[i]);
            let wi = self.subst3(
                wi,
                VarKind::K,
                &format!("w{} in {name}{tag}", self.link_name(i)),
            );
            let wdi = self.rot_down(&r, &wd[i]);
            let (wj, wdj, extra_a) = match (joint.kind, joint.speed) {
                (JointKind::Revolute, Some(s)) => {
                    let u = speed(self.ar, s);
                    let ud = accel(self.ar, s);
                    let ue = self.scale3(u, &e);
                    let ude = self.scale3(ud, &e);
                    let wxe = self.cross(&wi, &e);
                    let uwxe = self.scale3(u, &wxe);
                    let wj = self.add3(&wi, &ue);
                    let t = self.add3(&wdi, &ude);
                    let wdj = self.add3(&t, &uwxe);
                    (wj, wdj, [zero; 3])
                }
                (JointKind::Prismatic, Some(s)) => {
                    let u = speed(self.ar, s);
                    let ud = accel(self.ar, s);
                    let ude = self.scale3(ud, &e);
                    let wxe = self.cross(&wi, &e);
                    let two_u = self.ar.scale(u, 2.0);
                    let cor = self.scale3(two_u, &wxe);
                    let extra = self.add3(&ude, &cor);
                    (wi, wdi, extra)
                }
                _ => (wi, wdi, [zero; 3]),
            };
            w[l] = self.subst3(wj, VarKind::K, &format!("w{name}{tag}"));
            wd[l] = self.subst3(wdj, VarKind::K, &format!("wd{name}{tag}"));
            // a_j = jAi (a_i + α_i × P + ω_i × (ω_i × P)) (+ prismatic terms)
            let wxp = self.cross(&w[i], &p);
            let wxp = self.subst3(
                wxp,
                VarKind::K,
                &format!("w{}xP{name}{tag}", self.link_name(i)),
            );
            let t1 = self.cross(&wd[i], &p);
            let t2 = self.cross(&w[i], &wxp);
            let t = self.add3(&a[i], &t1);
            let t = self.add3(&t, &t2);
            let t = self.subst3(
                t,
                VarKind::K,
                &format!("a{name} in {}{tag}", self.link_name(i)),
            );
            let aj = self.rot_down(&r, &t);
            let aj = self.add3(&aj, &extra_a);
            a[l] = self.subst3(aj, VarKind::K, &format!("a{name}{tag}"));
            if let Some((fl, nl)) = self.body_force(l, &w[l], &wd[l], &a[l], tag) {
                (f[l], n[l]) = (fl, nl);
            }
        }
        // Backward accumulation over subtrees.
        for c in (1..links).rev() {
            self.accumulate(c, &mut f, &mut n, tag);
        }
        let mut out = vec![zero; model.dof()];
        for l in 1..links {
            let joint = model.links[l].joint.clone().expect("non-root");
            let Some(row) = joint.speed else { continue };
            let e = self.axis(l);
            out[row] = match joint.kind {
                JointKind::Prismatic => self.dot(&e, &f[l]),
                _ => self.dot(&e, &n[l]),
            };
        }
        if model.wheeled_base().is_some() {
            let (xs, kx, ps, kp) = self.wheel_terms().expect("wheeled");
            out[xs] = f[0][0];
            out[ps] = n[0][2];
            if with_accel {
                let xdd = self.ar.atom(Atom::Accel(xs as u32));
                let psidd = self.ar.atom(Atom::Accel(ps as u32));
                let tx = self.ar.mul(kx, xdd);
                let tp = self.ar.mul(kp, psidd);
                out[xs] = self.ar.add(out[xs], tx);
                out[ps] = self.ar.add(out[ps], tp);
            }
        }
        self.finish(out, if with_accel { "tau" } else { "c" })
    }

    // ---- Coriolis matrix ------------------------------------------------------------------------

    /// `C(q, u)` with `c = C u` and `Ṁ − 2C` skew-symmetric, as `(row, col, expr)` entries.
    ///
    /// Spatial vectors in body coordinates: motion `V = (ω; v)` (v of the frame origin), force
    /// `f = (n; f)` (n about the frame origin). Body k's spatial inertia `I_k` is constant in its
    /// frame, its body Jacobian `J_k` (`V_k = J_k u`) has the column `ᵏX_j S_j` for every speed j
    /// on its path to the root (`S_j` constant in the frame of joint j: `(e; 0)` revolute,
    /// `(0; e)` prismatic, `(0; x̂)` and `(ẑ; 0)` for ẋ, ψ̇ in frame 0), and
    /// `J̇_k,j = −(V_k − ᵏX_j V_j) × J_k,j`. With `M = Σ J_kᵀ I_k J_k` (plus constant wheel terms),
    ///
    /// `C = Σ_k J_kᵀ (I_k J̇_k + B_k J_k)`, `B_k = ½ [(I_k V_k)×̄* + I_k (V_k×) + (V_k×*) I_k]`
    ///
    /// (`(h×̄*) m := m ×* h`). B_k is skew-symmetric and `B_k V_k = V_k ×* I_k V_k`, so
    /// `C u = c` and `C + Cᵀ = Σ (J̇ᵀ I J + Jᵀ I J̇) = Ṁ`. This choice of B (the average of
    /// `(I V)×̄*` and `I (V×) − (I (V×))ᵀ`) makes `I_k J̇_k,j + B_k J_k,j = I_k ᵏX_j (V_j × S_j) +
    /// ½ (I_k V_k)×̄* J_k,j + ½ D_k J_k,j` with `D_k = (V_k×*) I_k − I_k (V_k×)`, the rate of
    /// the inertia in a fixed frame: symmetric, of the inertia form `[[J̇, [ċ]×], [−[ċ]×, 0]]`
    /// (`J̇ = [ω]× J − J [ω]× + 2 (c·v) 1 − c vᵀ − v cᵀ`, `ċ = ω × c + m v`, c = MS), so it is
    /// summed over subtrees exactly like composite inertias (with mass 0). Over the subtree of
    /// the link of speed i, in its frame: `I^c_i` (composite inertia), `h^c_i = Σ I_k V_k`
    /// (subtree momentum), `D^c_i = Σ D_k`; then
    ///
    /// * `h_i = I^c_i (V_i × S_i) + ½ S_i ×* h^c_i + ½ D^c_i S_i`: `C[j, i] = S_j · h_i` for i
    ///   and every speed j above it (h_i carried up as a force);
    /// * `G1_i = ½ D^c_i S_i − ½ S_i ×* h^c_i`, `G2_i = I^c_i S_i` (M's column force):
    ///   `C[i, j] = S_j · G1_i + (V_j × S_j) · G2_i` for every speed j strictly above i
    ///   (identity `a · (m ×* f) = −(m × a) · f`).
    ///
    /// Three force vectors carried per (descendant, ancestor) pair: the cost grows with the sum
    /// of depths, like M's.
    fn coriolis_matrix(&mut self, comp: &[Composite]) -> Vec<(usize, usize, ExprId)> {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let half = 0.5;
        // Velocities of the frames, in their own frames.
        let vel = self.velocities();
        // Body momenta h_k = I_k V_k and inertia rates D_k = (ċ_k, J̇_k).
        let mut hc: Vec<V6> = vec![[zero; 6]; links];
        let mut dc: Vec<(V3, [ExprId; 6])> = vec![([zero; 3], [zero; 6]); links];
        for l in 0..links {
            let Some((m, ms, j)) = self.body(l) else {
                continue;
            };
            let name = self.link_name(l).to_owned();
            let (w, v) = split3(&vel[l]);
            // h = (J ω + MS × v; m v + ω × MS); its linear part is also ċ of the inertia rate.
            let tag = "|ud=0,g=0";
            let wxms = self.cross(&w, &ms);
            let wxms = self.subst3(wxms, VarKind::D, &format!("w{name}xMS{name}{tag}"));
            let jw = self.sym_mul(&j, &w);
            let jw = self.subst3(jw, VarKind::D, &format!("J{name}w{name}{tag}"));
            let msxv = self.cross(&ms, &v);
            let n = self.add3(&jw, &msxv);
            let mv = self.scale3(m, &v);
            let f = self.add3(&mv, &wxms);
            hc[l] = self.subst_force(join3(&n, &f), &format!("h{name}"));
            // J̇ = W + Wᵀ + 2 (c·v) 1 − (c vᵀ + v cᵀ), W = [ω]× J (c = MS).
            let jm = Self::sym(&j);
            let mut wj = [[zero; 3]; 3];
            for b in 0..3 {
                let col = [jm[0][b], jm[1][b], jm[2][b]];
                let x = self.cross(&w, &col);
                for a in 0..3 {
                    wj[a][b] = x[a];
                }
            }
            let cv = self.dot(&ms, &v);
            let two_cv = self.ar.scale(cv, 2.0);
            let labels = ["xx", "xy", "xz", "yy", "yz", "zz"];
            let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
            let mut jd = [zero; 6];
            for (k, &(a, b)) in idx.iter().enumerate() {
                let cva = self.ar.mul(ms[a], v[b]);
                let vca = self.ar.mul(v[a], ms[b]);
                let sym = self.ar.add(cva, vca);
                let sym = self.ar.neg(sym);
                let diag = if a == b { two_cv } else { zero };
                let e = self.ar.sum([wj[a][b], wj[b][a], diag, sym]);
                jd[k] = self
                    .ar
                    .subst(e, VarKind::D, &format!("Jd{name}.{}", labels[k]));
            }
            // ċ = ω × MS + m v: the linear momentum.
            let cd = split3(&hc[l]).1;
            dc[l] = (cd, jd);
        }
        // Subtree sums, backward: momenta as forces, inertia rates as inertias of mass 0. The
        // first-moment rate ċ of a subtree is its linear momentum (both move up as R·x).
        let labels = ["xx", "xy", "xz", "yy", "yz", "zz"];
        for c in (1..links).rev() {
            let parent = model.links[c].parent.expect("non-root");
            let name = self.link_name(c).to_owned();
            let pname = self.link_name(parent).to_owned();
            hc[c] = self.subst_force(hc[c], &format!("hC{name}"));
            let jd = dc[c].1;
            let jd = [0, 1, 2, 3, 4, 5].map(|k| {
                self.ar
                    .subst(jd[k], VarKind::D, &format!("JdC{name}.{}", labels[k]))
            });
            dc[c] = (split3(&hc[c]).1, jd);
            if hc[c].iter().chain(jd.iter()).all(|x| self.ar.is_zero(*x)) {
                continue;
            }
            let r = self.rotation(c);
            let p = self.position(c);
            let up = self.force_up(c, &hc[c], &format!("hC{name} in {pname}"));
            hc[parent] = self.add6(&hc[parent], &up);
            let u = split3(&up).1;
            let mut pjd = dc[parent].1;
            self.add_inertia_to_parent(c, &r, &p, zero, &u, &jd, &name, "JdC", &mut pjd);
            dc[parent].1 = pjd;
        }
        {
            let name = self.link_name(0).to_owned();
            hc[0] = self.subst_force(hc[0], &format!("hC{name}"));
            let jd = dc[0]
                .1
                .map(|x| self.ar.subst(x, VarKind::D, &format!("JdC{name}")));
            dc[0] = (split3(&hc[0]).1, jd);
        }
        // The columns (speeds) of every link: a joint's, or the base's ẋ and ψ̇ at the root.
        let mut cols: Vec<Vec<(usize, V6)>> = vec![Vec::new(); links];
        if let Some(w) = model.wheeled_base() {
            let one = self.ar.one();
            cols[0].push((w.x_speed, [zero, zero, zero, one, zero, zero]));
            cols[0].push((w.psi_speed, [zero, zero, one, zero, zero, zero]));
        }
        for l in 1..links {
            let joint = model.links[l].joint.as_ref().expect("non-root");
            let Some(s) = joint.speed else { continue };
            let e = self.axis(l);
            let axis = match joint.kind {
                JointKind::Prismatic => [zero, zero, zero, e[0], e[1], e[2]],
                _ => [e[0], e[1], e[2], zero, zero, zero],
            };
            cols[l].push((s, axis));
        }
        // V_l × S for every column, in its frame (the Coriolis bias of a unit speed).
        let mut vxs: Vec<Vec<V6>> = vec![Vec::new(); links];
        for l in 0..links {
            for k in 0..cols[l].len() {
                let (sp, s) = cols[l][k];
                let x = self.motion_cross(&vel[l], &s);
                let label = format!("V{}xS({})", self.link_name(l), model.speeds[sp].name);
                let x = self.subst_motion(x, &label);
                vxs[l].push(x);
            }
        }
        let mut entries: BTreeMap<(usize, usize), ExprId> = BTreeMap::new();
        let put = |entries: &mut BTreeMap<(usize, usize), ExprId>, a: usize, b: usize, e| {
            let old = entries.insert((a, b), e);
            debug_assert!(old.is_none(), "C[{a},{b}] set twice");
        };
        for l in 0..links {
            for k in 0..cols[l].len() {
                let (sp, s) = cols[l][k];
                let sname = model.speeds[sp].name.clone();
                let name = self.link_name(l).to_owned();
                let c = &comp[l];
                let jc = c.inertia.expect("inertia computed");
                let ic_vxs = self.inertia_mul(c.mass, &c.first_moment, &jc, &vxs[l][k]);
                let ic_vxs = self.subst_force(ic_vxs, &format!("IC{name}(VxS({sname}))"));
                let sxh = self.force_cross(&s, &hc[l]);
                let sxh = self.subst_force(sxh, &format!("S({sname})x*hC{name}"));
                let (cd, jd) = dc[l];
                let ds = self.inertia_mul(zero, &cd, &jd, &s);
                let ds = self.subst_force(ds, &format!("DC{name}S({sname})"));
                let mut h = [zero; 6];
                let mut g1 = [zero; 6];
                for i in 0..6 {
                    let a = self.ar.scale(sxh[i], half);
                    let b = self.ar.scale(ds[i], half);
                    h[i] = self.ar.sum([ic_vxs[i], a, b]);
                    g1[i] = self.ar.sub(b, a);
                }
                let mut h = self.subst_force(h, &format!("h(C col {sname}) at {name}"));
                let mut g1 = self.subst_force(g1, &format!("G1(C row {sname}) at {name}"));
                let g2 = self.inertia_mul(c.mass, &c.first_moment, &jc, &s);
                let mut g2 = self.subst_force(g2, &format!("G2(C row {sname}) at {name}"));
                // Speeds of the same frame (the base's ẋ, ψ̇; or the joint itself).
                for &(sa, sv) in &cols[l] {
                    let e = self.dot6(&sv, &h);
                    put(&mut entries, sa, sp, e);
                }
                let mut at = l;
                while let Some(parent) = model.links[at].parent {
                    let pname = self.link_name(parent).to_owned();
                    h = self.force_up(at, &h, &format!("h(C col {sname}) at {pname}"));
                    g1 = self.force_up(at, &g1, &format!("G1(C row {sname}) at {pname}"));
                    g2 = self.force_up(at, &g2, &format!("G2(C row {sname}) at {pname}"));
                    at = parent;
                    for (ka, &(sa, sv)) in cols[at].iter().enumerate() {
                        let e = self.dot6(&sv, &h);
                        put(&mut entries, sa, sp, e);
                        let t1 = self.dot6(&sv, &g1);
                        let t2 = self.dot6(&vxs[at][ka], &g2);
                        let e = self.ar.add(t1, t2);
                        put(&mut entries, sp, sa, e);
                    }
                }
            }
        }
        let mut out = Vec::with_capacity(entries.len());
        for ((a, b), e) in entries {
            if self.ar.is_zero(e) {
                continue;
            }
            let e = if self.ar.hoist_params {
                self.ar.hoist(e, &format!("C[{a},{b}]"))
            } else {
                e
            };
            out.push((a, b, e));
        }
        out
    }

    /// Spatial velocities `(ω; v)` of every frame in its own frame (`v` of the origin).
    fn velocities(&mut self) -> Vec<V6> {
        let model = self.model;
        let links = model.links.len();
        let zero = self.ar.zero();
        let mut w: Vec<V3> = vec![[zero; 3]; links];
        let mut v: Vec<V3> = vec![[zero; 3]; links];
        if let Some(wb) = model.wheeled_base() {
            w[0] = [zero, zero, self.ar.atom(Atom::Speed(wb.psi_speed as u32))];
            v[0] = [self.ar.atom(Atom::Speed(wb.x_speed as u32)), zero, zero];
        }
        let tag = "|ud=0,g=0";
        for l in 1..links {
            let i = model.links[l].parent.expect("non-root");
            let joint = model.links[l].joint.clone().expect("non-root");
            let name = self.link_name(l).to_owned();
            let iname = self.link_name(i).to_owned();
            let r = self.rotation(l);
            let p = self.position(l);
            let e = self.axis(l);
            // ω as in the inverse dynamics (same variables).
            let wi = self.rot_down(&r, &w[i]);
            let wi = self.subst3(wi, VarKind::K, &format!("w{iname} in {name}{tag}"));
            let mut vl = {
                let wxp = self.cross(&w[i], &p);
                let wxp = self.subst3(wxp, VarKind::K, &format!("w{iname}xP{name}{tag}"));
                let t = self.add3(&v[i], &wxp);
                let t = self.subst3(t, VarKind::K, &format!("v{name} in {iname}"));
                self.rot_down(&r, &t)
            };
            let mut wl = wi;
            match (joint.kind, joint.speed) {
                (JointKind::Revolute, Some(s)) => {
                    let u = self.ar.atom(Atom::Speed(s as u32));
                    let ue = self.scale3(u, &e);
                    wl = self.add3(&wi, &ue);
                }
                (JointKind::Prismatic, Some(s)) => {
                    let u = self.ar.atom(Atom::Speed(s as u32));
                    let ue = self.scale3(u, &e);
                    vl = self.add3(&vl, &ue);
                }
                _ => {}
            }
            w[l] = self.subst3(wl, VarKind::K, &format!("w{name}{tag}"));
            v[l] = self.subst3(vl, VarKind::K, &format!("v{name}"));
        }
        (0..links)
            .map(|l| [w[l][0], w[l][1], w[l][2], v[l][0], v[l][1], v[l][2]])
            .collect()
    }

    // ---- spatial algebra (motion (ω; v), force (n; f)) ----------------------------------------

    /// Spatial inertia with mass `m`, first moment `c`, inertia `j` about the origin, times the
    /// motion `x`: `(J x_ω + c × x_v; m x_v − c × x_ω)`. With `m = 0` and `(c, j) = (ċ, J̇)`: D x.
    fn inertia_mul(&mut self, m: ExprId, c: &V3, j: &[ExprId; 6], x: &V6) -> V6 {
        let (xw, xv) = split3(x);
        let jw = self.sym_mul(j, &xw);
        let cxv = self.cross(c, &xv);
        let n = self.add3(&jw, &cxv);
        let mv = self.scale3(m, &xv);
        let cxw = self.cross(c, &xw);
        let f = self.sub3(&mv, &cxw);
        join3(&n, &f)
    }

    /// Motion cross product `a × b = (ω_a × ω_b; ω_a × v_b + v_a × ω_b)`.
    fn motion_cross(&mut self, a: &V6, b: &V6) -> V6 {
        let (aw, av) = split3(a);
        let (bw, bv) = split3(b);
        let w = self.cross(&aw, &bw);
        let t1 = self.cross(&aw, &bv);
        let t2 = self.cross(&av, &bw);
        let v = self.add3(&t1, &t2);
        join3(&w, &v)
    }

    /// Force cross product `m ×* f = (ω × n + v × f; ω × f)`.
    fn force_cross(&mut self, m: &V6, f: &V6) -> V6 {
        let (w, v) = split3(m);
        let (n, ff) = split3(f);
        let t1 = self.cross(&w, &n);
        let t2 = self.cross(&v, &ff);
        let top = self.add3(&t1, &t2);
        let bot = self.cross(&w, &ff);
        join3(&top, &bot)
    }

    fn dot6(&mut self, a: &V6, b: &V6) -> ExprId {
        let t: Vec<ExprId> = (0..6).map(|i| self.ar.mul(a[i], b[i])).collect();
        self.ar.sum(t)
    }

    fn add6(&mut self, a: &V6, b: &V6) -> V6 {
        [0, 1, 2, 3, 4, 5].map(|i| self.ar.add(a[i], b[i]))
    }

    /// Substitution variables (kind D) for a force: `{label}.n.x` … `{label}.f.z`.
    fn subst_force(&mut self, x: V6, label: &str) -> V6 {
        let (a, b) = split3(&x);
        let a = self.subst3(a, VarKind::D, &format!("{label}.n"));
        let b = self.subst3(b, VarKind::D, &format!("{label}.f"));
        join3(&a, &b)
    }

    /// Substitution variables (kind K) for a motion: `{label}.w.x` … `{label}.v.z`.
    fn subst_motion(&mut self, x: V6, label: &str) -> V6 {
        let (a, b) = split3(&x);
        let a = self.subst3(a, VarKind::K, &format!("{label}.w"));
        let b = self.subst3(b, VarKind::K, &format!("{label}.v"));
        join3(&a, &b)
    }

    /// A force of frame `child` moved to its parent: `(R n + P × R f; R f)`.
    fn force_up(&mut self, child: usize, x: &V6, label: &str) -> V6 {
        let r = self.rotation(child);
        let p = self.position(child);
        let (n, f) = split3(x);
        let fu = self.rot_up(&r, &f);
        let fu = self.subst3(fu, VarKind::D, &format!("{label}.f"));
        let nu = self.rot_up(&r, &n);
        let pxf = self.cross(&p, &fu);
        let nn = self.add3(&nu, &pxf);
        let nn = self.subst3(nn, VarKind::D, &format!("{label}.n"));
        join3(&nn, &fu)
    }
}

impl Derivation {
    /// Evaluate function `name` numerically from the symbolic expressions (no code generation):
    /// a dense row-major `n × n` matrix (both triangles) or an `n`-vector. Parameter values are
    /// used in [`ParamMode::Runtime`]; in baked mode the model's values are already folded in.
    pub fn evaluate(
        &self,
        name: &str,
        params: &[f64],
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        let f = self
            .function(name)
            .unwrap_or_else(|| panic!("no function `{name}`"));
        let vals = self.arena.eval(&crate::expr::Values { params, q, u, ud });
        let n = self.dof;
        match f.shape {
            Shape::SymmetricMatrix => {
                let mut m = vec![0.0; n * n];
                for &(r, c, e) in &f.entries {
                    m[r * n + c] = vals[e.index()];
                    m[c * n + r] = vals[e.index()];
                }
                m
            }
            Shape::Matrix => {
                let mut m = vec![0.0; n * n];
                for &(r, c, e) in &f.entries {
                    m[r * n + c] = vals[e.index()];
                }
                m
            }
            Shape::Vector => {
                let mut v = vec![0.0; n];
                for &(r, _, e) in &f.entries {
                    v[r] = vals[e.index()];
                }
                v
            }
        }
    }
}
