//! Printing lowered expressions as Rust tokens: identifiers, literals, sums and products.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

use crate::lower::{LExpr, Leaf, Stmt};
use crate::naming;
use crate::options::Precision;
use kanegen_model::Model;

/// A model-derived name as an identifier, by [`naming::identifier`] (never a keyword, so never
/// a raw identifier; the names of a validated model are unchanged).
pub(super) fn ident(name: &str) -> Ident {
    Ident::new(&naming::identifier(name), Span::call_site())
}

/// `|v|` as an unsuffixed literal of the module's precision.
pub(super) fn lit(v: f64, precision: Precision) -> Literal {
    let mut l = match precision {
        Precision::F64 => Literal::f64_unsuffixed(v.abs()),
        // The shortest literal that rounds to the same f32.
        Precision::F32 => Literal::f32_unsuffixed(v.abs() as f32),
    };
    l.set_span(Span::call_site());
    l
}

/// An index or size literal.
pub(super) fn idx(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// `v` as a literal with its sign.
pub(super) fn signed_lit(v: f64, precision: Precision) -> TokenStream {
    let l = lit(v, precision);
    if v < 0.0 { quote!(-#l) } else { quote!(#l) }
}

/// The two-lane text of a leaf (see [`Printer::lane`]).
pub(super) type LaneLeaf<'a> = dyn Fn(&Leaf) -> Option<String> + 'a;

/// Prints the expressions of one program: leaves by their names in the model.
#[derive(Clone, Copy)]
pub(super) struct Printer<'a> {
    pub model: &'a Model,
    /// The program's statements (for the names of locals).
    pub stmts: &'a [Stmt],
    /// Field names of the precomputed values.
    pub pre: &'a [String],
    pub precision: Precision,
    /// For a paired statement (arms in lanes): the two-lane text of the leaves that differ
    /// between the two subtrees (`None` for a shared leaf, printed as usual); its
    /// multiply-adds are then `lanes.mul_add(…)` (see `text::lane_block`).
    pub lane: Option<&'a LaneLeaf<'a>>,
}

impl Printer<'_> {
    fn leaf(&self, l: &Leaf) -> TokenStream {
        let m = self.model;
        let id = match *l {
            Leaf::Const(c) => return signed_lit(c, self.precision),
            Leaf::Param(p) => {
                let id = ident(&m.params[p].name);
                return quote!(p.#id);
            }
            Leaf::Pre(s) => {
                let id = ident(&self.pre[s]);
                return quote!(pc.#id);
            }
            Leaf::Speed(s) => ident(&m.speeds[s].name),
            Leaf::Accel(s) => ident(&naming::accel(&m.speeds[s].name)),
            Leaf::Sin(s) => ident(&naming::sin(&m.speeds[s].coordinate)),
            Leaf::Cos(s) => ident(&naming::cos(&m.speeds[s].coordinate)),
            Leaf::Coord(s) => ident(m.coordinate_names()[s]),
            Leaf::Local(i) => ident(&self.stmts[i].name),
        };
        quote!(#id)
    }

    /// An expression; `atomic` asks for parentheses around anything that is not a primary.
    pub fn expr(&self, e: &LExpr, atomic: bool) -> TokenStream {
        match e {
            LExpr::Leaf(Leaf::Const(c)) if *c < 0.0 && atomic => {
                let l = lit(*c, self.precision);
                quote!((-#l))
            }
            LExpr::Leaf(l) => self.leaf(l),
            LExpr::Sum { constant, terms } => {
                let ts = self.sum(*constant, terms);
                if atomic { quote!((#ts)) } else { ts }
            }
            LExpr::Prod(f) => {
                let out = self.product(f);
                if atomic { quote!((#out)) } else { out }
            }
        }
    }

    fn sum(&self, constant: f64, terms: &[(f64, LExpr)]) -> TokenStream {
        let mut ts = TokenStream::new();
        // Start with a positive term when there is one (`b - a`, not `-a + b`): saves a
        // negation per statement.
        let mut terms: Vec<&(f64, LExpr)> = terms.iter().collect();
        if let Some(first_pos) = terms.iter().position(|(k, _)| *k > 0.0) {
            let t = terms.remove(first_pos);
            terms.insert(0, t);
        }
        for (i, (k, t)) in terms.into_iter().enumerate() {
            let body = if k.abs() == 1.0 {
                self.expr(t, false)
            } else {
                let kl = lit(*k, self.precision);
                let inner = self.expr(t, true);
                quote!(#kl * #inner)
            };
            ts.extend(match (i, *k < 0.0) {
                (0, false) => body,
                (0, true) => quote!(-#body),
                (_, false) => quote!(+ #body),
                (_, true) => quote!(- #body),
            });
        }
        if constant != 0.0 {
            let cl = lit(constant, self.precision);
            ts.extend(if constant < 0.0 {
                quote!(- #cl)
            } else {
                quote!(+ #cl)
            });
        }
        ts
    }

    fn product(&self, f: &[(LExpr, i32)]) -> TokenStream {
        let mut num: Vec<TokenStream> = Vec::new();
        let mut den: Vec<TokenStream> = Vec::new();
        for (b, p) in f {
            let t = self.expr(b, true);
            for _ in 0..p.unsigned_abs() {
                if *p > 0 {
                    num.push(t.clone());
                } else {
                    den.push(t.clone());
                }
            }
        }
        let numt = if num.is_empty() {
            quote!(1.0)
        } else {
            let first = &num[0];
            let rest = &num[1..];
            quote!(#first #(* #rest)*)
        };
        if den.is_empty() {
            return numt;
        }
        let first = &den[0];
        let rest = &den[1..];
        if den.len() == 1 {
            quote!(#numt / #first)
        } else {
            quote!(#numt / (#first #(* #rest)*))
        }
    }

    /// The `let` statements of the program, with `after[0]` before the first and `after[i + 1]`
    /// right after statement `i` (missing entries: nothing).
    pub fn statements(&self, after: &[TokenStream]) -> TokenStream {
        let mut ts = after.first().cloned().unwrap_or_default();
        for (i, s) in self.stmts.iter().enumerate() {
            let id = ident(&s.name);
            let e = self.expr(&s.expr, false);
            ts.extend(quote!(let #id = #e;));
            if let Some(a) = after.get(i + 1) {
                ts.extend(a.clone());
            }
        }
        ts
    }
}

/// `s` made safe for a `//` comment: control characters (a newline would end the comment and
/// let the rest of the line be compiled) and the bidirectional-override characters that rustc
/// rejects in comments (`text_direction_codepoint_in_comment`) are written as escapes (`\n`,
/// `\u{202e}`). Every comment text that comes from input (header, notes, statement labels)
/// goes through this function.
pub(crate) fn comment_text(s: &str) -> String {
    kanegen_model::escape_unprintable(s)
}
