//! nalgebra results (column-major) into row-major (C-order) slices, as NumPy lays them out.

use nalgebra::{Isometry3, SMatrix};

/// Writes `m` into `out` row by row (`out.len()` must be `R * C`).
#[inline]
pub fn matrix<const R: usize, const C: usize>(out: &mut [f64], m: &SMatrix<f64, R, C>) {
    if C == 1 {
        out.copy_from_slice(m.as_slice());
        return;
    }
    for (r, row) in out.chunks_exact_mut(C).enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = m[(r, c)];
        }
    }
}

/// Writes `m`, a symmetric matrix, into `out` (its column-major storage is its row-major one).
#[inline]
pub fn symmetric<const N: usize>(out: &mut [f64], m: &SMatrix<f64, N, N>) {
    out.copy_from_slice(m.as_slice());
}

/// Writes the 4 × 4 homogeneous matrix `[R p; 0 0 0 1]` of `pose` into `out` (16 values).
#[inline]
pub fn isometry(out: &mut [f64], pose: &Isometry3<f64>) {
    matrix(out, &pose.to_homogeneous());
}
