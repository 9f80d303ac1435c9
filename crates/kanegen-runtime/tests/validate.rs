//! The checks of a generated `Params::validate`.

use kanegen_runtime::validate::{check_body, check_finite, check_non_negative, check_positive};
use kanegen_runtime::{InvalidParameter, Problem};

/// A solid box 0.2 × 0.4 × 0.6 m of 3 kg whose centre of mass is at `s` in the frame:
/// `(m, m·S, J)` with J the inertia about the frame origin (Huygens–Steiner).
fn box_at(s: [f64; 3]) -> (f64, [f64; 3], [f64; 6]) {
    let m = 3.0;
    let (a, b, c) = (0.2_f64, 0.4_f64, 0.6_f64);
    let ig = [
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
    ];
    let s2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    let j = [
        ig[0] + m * (s2 - s[0] * s[0]),
        -m * s[0] * s[1],
        -m * s[0] * s[2],
        ig[1] + m * (s2 - s[1] * s[1]),
        -m * s[1] * s[2],
        ig[2] + m * (s2 - s[2] * s[2]),
    ];
    (m, s.map(|x| m * x), j)
}

#[test]
fn a_solid_box_anywhere_in_its_frame_is_a_physical_body() {
    for s in [[0.0; 3], [0.3, -0.2, 1.5], [-2.0, 0.1, 0.0]] {
        let (m, ms, j) = box_at(s);
        check_body("b", "mb", m, ms, j, 1e-9).unwrap();
    }
}

#[test]
fn inertias_breaking_the_triangle_inequality_about_the_centre_of_mass_are_rejected() {
    let (m, ms, mut j) = box_at([0.3, -0.2, 1.5]);
    // About the centre of mass XX = 0.13 ≤ YY + ZZ = 0.1 + 0.05; raised by 0.05 it exceeds them.
    j[0] += 0.05;
    let e = check_body("b", "mb", m, ms, j, 1e-9).unwrap_err();
    assert_eq!((e.name(), e.problem()), ("b", Problem::InertiaNotPhysical));
    // The same J with the centre of mass moved: the shift no longer matches.
    let (m, _, j) = box_at([0.3, -0.2, 1.5]);
    assert!(check_body("b", "mb", m, [0.0; 3], j, 1e-9).is_ok());
    let (m, ms, j) = box_at([0.0; 3]);
    assert!(check_body("b", "mb", m, ms.map(|_| 1.0), j, 1e-9).is_err());
}

#[test]
fn masses_must_be_positive_and_values_finite() {
    let (_, ms, j) = box_at([0.0; 3]);
    assert_eq!(
        check_body("b", "mb", 0.0, ms, j, 1e-9),
        Err(InvalidParameter::new("mb", Problem::NotPositive))
    );
    assert!(check_positive("R", 0.25).is_ok());
    assert!(check_positive("R", 0.0).is_err());
    assert!(check_positive("R", f64::NAN).is_err());
    assert!(check_non_negative("YYw", 0.0).is_ok());
    assert_eq!(
        check_non_negative("YYw", -1e-3).unwrap_err().problem(),
        Problem::Negative
    );
    assert!(check_finite(&["a", "b"], &[1.0_f32, 2.0]).is_ok());
    let e = check_finite(&["a", "b", "c"], &[1.0, f64::INFINITY, f64::NAN]).unwrap_err();
    assert_eq!((e.name(), e.problem()), ("b", Problem::NotFinite));
    assert_eq!(e.to_string(), "parameter `b` is not finite");
}
