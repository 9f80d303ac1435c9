//! The looped part of generated inverse-dynamics derivatives `[∂τ/∂q | ∂τ/∂u]`: the
//! O(columns × ancestors) entries of the analytic recursion, run as one loop over a generated
//! table instead of straight-line code.
//!
//! The generated function computes, straight-line, everything that is per link or per column
//! into a workspace `w` (one flat array of the scalar type): each link's pose in frame 0, each
//! speed's motion subspace `S`, `Ψ̇` and `Ψ̈` **in frame 0** (as [`MOTION_LANES`] lanes per
//! component, see [`Speed::motion`]), and each column's four spatial forces `Φ`, `Ξ`, `H`, `G`
//! in its own link's frame. [`run`] moves the four forces of each column to frame 0 once (one
//! force transform by the link's pose) and then, for every speed on the column's path to the
//! root, writes the entries it reads from them (the formulas are those of the generator's
//! `kane/rnea_derivatives.rs`):
//!
//! * row `a` (an ancestor speed or a speed of the column's own link), column `i`:
//!   `∂τ_a/∂q_i = S_a · G_i` and `∂τ_a/∂u_i = S_a · H_i`;
//! * row `i`, column `a` (ancestors only): `∂τ_i/∂q_a = Φ_i · Ψ̈_a + Ξ_i · Ψ̇_a` and
//!   `∂τ_i/∂u_a = k Φ_i · Ψ̇_a + Ξ_i · S_a` (`k = 2` for a joint, 1 for the wheeled base's
//!   quasi-velocities, whose `Ψ̇` is `V_0 × S`).
//!
//! Every entry is a dot product of a motion and a force, which does not depend on the frame
//! both are expressed in: with both in frame 0, an ancestor step is four 12-term dot products
//! and no transform at all (the forces were carried up link by link before: a dense 6×6
//! transform of four forces per (column, ancestor) step). The transforms are per column (the
//! forces, here) and per speed (the motions, in the generated straight-line code, where the
//! zeros of axis-aligned joints are known).
//!
//! Allocation-free and infallible; the tables are generated together with the code that fills
//! the workspace, so every offset is in range.

use core::ops::{Add, Mul, Sub};

/// Marker of a link without a parent (the root) in [`Link::parent`].
pub const NO_PARENT: u16 = u16::MAX;

/// Number of lanes per component of a speed's motions in the workspace (see [`Speed::motion`]).
pub const MOTION_LANES: usize = 6;

/// One link of the tree, in the generated order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// Index of the parent link in [`Plan::links`], [`NO_PARENT`] for the root.
    pub parent: u16,
    /// Offset in the workspace of the link's pose in frame 0: the rotation `⁰R` (frame 0 ←
    /// link, 9 entries by rows) followed by the link's origin `⁰p` in frame 0 (3 entries).
    /// Read only for links with speeds.
    pub transform: u16,
    /// The link's speeds: the range `first..end` of [`Plan::speeds`].
    pub first: u16,
    /// End of the link's range of [`Plan::speeds`].
    pub end: u16,
}

/// One speed of the tree (a row and a column of the result).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Speed {
    /// Its index in the result (row `index`; columns `index` and `N + index`).
    pub index: u16,
    /// Offset in the workspace of its motions in frame 0, [`MOTION_LANES`] lanes per component
    /// `c` (`ω.x, ω.y, ω.z, v.x, v.y, v.z`): `w[motion + 6 c ..][..6]` is
    /// `[S, S, S, j Ψ̇, k Ψ̇, j Ψ̈]` (component `c` of each), `j` = 1 for a joint's speed and 0 for
    /// the wheeled base's (no coordinate of its own enters τ: no q-column), `k` = 2 for a
    /// joint and 1 for the base (whose `Ψ̇` is `V_0 × S`). The four lanes `S, S, S, j Ψ̇` meet
    /// a column's `G, H, Ξ, Ξ` and the two lanes `k Ψ̇, j Ψ̈` its `Φ, Φ`.
    pub motion: u16,
}

/// One column of the recursion: a speed and its four forces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// The link of the speed, index in [`Plan::links`].
    pub link: u16,
    /// The speed, index in [`Plan::speeds`].
    pub speed: u16,
    /// Offset in the workspace of the four forces `Φ`, `Ξ`, `H`, `G` in the link's frame,
    /// component-major (24 entries: `w[forces + 4 k + j]` is component `k` of force `j`; `G`
    /// is zero for the wheeled base's speeds).
    pub forces: u16,
}

/// The generated tables of one model.
#[derive(Clone, Copy, Debug)]
pub struct Plan<'a> {
    /// Number of independent speeds N: the result is `N × 2N`, column-major.
    pub dof: usize,
    /// The links.
    pub links: &'a [Link],
    /// The speeds, grouped by link.
    pub speeds: &'a [Speed],
    /// The columns, in the order they are run.
    pub columns: &'a [Column],
}

/// Four lanes: one component of the four forces `Φ`, `Ξ`, `H`, `G`.
#[derive(Clone, Copy)]
struct L4<T>([T; 4]);

impl<T> L4<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    #[inline(always)]
    fn load(w: &[T]) -> Self {
        L4([w[0], w[1], w[2], w[3]])
    }

    /// `x · self`.
    #[inline(always)]
    fn scale(self, x: T) -> Self {
        let a = self.0;
        L4([x * a[0], x * a[1], x * a[2], x * a[3]])
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        L4([a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]])
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        L4([a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]])
    }
}

/// Component-major forces: `f[k]` holds component `k` (`n.x, n.y, n.z, f.x, f.y, f.z`) of
/// `Φ`, `Ξ`, `H`, `G`.
type Forces<T> = [L4<T>; 6];

/// The four forces moved from a link's frame to frame 0: `(R n + p × R f; R f)`, `t` = the
/// pose `⁰R` by rows then `⁰p`.
#[inline(always)]
fn to_frame0<T>(t: &[T], f: &Forces<T>) -> Forces<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let t: [T; 12] = [
        t[0], t[1], t[2], t[3], t[4], t[5], t[6], t[7], t[8], t[9], t[10], t[11],
    ];
    let rot = |x: &[L4<T>], i: usize| {
        x[0].scale(t[3 * i])
            .add(x[1].scale(t[3 * i + 1]))
            .add(x[2].scale(t[3 * i + 2]))
    };
    let (p0, p1, p2) = (t[9], t[10], t[11]);
    let (f0, f1, f2) = (rot(&f[3..6], 0), rot(&f[3..6], 1), rot(&f[3..6], 2));
    let n0 = rot(&f[0..3], 0).add(f2.scale(p1).sub(f1.scale(p2)));
    let n1 = rot(&f[0..3], 1).add(f0.scale(p2).sub(f2.scale(p0)));
    let n2 = rot(&f[0..3], 2).add(f1.scale(p0).sub(f0.scale(p1)));
    [n0, n1, n2, f0, f1, f2]
}

/// Runs the steps of `plan` on the workspace `w` and writes the entries of
/// `[∂τ/∂q | ∂τ/∂u]` into `out` (column-major `N × 2N`, e.g. `SMatrix::as_mut_slice`).
/// Entries that no column reaches are left as they are (the generated function passes a zeroed
/// matrix: they are structural zeros).
///
/// A function of its own, not inlined into the generated function (whose straight-line part
/// is long). On x86-64 it runs a copy written with AVX2 and FMA intrinsics when
/// [`crate::isa::active`] is x86-64-v3 (or the crate is compiled for AVX2 and FMA): a
/// component of the four forces in one register, and an ancestor speed's four entries as one
/// 4-wide and one 2-wide chain of fused multiply-adds. LLVM does not vectorize the portable
/// form (it splits the lanes into scalars). Elsewhere the portable form runs. The two copies
/// differ in the last bits (the fused multiply-adds round once); the straight-line part of the
/// generated function is the same in both.
#[inline(never)]
pub fn run(plan: &Plan<'_>, w: &[f64], out: &mut [f64]) {
    #[cfg(all(
        feature = "dispatch",
        feature = "std",
        target_arch = "x86_64",
        not(all(target_feature = "avx2", target_feature = "fma"))
    ))]
    if crate::isa::active() == crate::isa::Isa::X86_64V3 {
        // SAFETY: `isa::active` is x86-64-v3 only when the CPU has AVX and AVX2 (it checks
        // every feature of x86-64-v3 before selecting it), the features `avx2::steps` is
        // compiled with.
        #[allow(unsafe_code)]
        unsafe {
            return avx2::steps(plan, w, out);
        }
    }
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    ))]
    return avx2::steps(plan, w, out);
    #[allow(unreachable_code)]
    steps(plan, w, out)
}

/// [`run`] for any scalar type (`f32` modules), in the portable form.
#[inline(never)]
pub fn run_generic<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    steps(plan, w, out)
}

/// `Σ_c m[6 c + lane] x[c]` over the six components.
#[inline(always)]
fn dot<T>(m: &[T], lane: usize, x: [T; 6]) -> T
where
    T: Copy + Add<Output = T> + Mul<Output = T>,
{
    let a = m[lane] * x[0] + m[6 + lane] * x[1] + m[12 + lane] * x[2];
    let b = m[18 + lane] * x[3] + m[24 + lane] * x[4] + m[30 + lane] * x[5];
    a + b
}

/// The loop of [`run`].
#[inline(always)]
fn steps<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let n = plan.dof;
    let len = 6 * MOTION_LANES;
    for col in plan.columns {
        let o = usize::from(col.forces);
        let x = &w[o..o + 24];
        let f: Forces<T> = [0, 1, 2, 3, 4, 5].map(|k| L4::load(&x[4 * k..4 * k + 4]));
        let mut l = usize::from(col.link);
        let t = usize::from(plan.links[l].transform);
        let f = to_frame0(&w[t..t + 12], &f);
        let [phi, xi, h, g] = [0, 1, 2, 3].map(|j| f.map(|c| c.0[j]));
        let ci = usize::from(plan.speeds[usize::from(col.speed)].index);
        // Rows of the column's own link: S_a · G, S_a · H.
        let link = plan.links[l];
        for a in &plan.speeds[usize::from(link.first)..usize::from(link.end)] {
            let m = usize::from(a.motion);
            let m = &w[m..m + len];
            let ai = usize::from(a.index);
            out[ai + n * ci] = dot(m, 0, g);
            out[ai + n * (n + ci)] = dot(m, 1, h);
        }
        // Up to the root: every ancestor speed's four entries.
        loop {
            let link = plan.links[l];
            if link.parent == NO_PARENT {
                break;
            }
            l = usize::from(link.parent);
            let parent = plan.links[l];
            for a in &plan.speeds[usize::from(parent.first)..usize::from(parent.end)] {
                let m = usize::from(a.motion);
                let m = &w[m..m + len];
                let ai = usize::from(a.index);
                out[ai + n * ci] = dot(m, 0, g);
                out[ai + n * (n + ci)] = dot(m, 1, h);
                out[ci + n * (n + ai)] = dot(m, 2, xi) + dot(m, 4, phi);
                out[ci + n * ai] = dot(m, 3, xi) + dot(m, 5, phi);
            }
        }
    }
}

/// The steps with AVX2 and FMA intrinsics: the portable [`steps`] with `L4<f64>` as one
/// `__m256d`, a multiply and an add fused where the portable form has them in sequence.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::{
        __m128d, __m256d, _mm_add_pd, _mm_cvtsd_f64, _mm_fmadd_pd, _mm_movedup_pd, _mm_mul_pd,
        _mm_set_pd, _mm_unpackhi_pd, _mm256_add_pd, _mm256_castpd256_pd128, _mm256_extractf128_pd,
        _mm256_fmadd_pd, _mm256_fnmadd_pd, _mm256_mul_pd, _mm256_permute4x64_pd, _mm256_set_pd,
        _mm256_set1_pd,
    };

    use super::{MOTION_LANES, NO_PARENT, Plan};

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn load(x: &[f64]) -> __m256d {
        _mm256_set_pd(x[3], x[2], x[1], x[0])
    }

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn load2(x: &[f64]) -> __m128d {
        _mm_set_pd(x[1], x[0])
    }

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn halves(v: __m128d) -> [f64; 2] {
        [_mm_cvtsd_f64(v), _mm_cvtsd_f64(_mm_unpackhi_pd(v, v))]
    }

    /// See [`super::to_frame0`].
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn to_frame0(t: &[f64], f: &[__m256d; 6]) -> [__m256d; 6] {
        let t = &t[..12];
        // Row i of R times (x0, x1, x2).
        macro_rules! rot {
            ($i:expr, $x0:expr, $x1:expr, $x2:expr) => {{
                let a = _mm256_fmadd_pd(
                    $x1,
                    _mm256_set1_pd(t[3 * $i + 1]),
                    _mm256_mul_pd($x0, _mm256_set1_pd(t[3 * $i])),
                );
                _mm256_fmadd_pd($x2, _mm256_set1_pd(t[3 * $i + 2]), a)
            }};
        }
        let (p0, p1, p2) = (
            _mm256_set1_pd(t[9]),
            _mm256_set1_pd(t[10]),
            _mm256_set1_pd(t[11]),
        );
        let f0 = rot!(0, f[3], f[4], f[5]);
        let f1 = rot!(1, f[3], f[4], f[5]);
        let f2 = rot!(2, f[3], f[4], f[5]);
        // R n + p × R f: two fused operations per component.
        let n0 = _mm256_fmadd_pd(f2, p1, _mm256_fnmadd_pd(f1, p2, rot!(0, f[0], f[1], f[2])));
        let n1 = _mm256_fmadd_pd(f0, p2, _mm256_fnmadd_pd(f2, p0, rot!(1, f[0], f[1], f[2])));
        let n2 = _mm256_fmadd_pd(f1, p0, _mm256_fnmadd_pd(f0, p1, rot!(2, f[0], f[1], f[2])));
        [n0, n1, n2, f0, f1, f2]
    }

    /// `Σ_c m[6 c ..][..4] ⊙ g[c]`: lanes `[S·G, S·H, S·Ξ, j Ψ̇·Ξ]` of a speed's motions `m`
    /// against a column's `g[c] = [G, H, Ξ, Ξ]`.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn four(m: &[f64], g: &[__m256d; 6]) -> __m256d {
        let m = &m[..6 * MOTION_LANES];
        let a = _mm256_fmadd_pd(load(&m[6..10]), g[1], _mm256_mul_pd(load(&m[0..4]), g[0]));
        let a = _mm256_fmadd_pd(load(&m[12..16]), g[2], a);
        let b = _mm256_fmadd_pd(
            load(&m[24..28]),
            g[4],
            _mm256_mul_pd(load(&m[18..22]), g[3]),
        );
        let b = _mm256_fmadd_pd(load(&m[30..34]), g[5], b);
        _mm256_add_pd(a, b)
    }

    /// `Σ_c m[6 c + 4 ..][..2] ⊙ p[c]`: lanes `[k Ψ̇·Φ, j Ψ̈·Φ]` against `p[c] = [Φ, Φ]`.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn two(m: &[f64], p: &[__m128d; 6]) -> __m128d {
        let m = &m[..6 * MOTION_LANES];
        let a = _mm_fmadd_pd(load2(&m[10..12]), p[1], _mm_mul_pd(load2(&m[4..6]), p[0]));
        let a = _mm_fmadd_pd(load2(&m[16..18]), p[2], a);
        let b = _mm_fmadd_pd(load2(&m[28..30]), p[4], _mm_mul_pd(load2(&m[22..24]), p[3]));
        let b = _mm_fmadd_pd(load2(&m[34..36]), p[5], b);
        _mm_add_pd(a, b)
    }

    /// See [`super::steps`].
    #[target_feature(enable = "avx,avx2,fma")]
    pub(super) fn steps(plan: &Plan<'_>, w: &[f64], out: &mut [f64]) {
        let n = plan.dof;
        let len = 6 * MOTION_LANES;
        for col in plan.columns {
            let o = usize::from(col.forces);
            let x = &w[o..o + 24];
            let f = [
                load(&x[0..4]),
                load(&x[4..8]),
                load(&x[8..12]),
                load(&x[12..16]),
                load(&x[16..20]),
                load(&x[20..24]),
            ];
            let mut l = usize::from(col.link);
            let t = usize::from(plan.links[l].transform);
            let f = to_frame0(&w[t..t + 12], &f);
            // [Φ, Ξ, H, G] → [G, H, Ξ, Ξ] and [Φ, Φ].
            let g = f.map(|x| _mm256_permute4x64_pd::<0b01_01_10_11>(x));
            let p = f.map(|x| _mm_movedup_pd(_mm256_castpd256_pd128(x)));
            let ci = usize::from(plan.speeds[usize::from(col.speed)].index);
            let link = plan.links[l];
            for a in &plan.speeds[usize::from(link.first)..usize::from(link.end)] {
                let m = usize::from(a.motion);
                let lo = halves(_mm256_castpd256_pd128(four(&w[m..m + len], &g)));
                let ai = usize::from(a.index);
                out[ai + n * ci] = lo[0];
                out[ai + n * (n + ci)] = lo[1];
            }
            loop {
                let link = plan.links[l];
                if link.parent == NO_PARENT {
                    break;
                }
                l = usize::from(link.parent);
                let parent = plan.links[l];
                for a in &plan.speeds[usize::from(parent.first)..usize::from(parent.end)] {
                    let m = usize::from(a.motion);
                    let m = &w[m..m + len];
                    let s = four(m, &g);
                    let hi = _mm_add_pd(_mm256_extractf128_pd::<1>(s), two(m, &p));
                    let lo = halves(_mm256_castpd256_pd128(s));
                    let hi = halves(hi);
                    let ai = usize::from(a.index);
                    out[ai + n * ci] = lo[0];
                    out[ai + n * (n + ci)] = lo[1];
                    out[ci + n * (n + ai)] = hi[0];
                    out[ci + n * ai] = hi[1];
                }
            }
        }
    }
}
