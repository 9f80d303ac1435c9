//! The `sin_cos` routines emitted into every generated module (one source: `sin_cos_impl.rs`):
//! the batched `sin_cos_n` that each generated function calls once over its joint angles, and
//! the scalar `sin_cos` it falls back to for a batch with a huge or non-finite lane.
//!
//! Exposed here so that their accuracy is tested in this crate; generated code carries its own
//! private copy so that generated modules stay self-contained.

/// Source text of the emitted routine.
pub const SIN_COS_SOURCE: &str = include_str!("sin_cos_impl.rs");

include!("sin_cos_impl.rs");

/// `(sin x, cos x)` by the scalar routine (what generated code computes for a batch that
/// holds a huge or non-finite angle; before batching, every generated function called it once
/// per joint).
#[inline]
pub fn fast_sin_cos(x: f64) -> (f64, f64) {
    sin_cos(x)
}

/// `(sin x[k], cos x[k])` for every `k`, as computed by generated code (the batched routine;
/// bit for bit the values of [`fast_sin_cos`]).
#[inline(always)]
pub fn fast_sin_cos_n<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    sin_cos_n(x)
}

#[cfg(test)]
mod tests {
    use super::{SIN_COS_SOURCE, fast_sin_cos, fast_sin_cos_n};

    #[test]
    fn source_defines_each_routine_once() {
        // `emit` renames the batched routine of `f32` modules by its definition.
        for def in ["fn sin_cos(", "fn sin_cos_n<", "fn sin_cos_n_slow<"] {
            assert_eq!(SIN_COS_SOURCE.matches(def).count(), 1, "{def}");
        }
    }

    fn check(x: f64, tol: f64) {
        let (s, c) = fast_sin_cos(x);
        let (se, ce) = x.sin_cos();
        assert!(
            (s - se).abs() <= tol && (c - ce).abs() <= tol,
            "x = {x:e}: ({s}, {c}) vs ({se}, {ce})"
        );
    }

    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// The batched routine on `x`: every lane within `tol` of `std` and bit for bit the scalar
    /// routine's value.
    fn check_batch<const N: usize>(x: [f64; N], tol: f64) {
        let (s, c) = fast_sin_cos_n(x);
        for k in 0..N {
            let (s1, c1) = fast_sin_cos(x[k]);
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
        assert_eq!(fast_sin_cos_n([0.0, -0.0]), ([0.0, 0.0], [1.0, 1.0]));
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
        assert!(fast_sin_cos(f64::NAN).0.is_nan());
        assert!(fast_sin_cos(f64::INFINITY).1.is_nan());
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
}
