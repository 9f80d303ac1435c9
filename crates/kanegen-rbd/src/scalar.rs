//! The scalar trait and small fixed-size vector helpers used by the hot paths.

use nalgebra::RealField;

/// A real scalar the recursions can run in: any nalgebra [`RealField`] that is `Copy`, plus the
/// joint-angle `sin`/`cos` (implemented for `f64`, with a fast batched version, and `f32`).
pub trait Scalar: RealField + Copy {
    /// `(sin x, cos x)`.
    fn sin_cos_joint(self) -> (Self, Self);

    /// `s[k] = sin x[k]`, `c[k] = cos x[k]` for every `k`.
    #[inline(always)]
    fn sin_cos_batch<const N: usize>(x: &[Self; N], s: &mut [Self; N], c: &mut [Self; N]) {
        for k in 0..N {
            (s[k], c[k]) = x[k].sin_cos_joint();
        }
    }
}

impl Scalar for f64 {
    /// [`kanegen_runtime::trig::sin_cos`] (the routine of generated code).
    #[inline(always)]
    fn sin_cos_joint(self) -> (Self, Self) {
        kanegen_runtime::trig::sin_cos(self)
    }

    /// [`kanegen_runtime::trig::sin_cos_n`], the batch of generated code: a branch-free
    /// polynomial kernel the compiler vectorizes across the batch (SSE2: two angles per
    /// instruction; the x86-64-v3 copy fuses its multiply-adds, within 2 ulp of
    /// [`Self::sin_cos_joint`]), with a cold lane-by-lane path for a batch holding
    /// `|x| ≥ 2¹⁹·π/2` or a non-finite angle.
    #[inline(always)]
    fn sin_cos_batch<const N: usize>(x: &[Self; N], s: &mut [Self; N], c: &mut [Self; N]) {
        (*s, *c) = kanegen_runtime::trig::sin_cos_n(*x);
    }
}

impl Scalar for f32 {
    #[inline(always)]
    fn sin_cos_joint(self) -> (Self, Self) {
        self.sin_cos()
    }
}

/// `(sin x, cos x)` for `f64`: [`kanegen_runtime::trig::sin_cos`], the routine generated code
/// uses (one shared Cody–Waite reduction by π/2 and the fdlibm minimax kernels on
/// `[−π/4, π/4]`; Payne–Hanek reduction for `|x| ≥ 2¹⁹·π/2`), within about one ulp of the
/// correctly rounded result for joint angles. NaN for NaN and ±∞.
#[inline]
pub fn sin_cos_f64(x: f64) -> (f64, f64) {
    kanegen_runtime::trig::sin_cos(x)
}

/// A 3-vector.
pub(crate) type V3<T> = [T; 3];
/// A 3×3 matrix stored by columns: `m[c]` is column `c`.
pub(crate) type M3<T> = [[T; 3]; 3];
/// A symmetric 3×3 matrix `[xx, xy, xz, yy, yz, zz]`.
pub(crate) type S3<T> = [T; 6];

#[inline(always)]
pub(crate) fn add<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(crate) fn scale<T: Scalar>(a: V3<T>, k: T) -> V3<T> {
    [a[0] * k, a[1] * k, a[2] * k]
}

#[inline(always)]
pub(crate) fn dot<T: Scalar>(a: V3<T>, b: V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
pub(crate) fn cross<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `R x` (child frame → parent frame).
#[inline(always)]
pub(crate) fn rot<T: Scalar>(r: &M3<T>, x: V3<T>) -> V3<T> {
    [
        r[0][0] * x[0] + r[1][0] * x[1] + r[2][0] * x[2],
        r[0][1] * x[0] + r[1][1] * x[1] + r[2][1] * x[2],
        r[0][2] * x[0] + r[1][2] * x[1] + r[2][2] * x[2],
    ]
}

/// `Rᵀ x` (parent frame → child frame).
#[inline(always)]
pub(crate) fn rot_t<T: Scalar>(r: &M3<T>, x: V3<T>) -> V3<T> {
    [dot(r[0], x), dot(r[1], x), dot(r[2], x)]
}

/// `A B` for column-stored matrices.
#[inline(always)]
pub(crate) fn mat_mul<T: Scalar>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    [rot(a, b[0]), rot(a, b[1]), rot(a, b[2])]
}

/// `J x` for a symmetric `J`.
#[inline(always)]
pub(crate) fn sym_mul<T: Scalar>(j: &S3<T>, x: V3<T>) -> V3<T> {
    [
        j[0] * x[0] + j[1] * x[1] + j[2] * x[2],
        j[1] * x[0] + j[3] * x[1] + j[4] * x[2],
        j[2] * x[0] + j[4] * x[1] + j[5] * x[2],
    ]
}

/// `Rot_z(θ) J Rot_z(θ)ᵀ` given `c = cos θ`, `s = sin θ`.
#[inline(always)]
pub(crate) fn sym_rot_z<T: Scalar>(j: &S3<T>, c: T, s: T) -> S3<T> {
    let cc = c * c;
    let ss = s * s;
    let cs = c * s;
    let cs_xy = (cs + cs) * j[1];
    let cs_d = cs * (j[0] - j[3]);
    [
        cc * j[0] + ss * j[3] - cs_xy,
        cs_d + (cc - ss) * j[1],
        c * j[2] - s * j[4],
        ss * j[0] + cc * j[3] + cs_xy,
        s * j[2] + c * j[4],
        j[5],
    ]
}

/// `R J Rᵀ` for a general (column-stored) `R`.
#[inline(always)]
pub(crate) fn sym_rot<T: Scalar>(r: &M3<T>, j: &S3<T>) -> S3<T> {
    // B = R J (columns: R·J[:, c]); out[a][b] = Σ_c B[a][c] R[b][c].
    let b0 = rot(r, [j[0], j[1], j[2]]);
    let b1 = rot(r, [j[1], j[3], j[4]]);
    let b2 = rot(r, [j[2], j[4], j[5]]);
    let e = |a: usize, b: usize| b0[a] * r[0][b] + b1[a] * r[1][b] + b2[a] * r[2][b];
    [e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2)]
}

/// The inertia about the origin `o_i` of a body whose first moment (about `o_j`, expressed in
/// frame `i`) is `h` and whose mass is `m`, minus its inertia about `o_j` (also in frame `i`),
/// where `p = o_j − o_i`: `m(|p|²1 − p pᵀ) + 2(p·h)1 − p hᵀ − h pᵀ`, written with
/// `k = h + (m/2) p` as `2(p·k)1 − (p kᵀ + k pᵀ)`; `half_mp = (m/2) p`.
#[inline(always)]
pub(crate) fn inertia_shift<T: Scalar>(p: V3<T>, h: V3<T>, half_mp: V3<T>) -> S3<T> {
    let k = add(h, half_mp);
    let px = p[0] * k[0];
    let py = p[1] * k[1];
    let pz = p[2] * k[2];
    [
        (py + pz) + (py + pz),
        -(p[0] * k[1] + p[1] * k[0]),
        -(p[0] * k[2] + p[2] * k[0]),
        (px + pz) + (px + pz),
        -(p[1] * k[2] + p[2] * k[1]),
        (px + py) + (px + py),
    ]
}

#[inline(always)]
pub(crate) fn add6<T: Scalar>(a: S3<T>, b: S3<T>) -> S3<T> {
    [
        a[0] + b[0],
        a[1] + b[1],
        a[2] + b[2],
        a[3] + b[3],
        a[4] + b[4],
        a[5] + b[5],
    ]
}
