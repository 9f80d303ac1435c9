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
    #[inline(always)]
    fn sin_cos_joint(self) -> (Self, Self) {
        self.sin_cos()
    }

    /// A branch-free polynomial kernel the compiler vectorizes across the batch (SSE2: two
    /// angles per instruction), then the standard library for the rare `|x| ≥ 2¹⁹`.
    #[inline(always)]
    fn sin_cos_batch<const N: usize>(x: &[Self; N], s: &mut [Self; N], c: &mut [Self; N]) {
        for k in 0..N {
            (s[k], c[k]) = sin_cos_kernel(x[k]);
        }
        for k in 0..N {
            if x[k].abs() >= SIN_COS_KERNEL_BOUND || x[k].is_nan() {
                (s[k], c[k]) = x[k].sin_cos();
            }
        }
    }
}

impl Scalar for f32 {
    #[inline(always)]
    fn sin_cos_joint(self) -> (Self, Self) {
        self.sin_cos()
    }
}

/// Arguments below this magnitude are handled by [`sin_cos_f64`]'s polynomial kernel.
const SIN_COS_KERNEL_BOUND: f64 = 524_288.0;

/// `(sin x, cos x)` for `f64`: one shared Cody–Waite reduction by π/2 and the fdlibm
/// (Sun Microsystems) minimax kernels on `[−π/4, π/4]`, within about one ulp of the correctly
/// rounded result. Arguments with `|x| ≥ 2¹⁹` (or not finite) go to the standard library.
#[inline]
pub fn sin_cos_f64(x: f64) -> (f64, f64) {
    if x.abs() < SIN_COS_KERNEL_BOUND {
        sin_cos_kernel(x)
    } else {
        x.sin_cos()
    }
}

/// The branch-free kernel of [`sin_cos_f64`], valid for `|x| < 2¹⁹`.
#[inline(always)]
fn sin_cos_kernel(x: f64) -> (f64, f64) {
    // The fdlibm constants (shortest round-trip decimal forms).
    // π/2 split as P1 (33 significant bits, so n·P1 is exact for |n| < 2²⁰) + P1T.
    const P1: f64 = 1.570_796_326_734_125_6;
    const P1T: f64 = 6.077_100_506_506_192e-11;
    const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
    // 1.5·2⁵²: adding it rounds to an integer n held in the low mantissa bits.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    const S1: f64 = -0.166_666_666_666_666_32;
    const S2: f64 = 0.008_333_333_333_322_49;
    const S3: f64 = -0.000_198_412_698_298_579_5;
    const S4: f64 = 2.755_731_370_707_006_8e-6;
    const S5: f64 = -2.505_076_025_340_686_3e-8;
    const S6: f64 = 1.589_690_995_211_55e-10;
    const C1: f64 = 0.041_666_666_666_666_6;
    const C2: f64 = -0.001_388_888_888_887_411;
    const C3: f64 = 2.480_158_728_947_673e-5;
    const C4: f64 = -2.755_731_435_139_066_3e-7;
    const C5: f64 = 2.087_572_321_298_175e-9;
    const C6: f64 = -1.135_964_755_778_819_5e-11;
    let t = x * TWO_OVER_PI + ROUND;
    // n mod 4 in the low bits of t (two's complement, so negative n work too).
    let k = t.to_bits();
    let n = t - ROUND;
    let r = (x - n * P1) - n * P1T;
    let z = r * r;
    let sin_r = r + (z * r) * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cos_r = w
        + (((1.0 - w) - hz) + (z * z) * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6))))));
    // Quadrant n mod 4: 0 → (s, c), 1 → (c, −s), 2 → (−s, −c), 3 → (−c, s).
    let swap = 0u64.wrapping_sub(k & 1);
    let (sb, cb) = (sin_r.to_bits(), cos_r.to_bits());
    let sin_bits = (sb & !swap) | (cb & swap);
    let cos_bits = (cb & !swap) | (sb & swap);
    let sin_sign = (k & 2) << 62;
    let cos_sign = (k.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(sin_bits ^ sin_sign),
        f64::from_bits(cos_bits ^ cos_sign),
    )
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
