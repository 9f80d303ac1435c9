//! Parameters as data: `Params::validate` on every generated model, serde round trips (TOML and
//! JSON), and the parameter values of a model file read at run time.

use krang_dynamics::{
    InvalidParameter, Params, Problem, SetParameterError, f32 as k32, fixed_wheels, two_link,
};

#[test]
fn default_parameters_of_every_model_are_valid() {
    Params::default().validate().unwrap();
    k32::Params::default().validate().unwrap();
    fixed_wheels::Params::default().validate().unwrap();
    two_link::Params::default().validate().unwrap();
}

#[test]
fn validate_names_the_non_finite_parameter() {
    let p = Params {
        L3: f64::NAN,
        ..Params::default()
    };
    let e = p.validate().unwrap_err();
    assert_eq!((e.name(), e.problem()), ("L3", Problem::NotFinite));
    let p = k32::Params {
        ZZ9r: f32::INFINITY,
        ..k32::Params::default()
    };
    assert_eq!(p.validate().unwrap_err().name(), "ZZ9r");
}

#[test]
fn validate_rejects_non_positive_masses_and_wheel_constants() {
    for (name, value) in [
        ("m4l", 0.0),
        ("m1", -2.0),
        ("R", 0.0),
        ("L", -0.68),
        ("mw", 0.0),
    ] {
        let mut values = Params::default().to_array();
        values[Params::NAMES.iter().position(|n| *n == name).unwrap()] = value;
        let p = Params::from_array(values);
        assert_eq!(
            p.validate(),
            Err(InvalidParameter::new(name, Problem::NotPositive)),
            "{name} = {value}"
        );
    }
    // `set` refuses it (set_refuses_values_that_are_not_finite_or_not_physical).
    let p = Params {
        YYw: -0.1,
        ..Params::default()
    };
    assert_eq!(
        p.validate().unwrap_err(),
        InvalidParameter::new("YYw", Problem::Negative)
    );
}

/// Regression: `Params::set` accepted NaN, ±∞ and negative masses (only an unknown name was an
/// error), so a bad value reached the dynamics unnoticed.
#[test]
fn set_refuses_values_that_are_not_finite_or_not_physical() {
    let invalid = |name: &str, problem| {
        Err(SetParameterError::Invalid(InvalidParameter::new(
            name, problem,
        )))
    };
    let mut p = Params::default();
    for (name, value, problem) in [
        ("L3", f64::NAN, Problem::NotFinite),
        ("g", f64::INFINITY, Problem::NotFinite),
        ("XX4l", f64::NEG_INFINITY, Problem::NotFinite),
        ("m4l", 0.0, Problem::NotPositive),
        ("m1", -2.0, Problem::NotPositive),
        ("R", 0.0, Problem::NotPositive),
        ("R", -0.25, Problem::NotPositive),
        ("L", -0.68, Problem::NotPositive),
        ("mw", 0.0, Problem::NotPositive),
        ("YYw", -0.1, Problem::Negative),
    ] {
        assert_eq!(
            p.set(name, value),
            invalid(name, problem),
            "{name} = {value}"
        );
        assert_eq!(
            p,
            Params::default(),
            "a refused value leaves the parameters unchanged"
        );
    }
    // Values only a combination can make unphysical, and signed parameters, are accepted.
    p.set("MX4l", -0.3).unwrap();
    p.set("XY4l", -0.01).unwrap();
    p.set("YYw", 0.0).unwrap();
    assert_eq!(
        k32::Params::default().set("m4l", f32::NAN),
        invalid("m4l", Problem::NotFinite)
    );
    let err = p.set("mw", -1.0).unwrap_err();
    assert_eq!(err.name(), "mw");
    assert!(err.to_string().contains("must be positive"), "{err}");
    assert!(core::error::Error::source(&err).is_some());
    // Deserialising goes through `set`: the same values are errors there.
    let e = toml::from_str::<Params>("m4l = -4.5\n").unwrap_err();
    assert!(e.to_string().contains("`m4l` must be positive"), "{e}");
    let e = serde_json::from_str::<Params>(r#"{"R": 0.0}"#).unwrap_err();
    assert!(e.to_string().contains("`R` must be positive"), "{e}");
}

#[test]
fn validate_rejects_inertias_that_break_the_triangle_inequality() {
    // Body 5l: raise XX beyond YY + ZZ about the centre of mass.
    let mut p = Params::default();
    p.XX5l += 10.0;
    let e = p.validate().unwrap_err();
    assert_eq!((e.name(), e.problem()), ("5l", Problem::InertiaNotPhysical));
    assert!(e.to_string().contains("triangle inequality"), "{e}");
    // A first moment too large for the inertia about the frame origin: the shift to the
    // centre of mass makes a principal moment negative.
    let p = two_link::Params {
        MX2: 5.0,
        ..two_link::Params::default()
    };
    assert_eq!(p.validate().unwrap_err().name(), "2");
    // A thin rod (principal moments 0, I, I) sits on the boundary: valid.
    let mut p = two_link::Params::default();
    (p.m2, p.MX2, p.MY2, p.MZ2) = (2.0, 0.0, 0.0, 0.0);
    (p.XX2, p.YY2, p.ZZ2, p.XY2, p.XZ2, p.YZ2) = (0.0, 0.5, 0.5, 0.0, 0.0, 0.0);
    p.validate().unwrap();
}

#[test]
fn params_round_trip_through_toml_and_json() {
    let mut p = Params::default();
    p.set("MX4l", 0.12).unwrap();
    let text = toml::to_string(&p).unwrap();
    assert!(text.contains("MX4l = 0.12"), "{text}");
    assert_eq!(toml::from_str::<Params>(&text).unwrap(), p);
    let json = serde_json::to_string(&p).unwrap();
    assert_eq!(serde_json::from_str::<Params>(&json).unwrap(), p);
    let q = k32::Params::default();
    assert_eq!(
        serde_json::from_str::<k32::Params>(&serde_json::to_string(&q).unwrap()).unwrap(),
        q
    );
}

#[test]
fn a_parameter_file_lists_only_what_it_changes_and_misspelt_names_are_errors() {
    let p: Params = toml::from_str("m4l = 4.5\nMX4l = 0.12\n").unwrap();
    assert_eq!((p.m4l, p.MX4l), (4.5, 0.12));
    assert_eq!(p.g, Params::default().g);
    let e = toml::from_str::<Params>("MX4k = 0.12\n").unwrap_err();
    assert!(e.to_string().contains("MX4k"), "{e}");
    let e = serde_json::from_str::<Params>(r#"{"m4l": "heavy"}"#).unwrap_err();
    assert!(e.to_string().contains("invalid type"), "{e}");
}

#[test]
fn model_file_parameters_are_read_at_run_time() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/krang.toml")).unwrap();
    let p: Params = krang_dynamics::params_from_model_toml(&text).unwrap();
    assert_eq!(p, Params::default());
    // An identified copy of the model file: changed values come through.
    let identified = text.replace("\nm4l = ", "\nm4l = 1.5 + 0 * ");
    assert!(krang_dynamics::params_from_model_toml::<Params>(&identified).is_err());
    let identified = text.replacen("\ng = 9.81", "\ng = 9.80665", 1);
    let p: Params = krang_dynamics::params_from_model_toml(&identified).unwrap();
    assert_eq!(p.g, 9.80665);
    let two: two_link::Params = krang_dynamics::params_from_model_toml(
        &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/two-link.toml")).unwrap(),
    )
    .unwrap();
    assert_eq!(two, two_link::Params::default());
    // A file for another model: its names are unknown here.
    assert!(krang_dynamics::params_from_model_toml::<two_link::Params>(&text).is_err());
    assert!(krang_dynamics::params_from_model_toml::<Params>("[frames]\n").is_err());
}
