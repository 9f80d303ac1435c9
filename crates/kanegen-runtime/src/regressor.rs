//! The loop form of a generated inverse-dynamics regressor `Y(q, u, u̇)` (`τ = Y π`).
//!
//! Kane's equations give `τ_r = Σ_k [(v_k)_r · F_k + (ω_k)_r · N_k]`: body k's inertia force and
//! moment about its frame origin, dotted with its partial velocities for speed r. Both are
//! linear in the body's ten standard parameters `π_k = (m, MX, MY, MZ, XX, XY, XZ, YY, YZ, ZZ)`
//! (about the frame origin, in the body frame): `(F_k; N_k) = W_k π_k`, a 6×10 matrix of the
//! body's motion (`ω`, `α` and the origin acceleration `a` minus gravity) with 36 structural
//! non-zeros. So the ten entries of row r in body k's columns are `φ_kr · W_k` with
//! `φ_kr = ((ω_k)_r; (v_k)_r)` in body k's frame.
//!
//! A generated function computes, straight-line, every link's motion, joint transform and the
//! coefficients of its body's entries (the [`KIN`] values per link of a `kin` table) and the
//! entries that are not a body's (a wheeled base's wheel columns), then calls
//! [`inverse_dynamics_regressor`] with a generated [`Plan`]: steps (link, chunk of [`LANES`]
//! consecutive rows), chunk by chunk and within a chunk depth-first, only for the chunks some
//! speed of which moves the link. A step carries the parent's partial velocities of its rows one
//! joint down at once (one transform, four rows: SIMD lanes; specialised for joints whose
//! rotation is about a coordinate axis, [`Step::rotation`]), adds the link's own joints' partial
//! velocities ([`Plan::seeds`]) and forms and stores the body's ten columns for the same rows: in
//! the column-major result four consecutive rows of a column are one contiguous store. A chain
//! of links passes its partial velocities from step to step ([`PREVIOUS`]); branch points keep
//! theirs in a small scratch. The body entries in rows no speed of which moves the body are
//! stored as zeros ([`Plan::zeros`]). The kernel is generic over the multiply-add
//! ([`crate::isa::Arith`]): a generated function runs it with [`crate::isa::Plain`] in its
//! baseline copy and with [`crate::isa::Fused`] (`vfmadd` on four lanes) in its x86-64-v3 copy.
//! The code that runs is one small loop body instead of one straight line per entry: it stays
//! in the instruction cache (Krang's straight-line regressor is five times its size).
//!
//! [`inverse_dynamics_regressor_with`] is the plain form the plan was derived from (every chunk
//! from row 0, dense transforms, per-link tables [`Link`] and [`Seed`]): the reference the
//! generator's tests compare with.
//!
//! Allocation-free and infallible: the scratch arrays are on the stack and an out-of-range
//! table entry (impossible in generated tables) skips its store instead of panicking.

use core::ops::{Add, Mul, Sub};

/// Values per link in the `kin` table, all in the link's own frame: `ω` (0..3), `α` (3..6), the
/// origin acceleration minus gravity `a` (6..9), the rotation `R` of the link relative to its
/// parent, row-major (9..18: a vector `x` of the parent's axes is `Rᵀ x` in the link's), the
/// link's origin in the parent's frame `P` (18..21), and the coefficients of its body's entries
/// (read by the [`Plan`] kernel; the plain kernel computes its own): `K = [α]× + [ω]×[ω]×`
/// row-major (21..30), `−a` (30..33) and `−ω` (33..36). The root's `R` and `P` are not read.
pub const KIN: usize = 36;

/// No result column (a base regressor leaves most of a body's parameters out).
pub const NO_COLUMN: u16 = u16::MAX;

/// Rows per chunk: the partial velocities of [`LANES`] consecutive rows are carried and dotted
/// together (AVX2 lanes in the x86-64-v3 copy of a generated function).
pub const LANES: usize = 4;

/// One link of the kinematic tree, for [`inverse_dynamics_regressor`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// Index of the parent link (the root's own index: it has none).
    pub parent: u16,
    /// Result column of each of the body's ten parameters `m, MX, MY, MZ, XX, XY, XZ, YY, YZ,
    /// ZZ`, or [`NO_COLUMN`] (a link without a body has none).
    pub columns: [u16; 10],
    /// Number of row chunks ([`LANES`] rows each, from row 0) that cover every speed that
    /// moves the link (0: none, the link is skipped).
    pub chunks: u16,
    /// Index of the link's first chunk in the partial-velocity scratch.
    pub slot: u16,
}

/// The partial velocity of a joint's own link for its speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seed<T> {
    /// The speed (result row).
    pub row: u16,
    /// The link the joint moves.
    pub link: u16,
    /// `(ω; v)` in the link's frame (a revolute joint's axis and zero, a prismatic joint's zero
    /// and axis; a wheeled base's forward and yaw speeds at the root).
    pub phi: [T; 6],
}

/// The arithmetic the kernel needs (`f64` and `f32`).
pub trait Scalar:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
}

impl<T: Copy + Default + Add<Output = T> + Sub<Output = T> + Mul<Output = T>> Scalar for T {}

#[inline(always)]
fn v3<T: Scalar>(x: &[T], at: usize) -> [T; 3] {
    [x[at], x[at + 1], x[at + 2]]
}

/// `K = [α]× + [ω]×[ω]×` (row-major): the first moment's part of the inertia force,
/// `F = m a + K MS`.
#[inline(always)]
fn first_moment_matrix<T: Scalar>(kin: &[T; KIN]) -> [T; 9] {
    let w = v3(kin, 0);
    let al = v3(kin, 3);
    let ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    // ω ωᵀ − |ω|² I + [α]×
    [
        w[0] * w[0] - ww,
        w[0] * w[1] - al[2],
        w[0] * w[2] + al[1],
        w[1] * w[0] + al[2],
        w[1] * w[1] - ww,
        w[1] * w[2] - al[0],
        w[2] * w[0] - al[1],
        w[2] * w[1] + al[0],
        w[2] * w[2] - ww,
    ]
}

/// Partial velocities of one chunk: component-major, `[ω_x, ω_y, ω_z, v_x, v_y, v_z]` each over
/// [`LANES`] rows.
pub type Chunk<T> = [[T; LANES]; 6];

/// [`inverse_dynamics_regressor`]'s plain form, over a [`Link`] table (every chunk from row 0,
/// dense joint transforms, seeds set lane by lane, `x * y + acc` with two roundings) and with
/// the partial-velocity scratch passed in (at least the sum of [`Link::chunks`] chunks): the
/// reference the generated [`Plan`] form is tested against, for callers whose sizes are not
/// constants (tests). Write into the column-major `rows × cols` result `out` the body entries
/// of the inverse-dynamics regressor. `kin` is every link's motion and joint transform
/// ([`KIN`]), `links` the tree (parents first) and `seeds` the joints' own partial velocities,
/// sorted by link. Every entry of the bodies' columns is written (zeros where no speed moves
/// the body); the columns that are not a body's are left as they are.
///
/// Flops per call: 23 per link with a body; per chunk, 42 per lane to carry the partial
/// velocities (none at the root) and 71 per lane for the body's entries.
#[inline(always)]
pub fn inverse_dynamics_regressor_with<T: Scalar>(
    kin: &[[T; KIN]],
    links: &[Link],
    seeds: &[Seed<T>],
    rows: usize,
    out: &mut [T],
    phi: &mut [Chunk<T>],
) {
    let z = T::default();
    let mut si = 0;
    for (l, (link, kl)) in links.iter().zip(kin).enumerate() {
        let n = link.chunks as usize;
        let slot = link.slot as usize;
        // The rows below the link's chunks (not moved by any speed that moves it): zero.
        for &col in &link.columns {
            let at = col as usize * rows;
            if col != NO_COLUMN
                && let Some(o) = out.get_mut(at + (n * LANES).min(rows)..at + rows)
            {
                o.fill(z);
            }
        }
        if n == 0 {
            continue;
        }
        let parent = link.parent as usize;
        let (from, inherited) = match links.get(parent) {
            Some(p) if parent != l => (p.slot as usize, p.chunks as usize),
            _ => (0, 0),
        };
        // Carry the parent's chunks one joint down; the rows beyond them start at zero.
        for j in 0..n {
            let c = match phi.get(from + j) {
                Some(pc) if j < inherited => carry_chunk(pc, kl),
                _ => [[z; LANES]; 6],
            };
            if let Some(dst) = phi.get_mut(slot + j) {
                *dst = c;
            }
        }
        // The link's own joints: their rows are zero in the parent (not its ancestors').
        while let Some(s) = seeds.get(si) {
            if s.link as usize != l {
                break;
            }
            let r = s.row as usize;
            if let Some(c) = phi.get_mut(slot + r / LANES) {
                for (d, x) in c.iter_mut().zip(s.phi) {
                    d[r % LANES] = x;
                }
            }
            si += 1;
        }
        if link.columns.iter().all(|&c| c == NO_COLUMN) {
            continue;
        }
        let k = first_moment_matrix(kl);
        for j in 0..n {
            let Some(c) = phi.get(slot + j) else {
                break;
            };
            let y = entries_chunk(c, kl, &k);
            let r0 = j * LANES;
            if r0 + LANES <= rows {
                // Four rows of a column: one contiguous store.
                for (&col, y) in link.columns.iter().zip(y) {
                    let at = col as usize * rows + r0;
                    if col != NO_COLUMN
                        && let Some(o) = out.get_mut(at..at + LANES)
                        && let Ok(o) = <&mut [T; LANES]>::try_from(o)
                    {
                        *o = y;
                    }
                }
            } else {
                // The last rows of the result.
                for (&col, y) in link.columns.iter().zip(y) {
                    let at = col as usize * rows + r0;
                    if col != NO_COLUMN {
                        for (i, &v) in y.iter().enumerate().take(rows.saturating_sub(r0)) {
                            if let Some(o) = out.get_mut(at + i) {
                                *o = v;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// One value per row of a chunk.
type V<T> = [T; LANES];

#[inline(always)]
fn vadd<T: Scalar>(a: V<T>, b: V<T>) -> V<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
}

#[inline(always)]
fn vsub<T: Scalar>(a: V<T>, b: V<T>) -> V<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]]
}

/// `s · a` (a scalar broadcast to the lanes).
#[inline(always)]
fn vscale<T: Scalar>(s: T, a: V<T>) -> V<T> {
    [s * a[0], s * a[1], s * a[2], s * a[3]]
}

/// `x · a` with scalar `x` and lane vectors `a`.
#[inline(always)]
fn vdot3<T: Scalar>(x: [T; 3], a: [V<T>; 3]) -> V<T> {
    vadd(
        vadd(vscale(x[0], a[0]), vscale(x[1], a[1])),
        vscale(x[2], a[2]),
    )
}

/// `s × a` with scalar `s` and lane vectors `a`.
#[inline(always)]
fn vcross_sv<T: Scalar>(s: [T; 3], a: [V<T>; 3]) -> [V<T>; 3] {
    [
        vsub(vscale(s[1], a[2]), vscale(s[2], a[1])),
        vsub(vscale(s[2], a[0]), vscale(s[0], a[2])),
        vsub(vscale(s[0], a[1]), vscale(s[1], a[0])),
    ]
}

/// The partial velocities of a chunk's rows carried one joint down from the parent's `pc`:
/// `ω' = Rᵀ ω`, `v' = Rᵀ (v + ω × P)`, lane-wise (the transform's entries broadcast).
#[inline(always)]
fn carry_chunk<T: Scalar>(pc: &Chunk<T>, kin: &[T; KIN]) -> Chunk<T> {
    let w = [pc[0], pc[1], pc[2]];
    let v = [pc[3], pc[4], pc[5]];
    // ω × P = −P × ω
    let pxw = vcross_sv(v3(kin, 18), w);
    let v2 = [vsub(v[0], pxw[0]), vsub(v[1], pxw[1]), vsub(v[2], pxw[2])];
    // Rᵀ x: column i of R dotted with x.
    let col = |i: usize| [kin[9 + i], kin[12 + i], kin[15 + i]];
    [
        vdot3(col(0), w),
        vdot3(col(1), w),
        vdot3(col(2), w),
        vdot3(col(0), v2),
        vdot3(col(1), v2),
        vdot3(col(2), v2),
    ]
}

/// The ten entries `φ · W` of a body for the rows of a chunk (`φ = (w; v)` its partial
/// velocities, `kin` its motion, `k` its [`first_moment_matrix`]), lane-wise: per parameter,
/// its entries in the rows. `m`: `v · a`; `MS`: `Kᵀ v + a × w` (from `v · K MS` and
/// `w · (MS × a)`); `J`: `w · (J α + ω × J ω) = Lᵀ(α) w + Lᵀ(ω) (w × ω)` with
/// `J x = L(x) (XX, XY, XZ, YY, YZ, ZZ)`.
#[inline(always)]
fn entries_chunk<T: Scalar>(pc: &Chunk<T>, kin: &[T; KIN], k: &[T; 9]) -> [V<T>; 10] {
    let w = [pc[0], pc[1], pc[2]];
    let v = [pc[3], pc[4], pc[5]];
    let om = v3(kin, 0);
    let al = v3(kin, 3);
    let a = v3(kin, 6);
    let m = vdot3(a, v);
    let axw = vcross_sv(a, w);
    let ms = |i: usize| vadd(vdot3([k[i], k[3 + i], k[6 + i]], v), axw[i]);
    // w × ω = −ω × w
    let oxw = vcross_sv(om, w);
    let x = [oxw[0], oxw[1], oxw[2]];
    // Lᵀ(α) w + Lᵀ(ω) (w × ω), the second with x = ω × w = −(w × ω).
    let sq = |i: usize| vsub(vscale(al[i], w[i]), vscale(om[i], x[i]));
    let mixed = |i: usize, j: usize| {
        vsub(
            vadd(vscale(al[j], w[i]), vscale(al[i], w[j])),
            vadd(vscale(om[j], x[i]), vscale(om[i], x[j])),
        )
    };
    standard_order(m, ms, sq, mixed)
}

/// [`Step::from`] of a step whose rows no ancestor speed moves (the root, or a chunk of rows
/// that only the link's own joints move): its partial velocities start from zero.
pub const NO_SLOT: u16 = u16::MAX;

/// [`Step::from`] of a step whose parent is the step just before it: its partial velocities
/// are taken from that step directly (registers), not from the scratch.
pub const PREVIOUS: u16 = u16::MAX - 1;

/// [`Step::seed`] of a step without seeds.
pub const NO_SEED: u16 = u16::MAX;

/// [`Step::rotation`] of a joint whose rotation has no constant ±1 entry: carried with the
/// dense `Rᵀ`.
pub const DENSE_ROTATION: u8 = u8::MAX;

/// One (link, row chunk) of a generated [`Plan`]: the partial velocities of the link for the
/// chunk's [`LANES`] rows, carried from the parent's, and, for a link with a body, its ten
/// result columns in those rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// The link (its `kin` values and its row of [`Plan::columns`]).
    pub link: u16,
    /// The row chunk: [`LANES`] rows from [`first_row`]`(chunk, rows)`.
    pub chunk: u16,
    /// Scratch slot the chunk's partial velocities are written to (the link's depth in the
    /// tree: the steps of a chunk run in depth-first order, so the parent's chunk is in the
    /// slot one up until the parent's next sibling overwrites it), or [`NO_SLOT`] when only
    /// the next step reads them (as [`PREVIOUS`]).
    pub slot: u16,
    /// Scratch slot holding the parent's partial velocities of the same rows, [`PREVIOUS`]
    /// (the parent is the step just before), or [`NO_SLOT`] (none: start from zero).
    pub from: u16,
    /// Index in [`Plan::seeds`] of the partial velocities of the link's own joints in these
    /// rows (added to the carried ones, whose lanes for those rows are zero), or [`NO_SEED`].
    pub seed: u16,
    /// `3 row + column` of the constant ±1 entry of the joint rotation `R` (parent ← link; the
    /// rest of that row and column are zero: a rotation about a coordinate axis of the link,
    /// after a constant signed permutation), or [`DENSE_ROTATION`]. A carried vector then costs
    /// 5 multiply(-add)s instead of 9.
    pub rotation: u8,
    /// Whether the link's origin `P` in the parent's frame can be non-zero (`false`: `v' =
    /// Rᵀ v`, no `ω × P`).
    pub offset: bool,
    /// Whether the link has a body with result columns (otherwise the step only carries).
    pub body: bool,
    /// The first of the body's ten result columns when they are consecutive (Y: one check,
    /// ten stores at constant distances), or [`NO_COLUMN`] (stored through
    /// [`Plan::columns`]: a base regressor).
    pub first: u16,
}

/// A (link, row chunk) whose partial velocities vanish (no speed in those rows moves the
/// link): its body's entries in those rows are zeros, stored without computing them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ZeroChunk {
    /// The link.
    pub link: u16,
    /// The row chunk (as [`Step::chunk`]).
    pub chunk: u16,
    /// As [`Step::first`].
    pub first: u16,
}

/// The generated tables of a loop-form regressor (see [`inverse_dynamics_regressor`]).
#[derive(Clone, Copy, Debug)]
pub struct Plan<'a, T> {
    /// Per link: the result column of each of its body's parameters `m, MX, MY, MZ, XX, XY,
    /// XZ, YY, YZ, ZZ`, or [`NO_COLUMN`].
    pub columns: &'a [[u16; 10]],
    /// The steps: chunk by chunk, each chunk's links in depth-first order (parents first).
    pub steps: &'a [Step],
    /// The joints' own partial velocities, one chunk each (zero in the lanes of other rows).
    pub seeds: &'a [Chunk<T>],
    /// The (link, chunk) pairs whose entries are zero.
    pub zeros: &'a [ZeroChunk],
}

/// Write into the column-major `rows × cols` result `out` the body entries of the
/// inverse-dynamics regressor, by the generated [`Plan`]: `kin` is every link's motion and
/// joint transform ([`KIN`]), `S` the number of scratch slots (the tree's depth plus one).
/// Every entry of the bodies' columns is written (computed or, for the plan's
/// [`ZeroChunk`]s, zeros); the columns that are not a body's are left as they are (the
/// generated function stores them itself). `A` is the multiply-add ([`crate::isa::Plain`] in
/// the baseline copy of a generated function, [`crate::isa::Fused`] in the x86-64-v3 copy).
///
/// Work per call (flops, a multiply-add counting 2): per step and lane, 26 to carry the
/// partial velocities through an axis-aligned joint with an offset (14 without, 42 and 30
/// dense, none from zero), 6 to add a seed and 71 for the body's ten entries (a generated
/// function's documentation gives a model's total). Nothing is zeroed but the small scratch
/// (`S` chunks).
#[inline(always)]
pub fn inverse_dynamics_regressor<A, T, const NL: usize, const S: usize>(
    kin: &[[T; KIN]; NL],
    plan: &Plan<'_, T>,
    rows: usize,
    out: &mut [T],
) where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let z = T::default();
    let mut phi = [[[z; LANES]; 6]; S];
    inverse_dynamics_regressor_plan::<A, T>(kin, plan, rows, out, &mut phi);
}

/// [`inverse_dynamics_regressor`] for sizes that are not constants (tests): the scratch `phi`
/// (at least the tree's depth plus one chunks) passed in.
#[inline(always)]
pub fn inverse_dynamics_regressor_plan<A, T>(
    kin: &[[T; KIN]],
    plan: &Plan<'_, T>,
    rows: usize,
    out: &mut [T],
    phi: &mut [Chunk<T>],
) where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let z = T::default();
    for zc in plan.zeros {
        if zc.first != NO_COLUMN {
            store_consecutive(out, rows, zc.first, zc.chunk as usize, [[z; LANES]; 10]);
        } else if let Some(columns) = plan.columns.get(zc.link as usize) {
            store(out, rows, columns, zc.chunk as usize, [[z; LANES]; 10]);
        }
    }
    // The previous step's partial velocities: a chain of links (an arm) carries them in
    // registers, and only branch points go through the scratch.
    let mut prev = [[z; LANES]; 6];
    for st in plan.steps {
        let l = st.link as usize;
        let (Some(kl), Some(columns)) = (kin.get(l), plan.columns.get(l)) else {
            continue;
        };
        let parent = if st.from == PREVIOUS {
            Some(&prev)
        } else if st.from == NO_SLOT {
            None
        } else {
            phi.get(st.from as usize)
        };
        let carried = match parent {
            Some(pc) => {
                macro_rules! axis {
                    ($($code:literal => $rr:literal, $rc:literal;)*) => {
                        match st.rotation {
                            $($code => carry::<A, T>(pc, kl, st.offset, rt_axis::<A, T, $rr, $rc>),)*
                            _ => carry::<A, T>(pc, kl, st.offset, rt_dense::<A, T>),
                        }
                    };
                }
                axis! {
                    0 => 0, 0; 1 => 0, 1; 2 => 0, 2;
                    3 => 1, 0; 4 => 1, 1; 5 => 1, 2;
                    6 => 2, 0; 7 => 2, 1; 8 => 2, 2;
                }
            }
            _ => [[z; LANES]; 6],
        };
        // The link's own joints' rows are zero in the parent's chunk: adding sets them.
        let c = match plan.seeds.get(st.seed as usize) {
            Some(s) if st.seed != NO_SEED => {
                let mut c = carried;
                for (d, s) in c.iter_mut().zip(s) {
                    *d = vadd(*d, *s);
                }
                c
            }
            _ => carried,
        };
        if st.slot != NO_SLOT
            && let Some(dst) = phi.get_mut(st.slot as usize)
        {
            *dst = c;
        }
        prev = c;
        if st.body {
            let y = entries_fused::<A, T>(&c, kl);
            if st.first != NO_COLUMN {
                store_consecutive(out, rows, st.first, st.chunk as usize, y);
            } else {
                store(out, rows, columns, st.chunk as usize, y);
            }
        }
    }
}

/// `s · a + acc`, lane-wise.
#[inline(always)]
fn vfma<A: crate::isa::Arith<T>, T: Scalar>(s: T, a: V<T>, acc: V<T>) -> V<T> {
    [
        A::mul_add(s, a[0], acc[0]),
        A::mul_add(s, a[1], acc[1]),
        A::mul_add(s, a[2], acc[2]),
        A::mul_add(s, a[3], acc[3]),
    ]
}

/// `x · a` with scalar `x` and lane vectors `a`, as a multiply-add chain.
#[inline(always)]
fn fdot3<A: crate::isa::Arith<T>, T: Scalar>(x: [T; 3], a: [V<T>; 3]) -> V<T> {
    vfma::<A, T>(x[2], a[2], vfma::<A, T>(x[1], a[1], vscale(x[0], a[0])))
}

/// The other two of the three axes, `(k + 1) % 3` and `(k + 2) % 3`.
#[inline(always)]
const fn others(k: usize) -> (usize, usize) {
    ((k + 1) % 3, (k + 2) % 3)
}

/// `Rᵀ x` for the rotation `r` (row-major) whose entry `(RR, RC)` is the constant ±1 and
/// whose other entries in row `RR` and column `RC` are zero: 1 multiplication for component
/// `RC` and 2 multiply(-add)s for each of the other two.
#[inline(always)]
fn rt_axis<A, T, const RR: usize, const RC: usize>(r: &[T], x: [V<T>; 3]) -> [V<T>; 3]
where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let (j1, j2) = others(RR);
    let (i1, i2) = others(RC);
    let mut o = [[T::default(); LANES]; 3];
    o[RC] = vscale(r[3 * RR + RC], x[RR]);
    o[i1] = vfma::<A, T>(r[3 * j2 + i1], x[j2], vscale(r[3 * j1 + i1], x[j1]));
    o[i2] = vfma::<A, T>(r[3 * j2 + i2], x[j2], vscale(r[3 * j1 + i2], x[j1]));
    o
}

/// `Rᵀ x` for a dense rotation `r` (row-major).
#[inline(always)]
fn rt_dense<A, T>(r: &[T], x: [V<T>; 3]) -> [V<T>; 3]
where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let col = |i: usize| [r[i], r[3 + i], r[6 + i]];
    [
        fdot3::<A, T>(col(0), x),
        fdot3::<A, T>(col(1), x),
        fdot3::<A, T>(col(2), x),
    ]
}

/// `v + ω × P` (`P` the link's origin in the parent, `kin[18..21]`).
#[inline(always)]
fn add_w_cross_p<A, T>(kin: &[T; KIN], w: &[V<T>; 3], v: [V<T>; 3]) -> [V<T>; 3]
where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let z = T::default();
    let p = v3(kin, 18);
    // (ω × P)_i = ω_j P_k − ω_k P_j
    [
        vfma::<A, T>(p[2], w[1], vfma::<A, T>(z - p[1], w[2], v[0])),
        vfma::<A, T>(p[0], w[2], vfma::<A, T>(z - p[2], w[0], v[1])),
        vfma::<A, T>(p[1], w[0], vfma::<A, T>(z - p[0], w[1], v[2])),
    ]
}

/// The partial velocities of a chunk carried one joint down: `ω' = Rᵀ ω`, `v' = Rᵀ (v + ω ×
/// P)`, `Rᵀ` applied by `rt` ([`rt_axis`] specialised by the joint's axis, or [`rt_dense`]).
#[inline(always)]
fn carry<A, T>(
    pc: &Chunk<T>,
    kin: &[T; KIN],
    offset: bool,
    rt: impl Fn(&[T], [V<T>; 3]) -> [V<T>; 3],
) -> Chunk<T>
where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let w = [pc[0], pc[1], pc[2]];
    let v = [pc[3], pc[4], pc[5]];
    let v = if offset {
        add_w_cross_p::<A, T>(kin, &w, v)
    } else {
        v
    };
    let r = &kin[9..18];
    let w = rt(r, w);
    let v = rt(r, v);
    [w[0], w[1], w[2], v[0], v[1], v[2]]
}

/// The ten entries `φ · W` of a body for the rows of a chunk as multiply-add chains (the
/// formulas of the plain form's `entries_chunk`, with the coefficients `K`, `−a`, `−ω` of
/// `kin[21..36]`): 42 multiply(-add)s per lane.
#[inline(always)]
fn entries_fused<A, T>(pc: &Chunk<T>, kin: &[T; KIN]) -> [V<T>; 10]
where
    A: crate::isa::Arith<T>,
    T: Scalar,
{
    let w = [pc[0], pc[1], pc[2]];
    let v = [pc[3], pc[4], pc[5]];
    let om = v3(kin, 0);
    let al = v3(kin, 3);
    let a = v3(kin, 6);
    let c = &kin[21..30];
    let na = v3(kin, 30);
    let nom = v3(kin, 33);
    let m = fdot3::<A, T>(a, v);
    // MS_i: (Kᵀ v)_i + (a × w)_i, (a × w)_i = a_j w_k − a_k w_j.
    let ms = |i: usize| {
        let (j, k) = others(i);
        let axw = vfma::<A, T>(a[j], w[k], vscale(na[k], w[j]));
        vfma::<A, T>(
            c[6 + i],
            v[2],
            vfma::<A, T>(c[3 + i], v[1], vfma::<A, T>(c[i], v[0], axw)),
        )
    };
    // y = w × ω: y_i = w_j ω_k − w_k ω_j.
    let y = |i: usize| {
        let (j, k) = others(i);
        vfma::<A, T>(om[k], w[j], vscale(nom[j], w[k]))
    };
    let y = [y(0), y(1), y(2)];
    // Lᵀ(α) w + Lᵀ(ω) y.
    let sq = |i: usize| vfma::<A, T>(om[i], y[i], vscale(al[i], w[i]));
    let mixed = |i: usize, j: usize| {
        vfma::<A, T>(
            om[i],
            y[j],
            vfma::<A, T>(om[j], y[i], vfma::<A, T>(al[i], w[j], vscale(al[j], w[i]))),
        )
    };
    standard_order(m, ms, sq, mixed)
}

/// A body's ten entries in the order of its standard parameters (`m`, `MX`, `MY`, `MZ`, `XX`,
/// `XY`, `XZ`, `YY`, `YZ`, `ZZ`): the mass's, the first moments' (`ms(i)`), the diagonal
/// inertias' (`sq(i)`) and the products of inertia's (`mixed(i, j)`).
#[inline(always)]
fn standard_order<V>(
    m: V,
    ms: impl Fn(usize) -> V,
    sq: impl Fn(usize) -> V,
    mixed: impl Fn(usize, usize) -> V,
) -> [V; 10] {
    [
        m,
        ms(0),
        ms(1),
        ms(2),
        sq(0),
        mixed(0, 1),
        mixed(0, 2),
        sq(1),
        mixed(1, 2),
        sq(2),
    ]
}

/// The first row of chunk `chunk` of a [`Plan`] for a result of `rows` rows: `LANES · chunk`,
/// but the last chunk ends at the last row (it overlaps the one before when `rows` is not a
/// multiple of [`LANES`], and those rows are computed twice, identically), so that every store
/// of a result with at least [`LANES`] rows is a whole vector.
#[inline(always)]
pub fn first_row(chunk: usize, rows: usize) -> usize {
    (chunk * LANES).min(rows.saturating_sub(LANES))
}

/// [`store`] for the ten consecutive columns from `first`: one bounds check, then stores at
/// distances that are constants when `rows` is.
#[inline(always)]
fn store_consecutive<T: Scalar>(
    out: &mut [T],
    rows: usize,
    first: u16,
    chunk: usize,
    y: [V<T>; 10],
) {
    let r0 = first_row(chunk, rows);
    let at = first as usize * rows + r0;
    if r0 + LANES <= rows {
        if let Some(o) = out.get_mut(at..at + 9 * rows + LANES) {
            for (t, y) in y.into_iter().enumerate() {
                if let Some(d) = o.get_mut(t * rows..t * rows + LANES)
                    && let Ok(d) = <&mut [T; LANES]>::try_from(d)
                {
                    *d = y;
                }
            }
        }
    } else {
        let n = rows.saturating_sub(r0).min(LANES);
        if let Some(o) = out.get_mut(at..at + 9 * rows + n) {
            for (t, y) in y.into_iter().enumerate() {
                for (i, v) in y.into_iter().enumerate().take(n) {
                    if let Some(d) = o.get_mut(t * rows + i) {
                        *d = v;
                    }
                }
            }
        }
    }
}

/// Store the ten lane vectors `y` of a body's `columns` in the rows of chunk `chunk`.
#[inline(always)]
fn store<T: Scalar>(out: &mut [T], rows: usize, columns: &[u16; 10], chunk: usize, y: [V<T>; 10]) {
    let r0 = first_row(chunk, rows);
    if r0 + LANES <= rows {
        // Four rows of a column: one contiguous store.
        for (&col, y) in columns.iter().zip(y) {
            let at = col as usize * rows + r0;
            if col != NO_COLUMN
                && let Some(o) = out.get_mut(at..at + LANES)
                && let Ok(o) = <&mut [T; LANES]>::try_from(o)
            {
                *o = y;
            }
        }
    } else {
        // The last rows of the result, one by one (a slice copy of variable length would be a
        // library call per column).
        for (&col, y) in columns.iter().zip(y) {
            let at = col as usize * rows + r0;
            if col != NO_COLUMN {
                for (i, v) in y.into_iter().enumerate() {
                    if r0 + i < rows
                        && let Some(o) = out.get_mut(at + i)
                    {
                        *o = v;
                    }
                }
            }
        }
    }
}
