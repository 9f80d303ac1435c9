//! The looped part of generated inverse-dynamics derivatives `[∂τ/∂q | ∂τ/∂u]`: the
//! O(columns × ancestors) steps of the analytic recursion, run as one loop over a generated
//! table instead of straight-line code.
//!
//! The generated function computes, straight-line, everything that is per link or per column
//! into a workspace `w` (one flat array of the scalar type): each link's transform to its
//! parent, each speed's motion subspace `S`, `Ψ̇` and `Ψ̈`, and each column's four spatial forces
//! `Φ`, `Ξ`, `H`, `G` in its own frame. [`run`] then carries the four forces of every column up
//! to the root, one [`Link`] at a time, and writes the entries each ancestor speed reads from
//! them (the formulas are those of the generator's `kane/rnea_derivatives.rs`):
//!
//! * row `a` (an ancestor speed or a speed of the column's own link), column `i`:
//!   `∂τ_a/∂q_i = S_a · G_i` and `∂τ_a/∂u_i = S_a · H_i`;
//! * row `i`, column `a` (ancestors only): `∂τ_i/∂q_a = Φ_i · Ψ̈_a + Ξ_i · Ψ̇_a` and
//!   `∂τ_i/∂u_a = k Φ_i · Ψ̇_a + Ξ_i · S_a` (`k = 2` for a joint, 1 for the wheeled base's
//!   quasi-velocities, whose `Ψ̇` is `V_0 × S`).
//!
//! The four forces are kept component-major (`[[T; 4]; 6]`: component `k` of `Φ`, `Ξ`, `H`,
//! `G` side by side), so that one step is one 4-wide transform: in the x86-64-v3 copy of a
//! generated function (`isa::dispatch`) the compiler issues it as AVX2 instructions. The loop's
//! code is a few hundred bytes and is read from the instruction cache on every step, where the
//! straight-line form of the same steps was read once from L2 (Krang: 233 KB of code).
//!
//! Allocation-free and infallible; the tables are generated together with the code that fills
//! the workspace, so every offset is in range.

use core::ops::{Add, Mul, Sub};

/// Marker of a link without a parent (the root) in [`Link::parent`].
pub const NO_PARENT: u16 = u16::MAX;

/// One link of the tree, in the generated order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Link {
    /// Index of the parent link in [`Plan::links`], [`NO_PARENT`] for the root.
    pub parent: u16,
    /// Offset in the workspace of the link's transform to its parent: the rotation `R`
    /// (parent ← link, 9 entries by rows) followed by the origin `P` of the link in its
    /// parent (3 entries). Unused for the root.
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
    /// Offset in the workspace of `S`, `Ψ̇`, `Ψ̈` (6 entries each, in the link's frame).
    pub motion: u16,
    /// A joint speed (`true`) or one of the wheeled base's quasi-velocities (`false`: no
    /// coordinate of its own enters τ, so it has no `Ψ̈` and no q-column).
    pub joint: bool,
}

/// One column of the recursion: a speed and its four forces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// The link of the speed, index in [`Plan::links`].
    pub link: u16,
    /// The speed, index in [`Plan::speeds`].
    pub speed: u16,
    /// Offset in the workspace of the four forces `Φ`, `Ξ`, `H`, `G`, component-major (24
    /// entries: `w[forces + 4 k + j]` is component `k` of force `j`).
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

/// `Σ_k x[k] f[k]`: the four dot products of a motion `x` with the four forces.
#[inline(always)]
fn dots<T>(x: &[T], f: &Forces<T>) -> L4<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let x = [x[0], x[1], x[2], x[3], x[4], x[5]];
    let a = f[0].scale(x[0]).add(f[1].scale(x[1]));
    let b = f[2].scale(x[2]).add(f[3].scale(x[3]));
    let c = f[4].scale(x[4]).add(f[5].scale(x[5]));
    a.add(b).add(c)
}

/// The four forces moved from a link to its parent: `(R n + P × R f; R f)`, `t` = `R` by rows
/// then `P`.
#[inline(always)]
fn up<T>(t: &[T], f: &Forces<T>) -> Forces<T>
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
/// is long). On x86-64 with run-time dispatch ([`crate::isa`]) it runs a copy written with
/// AVX2 intrinsics when [`crate::isa::active`] is x86-64-v3 (the four lanes in one register:
/// LLVM does not vectorize the portable form, measured: 46,000 instructions per Krang call
/// against 10,500), else the portable form. Both do the same operations in the same order
/// (no fused multiply-adds): the same bits.
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
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
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

/// The loop of [`run`].
#[inline(always)]
fn steps<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let n = plan.dof;
    for col in plan.columns {
        let o = usize::from(col.forces);
        let x = &w[o..o + 24];
        let mut f: Forces<T> = [0, 1, 2, 3, 4, 5].map(|k| L4::load(&x[4 * k..4 * k + 4]));
        let this = plan.speeds[usize::from(col.speed)];
        let ci = usize::from(this.index);
        // Rows of the column's own link: S_a · G, S_a · H.
        let mut l = usize::from(col.link);
        let link = plan.links[l];
        for a in &plan.speeds[usize::from(link.first)..usize::from(link.end)] {
            let m = usize::from(a.motion);
            let ds = dots(&w[m..m + 6], &f);
            let ai = usize::from(a.index);
            if this.joint {
                out[ai + n * ci] = ds.0[3];
            }
            out[ai + n * (n + ci)] = ds.0[2];
        }
        // Up to the root: every ancestor speed reads the four forces in its frame.
        loop {
            let link = plan.links[l];
            if link.parent == NO_PARENT {
                break;
            }
            let t = usize::from(link.transform);
            f = up(&w[t..t + 12], &f);
            l = usize::from(link.parent);
            let parent = plan.links[l];
            for a in &plan.speeds[usize::from(parent.first)..usize::from(parent.end)] {
                let m = usize::from(a.motion);
                let ds = dots(&w[m..m + 6], &f);
                let dpd = dots(&w[m + 6..m + 12], &f);
                let ai = usize::from(a.index);
                if this.joint {
                    out[ai + n * ci] = ds.0[3];
                }
                out[ai + n * (n + ci)] = ds.0[2];
                if a.joint {
                    let dpdd = dots(&w[m + 12..m + 18], &f);
                    out[ci + n * ai] = dpdd.0[0] + dpd.0[1];
                    out[ci + n * (n + ai)] = (dpd.0[0] + dpd.0[0]) + ds.0[1];
                } else {
                    out[ci + n * (n + ai)] = dpd.0[0] + ds.0[1];
                }
            }
        }
    }
}

/// The steps with AVX2 intrinsics: the portable [`steps`] with `L4<f64>` as one `__m256d`,
/// the same operations in the same order.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use core::arch::x86_64::{
        __m256d, _mm_cvtsd_f64, _mm_unpackhi_pd, _mm256_add_pd, _mm256_castpd256_pd128,
        _mm256_extractf128_pd, _mm256_fmadd_pd, _mm256_fnmadd_pd, _mm256_mul_pd, _mm256_set_pd,
        _mm256_set1_pd,
    };

    use super::{NO_PARENT, Plan};

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn load(x: &[f64]) -> __m256d {
        _mm256_set_pd(x[3], x[2], x[1], x[0])
    }

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn lanes(v: __m256d) -> [f64; 4] {
        let lo = _mm256_castpd256_pd128(v);
        let hi = _mm256_extractf128_pd::<1>(v);
        [
            _mm_cvtsd_f64(lo),
            _mm_cvtsd_f64(_mm_unpackhi_pd(lo, lo)),
            _mm_cvtsd_f64(hi),
            _mm_cvtsd_f64(_mm_unpackhi_pd(hi, hi)),
        ]
    }

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn dots(x: &[f64], f: &[__m256d; 6]) -> [f64; 4] {
        let x = [0, 1, 2, 3, 4, 5].map(|k| _mm256_set1_pd(x[k]));
        let a = _mm256_fmadd_pd(f[1], x[1], _mm256_mul_pd(f[0], x[0]));
        let b = _mm256_fmadd_pd(f[3], x[3], _mm256_mul_pd(f[2], x[2]));
        let c = _mm256_fmadd_pd(f[5], x[5], _mm256_mul_pd(f[4], x[4]));
        lanes(_mm256_add_pd(_mm256_add_pd(a, b), c))
    }

    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn up(t: &[f64], f: &[__m256d; 6]) -> [__m256d; 6] {
        let t = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11].map(|k| _mm256_set1_pd(t[k]));
        let rot = |x: &[__m256d], i: usize| {
            let a = _mm256_fmadd_pd(x[1], t[3 * i + 1], _mm256_mul_pd(x[0], t[3 * i]));
            _mm256_fmadd_pd(x[2], t[3 * i + 2], a)
        };
        let (p0, p1, p2) = (t[9], t[10], t[11]);
        let (f0, f1, f2) = (rot(&f[3..6], 0), rot(&f[3..6], 1), rot(&f[3..6], 2));
        // R n + (a pa − b pb): two fused operations per component.
        let cross = |r: __m256d, a: __m256d, pa: __m256d, b: __m256d, pb: __m256d| {
            _mm256_fmadd_pd(a, pa, _mm256_fnmadd_pd(b, pb, r))
        };
        let n0 = cross(rot(&f[0..3], 0), f2, p1, f1, p2);
        let n1 = cross(rot(&f[0..3], 1), f0, p2, f2, p0);
        let n2 = cross(rot(&f[0..3], 2), f1, p0, f0, p1);
        [n0, n1, n2, f0, f1, f2]
    }

    /// See [`super::steps`].
    #[target_feature(enable = "avx,avx2,fma")]
    pub(super) fn steps(plan: &Plan<'_>, w: &[f64], out: &mut [f64]) {
        let n = plan.dof;
        for col in plan.columns {
            let o = usize::from(col.forces);
            let x = &w[o..o + 24];
            let mut f = [0, 1, 2, 3, 4, 5].map(|k| load(&x[4 * k..4 * k + 4]));
            let this = plan.speeds[usize::from(col.speed)];
            let ci = usize::from(this.index);
            let mut l = usize::from(col.link);
            let link = plan.links[l];
            for a in &plan.speeds[usize::from(link.first)..usize::from(link.end)] {
                let m = usize::from(a.motion);
                let ds = dots(&w[m..m + 6], &f);
                let ai = usize::from(a.index);
                if this.joint {
                    out[ai + n * ci] = ds[3];
                }
                out[ai + n * (n + ci)] = ds[2];
            }
            loop {
                let link = plan.links[l];
                if link.parent == NO_PARENT {
                    break;
                }
                let t = usize::from(link.transform);
                f = up(&w[t..t + 12], &f);
                l = usize::from(link.parent);
                let parent = plan.links[l];
                for a in &plan.speeds[usize::from(parent.first)..usize::from(parent.end)] {
                    let m = usize::from(a.motion);
                    let ds = dots(&w[m..m + 6], &f);
                    let dpd = dots(&w[m + 6..m + 12], &f);
                    let ai = usize::from(a.index);
                    if this.joint {
                        out[ai + n * ci] = ds[3];
                    }
                    out[ai + n * (n + ci)] = ds[2];
                    if a.joint {
                        let dpdd = dots(&w[m + 12..m + 18], &f);
                        out[ci + n * ai] = dpdd[0] + dpd[1];
                        out[ci + n * (n + ai)] = (dpd[0] + dpd[0]) + ds[1];
                    } else {
                        out[ci + n * (n + ai)] = dpd[0] + ds[1];
                    }
                }
            }
        }
    }
}
