//! The sines and cosines of the joint angles, as the generated functions compute them.
//!
//! Every generated function calls [`sin_cos_n`] once, on all the joint angles it needs
//! (`f32` modules call [`sin_cos_n_f32`], which computes in `f32`); [`sin_cos`] is the scalar
//! routine the batch falls back to for a batch with a huge or non-finite lane. All of them need
//! only `core` (no `std`, no `libm`). [`sin_cos`] and the baseline copies of the batched
//! routines give, for a given argument, the same bits on every platform with IEEE-754
//! arithmetic (no fused multiply-add is introduced by the compiler); the x86-64-v3 copies of
//! [`sin_cos_n`] and [`sin_cos_slice`] fuse the kernels' Horner steps (one rounding each, a
//! step's latency 4 cycles instead of 6) and reduce the argument by three fused
//! multiply-adds, like the generated functions' own x86-64-v3 copies, and agree with
//! [`sin_cos`] to within 2 ulp (and with `std` to within 1 ulp, `tests/trig.rs`).
//!
//! Accuracy: `f64`, within about one ulp of the standard library for the angles robots use; a
//! few ulp for huge arguments (`|x| ≥ 2¹⁹·π/2`); NaN for NaN and ±∞. `f32`: absolute error
//! below 8·10⁻⁸, within one ulp of the correctly rounded result (measured by `tests/trig.rs`).

/// Arguments below this magnitude (≈ 2¹⁹·π/2, so that `n·PIO2_1` is exact) take the
/// Cody–Waite reduction; larger ones (never a robot angle) and non-finite ones take
/// `reduce_large`.
pub const SIN_COS_FAST_BOUND: f64 = 823_549.0;

use crate::isa::{Arith, Fused, Plain};

/// `(sin x, cos x)` for the generated code: Cody–Waite reduction by π/2 (fdlibm's constants)
/// and fdlibm's minimax kernels on [−π/4, π/4]; |x| ≥ 2¹⁹·π/2 (never a robot angle) takes a
/// cold Payne–Hanek reduction against 1280 bits of 2/π. Needs only `core` (no `std`, no
/// `libm`). Error within about one ulp of the standard library for the angles robots use (a
/// few ulp for huge arguments); several times faster because both values share one reduction
/// and the code inlines. [`sin_cos_n`] is the batched form the generated functions call.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    sin_cos_with::<Plain>(x)
}

/// [`sin_cos`] with the kernel's multiply-adds done by `A` (the fallback of the batches:
/// [`Fused`] in their x86-64-v3 copy, so a batch with a huge lane gives its other lanes the
/// bits they get without it).
#[inline(always)]
fn sin_cos_with<A: Arith<f64>>(x: f64) -> (f64, f64) {
    let (r, quadrant) = if x.abs() < SIN_COS_FAST_BOUND {
        sin_cos_reduce_with::<A>(x)
    } else {
        reduce_large(x)
    };
    sin_cos_kernel::<A>(r, quadrant)
}

/// `(sin x[k], cos x[k])` for every lane: in the baseline copy bit for bit the values of
/// [`sin_cos`], in the x86-64-v3 copy the same formulas with fused multiply-adds (every lane
/// the bits of a one-lane batch, whatever the other lanes hold). Every lane
/// runs through one branch-free loop that the compiler vectorizes (two lanes per SSE2
/// instruction, four with AVX2) and that also sets one flag for the whole batch: if a lane is
/// at or above the Cody–Waite bound or not finite (never, for robot angles), the batch is
/// recomputed lane by lane by the scalar routine. Not inlined: the generated functions are
/// long enough that their speed depends on their code size (one shared copy instead of one per
/// function).
///
/// Compiled for the baseline and for x86-64-v3 (four lanes per AVX2 instruction, the kernels'
/// Horner steps fused: Krang's 17 angles 1,112 → 1,061 instructions per `gravity` call, about
/// 15 ns less per call of M, c, g or τ) and run with the instruction set of
/// [`crate::isa::dispatch_fused`].
#[inline(never)]
pub fn sin_cos_n<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    crate::isa::dispatch_fused(
        #[inline(always)]
        || sin_cos_n_lanes::<Plain, N>(x),
        #[inline(always)]
        || sin_cos_n_lanes::<Fused, N>(x),
    )
}

/// The lane loop of [`sin_cos_n`], inlined into each instruction set's copy.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // lane loops over parallel arrays: what LLVM vectorizes
fn sin_cos_n_lanes<A: Arith<f64>, const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    // The check sits inside the loop and the fallback takes and returns arrays by value: a
    // separate check loop gets 512-bit compares under AVX-512 (which slowed the batch by a
    // third there), and passing the arrays by reference keeps them from being built in place.
    let (mut s, mut c) = ([0.0; N], [0.0; N]);
    let mut fast = true;
    for k in 0..N {
        let (r, quadrant) = sin_cos_reduce_with::<A>(x[k]);
        (s[k], c[k]) = sin_cos_kernel::<A>(r, quadrant);
        // False for NaN too. Huge and non-finite lanes give garbage above, never a panic.
        fast &= x[k].abs() < SIN_COS_FAST_BOUND;
    }
    if !fast {
        (s, c) = sin_cos_n_slow::<A, N>(x);
    }
    (s, c)
}

/// [`sin_cos_n`] lane by lane through [`sin_cos`] (a batch with a huge or non-finite lane).
#[cold]
#[inline(never)]
#[allow(clippy::needless_range_loop)]
fn sin_cos_n_slow<A: Arith<f64>, const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut out = ([0.0; N], [0.0; N]);
    for k in 0..N {
        (out.0[k], out.1[k]) = sin_cos_with::<A>(x[k]);
    }
    out
}

/// [`sin_cos_n`] over a slice: `(s[k], c[k]) = (sin x[k], cos x[k])` for every `k`, bit for
/// bit the values of [`sin_cos_n`] with the same instruction set, in one branch-free loop the
/// compiler vectorizes, with the same flag and cold per-value fallback for a huge or
/// non-finite value. The batched functions run this loop inline
/// ([`crate::lanes::sin_cos_n_inline`]) for all joint angles of all their states at once (one
/// call per angle instead took 39 % of Krang's batched c at 4 states). Compiled for the
/// baseline and for x86-64-v3 like [`sin_cos_n`], and for x86-64-v4 (8 lanes per AVX-512
/// instruction, the same fused kernels: the x86-64-v3 copy's bits) like the batched functions.
/// Slices of different lengths: the first `min` of the three lengths are computed, the rest of
/// `s` and `c` is left as it is.
#[inline(never)]
pub fn sin_cos_slice(x: &[f64], s: &mut [f64], c: &mut [f64]) {
    crate::isa::dispatch_fused_wide_with(
        (s, c),
        #[inline(always)]
        |(s, c)| sin_cos_slice_lanes::<Plain>(x, s, c),
        #[inline(always)]
        |(s, c)| sin_cos_slice_lanes::<Fused>(x, s, c),
    )
}

/// The loop of [`sin_cos_slice`], inlined into each instruction set's copy.
#[inline(always)]
pub(crate) fn sin_cos_slice_lanes<A: Arith<f64>>(x: &[f64], s: &mut [f64], c: &mut [f64]) {
    let mut fast = true;
    for ((x, s), c) in x.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
        let (r, quadrant) = sin_cos_reduce_with::<A>(*x);
        (*s, *c) = sin_cos_kernel::<A>(r, quadrant);
        // False for NaN too. Huge and non-finite values give garbage here, then the
        // fallback below.
        fast &= x.abs() < SIN_COS_FAST_BOUND;
    }
    if !fast {
        sin_cos_slice_slow::<A>(x, s, c);
    }
}

/// [`sin_cos_slice`] value by value through [`sin_cos`] (a batch with a huge or non-finite
/// value).
#[cold]
#[inline(never)]
fn sin_cos_slice_slow<A: Arith<f64>>(x: &[f64], s: &mut [f64], c: &mut [f64]) {
    for ((x, s), c) in x.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
        (*s, *c) = sin_cos_with::<A>(*x);
    }
}

/// `f32` arguments below this magnitude take the single-precision Cody–Waite reduction of
/// [`sin_cos_n_f32`] (π/2 in three parts of 8, 11 and 24 bits, exact products for
/// `|n| < 2¹³`); larger ones (never a robot angle) and non-finite ones are computed in `f64`.
pub const SIN_COS_F32_FAST_BOUND: f32 = 8192.0;

/// `(sin x[k], cos x[k])` in `f32` for every lane, computed in `f32` throughout: a
/// three-part Cody–Waite reduction by π/2 and Cephes' single-precision minimax kernels on
/// [−π/4, π/4], branch-free as [`sin_cos_n`], with a cold per-lane `f64` fallback for a batch
/// with a lane at or above [`SIN_COS_F32_FAST_BOUND`] or not finite. What the generated
/// functions of `f32` modules call, so that they need no double-precision arithmetic (a
/// single-precision FPU, such as a Cortex-M4F's).
///
/// Accuracy, measured against the `f64` [`sin_cos`] by `tests/trig.rs` (every 10⁻⁴ rad of
/// |x| ≤ 100, the neighbours of multiples of π/4, and |x| < 8192): absolute error below
/// 8·10⁻⁸, within 1 ulp of the correctly rounded `f32` result wherever that is at least 10⁻³
/// in magnitude (near a zero of sin or cos the absolute error is about 10⁻¹², a few ulp of
/// the tiny result).
#[inline(never)]
#[allow(clippy::needless_range_loop)]
pub fn sin_cos_n_f32<const N: usize>(x: [f32; N]) -> ([f32; N], [f32; N]) {
    let (mut s, mut c) = ([0.0; N], [0.0; N]);
    let mut fast = true;
    for k in 0..N {
        let (r, quadrant) = sin_cos_reduce_f32(x[k]);
        (s[k], c[k]) = sin_cos_kernel_f32(r, quadrant);
        fast &= x[k].abs() < SIN_COS_F32_FAST_BOUND;
    }
    if !fast {
        (s, c) = sin_cos_n_f32_slow(x);
    }
    (s, c)
}

/// [`sin_cos_n_f32`] lane by lane in `f64` through [`sin_cos`] (a batch with a huge or
/// non-finite lane).
#[cold]
#[inline(never)]
#[allow(clippy::needless_range_loop)]
fn sin_cos_n_f32_slow<const N: usize>(x: [f32; N]) -> ([f32; N], [f32; N]) {
    let mut out = ([0.0; N], [0.0; N]);
    for k in 0..N {
        let (s, c) = sin_cos(f64::from(x[k]));
        (out.0[k], out.1[k]) = (s as f32, c as f32);
    }
    out
}

/// `(r, n)` with `x = n·π/2 + r`, |r| ≤ π/4 (to within rounding), in `f32`, for |x| <
/// [`SIN_COS_F32_FAST_BOUND`]; only the low two bits of `n` are meaningful.
#[inline(always)]
#[allow(clippy::excessive_precision)]
fn sin_cos_reduce_f32(x: f32) -> (f32, u32) {
    // n = round(x · 2/π) by the 1.5·2²³ trick (exact for |x·2/π| < 2²²).
    let shifted = x * core::f32::consts::FRAC_2_PI + 12_582_912.0;
    let n = shifted - 12_582_912.0;
    // π/2 = 1.5703125 + 4.837512969970703125e-4 + 7.54978995489188216e-8 (Cephes' DP1..DP3
    // times two): the first two products are exact for |n| < 2¹³.
    let r = ((x - n * 1.570_312_5) - n * 4.837_512_969_970_703_125e-4)
        - n * 7.549_789_954_891_882_16e-8;
    (r, shifted.to_bits())
}

/// `(sin x, cos x)` in `f32` from `x = n·π/2 + r`: Cephes' `sinf`/`cosf` kernels on `r`,
/// then the quadrant `n mod 4` applied by bit masks as in the `f64` kernel.
#[inline(always)]
#[allow(clippy::excessive_precision)]
fn sin_cos_kernel_f32(r: f32, quadrant: u32) -> (f32, f32) {
    let z = r * r;
    let s = ((-1.951_529_589_1e-4 * z + 8.332_160_873_6e-3) * z - 1.666_665_461_1e-1) * z * r + r;
    let c = ((2.443_315_711_809_948e-5 * z - 1.388_731_625_493_765e-3) * z
        + 4.166_664_568_298_827e-2)
        * z
        * z
        - 0.5 * z
        + 1.0;
    let swap = 0u32.wrapping_sub(quadrant & 1);
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let t = (sb ^ cb) & swap;
    let (sin_bits, cos_bits) = (sb ^ t, cb ^ t);
    let sin_sign = (quadrant & 2) << 30;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 30;
    (
        f32::from_bits(sin_bits ^ sin_sign),
        f32::from_bits(cos_bits ^ cos_sign),
    )
}

/// `(r, n)` with `x = n·π/2 + r`, |r| ≤ π/4 (to within rounding), for |x| <
/// [`SIN_COS_FAST_BOUND`]; only the low two bits of `n` are meaningful.
///
/// With an `A` whose multiply-add rounds once ([`Fused`] with `std`: the x86-64-v3 and v4
/// copies), three fused multiply-adds against π/2 split into three 53-bit parts (Cody–Waite
/// with FMA: each `x − n·Cᵢ` is exact before its one rounding, so the parts need no spare
/// low bits): 5 operations and 19 cycles of latency instead of 12 and about 30. Measured
/// (Nov 2026, Intel Xeon with AVX-512): `sin_cos_17` 46.2 → 40–42 ns, Krang's `gravity` 82 → 76–78 ns, the
/// 8-state `gravity_batch_soa_into` 286 → 241–246 ns per call; within 1 ulp of `std` on 6.4
/// million arguments up to the bound, including the neighbours of every multiple of π/2
/// (there the result is tiny and the reduction's relative accuracy is what counts).
/// Otherwise ([`Plain`], and [`Fused`] without `std`, whose `mul_add` rounds twice) fdlibm's
/// reduction below, whose results the scalar [`sin_cos`] keeps bit for bit.
#[inline(always)]
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
fn sin_cos_reduce_with<A: Arith<f64>>(x: f64) -> (f64, u64) {
    if A::ROUNDS_ONCE {
        let shifted = A::mul_add(x, core::f64::consts::FRAC_2_PI, 6_755_399_441_055_744.0);
        let n = shifted - 6_755_399_441_055_744.0;
        // π/2 = C1 + C2 + C3 to 159 bits (C1 is `FRAC_PI_2`).
        let r = A::mul_add(-n, core::f64::consts::FRAC_PI_2, x);
        let r = A::mul_add(-n, 6.123_233_995_736_766e-17, r);
        let r = A::mul_add(-n, -1.497_384_904_859_169_8e-33, r);
        (r, shifted.to_bits())
    } else {
        sin_cos_reduce(x)
    }
}

/// fdlibm's Cody–Waite reduction (`__ieee754_rem_pio2`'s medium case), without fused
/// multiply-adds: see [`sin_cos_reduce_with`].
#[inline(always)]
#[allow(clippy::excessive_precision, clippy::unreadable_literal)]
fn sin_cos_reduce(x: f64) -> (f64, u64) {
    // n = round(x · 2/π) by the 1.5·2⁵² trick (exact for |x·2/π| < 2⁵¹); the low bits of
    // `shifted` hold n in two's complement.
    let shifted = x * core::f64::consts::FRAC_2_PI + 6_755_399_441_055_744.0;
    let n = shifted - 6_755_399_441_055_744.0;
    // r = x − n·π/2 in three parts (π/2 = PIO2_1 + PIO2_2 + PIO2_2T, 33 + 33 + 53 bits).
    let r1 = x - n * 1.570_796_326_734_125_614_17;
    let w = n * 6.077_100_506_303_965_976_60e-11;
    let r2 = r1 - w;
    let w2 = n * 2.022_266_248_795_950_631_54e-21 - ((r1 - r2) - w);
    (r2 - w2, shifted.to_bits())
}

/// `(sin x, cos x)` from `x = n·π/2 + r`: fdlibm's `__kernel_sin` / `__kernel_cos` on `r`,
/// then the quadrant `n mod 4` applied by bit masks (no branches).
///
/// The polynomials are Horner chains of [`Arith::mul_add`]: with [`Plain`] exactly the sums
/// written out (`S1 + z·(S2 + …)`, the same bits), with [`Fused`] one fused multiply-add per
/// step (the x86-64-v3 copy of [`sin_cos_n`] and [`sin_cos_slice`]: a step's latency 4 cycles
/// instead of 3 + 3; within about one ulp of the plain kernel, `tests/trig.rs`).
#[inline(always)]
#[allow(clippy::excessive_precision)]
fn sin_cos_kernel<A: Arith<f64>>(r: f64, quadrant: u64) -> (f64, f64) {
    let z = r * r;
    let horner = |coefficients: &[f64; 6]| {
        let mut acc = coefficients[5];
        for &k in coefficients[..5].iter().rev() {
            acc = A::mul_add(z, acc, k);
        }
        acc
    };
    // s = r + r·z·(S1 + z·(S2 + …)); poly_c = z·z·(C1 + z·(C2 + …)).
    let s = A::mul_add(
        r * z,
        horner(&[
            -1.666_666_666_666_663_243_48e-01,
            8.333_333_333_322_489_461_24e-03,
            -1.984_126_982_985_794_931_34e-04,
            2.755_731_370_707_006_767_89e-06,
            -2.505_076_025_340_686_341_95e-08,
            1.589_690_995_211_550_102_21e-10,
        ]),
        r,
    );
    let poly_c = horner(&[
        4.166_666_666_666_660_190_37e-02,
        -1.388_888_888_887_410_957_49e-03,
        2.480_158_728_947_672_941_78e-05,
        -2.755_731_435_139_066_330_35e-07,
        2.087_572_321_298_174_827_90e-09,
        -1.135_964_755_778_819_482_65e-11,
    ]);
    let hz = 0.5 * z;
    let one_minus_hz = 1.0 - hz;
    let c = one_minus_hz + A::mul_add(z * z, poly_c, (1.0 - one_minus_hz) - hz);
    // Quadrant n mod 4: 0 → (s, c), 1 → (c, −s), 2 → (−s, −c), 3 → (−c, s). Swap on odd n
    // (xor with the difference under an all-ones mask), then flip signs (sin on quadrants
    // 2, 3; cos on 1, 2).
    let swap = 0u64.wrapping_sub(quadrant & 1);
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let t = (sb ^ cb) & swap;
    let (sin_bits, cos_bits) = (sb ^ t, cb ^ t);
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(sin_bits ^ sin_sign),
        f64::from_bits(cos_bits ^ cos_sign),
    )
}

/// `(r, n mod 4)` with `x = n·π/2 + r`, |r| ≤ π/4, for huge `x` (NaN for NaN and ±∞): `x·2/π`
/// modulo 4 in 192-bit fixed point from `x`'s integer mantissa and a 192-bit window of 2/π.
#[cold]
#[inline(never)]
#[allow(clippy::unreadable_literal)]
fn reduce_large(x: f64) -> (f64, u64) {
    /// 2/π in binary: bits 1‥1280 after the point, most significant first.
    const TWO_OVER_PI: [u64; 20] = [
        0xa2f9836e4e441529,
        0xfc2757d1f534ddc0,
        0xdb6295993c439041,
        0xfe5163abdebbc561,
        0xb7246e3a424dd2e0,
        0x06492eea09d1921c,
        0xfe1deb1cb129a73e,
        0xe88235f52ebb4484,
        0xe99c7026b45f7e41,
        0x3991d639835339f4,
        0x9c845f8bbdf9283b,
        0x1ff897ffde05980f,
        0xef2f118b5a0a6d1f,
        0x6d367ecf27cb09b7,
        0x4f463f669e5fea2d,
        0x7527bac7ebe5f17b,
        0x3d0739f78a5292ea,
        0x6bfb5fb11f8d5d08,
        0x56033046fc7b6bab,
        0xf0cfbc209af4361d,
    ];
    /// Bits p‥p+63 of 2/π (bit 1 is the first after the point; bits p ≤ 0 are zero).
    fn window(p: i64) -> u64 {
        if p < 1 {
            return if 1 - p >= 64 {
                0
            } else {
                TWO_OVER_PI[0] >> (1 - p)
            };
        }
        let o = (p - 1) as usize;
        let (j, sh) = (o / 64, o % 64);
        if sh == 0 {
            TWO_OVER_PI[j]
        } else {
            (TWO_OVER_PI[j] << sh) | (TWO_OVER_PI[j + 1] >> (64 - sh))
        }
    }
    if !x.is_finite() {
        return (f64::NAN, 0);
    }
    // |x| = m·2^k with an integer m < 2⁵³ (here |x| ≥ 2¹⁹, so x is normal and k ≥ −33).
    let bits = x.to_bits();
    let m = (bits & 0x000f_ffff_ffff_ffff) | 0x0010_0000_0000_0000;
    let k = ((bits >> 52) & 0x7ff) as i64 - 1075;
    // Bits i ≤ k − 2 of 2/π contribute multiples of 4 to m·2^k·2/π: take bits k − 1 … k + 190,
    // so that (m·W mod 2¹⁹²)/2¹⁹⁰ = |x|·2/π mod 4 up to 2⁻¹³⁸.
    let (w0, w1, w2) = (window(k - 1), window(k + 63), window(k + 127));
    let lo = u128::from(m) * u128::from(w2);
    let mid = u128::from(m) * u128::from(w1) + (lo >> 64);
    let hi = (u128::from(m) * u128::from(w0) + (mid >> 64)) as u64;
    let mut quadrant = hi >> 62;
    let mut frac =
        (u128::from(hi) << 66) | ((mid as u64 as u128) << 2) | ((lo as u64 >> 62) as u128);
    let mut sign = 1.0;
    if frac >> 127 == 1 {
        // Round to the nearest quadrant: fraction f − 1 ∈ [−1/2, 0).
        quadrant += 1;
        frac = frac.wrapping_neg();
        sign = -1.0;
    }
    // 0x37f0… is 2⁻¹²⁸.
    let r =
        sign * (frac as f64 * f64::from_bits(0x37f0_0000_0000_0000)) * core::f64::consts::FRAC_PI_2;
    if x < 0.0 {
        (-r, quadrant.wrapping_neg() & 3)
    } else {
        (r, quadrant)
    }
}
