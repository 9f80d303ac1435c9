//! The looped part of generated inverse-dynamics derivatives `[∂τ/∂q | ∂τ/∂u]`: the
//! O(columns × ancestors) steps of the analytic recursion, run as one loop over a generated
//! table instead of straight-line code.
//!
//! The generated function computes, straight-line, everything that is per link or per column
//! into a workspace `w` (one flat array of the scalar type): each link's transform to its
//! parent, each speed's motion subspace `S`, `Ψ̇` and `Ψ̈`, and each column's four spatial forces
//! `Φ`, `Ξ`, `H`, `G` in its own frame. [`run`] then carries the four forces of every column up
//! to the root, one link at a time, and writes the entries each ancestor speed reads from
//! them (the formulas are those of the generator's `kane/rnea_derivatives.rs`):
//!
//! * row `a` (an ancestor speed or a speed of the column's own link), column `i`:
//!   `∂τ_a/∂q_i = S_a · G_i` and `∂τ_a/∂u_i = S_a · H_i`;
//! * row `i`, column `a` (ancestors only): `∂τ_i/∂q_a = Φ_i · Ψ̈_a + Ξ_i · Ψ̇_a` and
//!   `∂τ_i/∂u_a = k Φ_i · Ψ̇_a + Ξ_i · S_a` (`k = 2` for a joint, 1 for the wheeled or
//!   floating base's quasi-velocities, whose `Ψ̇` is `V_0 × S`);
//! * a floating base's rotation speeds `a` (a quasi-velocity whose step has a q-entry): row
//!   `i`, column `a`: `∂τ_i/∂q_a = Φ_i · Ψ̈_a`, for every column, those of the base's own speeds
//!   included (their `Ψ̈` slot holds the derivative of the base acceleration along the
//!   rotation, `(0; e_a × g_b)`).
//!
//! The four forces are kept component-major (component `k` of `Φ`, `Ξ`, `H`, `G` side by side),
//! so that one step is one 4-wide transform: one AVX2 register per component in the x86-64-v3
//! copy ([`run`]; on an AVX-512 CPU the same code compiled for AVX-512VL, still 256-bit). The
//! loop's code is about 2 KB and stays in the instruction cache, where the
//! straight-line form of the same steps was streamed from L2 on every call (Krang: 233 KB of
//! code in all). The transforms and dot products are dense (the loop does not know which
//! entries of an axis-aligned joint's `R`, `P`, `S` vanish): more arithmetic than the
//! straight-line form's, fewer instructions fetched from beyond L1.
//!
//! The tables are flat: each column's walk is a run of [`Step`]s, one per speed it reaches,
//! each with the offset of its transform and motion in the workspace and the four result
//! offsets it writes, computed by the generator. The loop therefore follows no parent links
//! and computes no index (Krang: 16,500 instructions per call instead of 19,500 when it walked
//! link and speed tables). Each step's transform and motion are read as fixed-size arrays
//! after one bounds check each, and a result offset is checked once against the result, which
//! also skips [`NO_ENTRY`]: 14,100 instructions.
//!
//! Allocation-free and infallible; the tables are generated together with the code that fills
//! the workspace, so every offset is in range.

use core::ops::{Add, Mul, Sub};

/// [`Step::transform`] of a step that stays on the link of the step before it (the second
/// speed of a link with two, such as the wheeled base's heading after its forward speed).
pub const NO_TRANSFORM: u16 = u16::MAX;

/// [`Step::entries`] of an entry the step does not write.
pub const NO_ENTRY: u32 = u32::MAX;

/// [`Step::axis`] of a speed whose `S` is not a rotation about a coordinate axis.
pub const DENSE: u8 = u8::MAX;

/// [`Step::axis`] of a floating base's root step, which reads the six base speeds at once.
/// Their `S` are the unit vectors of the base frame (`v` then `ω`), so `S_a · G`, `S_a · H`
/// and `Ξ · S_a` are components of the forces, `Φ · (V_0 × S_a)` is component `a` of
/// `−V_0 ×* Φ` and the rotations' q-entries `Φ · (0; e_k × g_b)` are the components of
/// `g_b × f_Φ`. [`Step::motion`] is then the offset of `V_0 = (ω; v)` and `g_b` (9 values),
/// and [`Step::entries`] are the first offsets of four runs: `∂τ_a/∂q_i` and `∂τ_a/∂u_i` for
/// the six base rows `a` (consecutive; the first [`NO_ENTRY`] when the column's speed `i` is
/// not a joint's), `∂τ_i/∂q_a` for the three rotations and `∂τ_i/∂u_a` for the six speeds
/// (every `N` entries, [`Plan::dof`]).
pub const FLOATING_ROOT: u8 = u8::MAX - 1;

/// One step of a column: move its four forces up one link (unless [`NO_TRANSFORM`]), then
/// write the entries that one speed of that link reads from them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// Offset in the workspace of the transform from the link below to this step's link: the
    /// rotation `R` (parent ← link, 9 entries by rows) followed by the origin `P` of the link
    /// in its parent (3 entries); [`NO_TRANSFORM`] for a step that stays on the link of the
    /// step before it, and for the rows of the column's own link.
    pub transform: u16,
    /// Offset in the workspace of the speed's `S`, `Ψ̇`, `Ψ̈` (6 entries each, in its link's
    /// frame); of `V_0` and `g_b` for a [`FLOATING_ROOT`] step.
    pub motion: u16,
    /// `k` when the speed's `S` is the unit rotation about axis `k` of its link's frame, times
    /// ±1 (`S = ±(e_k; 0)`, `k` in 0..3: then `Ψ̇ = V_λ × S` vanishes in components `k` and
    /// `3 + k` and the x86-64-v3 copy reads `S` as one component and `Ψ̇` as four); [`DENSE`]
    /// otherwise.
    pub axis: u8,
    /// A joint speed (`true`) or one of the wheeled or floating base's quasi-velocities
    /// (`false`: no coordinate of its own enters the recursion; its q-column, if
    /// `entries[2]` is written, is `Φ · Ψ̈`, a floating base's rotation).
    pub joint: bool,
    /// Where the step writes, as offsets in the column-major `N × 2N` result ([`NO_ENTRY`]:
    /// not written), for the speed `a` of the step and the column's speed `i`:
    /// `∂τ_a/∂q_i = S_a · G` (none when `i` is a quasi-velocity), `∂τ_a/∂u_i = S_a · H`,
    /// `∂τ_i/∂q_a = Φ · Ψ̈_a + Ξ · Ψ̇_a` (joints `a` that are ancestors only; `Φ · Ψ̈_a` for a
    /// floating base's rotation `a`, on the own link's rows too) and
    /// `∂τ_i/∂u_a = k Φ · Ψ̇_a + Ξ · S_a` (ancestors only; `k = 2` for a joint, 1 for a
    /// quasi-velocity, whose `Ψ̇` is `V_0 × S`).
    pub entries: [u32; 4],
}

/// One column of the recursion: a speed, its four forces and its steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Column {
    /// Offset in the workspace of the four forces `Φ`, `Ξ`, `H`, `G`, component-major (24
    /// entries: `w[forces + 4 k + j]` is component `k` of force `j`).
    pub forces: u16,
    /// The column's steps are `first..end` of [`Plan::steps`]: first the rows of its own link
    /// (`first..own`: `S_a · G`, `S_a · H`, no transform), then one step per ancestor speed,
    /// from the link's parent up to the root.
    pub first: u32,
    /// End of the own link's rows in [`Plan::steps`].
    pub own: u32,
    /// End of the column's steps in [`Plan::steps`].
    pub end: u32,
}

impl Column {
    /// The rows of the column's own link and its steps up to the root, as ranges of
    /// [`Plan::steps`].
    #[inline(always)]
    pub fn ranges(&self) -> (core::ops::Range<usize>, core::ops::Range<usize>) {
        let (first, own, end) = (self.first as usize, self.own as usize, self.end as usize);
        (first..own, own..end)
    }
}

/// The generated tables of one model: every column's walk to the root, flattened, with the
/// result offsets it writes, so that the loop reads one record per step and computes no
/// index.
#[derive(Clone, Copy, Debug)]
pub struct Plan<'a> {
    /// Number of independent speeds N: the result is `N × 2N`, column-major.
    pub dof: usize,
    /// The columns, in the order they are run.
    pub columns: &'a [Column],
    /// The steps of every column, column after column.
    pub steps: &'a [Step],
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
fn up<T>(t: &[T; 12], f: &Forces<T>) -> Forces<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
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
/// [`crate::isa::active`] is x86-64-v3 or x86-64-v4 (or the crate is compiled for AVX2 and
/// FMA): the four lanes in one register; when x86-64-v4 is active, that copy compiled for
/// AVX-512 F and VL (the same bits). LLVM does not vectorize the portable form (it splits the
/// lanes into scalars): Krang's 104 steps take 46,000 instructions in it even in the x86-64-v3
/// copy, 21,200 with AVX2 intrinsics and 18,600 with AVX2 and FMA (callgrind). Elsewhere the
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
    if crate::isa::active() != crate::isa::Isa::Baseline {
        // SAFETY: `isa::active` is x86-64-v3 or x86-64-v4 only when the CPU has AVX, AVX2 and
        // FMA (it checks every feature of x86-64-v3 before selecting either), the features
        // `avx2::steps` is compiled with, and x86-64-v4 only when it also has AVX-512 F and VL
        // (every feature of x86-64-v4), those of `avx512vl::steps`.
        #[allow(unsafe_code)]
        unsafe {
            if crate::isa::active() == crate::isa::Isa::X86_64V4 {
                return avx512vl::steps(plan, w, out);
            }
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
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    steps(plan, w, out)
}

/// Writes `v` at `entry` unless it is [`NO_ENTRY`]: one comparison for both, since
/// `NO_ENTRY` is beyond any result (and a generated table's other entries are within it).
#[inline(always)]
fn put<T>(out: &mut [T], entry: u32, v: T) {
    if let Some(o) = out.get_mut(entry as usize) {
        *o = v;
    }
}

/// The `K` entries of `w` from `at`, as an array: one bounds check, after which the reads of
/// its entries need none (a generated table's offsets are within the workspace).
#[inline(always)]
fn chunk<T, const K: usize>(w: &[T], at: usize) -> &[T; K] {
    w[at..at + K]
        .try_into()
        .expect("a slice of K entries is an array of K")
}

/// Writes the entries of an ancestor step `s` from its dot products with the four forces `Φ`,
/// `Ξ`, `H`, `G` (one lane each): `ds = S · F`, `dpd = Ψ̇ · F` and, when `s` is a joint or
/// writes a q-entry (a floating base's rotation), `dpdd = Ψ̈ · F` (not read otherwise).
#[inline(always)]
fn write_reads<T: Copy + Add<Output = T>>(
    out: &mut [T],
    s: &Step,
    ds: [T; 4],
    dpd: [T; 4],
    dpdd: [T; 4],
) {
    put(out, s.entries[0], ds[3]);
    put(out, s.entries[1], ds[2]);
    if s.joint {
        put(out, s.entries[2], dpdd[0] + dpd[1]);
        put(out, s.entries[3], (dpd[0] + dpd[0]) + ds[1]);
    } else {
        put(out, s.entries[2], dpdd[0]);
        put(out, s.entries[3], dpd[0] + ds[1]);
    }
}

/// Whether step `s` reads `Ψ̈`: a joint, or a quasi-velocity with a q-entry (a floating
/// base's rotation).
#[inline(always)]
fn reads_psidd(s: &Step) -> bool {
    s.joint || s.entries[2] != NO_ENTRY
}

/// The reads of a [`FLOATING_ROOT`] step `s` from the forces' components `f` (`f[k][j]`:
/// component `k` of `Φ`, `Ξ`, `H`, `G`), the base's `V_0` and `g_b` in `m`, for `n` speeds.
#[inline(always)]
fn root_reads<T>(out: &mut [T], n: usize, s: &Step, m: &[T; 9], f: &[[T; 4]; 6])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    let cross = |a: [T; 3], b: [T; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (w, v, g) = ([m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]);
    let (pn, pf) = ([f[0][0], f[1][0], f[2][0]], [f[3][0], f[4][0], f[5][0]]);
    // V_0 ×* Φ = (ω × n + v × f; ω × f), component-major like the forces.
    let (a, b, c) = (cross(w, pn), cross(v, pf), cross(w, pf));
    let x = [a[0] + b[0], a[1] + b[1], a[2] + b[2], c[0], c[1], c[2]];
    let [gq, hq, rq, uq] = s.entries.map(|e| e as usize);
    for a in 0..6 {
        // S_a picks component 3 + a (v) or a − 3 (ω) of a force.
        let k = if a < 3 { 3 + a } else { a - 3 };
        if s.entries[0] != NO_ENTRY {
            put(out, (gq + a) as u32, f[k][3]);
        }
        put(out, (hq + a) as u32, f[k][2]);
        put(out, (uq + n * a) as u32, f[k][1] - x[k]);
    }
    let r = cross(g, pf);
    for (k, rk) in r.into_iter().enumerate() {
        put(out, (rq + n * k) as u32, rk);
    }
}

/// The loop of [`run`].
#[inline(always)]
fn steps<T>(plan: &Plan<'_>, w: &[T], out: &mut [T])
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T>,
{
    for col in plan.columns {
        let x: &[T; 24] = chunk(w, usize::from(col.forces));
        let mut f: Forces<T> = [0, 1, 2, 3, 4, 5].map(|k| L4::load(&x[4 * k..4 * k + 4]));
        let (own_rows, up_steps) = col.ranges();
        // Rows of the column's own link: S_a · G, S_a · H (and Φ · Ψ̈_a for a floating
        // base's rotation a).
        for s in &plan.steps[own_rows] {
            let mo: &[T; 18] = chunk(w, usize::from(s.motion));
            let ds = dots(&mo[0..6], &f);
            put(out, s.entries[0], ds.0[3]);
            put(out, s.entries[1], ds.0[2]);
            if s.entries[2] != NO_ENTRY {
                put(out, s.entries[2], dots(&mo[12..18], &f).0[0]);
            }
        }
        // Up to the root: every ancestor speed reads the four forces in its frame.
        for s in &plan.steps[up_steps] {
            if s.transform != NO_TRANSFORM {
                f = up(chunk::<T, 12>(w, usize::from(s.transform)), &f);
            }
            if s.axis == FLOATING_ROOT {
                let comps = f.map(|c| c.0);
                root_reads(out, plan.dof, s, chunk(w, usize::from(s.motion)), &comps);
                continue;
            }
            let mo: &[T; 18] = chunk(w, usize::from(s.motion));
            let ds = dots(&mo[0..6], &f);
            let dpd = dots(&mo[6..12], &f);
            // Ψ̈ only where it is read (`write_reads` reads no `dpdd` otherwise: `ds` fills it).
            let dpdd = if reads_psidd(s) {
                dots(&mo[12..18], &f)
            } else {
                ds
            };
            write_reads(out, s, ds.0, dpd.0, dpdd.0);
        }
    }
}

/// The steps with AVX2 and FMA intrinsics (the module `$name`, every function compiled with the
/// target features `$features`): the portable [`steps`] with `L4<f64>` as one `__m256d`, a
/// multiply and an add fused where the portable form has them in sequence.
macro_rules! avx_steps {
    ($(#[$attr:meta])* $name:ident, $features:literal) => {
        $(#[$attr])*
        mod $name {
            use core::arch::x86_64::{
                __m256d, _mm_cvtsd_f64, _mm_unpackhi_pd, _mm256_add_pd,
                _mm256_castpd256_pd128, _mm256_extractf128_pd, _mm256_fmadd_pd,
                _mm256_fnmadd_pd, _mm256_mul_pd, _mm256_set_pd, _mm256_set1_pd,
            };

            use super::{
                FLOATING_ROOT, NO_ENTRY, NO_TRANSFORM, Plan, Step, put, reads_psidd, root_reads,
                write_reads,
            };

            #[target_feature(enable = $features)]
            #[inline]
            fn load(x: &[f64]) -> __m256d {
                _mm256_set_pd(x[3], x[2], x[1], x[0])
            }

            #[target_feature(enable = $features)]
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

            #[target_feature(enable = $features)]
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

            #[target_feature(enable = $features)]
            #[inline]
            fn up(t: &[f64; 12], f: &[__m256d; 6]) -> [__m256d; 6] {
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
                // R n + P × R f: two fused operations per component.
                let (m0, m1, m2) = (
                    rot!(0, f[0], f[1], f[2]),
                    rot!(1, f[0], f[1], f[2]),
                    rot!(2, f[0], f[1], f[2]),
                );
                let n0 = _mm256_fmadd_pd(f2, p1, _mm256_fnmadd_pd(f1, p2, m0));
                let n1 = _mm256_fmadd_pd(f0, p2, _mm256_fnmadd_pd(f2, p0, m1));
                let n2 = _mm256_fmadd_pd(f1, p0, _mm256_fnmadd_pd(f0, p1, m2));
                [n0, n1, n2, f0, f1, f2]
            }

            /// `Σ_j x[j] f[j]` over the four components `j` other than `k` and `3 + k`.
            #[target_feature(enable = $features)]
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

            /// The dot products the step `a` reads: `S·F`, `Ψ̇·F` and (joints) `Ψ̈·F`, from its
            /// motions `mo` (`S = ±e_k` read as one component and `Ψ̇` as four when `a.axis` is
            /// `k`).
            #[target_feature(enable = $features)]
            #[inline]
            fn reads<const K: usize>(mo: &[f64; 18], a: &Step, f: &[__m256d; 6]) -> [[f64; 4]; 3] {
                let ds = lanes(_mm256_mul_pd(f[K], _mm256_set1_pd(mo[K])));
                let dpd = dots4::<K>(&mo[6..12], f);
                [ds, dpd, psidd_dots(mo, a, f)]
            }

            /// `Ψ̈ · F` for a joint (`Ψ̈ = A_λ × S + V_λ × Ψ̇` has all six components in general)
            /// or a floating base's rotation, zeros for another quasi-velocity (not read).
            #[target_feature(enable = $features)]
            #[inline]
            fn psidd_dots(mo: &[f64; 18], a: &Step, f: &[__m256d; 6]) -> [f64; 4] {
                if reads_psidd(a) {
                    dots(&mo[12..18], f)
                } else {
                    [0.0; 4]
                }
            }

            /// [`reads`] for any `S`.
            #[target_feature(enable = $features)]
            #[inline]
            fn reads_dense(mo: &[f64; 18], a: &Step, f: &[__m256d; 6]) -> [[f64; 4]; 3] {
                [dots(&mo[0..6], f), dots(&mo[6..12], f), psidd_dots(mo, a, f)]
            }

            /// See [`super::steps`].
            #[target_feature(enable = $features)]
            pub(super) fn steps(plan: &Plan<'_>, w: &[f64], out: &mut [f64]) {
                for col in plan.columns {
                    let x: &[f64; 24] = super::chunk(w, usize::from(col.forces));
                    let mut f = [
                        load(&x[0..4]),
                        load(&x[4..8]),
                        load(&x[8..12]),
                        load(&x[12..16]),
                        load(&x[16..20]),
                        load(&x[20..24]),
                    ];
                    let (own_rows, up_steps) = col.ranges();
                    for s in &plan.steps[own_rows] {
                        let mo: &[f64; 18] = super::chunk(w, usize::from(s.motion));
                        let ds = dots(&mo[0..6], &f);
                        put(out, s.entries[0], ds[3]);
                        put(out, s.entries[1], ds[2]);
                        if s.entries[2] != NO_ENTRY {
                            put(out, s.entries[2], dots(&mo[12..18], &f)[0]);
                        }
                    }
                    for s in &plan.steps[up_steps] {
                        if s.transform != NO_TRANSFORM {
                            f = up(super::chunk::<f64, 12>(w, usize::from(s.transform)), &f);
                        }
                        if s.axis == FLOATING_ROOT {
                            let comps = [
                                lanes(f[0]),
                                lanes(f[1]),
                                lanes(f[2]),
                                lanes(f[3]),
                                lanes(f[4]),
                                lanes(f[5]),
                            ];
                            let m = super::chunk(w, usize::from(s.motion));
                            root_reads(out, plan.dof, s, m, &comps);
                            continue;
                        }
                        let mo: &[f64; 18] = super::chunk(w, usize::from(s.motion));
                        let [ds, dpd, dpdd] = match s.axis {
                            0 => reads::<0>(mo, s, &f),
                            1 => reads::<1>(mo, s, &f),
                            2 => reads::<2>(mo, s, &f),
                            _ => reads_dense(mo, s, &f),
                        };
                        write_reads(out, s, ds, dpd, dpdd);
                    }
                }
            }
        }
    };
}

avx_steps!(
    /// Compiled where [`run`] can call it: with run-time dispatch, or when the crate is built
    /// with AVX2 and FMA.
    #[cfg(all(
        target_arch = "x86_64",
        any(
            all(feature = "dispatch", feature = "std"),
            all(target_feature = "avx2", target_feature = "fma")
        )
    ))]
    avx2,
    "avx,avx2,fma"
);

avx_steps!(
    /// The same steps compiled for x86-64-v4, which [`run`] calls when the CPU has AVX-512
    /// (still 256-bit registers, no `zmm`: AVX-512VL's 32 registers and broadcasts folded into
    /// the multiply-adds). Krang's `inverse_dynamics_derivatives_with` 1,394–1,419 →
    /// 1,303–1,335 ns (profile driver, three alternated runs; the same bits). Only with
    /// run-time dispatch: a crate built for AVX-512 compiles `avx2` with it.
    #[cfg(all(
        target_arch = "x86_64",
        feature = "dispatch",
        feature = "std",
        not(all(target_feature = "avx2", target_feature = "fma"))
    ))]
    avx512vl,
    "avx,avx2,fma,avx512f,avx512vl"
);
