//! `Builder::batch_feature` puts every batched item, and only those, behind the named cargo
//! feature.

use std::path::PathBuf;

use kanegen::Builder;

fn two_link() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/two-link.toml")
}

/// `(name, gated)` of every function and method of the generated file, `gated` when it carries
/// `#[cfg(feature = "<feature>")]`.
fn functions(source: &str, feature: &str) -> Vec<(String, bool)> {
    let file = syn::parse_file(source).expect("the generated module parses");
    let gate = format!("cfg(feature = \"{feature}\")");
    let gated = |attrs: &[syn::Attribute]| {
        attrs.iter().any(|a| {
            let text = quote::quote!(#a).to_string();
            text.replace(' ', "") == format!("#[{}]", gate.replace(' ', ""))
        })
    };
    let mut out = Vec::new();
    let mut stack: Vec<&syn::Item> = file.items.iter().collect();
    while let Some(item) = stack.pop() {
        match item {
            syn::Item::Fn(f) => out.push((f.sig.ident.to_string(), gated(&f.attrs))),
            syn::Item::Mod(m) => {
                if let Some((_, items)) = &m.content {
                    stack.extend(items.iter());
                }
            }
            syn::Item::Impl(i) => {
                for it in &i.items {
                    if let syn::ImplItem::Fn(f) = it {
                        out.push((f.sig.ident.to_string(), gated(&f.attrs)));
                    }
                }
            }
            _ => {}
        }
    }
    out
}

#[test]
fn batch_feature_gates_every_batched_function_and_nothing_else() {
    let source = Builder::new(two_link())
        .batch_feature("sampling")
        .generate()
        .unwrap()
        .source;
    let fns = functions(&source, "sampling");
    let batched: Vec<_> = fns.iter().filter(|(n, _)| n.contains("_batch")).collect();
    // M, c, g, τ and C, each with a shared body and four free functions and four methods.
    assert!(
        batched.len() >= 5 * 9,
        "{} batched functions",
        batched.len()
    );
    for (name, gated) in &fns {
        assert_eq!(
            *gated,
            name.contains("_batch"),
            "`{name}`: gated {gated} (only batched functions are behind the feature)"
        );
    }
}

#[test]
fn batch_without_a_feature_gates_nothing() {
    let source = Builder::new(two_link())
        .batch(true)
        .generate()
        .unwrap()
        .source;
    assert!(
        !source.contains("cfg(feature"),
        "an ungated module has no feature gate"
    );
    let fns = functions(&source, "batch");
    assert!(fns.iter().any(|(n, _)| n.contains("_batch")));
    assert!(fns.iter().all(|(_, gated)| !gated));
}
