//! The `sin_cos` routine emitted into every generated module (one source: `sin_cos_impl.rs`).
//!
//! Exposed here so that its accuracy is tested in this crate; generated code carries its own
//! private copy so that generated modules stay self-contained.

/// Source text of the emitted routine.
pub const SIN_COS_SOURCE: &str = include_str!("sin_cos_impl.rs");

include!("sin_cos_impl.rs");

/// `(sin x, cos x)` as computed by generated code.
pub fn fast_sin_cos(x: f64) -> (f64, f64) {
    sin_cos(x)
}

#[cfg(test)]
mod tests {
    use super::fast_sin_cos;

    fn check(x: f64, tol: f64) {
        let (s, c) = fast_sin_cos(x);
        let (se, ce) = x.sin_cos();
        assert!(
            (s - se).abs() <= tol && (c - ce).abs() <= tol,
            "x = {x:e}: ({s}, {c}) vs ({se}, {ce})"
        );
    }

    #[test]
    fn agrees_with_std_within_an_ulp_on_robot_angles() {
        // Dense sweep of |x| ≤ 50 including every quadrant boundary neighbourhood.
        let mut x = -50.0;
        while x <= 50.0 {
            check(x, 2.3e-16);
            x += 0.000_37;
        }
        for k in -64..=64 {
            let b = k as f64 * std::f64::consts::FRAC_PI_2;
            for d in [0.0, 1e-12, -1e-12, 1e-6, -1e-6, 0.3] {
                check(b + d, 2.3e-16);
            }
        }
    }

    #[test]
    fn large_tiny_and_special_arguments() {
        for x in [
            1e-300, -1e-300, 0.0, -0.0, 1e-8, 1e3, -7.5e4, 8e5, 8.3e5, 1e6, 1e12, -1e300,
        ] {
            check(x, 1e-15);
        }
        // Payne–Hanek range: a spread of magnitudes up to the largest finite value.
        let mut x = 823_549.0_f64;
        while x < 1e308 {
            for y in [x, -x, x * 1.000_001, x * 0.999_999_7] {
                check(y, 1e-15);
            }
            x *= 1.37;
        }
        check(f64::MAX, 1e-15);
        check(823_548.999_999_9, 1e-15);
        assert!(fast_sin_cos(f64::NAN).0.is_nan());
        assert!(fast_sin_cos(f64::INFINITY).1.is_nan());
    }
}
