//! The arena itself: node and leaf types, interning, per-phase request tracking, mimic leaves, and
//! the canonicalising constructors (sums, products, powers) that keep every node simplified.

use std::collections::HashMap;
use std::hash::BuildHasher as _;

use rustc_hash::{FxBuildHasher, FxHashMap};

/// Handle of a node in an [`Arena`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct ExprId(pub u32);

impl ExprId {
    /// Position in the arena.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A hashable f64 (bit pattern, with −0 normalised to +0).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Num(u64);

impl Num {
    /// Wrap a value.
    pub fn new(v: f64) -> Self {
        Num(if v == 0.0 { 0 } else { v.to_bits() })
    }
    /// The value.
    pub fn get(self) -> f64 {
        f64::from_bits(self.0)
    }
}

/// Leaves of expressions.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Atom {
    /// Model parameter (index into `Model::params`).
    Param(u32),
    /// Generalized speed `u[i]`.
    Speed(u32),
    /// Generalized acceleration `u̇[i]`.
    Accel(u32),
    /// `sin(q[i])` of the coordinate whose speed index is `i`.
    Sin(u32),
    /// `cos(q[i])`.
    Cos(u32),
    /// The coordinate `q[i]` itself, by its index in `q` (prismatic joints; a floating base's
    /// position and quaternion). The index of speed `s`'s coordinate is `s`, or `s + 1` for a
    /// joint speed of a floating base ([`Arena::coordinate_index`]).
    Coord(u32),
    /// Substitution variable (index into [`Arena::vars`]).
    Var(u32),
}

/// An interned node.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub enum Node {
    /// A number.
    Const(Num),
    /// A leaf.
    Atom(Atom),
    /// `constant + Σ coef·term`.
    Sum {
        /// The constant part.
        constant: Num,
        /// `(term, coefficient)` pairs sorted by term.
        terms: Box<[(ExprId, Num)]>,
    },
    /// `Π base^power`, sorted by base.
    Prod(Box<[(ExprId, i32)]>),
}

/// Kind of a substitution variable, as in the reports.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum VarKind {
    /// Kinematic quantity (rotations, ω, v, α, a): depends on q, u, u̇ and lengths only.
    K,
    /// Inertial or gravity term: involves inertial parameters or gravity.
    D,
}

/// A substitution variable: a name for a compound subexpression.
#[derive(Clone, Debug)]
pub struct VarInfo {
    /// The expression it stands for.
    pub def: ExprId,
    /// The node `Atom::Var(i)` that refers to it.
    pub node: ExprId,
    /// K or D.
    pub kind: VarKind,
    /// What it is (`w2.x`, `f3.z`, `JC4l.xx`).
    pub label: String,
}

/// Names used when printing expressions.
#[derive(Clone, Debug, Default)]
pub struct Names {
    /// Parameter symbols by index.
    pub params: Vec<String>,
    /// Speed names by index (`qd_imu`).
    pub speeds: Vec<String>,
    /// Coordinate names by speed index (`q_imu`).
    pub coords: Vec<String>,
    /// Per parameter: whether it is a length (`L1`). A substitution variable that mentions no
    /// parameter other than lengths is kinematic (K); one that mentions a mass, a first moment,
    /// an inertia, a wheel constant or gravity is inertial/gravity (D). Missing entries count as
    /// not lengths.
    pub lengths: Vec<bool>,
}

/// The expression arena.
#[derive(Clone, Debug)]
pub struct Arena {
    pub(super) nodes: Vec<Node>,
    /// The interning table: the hash of every node of `nodes` and its handle (each node is
    /// stored once, in `nodes`; the hash is kept so that growing the table reads no node).
    pub(super) table: hashbrown::HashTable<(u64, ExprId)>,
    /// Per node: depends on parameters and constants only.
    pub(super) param_only: Vec<bool>,
    pub(super) vars: Vec<VarInfo>,
    pub(super) var_by_def: FxHashMap<ExprId, u32>,
    /// Names for printing.
    pub names: Names,
    /// Whether [`Arena::subst`] hoists parameter-only parts into their own variables.
    pub hoist_params: bool,
    /// Per node: when the current phase first asked for it (`u32::MAX`: not yet), see
    /// [`Arena::begin_phase`].
    pub(super) stamps: Vec<u32>,
    /// Requests so far in the current phase.
    pub(super) clock: u32,
    /// The nodes the current phase asked for, in the order it first asked (`stamps` of these
    /// are their positions): a phase is reset and read in time proportional to what it asked
    /// for, not to the arena (hundreds of per-frame phases over a large arena).
    pub(super) touched: Vec<ExprId>,
    /// Memo of [`Arena::diff`].
    pub(super) diff_memo: DiffMemo,
    /// Per speed index: the mimic constraint `q = a·q_master + b` of a dependent speed (see
    /// [`Arena::set_mimic`]), `None` for an independent one.
    pub(super) mimics: Vec<Option<MimicLeaf>>,
    /// Whether the coordinates are a floating base's (`q` has the base's seven coordinates, then
    /// the joints': speed `s ≥ 6` is the rate of `q[s + 1]`), see [`Arena::set_floating`].
    pub(super) floating: bool,
}

/// A dependent coordinate `q = multiplier · q[master] + offset` (a mimic joint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MimicLeaf {
    /// The independent speed index.
    pub master: u32,
    /// The factor `a`.
    pub multiplier: f64,
    /// The offset `b`.
    pub offset: f64,
}

/// Numeric values of the leaves, for [`Arena::eval`].
#[derive(Clone, Debug, Default)]
pub struct Values<'a> {
    /// Parameter values.
    pub params: &'a [f64],
    /// Coordinates `q` (sin/cos are taken of these).
    pub q: &'a [f64],
    /// Speeds `u`.
    pub u: &'a [f64],
    /// Accelerations `u̇`.
    pub ud: &'a [f64],
}

impl Arena {
    /// An empty arena.
    pub fn new(names: Names) -> Self {
        let mut a = Arena {
            nodes: Vec::new(),
            table: hashbrown::HashTable::new(),
            param_only: Vec::new(),
            vars: Vec::new(),
            var_by_def: FxHashMap::default(),
            names,
            hoist_params: false,
            stamps: Vec::new(),
            clock: 0,
            touched: Vec::new(),
            diff_memo: Default::default(),
            mimics: Vec::new(),
            floating: false,
        };
        a.constant(0.0);
        a.constant(1.0);
        a
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Is the arena empty (never: 0 and 1 are always present)?
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The node behind a handle.
    pub fn node(&self, e: ExprId) -> &Node {
        &self.nodes[e.index()]
    }

    /// All substitution variables, in creation order.
    pub fn vars(&self) -> &[VarInfo] {
        &self.vars
    }

    /// Does `e` depend on parameters and constants only?
    pub fn is_param_only(&self, e: ExprId) -> bool {
        self.param_only[e.index()]
    }

    /// Start a new phase: forget which nodes were asked for so far. The derivation runs one
    /// phase per generated function, so that each function's statements can be scheduled in
    /// the order its own recursion forms them, even where it reuses nodes that an earlier
    /// function created (see [`Arena::phase_order`]).
    pub fn begin_phase(&mut self) {
        for e in self.touched.drain(..) {
            self.stamps[e.index()] = u32::MAX;
        }
        self.clock = 0;
    }

    /// The nodes the current phase asked for (created or found interned), in the order it first
    /// asked for them.
    pub fn phase_order(&self) -> Vec<ExprId> {
        self.touched.clone()
    }

    /// Ask for `e` and everything it reads (through substitution variables) in the current
    /// phase, children first: a phase that reuses expressions another phase built (the base
    /// regressors reuse the regressors' columns) schedules them in this order.
    pub fn touch_tree(&mut self, e: ExprId) {
        let mut stack = vec![(e, false)];
        while let Some((n, done)) = stack.pop() {
            if self.stamps[n.index()] != u32::MAX {
                continue;
            }
            if done {
                self.touch(n);
                continue;
            }
            stack.push((n, true));
            match self.node(n) {
                Node::Sum { terms, .. } => {
                    stack.extend(terms.iter().rev().map(|(t, _)| (*t, false)))
                }
                Node::Prod(f) => stack.extend(f.iter().rev().map(|(b, _)| (*b, false))),
                Node::Atom(Atom::Var(v)) => stack.push((self.vars[*v as usize].def, false)),
                Node::Const(_) | Node::Atom(_) => {}
            }
        }
    }

    pub(super) fn touch(&mut self, id: ExprId) {
        let s = &mut self.stamps[id.index()];
        if *s == u32::MAX {
            *s = self.clock;
            self.clock += 1;
            self.touched.push(id);
        }
    }

    pub(super) fn intern(&mut self, n: Node) -> ExprId {
        let hash = FxBuildHasher.hash_one(&n);
        let nodes = &self.nodes;
        if let Some(&(_, id)) = self
            .table
            .find(hash, |(h, id)| *h == hash && nodes[id.index()] == n)
        {
            self.touch(id);
            return id;
        }
        let po = match &n {
            Node::Const(_) => true,
            Node::Atom(Atom::Param(_)) => true,
            Node::Atom(Atom::Var(v)) => self.param_only[self.vars[*v as usize].def.index()],
            Node::Atom(_) => false,
            Node::Sum { terms, .. } => terms.iter().all(|(t, _)| self.param_only[t.index()]),
            Node::Prod(f) => f.iter().all(|(b, _)| self.param_only[b.index()]),
        };
        let id = ExprId(self.nodes.len() as u32);
        self.nodes.push(n);
        self.param_only.push(po);
        self.stamps.push(u32::MAX);
        self.touch(id);
        self.table.insert_unique(hash, (hash, id), |(h, _)| *h);
        id
    }

    /// The constant `v`.
    pub fn constant(&mut self, v: f64) -> ExprId {
        self.intern(Node::Const(Num::new(v)))
    }
    /// Zero.
    pub fn zero(&self) -> ExprId {
        ExprId(0)
    }
    /// One.
    pub fn one(&self) -> ExprId {
        ExprId(1)
    }
    /// A leaf. For a dependent speed `i` ([`Arena::set_mimic`]) the leaves are expressions of its
    /// master's: `u[i] = a·u[m]`, `u̇[i] = a·u̇[m]`, `q[i] = a·q[m] + b`, and for `a = ±1, b = 0`
    /// `sin q[i] = ±sin q[m]`, `cos q[i] = cos q[m]`; otherwise `sin q[i]`, `cos q[i]` stay leaves,
    /// whose angle `a·q[m] + b` the generated code forms before its batched sine and cosine
    /// ([`Arena::mimic`]).
    pub fn atom(&mut self, a: Atom) -> ExprId {
        if let Some(e) = self.mimic_atom(a) {
            return e;
        }
        self.intern(Node::Atom(a))
    }

    /// Declares speed `speed` dependent: `q[speed] = m.multiplier · q[m.master] + m.offset` (and
    /// its speed and acceleration `a` times the master's). Call before building expressions.
    pub fn set_mimic(&mut self, speed: u32, m: MimicLeaf) {
        let s = speed as usize;
        if self.mimics.len() <= s {
            self.mimics.resize(s + 1, None);
        }
        self.mimics[s] = Some(m);
    }

    /// Declare the coordinates a floating base's: the coordinate of joint speed `s ≥ 6` is
    /// `q[s + 1]` (the base's quaternion has four entries for three speeds).
    pub fn set_floating(&mut self) {
        self.floating = true;
    }

    /// Index in `q` of speed `s`'s coordinate (`s`, or `s + 1` for a floating base's joints).
    pub fn coordinate_index(&self, s: u32) -> u32 {
        if self.floating && s >= 6 { s + 1 } else { s }
    }

    /// The mimic constraint of speed `s`, if it is dependent.
    pub fn mimic(&self, s: u32) -> Option<MimicLeaf> {
        self.mimics.get(s as usize).copied().flatten()
    }

    /// The angle of `sin`/`cos` leaf `s` given the coordinates (`q[s]`, or `a·q[m] + b` for a
    /// dependent speed).
    pub fn angle(&self, q: &[f64], s: u32) -> f64 {
        match self.mimic(s) {
            Some(m) => m.multiplier * q[self.coordinate_index(m.master) as usize] + m.offset,
            None => q[self.coordinate_index(s) as usize],
        }
    }

    /// The expression of a dependent speed's leaf, if it is not a leaf of its own.
    pub(super) fn mimic_atom(&mut self, a: Atom) -> Option<ExprId> {
        let (s, ctor): (u32, fn(u32) -> Atom) = match a {
            Atom::Speed(s) => (s, Atom::Speed),
            Atom::Accel(s) => (s, Atom::Accel),
            // A floating base's own coordinates (q[0..7]) are never dependent.
            Atom::Coord(k) if self.floating && k < 7 => return None,
            Atom::Coord(k) => (k - u32::from(self.floating), Atom::Coord),
            Atom::Sin(s) => (s, Atom::Sin),
            Atom::Cos(s) => (s, Atom::Cos),
            Atom::Param(_) | Atom::Var(_) => return None,
        };
        let m = self.mimic(s)?;
        let (k, b) = (m.multiplier, m.offset);
        let pure_sign = b == 0.0 && (k == 1.0 || k == -1.0);
        let master = match a {
            Atom::Coord(_) => self.coordinate_index(m.master),
            _ => m.master,
        };
        let master = self.intern(Node::Atom(ctor(master)));
        Some(match a {
            Atom::Speed(_) | Atom::Accel(_) => self.scale(master, k),
            Atom::Coord(_) => {
                let t = self.scale(master, k);
                let b = self.constant(b);
                self.add(t, b)
            }
            Atom::Sin(_) if pure_sign => self.scale(master, k),
            Atom::Cos(_) if pure_sign => master,
            _ => return None,
        })
    }

    /// The value of `e` if it is a constant.
    pub fn as_const(&self, e: ExprId) -> Option<f64> {
        match self.node(e) {
            Node::Const(c) => Some(c.get()),
            _ => None,
        }
    }

    /// Is `e` the constant zero?
    pub fn is_zero(&self, e: ExprId) -> bool {
        self.as_const(e) == Some(0.0)
    }

    /// `c₀ + Σ cᵢ tᵢ` view of any expression.
    pub(super) fn linear(&self, e: ExprId) -> (f64, Vec<(ExprId, f64)>) {
        match self.node(e) {
            Node::Const(c) => (c.get(), Vec::new()),
            Node::Sum { constant, terms } => (
                constant.get(),
                terms.iter().map(|(t, c)| (*t, c.get())).collect(),
            ),
            _ => (0.0, vec![(e, 1.0)]),
        }
    }

    /// `k · Π bᵢ^nᵢ` view of any expression.
    pub(super) fn monomial(&self, e: ExprId) -> (f64, Vec<(ExprId, i32)>) {
        match self.node(e) {
            Node::Const(c) => (c.get(), Vec::new()),
            Node::Sum { constant, terms } if constant.get() == 0.0 && terms.len() == 1 => {
                let (t, k) = terms[0];
                let (_, f) = self.monomial(t);
                (k.get(), f)
            }
            Node::Prod(f) => (1.0, f.to_vec()),
            _ => (1.0, vec![(e, 1)]),
        }
    }

    /// `constant + Σ k·t` from terms sorted by `t` without repeats.
    pub(super) fn build_sum(&mut self, constant: f64, terms: Vec<(ExprId, f64)>) -> ExprId {
        let terms: Vec<(ExprId, Num)> = terms
            .into_iter()
            .filter(|(_, c)| *c != 0.0)
            .map(|(t, c)| (t, Num::new(c)))
            .collect();
        if terms.is_empty() {
            return self.constant(constant);
        }
        if constant == 0.0 && terms.len() == 1 && terms[0].1.get() == 1.0 {
            return terms[0].0;
        }
        self.intern(Node::Sum {
            constant: Num::new(constant),
            terms: terms.into_boxed_slice(),
        })
    }

    /// `Π b^p` from factors sorted by `b` without repeats.
    pub(super) fn build_prod(&mut self, factors: Vec<(ExprId, i32)>) -> ExprId {
        let f: Vec<(ExprId, i32)> = factors.into_iter().filter(|(_, p)| *p != 0).collect();
        match f.as_slice() {
            [] => self.one(),
            [(b, 1)] => *b,
            _ => self.intern(Node::Prod(f.into_boxed_slice())),
        }
    }

    /// Sum of any number of expressions.
    pub fn sum<I: IntoIterator<Item = ExprId>>(&mut self, items: I) -> ExprId {
        let mut constant = 0.0;
        let mut acc: Vec<(ExprId, f64)> = Vec::new();
        for e in items {
            match self.node(e) {
                Node::Const(c) => constant += c.get(),
                Node::Sum { constant: c, terms } => {
                    constant += c.get();
                    acc.extend(terms.iter().map(|(t, k)| (*t, k.get())));
                }
                _ => acc.push((e, 1.0)),
            }
        }
        let acc = collect_terms(acc);
        self.build_sum(constant, acc)
    }

    /// `a + b`.
    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.sum([a, b])
    }

    /// `a − b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let nb = self.scale(b, -1.0);
        self.sum([a, nb])
    }

    /// `−a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        self.scale(a, -1.0)
    }

    /// `k · e` (distributes over sums).
    pub fn scale(&mut self, e: ExprId, k: f64) -> ExprId {
        if k == 0.0 {
            return self.zero();
        }
        if k == 1.0 {
            return e;
        }
        let (c, terms) = self.linear(e);
        // The terms of one expression are sorted and distinct already.
        let acc: Vec<(ExprId, f64)> = terms.into_iter().map(|(t, x)| (t, x * k)).collect();
        self.build_sum(c * k, acc)
    }

    /// `a · b`.
    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        if let Some(k) = self.as_const(a) {
            return self.scale(b, k);
        }
        if let Some(k) = self.as_const(b) {
            return self.scale(a, k);
        }
        let (ka, fa) = self.monomial(a);
        let (kb, fb) = self.monomial(b);
        let mut f = fa;
        f.extend(fb);
        let m = self.build_prod(collect_factors(f));
        self.scale(m, ka * kb)
    }

    /// Product of any number of expressions.
    pub fn product<I: IntoIterator<Item = ExprId>>(&mut self, items: I) -> ExprId {
        let mut acc = self.one();
        for e in items {
            acc = self.mul(acc, e);
        }
        acc
    }

    /// `e^n` for a small integer `n` (negative powers divide).
    pub fn powi(&mut self, e: ExprId, n: i32) -> ExprId {
        if n == 0 {
            return self.one();
        }
        let (k, f) = self.monomial(e);
        let f: Vec<(ExprId, i32)> = f.into_iter().map(|(b, p)| (b, p * n)).collect();
        let m = self.build_prod(f);
        self.scale(m, k.powi(n))
    }

    /// Is `e` a constant, a leaf, or a constant times a leaf (never worth a variable)?
    pub fn is_simple(&self, e: ExprId) -> bool {
        match self.node(e) {
            Node::Const(_) | Node::Atom(_) => true,
            Node::Sum { constant, terms } => {
                constant.get() == 0.0
                    && terms.len() == 1
                    && matches!(self.node(terms[0].0), Node::Atom(_))
            }
            Node::Prod(_) => false,
        }
    }
}

/// The independent variable of a derivative.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Wrt {
    /// The coordinate `q[i]` (speed index `i`): `sin q[i]`, `cos q[i]` and `q[i]` depend on it.
    Coord(u32),
    /// The speed `u[i]`.
    Speed(u32),
    /// The acceleration `u̇[i]`.
    Accel(u32),
    /// The model parameter `p` (index into `Model::params`).
    Param(u32),
}

/// Memo of [`Arena::diff`]: `(node, variable) → derivative`.
pub(super) type DiffMemo = HashMap<(ExprId, Wrt), ExprId>;

/// Terms sorted by term with repeats merged: the coefficients of equal terms are added in the
/// order given, starting from zero (what accumulating them in a map did).
fn collect_terms(mut v: Vec<(ExprId, f64)>) -> Vec<(ExprId, f64)> {
    // Stable: equal terms keep their order, so their sum rounds the same way.
    v.sort_by_key(|(t, _)| *t);
    let mut out: Vec<(ExprId, f64)> = Vec::with_capacity(v.len());
    for (t, k) in v {
        match out.last_mut() {
            Some((last, acc)) if *last == t => *acc += k,
            _ => out.push((t, 0.0 + k)),
        }
    }
    out
}

/// Factors sorted by base with the powers of equal bases added.
fn collect_factors(mut v: Vec<(ExprId, i32)>) -> Vec<(ExprId, i32)> {
    v.sort_unstable_by_key(|(b, _)| *b);
    let mut out: Vec<(ExprId, i32)> = Vec::with_capacity(v.len());
    for (b, p) in v {
        match out.last_mut() {
            Some((last, acc)) if *last == b => *acc += p,
            _ => out.push((b, p)),
        }
    }
    out
}

/// A two-parameter, one-speed arena for the stage's unit tests.
#[cfg(test)]
pub(crate) fn test_arena() -> Arena {
    Arena::new(Names {
        params: vec!["a".into(), "b".into()],
        speeds: vec!["qd1".into()],
        coords: vec!["q1".into()],
        lengths: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use test_arena as arena;

    #[test]
    fn identical_subexpressions_are_shared() {
        let mut ar = arena();
        let a = ar.atom(Atom::Param(0));
        let b = ar.atom(Atom::Param(1));
        let x = ar.mul(a, b);
        let y = ar.mul(b, a);
        assert_eq!(x, y);
        let s1 = ar.add(x, a);
        let s2 = ar.add(a, y);
        assert_eq!(s1, s2);
    }

    #[test]
    fn like_terms_collect_and_cancel() {
        let mut ar = arena();
        let a = ar.atom(Atom::Param(0));
        let b = ar.atom(Atom::Param(1));
        let two_a = ar.add(a, a);
        assert_eq!(ar.display(two_a), "2.0*a");
        let ab = ar.mul(a, b);
        let e = ar.sum([ab, b, ab]);
        let f = ar.scale(ab, -2.0);
        let g = ar.sum([e, f]);
        assert_eq!(g, b);
        let z = ar.sub(a, a);
        assert!(ar.is_zero(z));
    }

    #[test]
    fn constants_fold_and_identities_hold() {
        let mut ar = arena();
        let a = ar.atom(Atom::Param(0));
        let zero = ar.zero();
        let one = ar.one();
        assert_eq!(ar.mul(a, one), a);
        assert!(ar.is_zero(ar.clone().mul(a, zero)));
        let two = ar.constant(2.0);
        let three = ar.constant(3.0);
        let six = ar.mul(two, three);
        assert_eq!(ar.as_const(six), Some(6.0));
        assert_eq!(ar.add(a, zero), a);
        let a2 = ar.mul(a, a);
        let p = ar.powi(a, 2);
        assert_eq!(a2, p);
        let inv = ar.powi(a, -1);
        assert_eq!(ar.mul(a, inv), one);
    }

    #[test]
    fn cos_plus_one_minus_cos_is_one() {
        let mut ar = arena();
        let c = ar.atom(Atom::Cos(0));
        let one = ar.one();
        let omc = ar.sub(one, c);
        assert_eq!(ar.add(c, omc), one);
    }
}
