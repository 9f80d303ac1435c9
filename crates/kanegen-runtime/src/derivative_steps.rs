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
//! The four forces are kept component-major (component `k` of `Φ`, `Ξ`, `H`, `G` side by side),
//! so that one step is one 4-wide transform: one AVX2 register per component in the x86-64-v3
//! copy ([`run`]). The loop's code is about 2 KB and stays in the instruction cache, where the
//! straight-line form of the same steps was streamed from L2 on every call (Krang: 233 KB of
//! code in all). The transforms and dot products are dense (the loop does not know which
//! entries of an axis-aligned joint's `R`, `P`, `S` vanish): more arithmetic than the
//! straight-line form's, fewer instructions fetched from beyond L1.
//!
//! Allocation-free and infallible; the tables are generated together with the code that fills
//! the workspace, so every offset is in range.

use core::ops::{Add, Mul, Neg, Sub};

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
    /// The structure of `R`, known at generation time: `3 row + column` of its constant ±1
    /// entry (plus 9 when the entry is −1) whose row and column are otherwise zero — a
    /// rotation about a coordinate axis after a constant signed permutation — or [`DENSE`].
    /// A shaped rotation moves a 3-vector with 4 multiply(-add)s instead of 9 and does not
    /// read the ±1 entry.
    pub rotation: u8,
    /// The structure of `P`: `k` when only component `k` can be non-zero (`P × f` is then two
    /// multiply-adds), [`ZERO_OFFSET`] when `P = 0` (no `P ×` term), or [`DENSE`].
    pub offset: u8,
}

/// [`Link::offset`] of a link whose origin is that of its parent.
pub const ZERO_OFFSET: u8 = 3;

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
    /// `k` when `S` is the unit rotation about axis `k` of the link's frame, times ±1
    /// (`S = ±(e_k; 0)`, `k` in 0..3: then `Ψ̇ = V_λ × S` vanishes in components `k` and
    /// `3 + k` and the x86-64-v3 copy reads `S` as one component and `Ψ̇` as four);
    /// [`DENSE`] otherwise.
    pub axis: u8,
}

/// [`Speed::axis`] of a speed whose `S` is not a rotation about a coordinate axis;
/// [`Link::rotation`] and [`Link::offset`] of a dense `R` or `P`.
pub const DENSE: u8 = u8::MAX;

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

    #[inline(always)]
    fn neg(self) -> Self
    where
        T: Neg<Output = T>,
    {
        let a = self.0;
        L4([-a[0], -a[1], -a[2], -a[3]])
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

/// The other two of the three axes, `(k + 1) % 3` and `(k + 2) % 3`.
#[inline(always)]
const fn others(k: usize) -> (usize, usize) {
    ((k + 1) % 3, (k + 2) % 3)
}

/// `R x` for a rotation whose entry `(RR, RC)` is the constant `±1` (`−1` when `NEG`) and whose
/// other entries in row `RR` and column `RC` are zero (`t` = `R` by rows): component `RR` is
/// `±x[RC]`, the other two take two products each.
#[inline(always)]
fn rot_axis<T, const RR: usize, const RC: usize, const NEG: bool>(
    t: &[T; 12],
    x: [L4<T>; 3],
) -> [L4<T>; 3]
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Neg<Output = T>,
{
    let (i1, i2) = others(RR);
    let (c1, c2) = others(RC);
    let mut o = x;
    o[RR] = if NEG { x[RC].neg() } else { x[RC] };
    o[i1] = x[c1].scale(t[3 * i1 + c1]).add(x[c2].scale(t[3 * i1 + c2]));
    o[i2] = x[c1].scale(t[3 * i2 + c1]).add(x[c2].scale(t[3 * i2 + c2]));
    o
}

/// `R x` for a dense rotation (`t` = `R` by rows).
#[inline(always)]
fn rot_dense<T>(t: &[T; 12], x: [L4<T>; 3]) -> [L4<T>; 3]
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Neg<Output = T>,
{
    let row = |i: usize| {
        x[0].scale(t[3 * i])
            .add(x[1].scale(t[3 * i + 1]))
            .add(x[2].scale(t[3 * i + 2]))
    };
    [row(0), row(1), row(2)]
}

/// `n + P × g` for `P = p e_A` (`p = t[9 + A]`): components `A + 1` and `A + 2` only.
#[inline(always)]
fn cross_axis<T, const A: usize>(t: &[T; 12], g: &[L4<T>; 3], mut n: [L4<T>; 3]) -> [L4<T>; 3]
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let (b, c) = others(A);
    let p = t[9 + A];
    n[b] = n[b].sub(g[c].scale(p));
    n[c] = n[c].add(g[b].scale(p));
    n
}

/// `n + P × g` for any `P`.
#[inline(always)]
fn cross_dense<T>(t: &[T; 12], g: &[L4<T>; 3], n: [L4<T>; 3]) -> [L4<T>; 3]
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let (p0, p1, p2) = (t[9], t[10], t[11]);
    [
        n[0].add(g[2].scale(p1).sub(g[1].scale(p2))),
        n[1].add(g[0].scale(p2).sub(g[2].scale(p0))),
        n[2].add(g[1].scale(p0).sub(g[0].scale(p1))),
    ]
}

/// The four forces moved from `link` to its parent, `(R n + P × R f; R f)`, by the link's
/// [`Link::rotation`] and [`Link::offset`] (`t` = `R` by rows then `P`).
#[inline(always)]
fn up_shaped<T>(link: &Link, t: &[T; 12], f: &Forces<T>) -> Forces<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Neg<Output = T>,
{
    let fv = [f[3], f[4], f[5]];
    let nv = [f[0], f[1], f[2]];
    macro_rules! rot {
        ($($code:literal => $rr:literal, $rc:literal, $neg:literal;)*) => {
            match link.rotation {
                $($code => (rot_axis::<T, $rr, $rc, $neg>(t, fv), rot_axis::<T, $rr, $rc, $neg>(t, nv)),)*
                _ => (rot_dense(t, fv), rot_dense(t, nv)),
            }
        };
    }
    let (g, n) = rot! {
        0 => 0, 0, false; 1 => 0, 1, false; 2 => 0, 2, false;
        3 => 1, 0, false; 4 => 1, 1, false; 5 => 1, 2, false;
        6 => 2, 0, false; 7 => 2, 1, false; 8 => 2, 2, false;
        9 => 0, 0, true; 10 => 0, 1, true; 11 => 0, 2, true;
        12 => 1, 0, true; 13 => 1, 1, true; 14 => 1, 2, true;
        15 => 2, 0, true; 16 => 2, 1, true; 17 => 2, 2, true;
    };
    let n = match link.offset {
        0 => cross_axis::<T, 0>(t, &g, n),
        1 => cross_axis::<T, 1>(t, &g, n),
        2 => cross_axis::<T, 2>(t, &g, n),
        ZERO_OFFSET => n,
        _ => cross_dense(t, &g, n),
    };
    [n[0], n[1], n[2], g[0], g[1], g[2]]
}

/// Runs the steps of `plan` on the workspace `w` and writes the entries of
/// `[∂τ/∂q | ∂τ/∂u]` into `out` (column-major `N × 2N`, e.g. `SMatrix::as_mut_slice`).
/// Entries that no column reaches are left as they are (the generated function passes a zeroed
/// matrix: they are structural zeros).
///
/// A function of its own, not inlined into the generated function (whose straight-line part
/// is long). On x86-64 it runs a copy written with AVX2 and FMA intrinsics when
/// [`crate::isa::active`] is x86-64-v3 (or the crate is compiled for AVX2 and FMA): the four
/// lanes in one register. LLVM does not vectorize the portable form (it splits the lanes into
/// scalars): Krang's 104 steps take 46,000 instructions in it even in the x86-64-v3 copy,
/// 21,200 with AVX2 intrinsics and 18,600 with AVX2 and FMA (callgrind). Elsewhere the
/// portable form runs. The two copies differ in the last bits (the fused multiply-adds round
/// once); the straight-line part of the generated function is the same in both.
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
    // SAFETY: the crate is compiled with AVX2 and FMA enabled (`-C target-cpu=…`), so every CPU
    // it runs on has the features `avx2::steps` is compiled with. (A crate-wide target feature
    // does not make the call safe: `run` itself has no `#[target_feature]`.)
    #[allow(unsafe_code)]
    return unsafe { avx2::steps(plan, w, out) };
    #[allow(unreachable_code)]
    steps(plan, w, out)
}

/// [`run`] for any scalar type (`f32` modules), in the portable form.
#[inline(never)]
pub fn run_generic<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Neg<Output = T>,
{
    steps(plan, w, out)
}

/// The loop of [`run`].
#[inline(always)]
fn steps<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Neg<Output = T>,
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
            let t: &[T; 12] = w[t..t + 12].try_into().expect("12 entries");
            f = up_shaped(&link, t, &f);
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

/// The steps with AVX2 and FMA intrinsics: the portable [`steps`] with `L4<f64>` as one
/// `__m256d`, a multiply and an add fused where the portable form has them in sequence. Compiled
/// where [`run`] can call it: with run-time dispatch, or when the crate is built with AVX2 and FMA.
#[cfg(all(
    target_arch = "x86_64",
    any(
        all(feature = "dispatch", feature = "std"),
        all(target_feature = "avx2", target_feature = "fma")
    )
))]
mod avx2 {
    use core::arch::x86_64::{
        __m256d, _mm_cvtsd_f64, _mm_unpackhi_pd, _mm256_add_pd, _mm256_castpd256_pd128,
        _mm256_extractf128_pd, _mm256_fmadd_pd, _mm256_fnmadd_pd, _mm256_mul_pd, _mm256_set_pd,
        _mm256_set1_pd, _mm256_setzero_pd, _mm256_sub_pd,
    };

    use super::{Link, NO_PARENT, Plan, Speed, ZERO_OFFSET};

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
        let a = _mm256_fmadd_pd(
            f[1],
            _mm256_set1_pd(x[1]),
            _mm256_mul_pd(f[0], _mm256_set1_pd(x[0])),
        );
        let b = _mm256_fmadd_pd(
            f[3],
            _mm256_set1_pd(x[3]),
            _mm256_mul_pd(f[2], _mm256_set1_pd(x[2])),
        );
        let c = _mm256_fmadd_pd(
            f[5],
            _mm256_set1_pd(x[5]),
            _mm256_mul_pd(f[4], _mm256_set1_pd(x[4])),
        );
        lanes(_mm256_add_pd(_mm256_add_pd(a, b), c))
    }

    /// `R x` for a shaped rotation (see [`super::rot_axis`]), `t` = `R` by rows.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn rot_axis<const RR: usize, const RC: usize, const NEG: bool>(
        t: &[f64; 12],
        x: [__m256d; 3],
    ) -> [__m256d; 3] {
        let (i1, i2) = super::others(RR);
        let (c1, c2) = super::others(RC);
        let mut o = x;
        o[RR] = if NEG {
            _mm256_sub_pd(_mm256_setzero_pd(), x[RC])
        } else {
            x[RC]
        };
        o[i1] = _mm256_fmadd_pd(
            x[c2],
            _mm256_set1_pd(t[3 * i1 + c2]),
            _mm256_mul_pd(x[c1], _mm256_set1_pd(t[3 * i1 + c1])),
        );
        o[i2] = _mm256_fmadd_pd(
            x[c2],
            _mm256_set1_pd(t[3 * i2 + c2]),
            _mm256_mul_pd(x[c1], _mm256_set1_pd(t[3 * i2 + c1])),
        );
        o
    }

    /// `R x` for a dense rotation.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn rot_dense(t: &[f64; 12], x: [__m256d; 3]) -> [__m256d; 3] {
        let row = |i: usize| {
            let a = _mm256_fmadd_pd(
                x[1],
                _mm256_set1_pd(t[3 * i + 1]),
                _mm256_mul_pd(x[0], _mm256_set1_pd(t[3 * i])),
            );
            _mm256_fmadd_pd(x[2], _mm256_set1_pd(t[3 * i + 2]), a)
        };
        [row(0), row(1), row(2)]
    }

    /// `n + P × g` for `P = p e_A`.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn cross_axis<const A: usize>(
        t: &[f64; 12],
        g: &[__m256d; 3],
        mut n: [__m256d; 3],
    ) -> [__m256d; 3] {
        let (b, c) = super::others(A);
        let p = _mm256_set1_pd(t[9 + A]);
        n[b] = _mm256_fnmadd_pd(g[c], p, n[b]);
        n[c] = _mm256_fmadd_pd(g[b], p, n[c]);
        n
    }

    /// `n + P × g` for any `P`: two fused operations per component.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn cross_dense(t: &[f64; 12], g: &[__m256d; 3], n: [__m256d; 3]) -> [__m256d; 3] {
        let (p0, p1, p2) = (
            _mm256_set1_pd(t[9]),
            _mm256_set1_pd(t[10]),
            _mm256_set1_pd(t[11]),
        );
        [
            _mm256_fmadd_pd(g[2], p1, _mm256_fnmadd_pd(g[1], p2, n[0])),
            _mm256_fmadd_pd(g[0], p2, _mm256_fnmadd_pd(g[2], p0, n[1])),
            _mm256_fmadd_pd(g[1], p0, _mm256_fnmadd_pd(g[0], p1, n[2])),
        ]
    }

    /// See [`super::up_shaped`].
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn up_shaped(link: &Link, t: &[f64; 12], f: &[__m256d; 6]) -> [__m256d; 6] {
        let fv = [f[3], f[4], f[5]];
        let nv = [f[0], f[1], f[2]];
        macro_rules! rot {
            ($($code:literal => $rr:literal, $rc:literal, $neg:literal;)*) => {
                match link.rotation {
                    $($code => (rot_axis::<$rr, $rc, $neg>(t, fv), rot_axis::<$rr, $rc, $neg>(t, nv)),)*
                    _ => (rot_dense(t, fv), rot_dense(t, nv)),
                }
            };
        }
        let (g, n) = rot! {
            0 => 0, 0, false; 1 => 0, 1, false; 2 => 0, 2, false;
            3 => 1, 0, false; 4 => 1, 1, false; 5 => 1, 2, false;
            6 => 2, 0, false; 7 => 2, 1, false; 8 => 2, 2, false;
            9 => 0, 0, true; 10 => 0, 1, true; 11 => 0, 2, true;
            12 => 1, 0, true; 13 => 1, 1, true; 14 => 1, 2, true;
            15 => 2, 0, true; 16 => 2, 1, true; 17 => 2, 2, true;
        };
        let n = match link.offset {
            0 => cross_axis::<0>(t, &g, n),
            1 => cross_axis::<1>(t, &g, n),
            2 => cross_axis::<2>(t, &g, n),
            ZERO_OFFSET => n,
            _ => cross_dense(t, &g, n),
        };
        [n[0], n[1], n[2], g[0], g[1], g[2]]
    }

    /// `Σ_j x[j] f[j]` over the four components `j` other than `k` and `3 + k`.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn dots4<const K: usize>(x: &[f64], f: &[__m256d; 6]) -> [f64; 4] {
        let (a, b) = ((K + 1) % 3, (K + 2) % 3);
        let p = _mm256_fmadd_pd(
            f[b],
            _mm256_set1_pd(x[b]),
            _mm256_mul_pd(f[a], _mm256_set1_pd(x[a])),
        );
        let q = _mm256_fmadd_pd(
            f[3 + b],
            _mm256_set1_pd(x[3 + b]),
            _mm256_mul_pd(f[3 + a], _mm256_set1_pd(x[3 + a])),
        );
        lanes(_mm256_add_pd(p, q))
    }

    /// The dot products a speed `a` reads: `S·F`, `Ψ̇·F` and (joints) `Ψ̈·F`, from the motions
    /// at `m` (`S = ±e_k` read as one component and `Ψ̇` as four when `a.axis` is `k`).
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn reads<const K: usize>(w: &[f64], m: usize, a: &Speed, f: &[__m256d; 6]) -> [[f64; 4]; 3] {
        let ds = lanes(_mm256_mul_pd(f[K], _mm256_set1_pd(w[m + K])));
        let dpd = dots4::<K>(&w[m + 6..m + 12], f);
        // Ψ̈ = A_λ × S + V_λ × Ψ̇ has all six components in general.
        let dpdd = if a.joint {
            dots(&w[m + 12..m + 18], f)
        } else {
            [0.0; 4]
        };
        [ds, dpd, dpdd]
    }

    /// [`reads`] for any `S`.
    #[target_feature(enable = "avx,avx2,fma")]
    #[inline]
    fn reads_dense(w: &[f64], m: usize, a: &Speed, f: &[__m256d; 6]) -> [[f64; 4]; 3] {
        let ds = dots(&w[m..m + 6], f);
        let dpd = dots(&w[m + 6..m + 12], f);
        let dpdd = if a.joint {
            dots(&w[m + 12..m + 18], f)
        } else {
            [0.0; 4]
        };
        [ds, dpd, dpdd]
    }

    /// See [`super::steps`].
    #[target_feature(enable = "avx,avx2,fma")]
    pub(super) fn steps(plan: &Plan<'_>, w: &[f64], out: &mut [f64]) {
        let n = plan.dof;
        for col in plan.columns {
            let o = usize::from(col.forces);
            let x = &w[o..o + 24];
            let mut f = [
                load(&x[0..4]),
                load(&x[4..8]),
                load(&x[8..12]),
                load(&x[12..16]),
                load(&x[16..20]),
                load(&x[20..24]),
            ];
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
                let t: &[f64; 12] = w[t..t + 12].try_into().expect("12 entries");
                f = up_shaped(&link, t, &f);
                l = usize::from(link.parent);
                let parent = plan.links[l];
                for a in &plan.speeds[usize::from(parent.first)..usize::from(parent.end)] {
                    let m = usize::from(a.motion);
                    let [ds, dpd, dpdd] = match a.axis {
                        0 => reads::<0>(w, m, a, &f),
                        1 => reads::<1>(w, m, a, &f),
                        2 => reads::<2>(w, m, a, &f),
                        _ => reads_dense(w, m, a, &f),
                    };
                    let ai = usize::from(a.index);
                    if this.joint {
                        out[ai + n * ci] = ds[3];
                    }
                    out[ai + n * (n + ci)] = ds[2];
                    if a.joint {
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

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec;

    /// Uniform in [−1, 1) from a 64-bit LCG.
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// Every rotation shape (18 codes and dense) with every offset shape (three axes, zero,
    /// dense): a root with one speed and 95 children, each with one speed and a column, so
    /// that each child's forces take one step up through its own shape. The shaped tables
    /// against the same workspace run with every link marked dense (the workspace holds the
    /// full `R`, its ±1 entry included, and the zeros).
    #[test]
    fn shaped_transforms_equal_the_dense_transform_for_every_rotation_and_offset_shape() {
        let mut rng = Lcg(7);
        let offsets = [0, 1, 2, ZERO_OFFSET, DENSE];
        let children = 95;
        let mut w = Vec::new();
        let mut links = vec![Link {
            parent: NO_PARENT,
            transform: 0,
            first: 0,
            end: 1,
            rotation: DENSE,
            offset: DENSE,
        }];
        let mut speeds = Vec::new();
        let mut columns = Vec::new();
        let motion = |w: &mut Vec<f64>, rng: &mut Lcg| {
            let at = w.len();
            w.extend((0..18).map(|_| rng.next()));
            at as u16
        };
        speeds.push(Speed {
            index: 0,
            motion: motion(&mut w, &mut rng),
            joint: true,
            axis: DENSE,
        });
        for i in 0..children {
            let rotation = if i % 19 == 18 { DENSE } else { (i % 19) as u8 };
            let offset = offsets[i % 5];
            let mut t: Vec<f64> = (0..12).map(|_| rng.next()).collect();
            if rotation != DENSE {
                let (code, negative) = (usize::from(rotation % 9), rotation >= 9);
                let (rr, rc) = (code / 3, code % 3);
                for k in 0..3 {
                    t[3 * rr + k] = 0.0;
                    t[3 * k + rc] = 0.0;
                }
                t[3 * rr + rc] = if negative { -1.0 } else { 1.0 };
            }
            match offset {
                ZERO_OFFSET => t[9..12].fill(0.0),
                k if k < 3 => {
                    for j in 0..3 {
                        if j != usize::from(k) {
                            t[9 + j] = 0.0;
                        }
                    }
                }
                _ => {}
            }
            let transform = w.len() as u16;
            w.extend_from_slice(&t);
            let s = speeds.len() as u16;
            speeds.push(Speed {
                index: s,
                motion: motion(&mut w, &mut rng),
                joint: i % 2 == 0,
                axis: DENSE,
            });
            links.push(Link {
                parent: 0,
                transform,
                first: s,
                end: s + 1,
                rotation,
                offset,
            });
            let forces = w.len() as u16;
            w.extend((0..24).map(|_| rng.next()));
            columns.push(Column {
                link: (i + 1) as u16,
                speed: s,
                forces,
            });
        }
        let dense_links: Vec<Link> = links
            .iter()
            .map(|l| Link {
                rotation: DENSE,
                offset: DENSE,
                ..*l
            })
            .collect();
        let n = speeds.len();
        let plan = |links| Plan {
            dof: n,
            links,
            speeds: &speeds,
            columns: &columns,
        };
        let result = |plan: &Plan<'_>, kernel: fn(&Plan<'_>, &[f64], &mut [f64])| {
            let mut out = vec![0.0; 2 * n * n];
            kernel(plan, &w, &mut out);
            out
        };
        let dense = result(&plan(&dense_links), run_generic::<f64>);
        let shaped = result(&plan(&links), run_generic::<f64>);
        let dispatched = result(&plan(&links), run);
        let scale = dense.iter().fold(1.0f64, |m, v| m.max(v.abs()));
        for (k, d) in dense.iter().enumerate() {
            let (s, r) = (shaped[k], dispatched[k]);
            assert!(
                (s - d).abs() <= 1e-14 * scale,
                "entry {k}: shaped {s} vs dense {d} (portable kernel)"
            );
            assert!(
                (r - d).abs() <= 1e-13 * scale,
                "entry {k}: shaped {r} vs dense {d} (dispatched kernel)"
            );
        }
    }
}
