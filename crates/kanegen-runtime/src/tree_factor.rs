//! The mass matrix of a kinematic tree factorised without fill-in: [`TreeFactor`], Featherstone's
//! `LᵀDL` factorisation for branched kinematic trees ("Efficient factorization of the
//! joint-space inertia matrix for branched kinematic trees", IJRR 24(6), 2005).
//!
//! # The parent array
//!
//! Number the speeds so that every speed's *parent* comes before it: `λ(i) < i`, `λ(i)` the
//! speed nearest to speed `i` on the path from `i`'s body towards the root (`None` where there is
//! none). A floating base's six speeds form a chain at the root (`λ = [None, 0, 1, 2, 3, 4]`) and
//! the first joint of every limb has parent 5; a wheeled base's two speeds likewise. Then
//! `M(i, j)` is structurally zero unless one of `i`, `j` is an ancestor of the other (two legs
//! never couple), and `M = Lᵀ D L` with `L` unit lower triangular of the same pattern: no fill-in.
//! The factorisation costs `Σ_k d_k (d_k + 1) / 2` multiply-adds and a solve `2 Σ_k d_k`, `d_k`
//! the number of ancestors of speed `k`, where a dense Cholesky factorisation costs `N³ / 6`.
//! A generated module whose mass matrix has the pattern exports its parent array as
//! `SPEED_PARENTS` (the traits' `SPEED_PARENTS`); [`chain_parents`] (every speed the parent of
//! the next) describes a dense matrix, so that every symmetric positive definite matrix can be
//! factored here.
//!
//! # Storage and loops
//!
//! The factor is kept in an `N × N` array (no heap, fixed size): `L(k, i)` in column `k`, row
//! `i` (so that column `k` holds row `k` of `L`), `1 / D(k)` on the diagonal; entries outside the
//! pattern are never read. The ancestors of a speed are visited as *runs* of consecutive indices
//! (a limb's joints numbered one after another, the floating base's six speeds): every update
//! of the factorisation and of the substitutions is a loop over a contiguous slice of a column,
//! which the compiler vectorises, rather than a walk of the parent array one entry at a time.
//!
//! ```
//! use kanegen_runtime::nalgebra::{SMatrix, SVector};
//! use kanegen_runtime::tree_factor::TreeFactor;
//!
//! // Two branches (speeds 1 and 2) on one root speed 0: M(1, 2) = M(2, 1) = 0.
//! let parents = [None, Some(0), Some(0)];
//! let m = SMatrix::<f64, 3, 3>::new(4.0, 1.0, 2.0, 1.0, 3.0, 0.0, 2.0, 0.0, 5.0);
//! let factor = TreeFactor::new(&m, &parents).unwrap();
//! let b = SVector::from([1.0, 2.0, 3.0]);
//! let x = factor.solve(&b);
//! assert!((m * x - b).norm() < 1e-14);
//! // Not positive definite: no factor.
//! assert!(TreeFactor::new(&(-m), &parents).is_none());
//! ```

use nalgebra::{RealField, SMatrix, SVector};

/// The parent array of a chain, `[None, Some(0), Some(1), …]`: every entry of a matrix may be
/// non-zero, and [`TreeFactor::new`] with it is a dense `LᵀDL` factorisation.
pub const fn chain_parents<const N: usize>() -> [Option<usize>; N] {
    let mut p = [None; N];
    let mut i = 1;
    while i < N {
        p[i] = Some(i - 1);
        i += 1;
    }
    p
}

/// Whether `parents` is a parent array: every parent before its child (`λ(i) < i`).
pub const fn is_parent_array<const N: usize>(parents: &[Option<usize>; N]) -> bool {
    let mut i = 0;
    while i < N {
        if let Some(p) = parents[i]
            && p >= i
        {
            return false;
        }
        i += 1;
    }
    true
}

/// Straight-line kernels of the factorisation and the two substitutions for one parent array,
/// generated with a module (its `TREE_KERNELS`, the loops of [`TreeFactor`] unrolled at
/// generation time: no loop or index arithmetic left, which on a quadruped or a humanoid is most
/// of the loops' time). The arrays are [`TreeFactor`]'s storage: column `k` holds `L(k, i)` in
/// row `i` and `1 / D(k)` in row `k`.
#[derive(Clone, Copy, Debug)]
pub struct TreeKernels<T, const N: usize> {
    /// The factorisation in place (the matrix in, the factor out); `false` when a pivot is not
    /// positive.
    pub factorise: fn(&mut [[T; N]; N]) -> bool,
    /// `y ← L⁻ᵀ y` ([`TreeFactor::solve_transposed_unit`]).
    pub solve_transposed_unit: fn(&[[T; N]; N], &mut [T; N]),
    /// `x ← L⁻¹ D⁻¹ x` ([`TreeFactor::finish_solve`]).
    pub finish_solve: fn(&[[T; N]; N], &mut [T; N]),
}

/// `M = Lᵀ D L` for a symmetric positive definite `M` whose pattern fits a parent array (see the
/// [module docs](self)), on the stack: [`new`](Self::new), then [`solve`](Self::solve) or
/// [`solve_columns`](Self::solve_columns) (`M⁻¹ b`), or the two halves
/// ([`solve_transposed_unit`](Self::solve_transposed_unit), then
/// [`finish_solve`](Self::finish_solve)) where `M⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ` is needed as a product
/// (the contact Schur complement, [`crate::contact`]).
#[derive(Clone, Copy, Debug)]
pub struct TreeFactor<T, const N: usize> {
    /// Column `k`: `L(k, i)` in row `i` for the ancestors `i` of `k`, `1 / D(k)` in row `k`.
    cols: [[T; N]; N],
    /// `λ`.
    parents: [Option<usize>; N],
    /// The first speed of the run of consecutive ancestors that ends at `k`: every `j` in
    /// `run_start[k] + 1 ..= k` has parent `j − 1`.
    run_start: [usize; N],
    /// Straight-line kernels for `parents`, if generated.
    kernels: Option<TreeKernels<T, N>>,
}

impl<T: RealField + Copy, const N: usize> TreeFactor<T, N> {
    /// Factorise `m` with the parent array `parents`: only the entries `m(i, k)` with `i` an
    /// ancestor of `k` or `k` itself are read (either triangle: `m` is symmetric), the others
    /// are taken as zero. `None` when a pivot `D(k)` is not positive (`m` is not positive
    /// definite, or has a NaN entry) or `parents` is not a parent array (`λ(i) ≥ i`).
    #[inline]
    pub fn new(m: &SMatrix<T, N, N>, parents: &[Option<usize>; N]) -> Option<Self> {
        Self::build(m, parents, None)
    }

    /// [`new`](Self::new) through the straight-line `kernels` generated for `parents` (a
    /// generated module's `TREE_KERNELS` with its `SPEED_PARENTS`), which then also run the
    /// substitutions. Kernels generated for another parent array give a wrong factor.
    #[inline(always)]
    pub fn with_kernels(
        m: &SMatrix<T, N, N>,
        parents: &[Option<usize>; N],
        kernels: TreeKernels<T, N>,
    ) -> Option<Self> {
        Self::build(m, parents, Some(kernels))
    }

    #[inline(always)]
    fn build(
        m: &SMatrix<T, N, N>,
        parents: &[Option<usize>; N],
        kernels: Option<TreeKernels<T, N>>,
    ) -> Option<Self> {
        if !is_parent_array(parents) {
            return None;
        }
        let mut run_start = [0; N];
        for i in 0..N {
            run_start[i] = match parents[i] {
                Some(p) if p + 1 == i => run_start[p],
                _ => i,
            };
        }
        let mut factor = Self {
            cols: m.data.0,
            parents: *parents,
            run_start,
            kernels,
        };
        if let Some(k) = kernels {
            return if (k.factorise)(&mut factor.cols) {
                Some(factor)
            } else {
                None
            };
        }
        let ok = crate::isa::dispatch_fused_with(
            &mut factor,
            #[inline(always)]
            |f| f.factorise::<false>(),
            #[inline(always)]
            |f| f.factorise::<true>(),
        );
        ok.then_some(factor)
    }

    /// `λ`, as given to [`new`](Self::new).
    pub fn parents(&self) -> &[Option<usize>; N] {
        &self.parents
    }

    /// `D(k)`, the pivots (positive).
    pub fn pivots(&self) -> SVector<T, N> {
        SVector::from_fn(|k, _| T::one() / self.cols[k][k])
    }

    /// Calls `f` with the runs of the ancestors of `i` (`i` itself included when `inclusive`),
    /// nearest first: half-open ranges of consecutive indices, in decreasing order.
    #[inline(always)]
    fn for_each_run(&self, i: usize, inclusive: bool, mut f: impl FnMut(usize, usize)) {
        let s = self.run_start[i];
        let end = if inclusive { i + 1 } else { i };
        if s < end {
            f(s, end);
        }
        let mut top = self.parents[s];
        while let Some(t) = top {
            let s = self.run_start[t];
            f(s, t + 1);
            top = self.parents[s];
        }
    }

    /// Featherstone's LTDL in place: for `k = N − 1, …, 0` and each ancestor `i` of `k`,
    /// nearest first, `a = M(k, i) / M(k, k)`, `M(i, j) −= a M(k, j)` for `j` = `i` and its
    /// ancestors, `M(k, i) ← a`. `false` on a pivot that is not positive.
    #[inline(always)]
    fn factorise<const FUSED: bool>(&mut self) -> bool {
        for k in (0..N).rev() {
            let d = self.cols[k][k];
            // Not positive, or NaN.
            if d.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
                return false;
            }
            let inv = T::one() / d;
            self.cols[k][k] = inv;
            let (before, after) = self.cols.split_at_mut(k);
            let ck = &mut after[0];
            let (parents, run_start) = (&self.parents, &self.run_start);
            // The ancestors of k, run by run, each run from its last index down.
            let mut top = parents[k];
            while let Some(t) = top {
                let s = run_start[t];
                for i in (s..=t).rev() {
                    let a = ck[i] * inv;
                    let ci = &mut before[i];
                    // j = i and its ancestors in the same run, then the runs above.
                    axpy::<T, FUSED>(&mut ci[s..=i], a, &ck[s..=i]);
                    let mut up = parents[s];
                    while let Some(u) = up {
                        let s2 = run_start[u];
                        axpy::<T, FUSED>(&mut ci[s2..=u], a, &ck[s2..=u]);
                        up = parents[s2];
                    }
                    ck[i] = a;
                }
                top = parents[s];
            }
        }
        true
    }

    /// `y ← L⁻ᵀ y` (`Lᵀ` unit upper triangular): for `i = N − 1, …, 0`, `y(j) −= L(i, j) y(i)`
    /// for the ancestors `j` of `i`. The first half of a solve, `M⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ`; a `y`
    /// that is zero outside the ancestors of some speed stays so (a contact Jacobian's row).
    #[inline]
    pub fn solve_transposed_unit(&self, y: &mut SVector<T, N>) {
        self.solve_transposed_unit_array(&mut y.data.0[0]);
    }

    /// [`solve_transposed_unit`](Self::solve_transposed_unit) of an array (a column of a
    /// matrix's storage).
    #[inline]
    pub(crate) fn solve_transposed_unit_array(&self, y: &mut [T; N]) {
        if let Some(k) = &self.kernels {
            return (k.solve_transposed_unit)(&self.cols, y);
        }
        crate::isa::dispatch_fused_with(
            y,
            #[inline(always)]
            |y| self.backward::<false>(y),
            #[inline(always)]
            |y| self.backward::<true>(y),
        );
    }

    /// `x ← L⁻¹ D⁻¹ x`: the second half of a solve, after
    /// [`solve_transposed_unit`](Self::solve_transposed_unit).
    #[inline]
    pub fn finish_solve(&self, x: &mut SVector<T, N>) {
        if let Some(k) = &self.kernels {
            return (k.finish_solve)(&self.cols, &mut x.data.0[0]);
        }
        crate::isa::dispatch_fused_with(
            x,
            #[inline(always)]
            |x| self.forward::<false>(x.as_mut_slice()),
            #[inline(always)]
            |x| self.forward::<true>(x.as_mut_slice()),
        );
    }

    /// `M⁻¹ b`.
    #[inline]
    pub fn solve(&self, b: &SVector<T, N>) -> SVector<T, N> {
        let mut x = *b;
        if let Some(k) = &self.kernels {
            (k.solve_transposed_unit)(&self.cols, &mut x.data.0[0]);
            (k.finish_solve)(&self.cols, &mut x.data.0[0]);
            return x;
        }
        crate::isa::dispatch_fused_with(
            &mut x,
            #[inline(always)]
            |x| {
                self.backward::<false>(x.as_mut_slice());
                self.forward::<false>(x.as_mut_slice());
            },
            #[inline(always)]
            |x| {
                self.backward::<true>(x.as_mut_slice());
                self.forward::<true>(x.as_mut_slice());
            },
        );
        x
    }

    /// `X ← M⁻¹ X`, column by column.
    #[inline]
    pub fn solve_columns<const C: usize>(&self, x: &mut SMatrix<T, N, C>) {
        if let Some(k) = &self.kernels {
            for c in x.data.0.iter_mut() {
                (k.solve_transposed_unit)(&self.cols, c);
                (k.finish_solve)(&self.cols, c);
            }
            return;
        }
        crate::isa::dispatch_fused_with(
            x,
            #[inline(always)]
            |x| {
                for c in x.data.0.iter_mut() {
                    self.backward::<false>(c);
                    self.forward::<false>(c);
                }
            },
            #[inline(always)]
            |x| {
                for c in x.data.0.iter_mut() {
                    self.backward::<true>(c);
                    self.forward::<true>(c);
                }
            },
        );
    }

    /// `y ← L⁻ᵀ y`, skipping the rows that are zero.
    #[inline(always)]
    fn backward<const FUSED: bool>(&self, y: &mut [T]) {
        for i in (0..N).rev() {
            let yi = y[i];
            if yi == T::zero() {
                continue;
            }
            let ci = &self.cols[i];
            self.for_each_run(i, false, |s, e| {
                axpy::<T, FUSED>(&mut y[s..e], yi, &ci[s..e])
            });
        }
    }

    /// `x ← L⁻¹ D⁻¹ x`: `x(i) = x(i) / D(i) − Σ_j L(i, j) x(j)` over the ancestors `j` of `i`,
    /// `i = 0, 1, …`.
    #[inline(always)]
    fn forward<const FUSED: bool>(&self, x: &mut [T]) {
        for i in 0..N {
            let ci = &self.cols[i];
            let mut acc = x[i] * ci[i];
            self.for_each_run(i, false, |s, e| {
                acc = dot_sub::<T, FUSED>(acc, &ci[s..e], &x[s..e]);
            });
            x[i] = acc;
        }
    }
}

/// `y −= a x`, entry by entry (one fused multiply-add each with `FUSED`).
#[inline(always)]
fn axpy<T: RealField + Copy, const FUSED: bool>(y: &mut [T], a: T, x: &[T]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y = if FUSED {
            (-a).mul_add(*x, *y)
        } else {
            *y - a * *x
        };
    }
}

/// `acc − Σ l_j x_j`, in order.
#[inline(always)]
fn dot_sub<T: RealField + Copy, const FUSED: bool>(mut acc: T, l: &[T], x: &[T]) -> T {
    for (l, x) in l.iter().zip(x) {
        acc = if FUSED {
            (-*l).mul_add(*x, acc)
        } else {
            acc - *l * *x
        };
    }
    acc
}

#[cfg(test)]
pub(crate) mod tests {
    use super::{TreeFactor, chain_parents, is_parent_array};
    use nalgebra::{SMatrix, SVector};
    use std::vec::Vec;

    /// A deterministic uniform source in [−1, 1) (the contact tests' too).
    pub(crate) fn source(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            2.0 * ((z >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        }
    }

    fn ancestors<const N: usize>(parents: &[Option<usize>; N], mut i: usize) -> Vec<usize> {
        let mut out = Vec::new();
        while let Some(p) = parents[i] {
            out.push(p);
            i = p;
        }
        out
    }

    /// A random symmetric positive definite matrix with the pattern of `parents`: a sum of
    /// `JᵀBJ` over "bodies", each `J` non-zero only on a speed and its ancestors (as a body's
    /// Jacobian), plus a positive diagonal.
    fn tree_spd<const N: usize>(parents: &[Option<usize>; N], seed: u64) -> SMatrix<f64, N, N> {
        let mut r = source(seed);
        let mut m = SMatrix::<f64, N, N>::identity() * 0.1;
        for k in 0..N {
            let mut support = ancestors(parents, k);
            support.push(k);
            for _ in 0..3 {
                let mut v = SVector::<f64, N>::zeros();
                for &j in &support {
                    v[j] = r();
                }
                m += v * v.transpose();
            }
        }
        m
    }

    /// Solo 12 on a floating base: the base chain, four legs of three.
    fn quadruped() -> [Option<usize>; 18] {
        let mut p = chain_parents::<18>();
        for leg in 0..4 {
            p[6 + 3 * leg] = Some(5);
        }
        p
    }

    /// A fixed-base tree whose branches are not numbered run by run: 0, 1 ← 0, 2 ← 0, 3 ← 1,
    /// 4 ← 2, 5 ← 3, 6 (a second root), 7 ← 6, 8 ← 5.
    fn interleaved() -> [Option<usize>; 9] {
        [
            None,
            Some(0),
            Some(0),
            Some(1),
            Some(2),
            Some(3),
            None,
            Some(6),
            Some(5),
        ]
    }

    fn agrees_with_dense<const N: usize>(parents: [Option<usize>; N]) {
        for seed in 0..10 {
            let m = tree_spd(&parents, seed);
            for i in 0..N {
                for j in 0..N {
                    let related = i == j
                        || ancestors(&parents, i).contains(&j)
                        || ancestors(&parents, j).contains(&i);
                    assert!(related || m[(i, j)] == 0.0);
                }
            }
            let factor = TreeFactor::new(&m, &parents).unwrap();
            let mut r = source(100 + seed);
            let b = SVector::<f64, N>::from_fn(|_, _| r());
            let expected = m.cholesky().unwrap().solve(&b);
            let x = factor.solve(&b);
            assert!(
                (x - expected).norm() <= 1e-12 * expected.norm(),
                "{x} {expected}"
            );
            let mut cols = SMatrix::<f64, N, 5>::from_fn(|_, _| r());
            let expected = m.cholesky().unwrap().solve(&cols);
            factor.solve_columns(&mut cols);
            assert!((cols - expected).norm() <= 1e-12 * expected.norm());
            // The halves: M⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ, and bᵀ M⁻¹ b = |L⁻ᵀ b|²_{D⁻¹}.
            let mut y = b;
            factor.solve_transposed_unit(&mut y);
            let quadratic: f64 = (0..N).map(|i| y[i] * y[i] / factor.pivots()[i]).sum();
            assert!((quadratic - b.dot(&m.cholesky().unwrap().solve(&b))).abs() < 1e-12);
            factor.finish_solve(&mut y);
            assert!((y - factor.solve(&b)).norm() <= 1e-14 * y.norm());
            // The dense factorisation of the same matrix (a chain) agrees too.
            let dense = TreeFactor::new(&m, &chain_parents()).unwrap();
            assert!((dense.solve(&b) - factor.solve(&b)).norm() <= 1e-12 * x.norm());
        }
    }

    #[test]
    fn tree_factor_solves_like_a_dense_cholesky_on_tree_patterns() {
        agrees_with_dense(quadruped());
        agrees_with_dense(interleaved());
        agrees_with_dense(chain_parents::<7>());
        agrees_with_dense([None; 4]);
        agrees_with_dense::<1>([None]);
    }

    #[test]
    fn entries_outside_the_pattern_are_not_read() {
        let parents = quadruped();
        let m = tree_spd(&parents, 3);
        let mut polluted = m;
        // Two legs' coupling (structurally zero) filled with garbage.
        polluted[(7, 10)] = 5.0;
        polluted[(10, 7)] = f64::NAN;
        let b = SVector::<f64, 18>::from_fn(|i, _| i as f64);
        let a = TreeFactor::new(&m, &parents).unwrap().solve(&b);
        let p = TreeFactor::new(&polluted, &parents).unwrap().solve(&b);
        assert_eq!(a, p);
    }

    #[test]
    fn non_positive_pivots_and_bad_parent_arrays_give_no_factor() {
        let parents = quadruped();
        let m = tree_spd(&parents, 1);
        assert!(TreeFactor::new(&(-m), &parents).is_none());
        let mut nan = m;
        nan[(17, 17)] = f64::NAN;
        assert!(TreeFactor::new(&nan, &parents).is_none());
        // Singular: a zero row and column.
        let mut singular = m;
        for i in 0..18 {
            singular[(4, i)] = 0.0;
            singular[(i, 4)] = 0.0;
        }
        assert!(TreeFactor::new(&singular, &parents).is_none());
        let mut bad = parents;
        bad[3] = Some(3);
        assert!(!is_parent_array(&bad));
        assert!(TreeFactor::new(&m, &bad).is_none());
        bad[3] = Some(9);
        assert!(TreeFactor::new(&m, &bad).is_none());
    }
}
