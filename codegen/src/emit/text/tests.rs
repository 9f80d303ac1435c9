//! The printed statements against what prettyplease prints for the same tokens, byte for byte,
//! and the splicing of blocks into formatted modules.

use super::*;
use crate::emit::print::Printer;
use crate::options::{Options, ParamMode, Precision};
use crate::registry::{FunctionId, FunctionSet};

/// prettyplease's text of `tokens` as a statement at indentation `indent`.
fn formatted(indent: usize, tokens: TokenStream) -> String {
    format_long(indent, &tokens.to_string())
        .expect("parses")
        .join("\n")
}

/// Every statement and result entry of every function of `model`, for each
/// `(parameters, functions, precision)` and indentation: the text printer gives what
/// prettyplease prints for the tokens, on one line wherever it fits (longer statements are
/// formatted by prettyplease one by one, [`format_long`]).
fn check_model(path: &str, variants: &[(ParamMode, FunctionSet, Precision)], indents: &[usize]) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let model = kanegen_model::Model::from_toml_file(format!("{root}/{path}")).unwrap();
    let names = LeafNames::new(&model);
    for &(params, functions, precision) in variants {
        let options = Options { params, functions };
        let d = crate::kane::derive(&model, options);
        let low = crate::lower::lower(&d);
        let pre: Vec<String> = low
            .pre_slots
            .iter()
            .map(|&i| low.precompute.stmts[i].name.clone())
            .collect();
        let programs =
            std::iter::once(&low.precompute).chain(low.functions.iter().map(|f| &f.program));
        for p in programs {
            let printer = Printer {
                model: &model,
                stmts: &p.stmts,
                pre: &pre,
                precision,
                lane: None,
            };
            // Statements, and result entries as `let`, matrix and vector stores.
            let mut cases: Vec<(String, TokenStream)> = Vec::new();
            for s in &p.stmts {
                let id = crate::emit::print::ident(&s.name);
                let tokens = printer.expr(&s.expr, false);
                let mut text = format!("let {id} = ");
                printer.expr_text(&names, &s.expr, false, &mut text);
                cases.push((format!("{text};"), quote!(let #id = #tokens;)));
            }
            for (r, c, e) in &p.outputs {
                let tokens = printer.expr(e, false);
                let mut v = String::new();
                printer.expr_text(&names, e, false, &mut v);
                let (ri, ci) = (
                    proc_macro2::Literal::usize_unsuffixed(*r),
                    proc_macro2::Literal::usize_unsuffixed(*c),
                );
                cases.push((format!("let out = {v};"), quote!(let out = #tokens;)));
                cases.push((
                    format!("m[({r}, {c})] = {v};"),
                    quote!(m[(#ri, #ci)] = #tokens;),
                ));
                cases.push((format!("pos[{r}] = {v};"), quote!(pos[#ri] = #tokens;)));
            }
            for (text, tokens) in cases {
                for &indent in indents {
                    let want = formatted(indent, tokens.clone());
                    let got = if fits(indent, text.len()) {
                        format!("{}{text}", " ".repeat(indent))
                    } else {
                        format_long(indent, &text).expect("parses").join("\n")
                    };
                    assert_eq!(got, want, "{path}, {}", p.name);
                }
            }
        }
    }
}

#[test]
fn text_printer_matches_prettyplease_on_every_statement_of_krang() {
    // The derivatives have the longest statements; the regressors add nothing new and are
    // slow to derive in a debug build.
    let most = FunctionSet::all()
        .without(FunctionId::InverseDynamicsRegressor)
        .without(FunctionId::GravityRegressor)
        .without(FunctionId::BaseRegressor)
        .without(FunctionId::BaseGravityRegressor);
    check_model(
        "models/krang.toml",
        &[
            (ParamMode::Runtime, most, Precision::F64),
            (ParamMode::Baked, FunctionSet::default(), Precision::F32),
        ],
        &[16],
    );
}

#[test]
fn text_printer_matches_prettyplease_on_every_statement_of_the_two_link_model() {
    let all = FunctionSet::all();
    check_model(
        "models/two-link.toml",
        &[
            (ParamMode::Runtime, all, Precision::F64),
            (ParamMode::Baked, all, Precision::F32),
        ],
        &[8, 16, 40],
    );
}

#[test]
fn statements_stay_on_one_line_exactly_where_prettyplease_keeps_them() {
    // Sums of growing length around the line width: the break decision at the margin.
    let mut e = String::from("let d1 = a0");
    for i in 1..40 {
        e.push_str(&format!(" + b{i} * c{i}"));
        let code = format!("{e};");
        for indent in [4, 8, 16, 28, 32, 44] {
            let tokens: TokenStream = code.parse().unwrap();
            let want = formatted(indent, tokens);
            if fits(indent, code.len()) {
                assert_eq!(want, format!("{}{code}", " ".repeat(indent)), "{indent}");
            } else {
                assert!(want.lines().count() > 1, "{indent}: {want}");
            }
        }
    }
}

#[test]
fn split_functions_are_valid_rust_with_every_block_passing_on_what_is_read_later() {
    // Krang's default module split into blocks of 500 above 100 statements: it parses, and
    // every name a statement reads is bound before it (in its block or passed on by an
    // earlier one), which the tuple values and patterns make rustc check in
    // `tests/big_tree.rs`; here: the split module differs from the unsplit one only by
    // the blocks' lines and indentation.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let model = kanegen_model::Model::from_toml_file(format!("{root}/models/krang.toml")).unwrap();
    let emit = |split_above| {
        let options = crate::emit::EmitOptions {
            split_above,
            ..crate::emit::EmitOptions::default()
        };
        crate::generate_with(model.clone(), Options::default(), &options)
            .unwrap()
            .source
    };
    let split = emit(100);
    let whole = emit(usize::MAX);
    assert_eq!(
        whole,
        emit(SPLIT_ABOVE),
        "Krang's default module is not split"
    );
    syn::parse_file(&split).expect("the split module parses");
    let blocks = split.lines().filter(|l| l.ends_with(" = {")).count();
    assert!(blocks >= 5, "{blocks} blocks");
    // The same statements and stores in the same order (line breaks may differ: the
    // blocks' statements are indented one level deeper).
    let statements = |src: &str| -> Vec<String> {
        src.split_whitespace()
            .collect::<String>()
            // A call broken over lines has a trailing comma.
            .replace(",)", ")")
            .split(';')
            .filter_map(|s| {
                let s = s.rsplit("//").next().unwrap_or(s);
                let at = s
                    .find("letk")
                    .or(s.find("letd"))
                    .or(s.find("lett"))
                    .or(s.find("m[("))?;
                Some(s[at..].to_owned())
            })
            .collect()
    };
    assert_eq!(statements(&split), statements(&whole));
}

/// The value of a printed expression (`+ - * /`, unary `-`, parentheses, literals,
/// `A::mul_add(x, y, acc)` fused or as `x * y + acc`), with the value of each name (`k12`,
/// `p.m4`, `s_q1`) from `values` or, the first time it is seen, a random one in [-2, 2].
fn value(
    e: &syn::Expr,
    values: &mut std::collections::HashMap<String, f64>,
    rng: &mut impl rand::RngExt,
    fused: bool,
) -> f64 {
    use syn::{BinOp, Expr, UnOp};
    let mut name = |n: String, values: &mut std::collections::HashMap<String, f64>| {
        *values
            .entry(n)
            .or_insert_with(|| rng.random_range(-2.0..2.0))
    };
    match e {
        Expr::Lit(l) => match &l.lit {
            syn::Lit::Float(f) => f.base10_parse().unwrap(),
            syn::Lit::Int(i) => i.base10_parse::<i64>().unwrap() as f64,
            other => panic!("literal {}", quote!(#other)),
        },
        Expr::Path(p) => name(quote!(#p).to_string(), values),
        Expr::Field(f) => name(quote!(#f).to_string(), values),
        Expr::Paren(p) => value(&p.expr, values, rng, fused),
        Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) => -value(&u.expr, values, rng, fused),
        Expr::Binary(b) => {
            let (l, r) = (
                value(&b.left, values, rng, fused),
                value(&b.right, values, rng, fused),
            );
            match b.op {
                BinOp::Add(_) => l + r,
                BinOp::Sub(_) => l - r,
                BinOp::Mul(_) => l * r,
                BinOp::Div(_) => l / r,
                _ => panic!("operator in {}", quote!(#b)),
            }
        }
        Expr::Call(c) => {
            let f = &c.func;
            assert_eq!(quote!(#f).to_string(), "A :: mul_add");
            let a: Vec<f64> = c
                .args
                .iter()
                .map(|a| value(a, values, rng, fused))
                .collect();
            if fused {
                a[0].mul_add(a[1], a[2])
            } else {
                a[0] * a[1] + a[2]
            }
        }
        other => panic!("expression {}", quote!(#other)),
    }
}

#[test]
fn multiply_add_chains_give_the_printed_sums_bits_unfused_and_fuse_where_counted() {
    // Every statement and result entry of Krang's and the two-link model's functions,
    // printed plain and with multiply-add chains, evaluated on random values: `Plain`
    // (the baseline copy) gives the plain sum's bits, `Fused` agrees to rounding, and the
    // chains hold as many `A::mul_add` as `OpCount::fmas` counts.
    use rand::SeedableRng;
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut rng = rand::rngs::StdRng::seed_from_u64(14);
    let (mut fused_total, mut differing) = (0usize, 0usize);
    for path in ["models/krang.toml", "models/two-link.toml"] {
        let model = kanegen_model::Model::from_toml_file(format!("{root}/{path}")).unwrap();
        let names = LeafNames::new(&model);
        let options = Options {
            params: ParamMode::Runtime,
            functions: FunctionSet::default(),
        };
        let low = crate::lower::lower(&crate::kane::derive(&model, options));
        let pre: Vec<String> = low
            .pre_slots
            .iter()
            .map(|&i| low.precompute.stmts[i].name.clone())
            .collect();
        for p in low.functions.iter().map(|f| &f.program) {
            let printer = Printer {
                model: &model,
                stmts: &p.stmts,
                pre: &pre,
                precision: Precision::F64,
                lane: None,
            };
            // Leaves and statement values (each statement's plain value: every expression
            // is evaluated three ways on the same inputs).
            let mut env = std::collections::HashMap::new();
            let mut calls = 0;
            let exprs = p
                .stmts
                .iter()
                .map(|s| (Some(&s.name), &s.expr))
                .chain(p.outputs.iter().map(|(_, _, e)| (None, e)));
            for (name, e) in exprs {
                let (mut plain, mut fused) = (String::new(), String::new());
                printer.expr_text(&names, e, false, &mut plain);
                printer.expr_text_with(&names, e, false, true, &mut fused);
                calls += fused.matches("A::mul_add(").count();
                let plain: syn::Expr = syn::parse_str(&plain).unwrap();
                let fused: syn::Expr = syn::parse_str(&fused).unwrap();
                let a = value(&plain, &mut env, &mut rng, false);
                let b = value(&fused, &mut env, &mut rng, false);
                let c = value(&fused, &mut env, &mut rng, true);
                assert_eq!(a.to_bits(), b.to_bits(), "{}: {}", p.name, quote!(#fused));
                let scale = 1.0 + a.abs().max(c.abs());
                assert!((a - c).abs() <= 1e-9 * scale, "{}: {a} vs {c}", p.name);
                differing += usize::from(a.to_bits() != c.to_bits());
                if let Some(n) = name {
                    env.insert(n.clone(), a);
                }
            }
            assert_eq!(calls, p.ops.fmas, "{}: FMAs printed and counted", p.name);
            fused_total += calls;
        }
    }
    assert!(fused_total > 1000, "{fused_total} multiply-adds fused");
    assert!(differing > 0, "fusing changed no value");
}

#[test]
fn placeholders_are_replaced_at_their_indentation() {
    let mut b = Block::default();
    b.push("let k1 = a * b;".into(), "w1.x\nfn injected() {}");
    b.push("m[(0, 1)] = k1;".into(), "");
    let src = "fn f() {\n    __kanegen_block!(0);\n    m\n}\n";
    let out = splice(src, &[b]).unwrap();
    assert_eq!(
        out,
        "fn f() {\n    let k1 = a * b; // w1.x\\nfn injected() {}\n    m[(0, 1)] = k1;\n    m\n}\n"
    );
}
