//! `UnknownParameter` keeps the name inline (no allocation, `no_std`), truncated at a character
//! boundary, with the messages generated modules have always given.

use kanegen_runtime::UnknownParameter;

#[test]
fn keeps_the_name_and_formats_it() {
    let err = UnknownParameter::new("no_such_parameter");
    assert_eq!(err.name(), "no_such_parameter");
    assert_eq!(
        err.to_string(),
        "unknown parameter `no_such_parameter`; the valid names are listed in Params::NAMES"
    );
    assert_eq!(
        format!("{err:?}"),
        r#"UnknownParameter { name: "no_such_parameter" }"#
    );
    let _: &dyn core::error::Error = &err;
    assert_eq!(UnknownParameter::new("").name(), "");
}

#[test]
fn truncates_long_names_at_a_character_boundary() {
    assert_eq!(UnknownParameter::CAPACITY, 48);
    let long = "é".repeat(40); // 80 bytes
    assert_eq!(UnknownParameter::new(&long).name(), "é".repeat(24));
    let err = UnknownParameter::new("abcdefghijklmnopqrstuvwxyzabcdefghijklmnopqrstuvwxyz");
    assert_eq!(
        err.name(),
        "abcdefghijklmnopqrstuvwxyzabcdefghijklmnopqrstuv"
    );
    // 47 ASCII bytes then a 2-byte character: cut before it.
    let name = format!("{}é", "a".repeat(47));
    assert_eq!(UnknownParameter::new(&name).name(), "a".repeat(47));
    // Equality is by the kept name.
    assert_eq!(
        UnknownParameter::new(&long),
        UnknownParameter::new(&"é".repeat(30))
    );
    assert_ne!(UnknownParameter::new("a"), UnknownParameter::new("b"));
}
