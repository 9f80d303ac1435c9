//! Accuracy of the `trig` routines: within an ulp of `std` on robot angles, a few ulp on huge
//! ones, NaN for non-finite ones; every lane of the batched routine bit for bit a one-lane
//! batch's value (whichever path the batch takes; the baseline copy gives the scalar routine's
//! bits, the x86-64-v3 copy fuses its kernels: `tests/isa_batch.rs`), the slice routine of the
//! batched functions too; the `f32` kernel within an ulp of the correctly rounded
//! result, measured against the `f64` routine.

use kanegen_runtime::trig::{
    SIN_COS_F32_FAST_BOUND, SIN_COS_FAST_BOUND, sin_cos, sin_cos_n, sin_cos_n_f32, sin_cos_slice,
};

fn check(x: f64, tol: f64) {
    let (s, c) = sin_cos(x);
    let (se, ce) = x.sin_cos();
    assert!(
        (s - se).abs() <= tol && (c - ce).abs() <= tol,
        "x = {x:e}: ({s}, {c}) vs ({se}, {ce})"
    );
}

/// One angle through the batched routine: the bits every lane of a batch must have, whichever
/// instruction set runs (the x86-64-v3 copy fuses the kernels' multiply-adds, the baseline copy
/// gives `sin_cos`'s bits; `tests/isa_batch.rs` compares the two).
fn one(x: f64) -> (f64, f64) {
    let (s, c) = sin_cos_n([x]);
    (s[0], c[0])
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// The batched routine on `x`: every lane within `tol` of `std` and bit for bit a one-lane
/// batch's value (the scalar routine's in the baseline copy).
fn check_batch<const N: usize>(x: [f64; N], tol: f64) {
    let (s, c) = sin_cos_n(x);
    for k in 0..N {
        let (s1, c1) = one(x[k]);
        assert!(
            same(s[k], s1) && same(c[k], c1),
            "lane {k} of {N}, x = {:e}: batched ({}, {}) vs scalar ({s1}, {c1})",
            x[k],
            s[k],
            c[k]
        );
        if x[k].is_finite() {
            let (se, ce) = x[k].sin_cos();
            assert!(
                (s[k] - se).abs() <= tol && (c[k] - ce).abs() <= tol,
                "lane {k} of {N}, x = {:e}: ({}, {}) vs ({se}, {ce})",
                x[k],
                s[k],
                c[k]
            );
        } else {
            assert!(
                s[k].is_nan() && c[k].is_nan(),
                "lane {k} of {N}: {:e}",
                x[k]
            );
        }
    }
}

/// `check_batch` on consecutive windows of `xs` with batch sizes that leave every possible
/// remainder for vectors of 2, 4 and 8 lanes.
fn check_batches(xs: &[f64], tol: f64) {
    fn windows<const N: usize>(xs: &[f64], tol: f64) {
        for w in xs.windows(N).step_by(N.max(1) / 2 + 1) {
            check_batch::<N>(w.try_into().unwrap(), tol);
        }
    }
    windows::<1>(xs, tol);
    windows::<2>(xs, tol);
    windows::<3>(xs, tol);
    windows::<4>(xs, tol);
    windows::<5>(xs, tol);
    windows::<7>(xs, tol);
    windows::<8>(xs, tol);
    windows::<9>(xs, tol);
    windows::<17>(xs, tol);
    windows::<19>(xs, tol);
}

fn robot_angles() -> Vec<f64> {
    // Dense sweep of |x| ≤ 50 plus every quadrant boundary neighbourhood.
    let mut xs = Vec::new();
    let mut x = -50.0;
    while x <= 50.0 {
        xs.push(x);
        x += 0.000_37;
    }
    for k in -64..=64 {
        let b = k as f64 * std::f64::consts::FRAC_PI_2;
        for d in [0.0, 1e-12, -1e-12, 1e-6, -1e-6, 0.3] {
            xs.push(b + d);
        }
    }
    xs
}

#[test]
fn agrees_with_std_within_an_ulp_on_robot_angles() {
    for x in robot_angles() {
        check(x, 2.3e-16);
    }
}

#[test]
fn batched_agrees_with_std_and_scalar_on_robot_angles() {
    check_batches(&robot_angles(), 2.3e-16);
    check_batch([0.0; 0], 0.0);
    // (Like the scalar routine, sin(−0) comes out as +0.)
    assert_eq!(sin_cos_n([0.0, -0.0]), ([0.0, 0.0], [1.0, 1.0]));
}

fn large_and_tiny() -> Vec<f64> {
    let mut xs = vec![
        1e-300, -1e-300, 0.0, -0.0, 1e-8, 1e3, -7.5e4, 8e5, 8.3e5, 1e6, 1e12, -1e300,
    ];
    // Payne–Hanek range: a spread of magnitudes up to the largest finite value.
    let mut x = 823_549.0_f64;
    while x < 1e308 {
        xs.extend([x, -x, x * 1.000_001, x * 0.999_999_7]);
        x *= 1.37;
    }
    xs.extend([f64::MAX, -f64::MAX, 823_548.999_999_9, -823_548.999_999_9]);
    xs
}

#[test]
fn large_tiny_and_special_arguments() {
    for x in large_and_tiny() {
        check(x, 1e-15);
    }
    assert!(sin_cos(f64::NAN).0.is_nan());
    assert!(sin_cos(f64::INFINITY).1.is_nan());
}

#[test]
fn batched_large_tiny_and_special_arguments() {
    check_batches(&large_and_tiny(), 1e-15);
    // One huge or non-finite lane among robot angles, at every position of a batch of 17
    // (the whole batch then takes the scalar routine) and of smaller batches.
    let angles: [f64; 17] = core::array::from_fn(|k| 0.37 * k as f64 - 3.1);
    for odd in [
        f64::NAN,
        -f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        823_549.0,
        -823_549.0,
        1e22,
        f64::MAX,
    ] {
        for k in 0..17 {
            let mut x = angles;
            x[k] = odd;
            check_batch(x, 1e-15);
            let mut y = [x[k], 1e-300, -2.5];
            y.rotate_left(k % 3);
            check_batch(y, 1e-15);
        }
    }
    // All lanes just below the bound: the vectorized path.
    check_batch(
        [823_548.999_999_9, -823_548.999_999_9, 823_548.5, 1e-310],
        1e-15,
    );
}

#[test]
fn both_sides_of_the_fast_bound() {
    // ≈ 2¹⁹·π/2: below it `n·PIO2_1` is exact; at and above it the Payne–Hanek path.
    let below = f64::from_bits(SIN_COS_FAST_BOUND.to_bits() - 1);
    check_batch([below, -below, 1.0], 1e-15);
    check_batch([SIN_COS_FAST_BOUND, -SIN_COS_FAST_BOUND, 1.0], 1e-15);
    check(SIN_COS_FAST_BOUND, 1e-15);
    check(below, 1e-15);
}

/// `sin_cos_slice` (all angles of all states of a batched function in one call) gives the
/// one-lane batch's bits for every value, at every length (every remainder of 2-, 4- and
/// 8-lane vectors), with and without a huge or non-finite value somewhere in the slice; the
/// lanes form (`lanes::sin_cos_n`, `[[f64; L]; N]`) the same.
#[test]
fn slice_routine_gives_the_scalar_bits_at_every_length_and_path() {
    let mut xs = robot_angles();
    xs.truncate(200);
    let odd = [f64::NAN, f64::INFINITY, -823_549.0, 1e22];
    for n in 0..70 {
        for poison in [None, Some(n / 2)] {
            let mut x: Vec<f64> = xs.iter().cycle().skip(n).take(n).copied().collect();
            if let Some(k) = poison.filter(|&k| k < n) {
                x[k] = odd[n % odd.len()];
            }
            let (mut s, mut c) = (vec![0.0; n], vec![0.0; n]);
            sin_cos_slice(&x, &mut s, &mut c);
            for k in 0..n {
                let (s1, c1) = one(x[k]);
                assert!(
                    same(s[k], s1) && same(c[k], c1),
                    "value {k} of {n}, x = {:e}: slice ({}, {}) vs scalar ({s1}, {c1})",
                    x[k],
                    s[k],
                    c[k]
                );
            }
        }
    }
    // Slices of different lengths: the common length, the rest left alone.
    let (mut s, mut c) = ([7.0; 3], [7.0; 2]);
    sin_cos_slice(&[0.5, 1.0, 1.5, 2.0], &mut s, &mut c);
    assert_eq!((s[2], s[0], c[1]), (7.0, one(0.5).0, one(1.0).1));
    // The lanes form: x[k][l].
    let x: [[f64; 4]; 3] = core::array::from_fn(|k| core::array::from_fn(|l| xs[4 * k + l]));
    let (s, c) = kanegen_runtime::lanes::sin_cos_n(x);
    for k in 0..3 {
        for l in 0..4 {
            let (s1, c1) = one(x[k][l]);
            assert!(
                same(s[k][l], s1) && same(c[k][l], c1),
                "angle {k}, lane {l}"
            );
        }
    }
}

/// The inline lanes form the batched functions use (`lanes::sin_cos_n_inline`): with `Plain`
/// the scalar routine's bits, with `Fused` within 2 ulp of them (the fused kernels), on robot
/// angles and with a huge value in one lane (the per-value fallback).
#[test]
fn inline_lanes_form_gives_the_plain_bits_and_fuses_within_two_ulp() {
    use kanegen_runtime::isa::{Fused, Plain};
    use kanegen_runtime::lanes::sin_cos_n_inline;
    let xs = robot_angles();
    let mut x: [[f64; 4]; 5] = core::array::from_fn(|k| core::array::from_fn(|l| xs[4 * k + l]));
    for huge in [false, true] {
        if huge {
            x[3][1] = 1e22;
        }
        let (sp, cp) = sin_cos_n_inline::<Plain, 5, 4>(x);
        let (sf, cf) = sin_cos_n_inline::<Fused, 5, 4>(x);
        for k in 0..5 {
            for l in 0..4 {
                let (s1, c1) = sin_cos(x[k][l]);
                assert!(
                    same(sp[k][l], s1) && same(cp[k][l], c1),
                    "plain, angle {k} lane {l}"
                );
                for (f, p) in [(sf[k][l], s1), (cf[k][l], c1)] {
                    let tol = 2.0 * f64::EPSILON * p.abs().max(f64::MIN_POSITIVE);
                    assert!(
                        (f - p).abs() <= tol,
                        "fused, angle {k} lane {l}: {f:e} vs {p:e}"
                    );
                }
            }
        }
    }
}

/// Distance of `got` from `std`'s `exact` in units of the last place of `exact`.
fn ulps_f64(got: f64, exact: f64) -> f64 {
    if got == exact {
        return 0.0;
    }
    let e = exact.abs();
    let ulp = f64::from_bits(e.to_bits() + 1) - e;
    (got - exact).abs() / ulp
}

/// The fused copies reduce the argument by three fused multiply-adds (`A::ROUNDS_ONCE`), not
/// by fdlibm's two-part sums: both kinds of copy stay within 1 ulp of `std` up to the fast
/// bound, also next to the multiples of π/2 (every one of them up to the bound, ±3 ulp of
/// the argument), where the result is tiny and only a reduction accurate to about 2⁻¹⁵⁰
/// absolute keeps it within an ulp. `Fused` is run explicitly, so this holds on any CPU.
#[test]
fn fused_and_plain_reductions_stay_within_an_ulp_of_std_up_to_the_fast_bound() {
    use kanegen_runtime::isa::{Fused, Plain};
    use kanegen_runtime::lanes::sin_cos_n_inline;
    let mut xs = robot_angles();
    let bound = (SIN_COS_FAST_BOUND / std::f64::consts::FRAC_PI_2) as i64;
    for k in (1..=bound).step_by(5).chain([bound - 1, bound]) {
        let b = k as f64 * std::f64::consts::FRAC_PI_2;
        for d in -3..=3_i64 {
            let x = f64::from_bits(b.to_bits().wrapping_add_signed(d));
            if x < SIN_COS_FAST_BOUND {
                xs.extend([x, -x]);
            }
        }
    }
    xs.resize(xs.len().next_multiple_of(8), 0.5);
    let (mut worst_fused, mut worst_plain) = ((0.0, 0.0), (0.0, 0.0));
    for chunk in xs.chunks_exact(8) {
        let x: [[f64; 4]; 2] = [
            chunk[..4].try_into().unwrap(),
            chunk[4..].try_into().unwrap(),
        ];
        let (sf, cf) = sin_cos_n_inline::<Fused, 2, 4>(x);
        let (sp, cp) = sin_cos_n_inline::<Plain, 2, 4>(x);
        for k in 0..2 {
            for l in 0..4 {
                let (se, ce) = x[k][l].sin_cos();
                let f = ulps_f64(sf[k][l], se).max(ulps_f64(cf[k][l], ce));
                let p = ulps_f64(sp[k][l], se).max(ulps_f64(cp[k][l], ce));
                if f > worst_fused.0 {
                    worst_fused = (f, x[k][l]);
                }
                if p > worst_plain.0 {
                    worst_plain = (p, x[k][l]);
                }
            }
        }
    }
    eprintln!(
        "{} arguments: fused {:.3} ulp (x = {:e}), plain {:.3} ulp (x = {:e})",
        xs.len(),
        worst_fused.0,
        worst_fused.1,
        worst_plain.0,
        worst_plain.1
    );
    assert!(worst_fused.0 <= 1.0, "fused: {worst_fused:?}");
    assert!(worst_plain.0 <= 1.0, "plain: {worst_plain:?}");
}

/// Distance in units in the last place between two finite `f32` of any sign.
fn ulps(a: f32, b: f32) -> u32 {
    fn key(x: f32) -> i64 {
        let b = i64::from(x.to_bits() as i32);
        if b < 0 { i64::from(i32::MIN) - b } else { b }
    }
    (key(a) - key(b)).unsigned_abs() as u32
}

/// Worst error of the `f32` batch against the `f64` [`sin_cos`] over `xs` (windows of 7 lanes):
/// `(ulps from the correctly rounded f32 result where it is at least 10⁻³ in magnitude,
/// absolute error everywhere)`. Near a zero of sin or cos the reduction's absolute error
/// (≈ 10⁻¹²) is many ulps of the tiny result.
fn f32_error(xs: &[f32]) -> (u32, f64) {
    let (mut worst_ulps, mut worst_abs) = (0, 0.0_f64);
    for w in xs.chunks(7) {
        let mut x = [0.0_f32; 7];
        x[..w.len()].copy_from_slice(w);
        let (s, c) = sin_cos_n_f32(x);
        for k in 0..7 {
            let (se, ce) = sin_cos(f64::from(x[k]));
            for (got, exact) in [(s[k], se), (c[k], ce)] {
                if exact.abs() >= 1e-3 {
                    worst_ulps = worst_ulps.max(ulps(got, exact as f32));
                }
                worst_abs = worst_abs.max((f64::from(got) - exact).abs());
            }
        }
    }
    (worst_ulps, worst_abs)
}

#[test]
fn f32_kernel_is_within_an_ulp_of_the_rounded_f64_result_on_robot_angles() {
    // A dense grid of |x| ≤ 100, and the neighbours of multiples of π/4 (where the reduction
    // cancels, and where the quadrant changes).
    let mut xs: Vec<f32> = (-1_000_000..=1_000_000).map(|i| i as f32 * 1e-4).collect();
    for k in -130..=130 {
        let m = (f64::from(k) * core::f64::consts::FRAC_PI_4) as f32;
        let mut y = m;
        for _ in 0..20 {
            xs.extend([y, -y]);
            y = f32::from_bits(y.to_bits() + 1);
        }
    }
    xs.extend([1e-30, -1e-30, 1e-6, f32::MIN_POSITIVE, 0.0, -0.0]);
    let (worst_ulps, worst_abs) = f32_error(&xs);
    eprintln!("f32 sin/cos vs f64, |x| <= 100: {worst_ulps} ulp, absolute {worst_abs:e}");
    assert!(worst_ulps <= 1, "{worst_ulps} ulp");
    assert!(worst_abs < 8e-8, "{worst_abs:e}");
}

#[test]
fn f32_kernel_stays_accurate_up_to_its_fast_bound() {
    let xs: Vec<f32> = (-200_000..=200_000)
        .map(|i| i as f32 * (SIN_COS_F32_FAST_BOUND / 200_000.0))
        .collect();
    let (worst_ulps, worst_abs) = f32_error(&xs);
    eprintln!("f32 sin/cos vs f64, |x| <= 8192: {worst_ulps} ulp, absolute {worst_abs:e}");
    assert!(worst_ulps <= 2, "{worst_ulps} ulp");
    assert!(worst_abs < 1e-7, "{worst_abs:e}");
}

#[test]
fn f32_batch_takes_the_f64_path_for_huge_and_non_finite_lanes() {
    let below = f32::from_bits(SIN_COS_F32_FAST_BOUND.to_bits() - 1);
    for x in [
        [SIN_COS_F32_FAST_BOUND, 1.0, -2.0],
        [-SIN_COS_F32_FAST_BOUND, 1.0, below],
        [1e30, f32::MAX, 0.5],
    ] {
        let (s, c) = sin_cos_n_f32(x);
        for k in 0..3 {
            let (se, ce) = sin_cos(f64::from(x[k]));
            assert_eq!((s[k], c[k]), (se as f32, ce as f32), "x = {:e}", x[k]);
        }
    }
    let (s, c) = sin_cos_n_f32([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1.0]);
    assert!(s[..3].iter().chain(&c[..3]).all(|v| v.is_nan()));
    assert_eq!((s[3], c[3]), (1.0_f64.sin() as f32, 1.0_f64.cos() as f32));
    assert_eq!(sin_cos_n_f32([0.0_f32; 0]), ([], []));
    assert_eq!(sin_cos_n_f32([0.0, -0.0]), ([0.0, 0.0], [1.0, 1.0]));
}
