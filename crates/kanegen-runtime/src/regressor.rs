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
//! A generated function computes, straight-line, every link's motion and joint transform (the
//! [`KIN`] values per link of a `kin` table) and the entries that are not a body's (a wheeled
//! base's wheel columns), then calls [`inverse_dynamics_regressor`] with two constant tables:
//! per link its parent, the result columns of its body's parameters and the rows its partial
//! velocities can be non-zero in ([`Link`]), and the joints' own partial velocities ([`Seed`]:
//! speed, link, a constant 6-vector). Links are visited parents first; a link's partial
//! velocities for all rows are carried one joint down from its parent's at once, in chunks of
//! [`LANES`] consecutive rows (one transform, four rows: SIMD lanes), then its seeds are set,
//! then the body's ten columns are formed for the same rows and stored: in the column-major
//! result four consecutive rows of a column are one contiguous store. Rows a chunk covers that
//! are not the link's ancestors' have zero partial velocities and store zeros (which those
//! entries are). The code that runs is one small loop body instead of one straight line per
//! entry: it stays in the instruction cache (Krang's straight-line regressor is five times its
//! size).
//!
//! Allocation-free and infallible: the scratch arrays are on the stack and an out-of-range
//! table entry (impossible in generated tables) skips its store instead of panicking.

use core::ops::{Add, Mul, Sub};

/// Values per link in the `kin` table, all in the link's own frame: `ω` (0..3), `α` (3..6), the
/// origin acceleration minus gravity `a` (6..9), the rotation `R` of the link relative to its
/// parent, row-major (9..18: a vector `x` of the parent's axes is `Rᵀ x` in the link's), and the
/// link's origin in the parent's frame `P` (18..21). The root's `R` and `P` are not read.
pub const KIN: usize = 21;

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

/// Write into the column-major `rows × cols` result `out` the body entries of the
/// inverse-dynamics regressor. `kin` is every link's motion and joint transform ([`KIN`]),
/// `links` the tree (parents first) and `seeds` the joints' own partial velocities, sorted by
/// link. `S` is the number of chunk slots (the sum of [`Link::chunks`]). Every entry of the
/// bodies' columns is written (zeros where no speed moves the body); the columns that are not
/// a body's are left as they are (the generated function stores them itself).
///
/// Flops per call: 23 per link with a body; per chunk, 42 per lane to carry the partial
/// velocities (none at the root) and 71 per lane for the body's entries (a generated
/// function's documentation gives a model's total).
#[inline(always)]
pub fn inverse_dynamics_regressor<T: Scalar, const NL: usize, const S: usize>(
    kin: &[[T; KIN]; NL],
    links: &[Link; NL],
    seeds: &[Seed<T>],
    rows: usize,
    out: &mut [T],
) {
    let z = T::default();
    let mut phi = [[[z; LANES]; 6]; S];
    inverse_dynamics_regressor_with(kin, links, seeds, rows, out, &mut phi);
}

/// [`inverse_dynamics_regressor`] with the partial-velocity scratch passed in (at least the sum
/// of [`Link::chunks`] chunks), for callers whose sizes are not constants (tests).
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
