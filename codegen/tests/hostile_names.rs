//! Hostile names never give wrong or injected code and never panic: the generator checks the
//! names of any model (also one built in memory, past the loaders), and every comment that
//! carries input is escaped.

use std::path::PathBuf;

use kanegen::model::{Model, ModelErrorKind as K, UrdfImport, UrdfOptions};
use kanegen::{Builder, Error};

fn two_link() -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/two-link.toml");
    Model::from_toml_file(path).expect("two-link loads")
}

/// The `BadName` of generating `model`; the name it reports.
fn rejected_name(model: Model) -> String {
    match Builder::from_model(model).generate() {
        Err(Error::Model(e)) => match e.kind {
            K::BadName(b) => b.name,
            other => panic!("expected BadName, got {other:?}"),
        },
        Err(e) => panic!("expected a model error, got {e}"),
        Ok(_) => panic!("the model should have been rejected"),
    }
}

#[test]
fn a_model_built_in_memory_with_a_reserved_speed_is_rejected_not_miscompiled() {
    // A speed `d1` would be shadowed by the generated `let d1 = …`: c would be wrong.
    let mut m = two_link();
    m.speeds[1].name = "d1".into();
    assert_eq!(rejected_name(m), "d1");
    let mut m = two_link();
    m.speeds[0].name = "s_q_w".into();
    assert_eq!(rejected_name(m), "s_q_w");
}

#[test]
fn self_self_and_underscore_are_errors_not_panics() {
    for name in ["self", "Self", "_", "crate"] {
        let mut m = two_link();
        m.speeds[0].name = name.into();
        assert_eq!(rejected_name(m), name);
        let mut m = two_link();
        m.params[0].name = name.into();
        assert_eq!(rejected_name(m), name);
    }
    let mut m = two_link();
    m.name = "self".into();
    assert_eq!(rejected_name(m), "self");
}

/// The names of every `fn` item of `items`, nested modules included.
fn fn_names(items: &[syn::Item], out: &mut Vec<String>) {
    for item in items {
        match item {
            syn::Item::Fn(f) => out.push(f.sig.ident.to_string()),
            syn::Item::Mod(m) => {
                if let Some((_, inner)) = &m.content {
                    fn_names(inner, out);
                }
            }
            syn::Item::Impl(i) => {
                for ii in &i.items {
                    if let syn::ImplItem::Fn(f) = ii {
                        out.push(f.sig.ident.to_string());
                    }
                }
            }
            _ => {}
        }
    }
}

/// A two-joint arm whose link names (statement labels, merge notes) try to end the comment they
/// are written into, or to reverse its text direction.
const HOSTILE: &str = r#"<robot name="arm">
  <link name="base"/>
  <link name="a&#10;pub fn injected() -> u32 { 42 }">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="b&#13;&#x202E;pub fn injected2() -> u32 { 42 }">
    <inertial><origin xyz="0 0 0.2"/><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="c&#10;pub fn injected3() -> u32 { 42 }">
    <inertial><mass value="0.5"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="a&#10;pub fn injected() -> u32 { 42 }"/>
    <origin xyz="0 0 0.1" rpy="0.3 0 0"/><axis xyz="0 1 0"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="a&#10;pub fn injected() -> u32 { 42 }"/><child link="b&#13;&#x202E;pub fn injected2() -> u32 { 42 }"/>
    <origin xyz="0 0 0.4" rpy="0 0.2 0"/><axis xyz="1 0 0"/>
  </joint>
  <joint name="tool" type="fixed">
    <parent link="b&#13;&#x202E;pub fn injected2() -> u32 { 42 }"/><child link="c&#10;pub fn injected3() -> u32 { 42 }"/>
    <origin xyz="0.3 0 0"/>
  </joint>
</robot>"#;

/// Link names with control characters (a newline would end a generated comment) are typed
/// errors naming the frame, escaped.
#[test]
fn link_names_with_control_characters_are_typed_errors() {
    let e = UrdfImport::parse(HOSTILE, "hostile.urdf", &UrdfOptions::default()).unwrap_err();
    let K::BadName(b) = &e.kind else {
        panic!("expected BadName, got {:?}", e.kind)
    };
    assert_eq!(b.item, r"frame `a\npub fn injected() -> u32 { 42 }`");
    assert!(b.problem.contains("'\\n'"), "{}", b.problem);
}

/// A frame name with a newline in a model built in memory is refused by the generator too.
#[test]
fn a_frame_name_with_a_newline_is_a_typed_error() {
    let mut m = two_link();
    let last = m.links.len() - 1;
    m.links[last].name = "2\nlet d1 = 0.0;\n".into();
    match Builder::from_model(m).generate() {
        Err(Error::Model(e)) => match e.kind {
            K::BadName(b) => {
                assert_eq!(b.item, r"frame `2\nlet d1 = 0.0;\n`");
                assert_eq!(b.name, r"2\nlet d1 = 0.0;\n");
            }
            other => panic!("expected BadName, got {other:?}"),
        },
        other => panic!("expected a model error, got {other:?}"),
    }
}

/// Every comment that carries input is escaped: notes with a newline or a bidirectional
/// override cannot inject code.
#[test]
fn notes_cannot_inject_code_through_comments() {
    let import = UrdfImport {
        model: two_link(),
        notes: vec![
            "c\npub fn injected3() -> u32 { 42 }".into(),
            "b\r\u{202E}pub fn injected2() -> u32 { 42 }".into(),
        ],
    };
    let g = Builder::from_import(import).generate().expect("generates");
    let src = &g.source;
    assert!(src.contains(r"c\npub fn injected3()"), "notes");
    assert!(src.contains(r"b\r\u{202e}pub fn injected2()"), "notes");
    assert!(!src.contains('\u{202E}') && !src.contains('\r'));
    for line in src.lines().filter(|l| l.contains("pub fn injected")) {
        let comment = line
            .find("//")
            .expect("only comments hold `pub fn injected`");
        assert!(comment < line.find("pub fn injected").unwrap(), "{line}");
    }
    // The file parses and defines no function of the input.
    let file = syn::parse_file(src).expect("the generated file parses");
    let mut fns = Vec::new();
    fn_names(&file.items, &mut fns);
    assert!(fns.contains(&"mass_matrix".to_owned()), "{fns:?}");
    assert!(!fns.iter().any(|f| f.starts_with("injected")), "{fns:?}");
}
