//! Statement blocks printed as text, spliced into the formatted module.
//!
//! The module's items go through proc-macro2 → syn → prettyplease. The straight-line
//! statements of the generated functions (almost all of a large model's bytes: 47 MB for a
//! 200-link chain) are not built as tokens: each statement is printed directly as the line
//! prettyplease would print for it ([`Printer::expr_text_with`]), and the function body holds a
//! placeholder statement `__kanegen_block!(N);` where the block goes. After formatting,
//! [`splice`] replaces every placeholder line by its block at the placeholder's indentation.
//! A statement longer than prettyplease's line (at that indentation) is formatted by
//! prettyplease on its own, so that the output stays byte for byte what formatting the whole
//! module at once gave (checked by the tests in `text/tests.rs`, the golden file and the pre-generated Krang
//! module). Tokens, syntax trees and the formatter's buffers of a whole module took most of
//! the generator's time and memory on large models.

use std::cell::RefCell;
use std::fmt::Write as _;

use proc_macro2::TokenStream;
use quote::quote;

use super::print::comment_text;
use super::print::{Printer, lit};
use crate::lower::{LExpr, Leaf, fused_terms, sum_order};
use crate::naming;
use kanegen_model::Model;

/// prettyplease's line width ([`MARGIN`] columns including the indentation, at least
/// [`MIN_SPACE`] after it): a statement that fits stays on one line.
const MARGIN: usize = 89;
/// See [`MARGIN`].
const MIN_SPACE: usize = 60;

/// The name of the placeholder macro (a statement `__kanegen_block!(N);` in the token stream).
const PLACEHOLDER: &str = "__kanegen_block!(";

/// The default of [`EmitOptions::split_above`](super::EmitOptions::split_above): functions with
/// more statements than this have their statements in blocks of 500 statements (`SPLIT_CHUNK`)
/// (`let (k5, d7) = { …; (k5, d7) };`). rustc's debug info nests one lexical scope per `let`,
/// and its DWARF writer recursed through them until it overflowed its stack (SIGSEGV): measured
/// with rustc 1.95 and the ISA-dispatch closures, 2,556 statements compiled (Krang's Coriolis
/// matrix) and 2,850 crashed (c of a 100-DOF tree). A block ends the nesting; what later
/// statements read leaves it as a tuple, which optimised code does not see. Every function of
/// Krang's default module is at most 2,556 statements and stays as it was; its derivatives
/// (≈ 9,000) and regressors (≈ 3,600) are split.
pub const SPLIT_ABOVE: usize = 2600;
/// Statements per block of a split function (see [`SPLIT_ABOVE`]).
pub const SPLIT_CHUNK: usize = 500;

/// One line of a block: a statement on one line (`let d5 = c_q7r * d3 + s_q7r * d4;`), laid out
/// like prettyplease at splice time, or a line written as it is (`raw`: the start and end of a
/// block of a split function); `depth` levels of indentation deeper than the placeholder, and
/// the label written after it as a comment (escaped; empty: none).
struct Line {
    code: String,
    label: String,
    depth: usize,
    raw: bool,
}

/// A block of statements, in order.
#[derive(Default)]
pub(super) struct Block {
    lines: Vec<Line>,
}

impl Block {
    /// Add a statement; `label` (raw model text, escaped here) is written after it as a
    /// comment unless it is empty.
    pub(super) fn push(&mut self, code: String, label: &str) {
        let label = if label.is_empty() {
            String::new()
        } else {
            comment_text(label)
        };
        self.lines.push(Line {
            code,
            label,
            depth: 0,
            raw: false,
        });
    }

    /// Add a line written as it is, `depth` levels deeper than the placeholder.
    fn push_raw(&mut self, code: String, depth: usize) {
        self.lines.push(Line {
            code,
            label: String::new(),
            depth,
            raw: true,
        });
    }

    /// Number of bytes the block takes at indentation `indent` (an estimate for capacity).
    fn len_at(&self, indent: usize) -> usize {
        self.lines
            .iter()
            .map(|l| indent + 4 * l.depth + l.code.len() + l.label.len() + 5)
            .sum()
    }
}

/// The blocks of a module, by placeholder number.
#[derive(Default)]
pub(super) struct Blocks(RefCell<Vec<Block>>);

impl Blocks {
    /// Keep `block` and return its placeholder statement.
    pub(super) fn placeholder(&self, block: Block) -> TokenStream {
        let mut blocks = self.0.borrow_mut();
        let n = proc_macro2::Literal::usize_unsuffixed(blocks.len());
        blocks.push(block);
        quote!(__kanegen_block!(#n);)
    }

    /// The blocks, in placeholder order.
    pub(super) fn take(&self) -> Vec<Block> {
        std::mem::take(&mut self.0.borrow_mut())
    }
}

/// The identifiers of the model's leaves as they are printed (`p.` and `pc.` prefixes
/// aside), made once per module instead of once per leaf.
pub(super) struct LeafNames {
    params: Vec<String>,
    speeds: Vec<String>,
    accels: Vec<String>,
    sins: Vec<String>,
    coss: Vec<String>,
    coords: Vec<String>,
}

impl LeafNames {
    /// The names of `model`'s parameters and of its speeds' leaves.
    pub(super) fn new(model: &Model) -> Self {
        let speeds = |f: &dyn Fn(&kanegen_model::Speed) -> String| -> Vec<String> {
            model
                .speeds
                .iter()
                .map(|s| naming::identifier(&f(s)))
                .collect()
        };
        Self {
            params: model
                .params
                .iter()
                .map(|p| naming::identifier(&p.name))
                .collect(),
            speeds: speeds(&|s| s.name.clone()),
            accels: speeds(&|s| naming::accel(&s.name)),
            sins: speeds(&|s| naming::sin(&s.coordinate)),
            coss: speeds(&|s| naming::cos(&s.coordinate)),
            // Indexed like `q` (a floating base's `base_qw` has no speed).
            coords: model
                .coordinate_names()
                .into_iter()
                .map(naming::identifier)
                .collect(),
        }
    }
}

impl Printer<'_> {
    /// The statements of the program as a block: `let NAME = EXPR; // label`, with `after[0]`
    /// before the first and `after[i + 1]` right after statement `i` (stores, printed by
    /// [`Printer::expr_text_with`]). The text form of [`Printer::statements`] plus the labels.
    /// `stored` are the expressions of the stores (each stored right after the last statement
    /// it reads), `read_at_end` what the function reads after the block (a scalar result):
    /// a function of more than `split_above` statements is split into blocks (see
    /// [`SPLIT_ABOVE`]), and a block passes on the values that later statements, stores or the
    /// end read. With `fma` the statements are printed with multiply-add chains
    /// ([`Printer::expr_text_with`]).
    pub(super) fn statement_block(
        &self,
        names: &LeafNames,
        after: Vec<Vec<String>>,
        (stored, read_at_end): (&[&LExpr], &[&LExpr]),
        split_above: usize,
        fma: bool,
    ) -> Block {
        let n = self.stmts.len();
        let split = n > split_above;
        let chunk = if split { SPLIT_CHUNK } else { n.max(1) };
        let last_use = if split {
            self.last_uses(stored, read_at_end)
        } else {
            Vec::new()
        };
        let mut block = Block::default();
        let mut after = after.into_iter();
        for code in after.next().unwrap_or_default() {
            block.push(code, "");
        }
        let mut code = String::new();
        for start in (0..n).step_by(chunk) {
            let end = (start + chunk).min(n);
            // The values of this block that are read after it.
            let live: Vec<&str> = if split {
                (start..end)
                    .filter(|&i| last_use[i] >= end)
                    .map(|i| self.stmts[i].name.as_str())
                    .collect()
            } else {
                Vec::new()
            };
            if split {
                let head = match live.as_slice() {
                    [] => "{".to_owned(),
                    [one] => format!("let {one} = {{"),
                    _ => format!("let ({}) = {{", live.join(", ")),
                };
                block.push_raw(head, 0);
            }
            let depth = usize::from(split);
            for s in &self.stmts[start..end] {
                // Statement names are generated identifiers (`k12`, `d5`).
                code.clear();
                code.push_str("let ");
                code.push_str(&s.name);
                code.push_str(" = ");
                self.expr_text_with(names, &s.expr, false, fma, &mut code);
                code.push(';');
                block.push(code.clone(), &s.comment);
                block.lines.last_mut().expect("pushed").depth = depth;
                for store in after.next().unwrap_or_default() {
                    block.push(store, "");
                    block.lines.last_mut().expect("pushed").depth = depth;
                }
            }
            if split {
                match live.as_slice() {
                    [] => block.push_raw("}".to_owned(), 0),
                    [one] => {
                        block.push_raw((*one).to_owned(), 1);
                        block.push_raw("};".to_owned(), 0);
                    }
                    _ => {
                        block.push_raw(format!("({})", live.join(", ")), 1);
                        block.push_raw("};".to_owned(), 0);
                    }
                }
            }
        }
        block
    }

    /// Per statement, the position of its last reader: a statement's index, the statement a
    /// store follows, or `n` for the end.
    fn last_uses(&self, stored: &[&LExpr], read_at_end: &[&LExpr]) -> Vec<usize> {
        let n = self.stmts.len();
        let mut last: Vec<usize> = (0..n).collect();
        let mut reads = Vec::new();
        let mut mark = |e: &LExpr, at: Option<usize>, last: &mut Vec<usize>| {
            reads.clear();
            locals_of(e, &mut reads);
            let at = at.or_else(|| reads.iter().copied().max());
            if let Some(at) = at {
                for &i in &reads {
                    last[i] = last[i].max(at);
                }
            }
        };
        for (j, s) in self.stmts.iter().enumerate() {
            mark(&s.expr, Some(j), &mut last);
        }
        for e in stored {
            mark(e, None, &mut last);
        }
        for e in read_at_end {
            mark(e, Some(n), &mut last);
        }
        last
    }

    /// Appends the text prettyplease prints for [`Printer::expr`]`(e, atomic)` on one line.
    #[cfg(test)]
    pub(super) fn expr_text(&self, names: &LeafNames, e: &LExpr, atomic: bool, out: &mut String) {
        self.expr_text_with(names, e, atomic, false, out);
    }

    /// Appends the text prettyplease prints for [`Printer::expr`]`(e, atomic)` on one line, or
    /// with `fma` the sums of products as multiply-add chains for a body generic over
    /// `A: kanegen_runtime::isa::Arith` (`A::mul_add(x, y, acc)`, the terms [`fused_terms`]
    /// picks): the same IEEE operations in the same order in the baseline copy.
    pub(super) fn expr_text_with(
        &self,
        names: &LeafNames,
        e: &LExpr,
        atomic: bool,
        fma: bool,
        out: &mut String,
    ) {
        match e {
            LExpr::Sum { constant, terms }
                if fma && fused_terms(*constant, terms).contains(&true) =>
            {
                // A multiply-add chain is a call (a primary expression), unless plain terms
                // follow it.
                let mut chain = String::new();
                let plain_after = self.fused_sum_text(names, *constant, terms, &mut chain);
                if atomic && plain_after {
                    out.push('(');
                    out.push_str(&chain);
                    out.push(')');
                } else {
                    out.push_str(&chain);
                }
            }
            LExpr::Leaf(Leaf::Const(c)) if *c < 0.0 && atomic => {
                out.push_str("(-");
                push_lit(out, *c, self);
                out.push(')');
            }
            LExpr::Leaf(l) => self.leaf_text(names, l, out),
            LExpr::Sum { constant, terms } => {
                if atomic {
                    out.push('(');
                }
                self.sum_text(names, *constant, terms, fma, out);
                if atomic {
                    out.push(')');
                }
            }
            LExpr::Prod(f) => {
                if atomic {
                    out.push('(');
                }
                self.product_text(names, f, fma, out);
                if atomic {
                    out.push(')');
                }
            }
        }
    }

    /// A sum with [`fused_terms`] as a multiply-add chain (`fma` mode of
    /// [`Printer::expr_text_with`]); whether plain terms (`+ t`, `+ c`) follow the last call.
    fn fused_sum_text(
        &self,
        names: &LeafNames,
        constant: f64,
        terms: &[(f64, LExpr)],
        out: &mut String,
    ) -> bool {
        let fused = fused_terms(constant, terms);
        // A term with its sign, as the sum prints it first (`-2.0 * t`, `-t`, `t`).
        let signed = |k: f64, t: &LExpr| {
            let mut s = String::new();
            if k < 0.0 {
                s.push('-');
            }
            if k.abs() == 1.0 {
                self.expr_text_with(names, t, false, true, &mut s);
            } else {
                push_lit(&mut s, k, self);
                s.push_str(" * ");
                self.expr_text_with(names, t, true, true, &mut s);
            }
            s
        };
        // A fusable term as the factors `(x, y)` of `x * y` (the sign on `x`).
        let factors = |k: f64, t: &LExpr| {
            let (mut x, mut y) = (String::new(), String::new());
            if k < 0.0 {
                x.push('-');
            }
            if k.abs() != 1.0 {
                push_lit(&mut x, k, self);
                // An argument: no parentheses needed.
                self.expr_text_with(names, t, false, true, &mut y);
            } else if let LExpr::Prod(f) = t {
                let all: Vec<&LExpr> = f
                    .iter()
                    .flat_map(|(b, p)| std::iter::repeat_n(b, p.unsigned_abs() as usize))
                    .collect();
                let (last, rest) = all.split_last().expect("a fusable product");
                for (i, b) in rest.iter().enumerate() {
                    if i > 0 {
                        x.push_str(" * ");
                    }
                    self.expr_text_with(names, b, true, true, &mut x);
                }
                self.expr_text_with(names, last, false, true, &mut y);
            }
            (x, y)
        };
        let mul_add = if self.lane.is_some() {
            "lanes.mul_add("
        } else {
            "A::mul_add("
        };
        let call = |x: &str, y: &str, acc: &str| format!("{mul_add}{x}, {y}, {acc})");
        let order: Vec<usize> = sum_order(terms).collect();
        let (k0, t0) = (terms[order[0]].0, &terms[order[0]].1);
        let mut plain_after = false;
        let mut acc = if order.len() == 1 {
            // `x * y + c`: the constant is the addend.
            let (x, y) = factors(k0, t0);
            let mut c = String::new();
            if constant < 0.0 {
                c.push('-');
            }
            push_lit(&mut c, constant, self);
            out.push_str(&call(&x, &y, &c));
            return false;
        } else if fused[order[0]] {
            // `x * y + t` with the second term as the addend.
            let (k1, t1) = (terms[order[1]].0, &terms[order[1]].1);
            let (x, y) = factors(k0, t0);
            call(&x, &y, &signed(k1, t1))
        } else {
            signed(k0, t0)
        };
        let skip = if fused[order[0]] { 2 } else { 1 };
        for &i in &order[skip..] {
            let (k, t) = (terms[i].0, &terms[i].1);
            if fused[i] {
                let (x, y) = factors(k, t);
                acc = call(&x, &y, &acc);
                plain_after = false;
            } else {
                acc.push_str(if k < 0.0 { " - " } else { " + " });
                self.expr_text_with(names, t, false, true, &mut acc);
                plain_after = true;
            }
        }
        if constant != 0.0 {
            acc.push_str(if constant < 0.0 { " - " } else { " + " });
            push_lit(&mut acc, constant, self);
            plain_after = true;
        }
        out.push_str(&acc);
        plain_after || !acc.starts_with(mul_add)
    }

    pub(super) fn leaf_text(&self, names: &LeafNames, l: &Leaf, out: &mut String) {
        if let Some(text) = self.lane.and_then(|lane| lane(l)) {
            out.push_str(&text);
            return;
        }
        let name: &str = match *l {
            Leaf::Const(c) => {
                if c < 0.0 {
                    out.push('-');
                }
                push_lit(out, c, self);
                return;
            }
            Leaf::Param(p) => {
                out.push_str("p.");
                &names.params[p]
            }
            // Precomputed slots and statements have generated names (`pc3`, `k12`).
            Leaf::Pre(s) => {
                out.push_str("pc.");
                &self.pre[s]
            }
            Leaf::Local(i) => &self.stmts[i].name,
            Leaf::Speed(s) => &names.speeds[s],
            Leaf::Accel(s) => &names.accels[s],
            Leaf::Sin(s) => &names.sins[s],
            Leaf::Cos(s) => &names.coss[s],
            Leaf::Coord(s) => &names.coords[s],
        };
        out.push_str(name);
    }

    fn sum_text(
        &self,
        names: &LeafNames,
        constant: f64,
        terms: &[(f64, LExpr)],
        fma: bool,
        out: &mut String,
    ) {
        // The order of `Printer::sum`: the first positive term first.
        let first = terms.iter().position(|(k, _)| *k > 0.0).unwrap_or(0);
        let order = std::iter::once(first).chain((0..terms.len()).filter(|&i| i != first));
        for (i, j) in order.enumerate() {
            let Some((k, t)) = terms.get(j) else { break };
            match (i, *k < 0.0) {
                (0, false) => {}
                (0, true) => out.push('-'),
                (_, false) => out.push_str(" + "),
                (_, true) => out.push_str(" - "),
            }
            if k.abs() == 1.0 {
                self.expr_text_with(names, t, false, fma, out);
            } else {
                push_lit(out, *k, self);
                out.push_str(" * ");
                self.expr_text_with(names, t, true, fma, out);
            }
        }
        if constant != 0.0 {
            out.push_str(if constant < 0.0 { " - " } else { " + " });
            push_lit(out, constant, self);
        }
    }

    fn product_text(&self, names: &LeafNames, f: &[(LExpr, i32)], fma: bool, out: &mut String) {
        let mut first = true;
        for (b, p) in f.iter().filter(|(_, p)| *p > 0) {
            for _ in 0..*p {
                if !first {
                    out.push_str(" * ");
                }
                first = false;
                self.expr_text_with(names, b, true, fma, out);
            }
        }
        if first {
            out.push_str("1.0");
        }
        let den: usize = f
            .iter()
            .filter(|(_, p)| *p < 0)
            .map(|(_, p)| p.unsigned_abs() as usize)
            .sum();
        if den == 0 {
            return;
        }
        out.push_str(" / ");
        if den > 1 {
            out.push('(');
        }
        let mut first = true;
        for (b, p) in f.iter().filter(|(_, p)| *p < 0) {
            for _ in 0..p.unsigned_abs() {
                if !first {
                    out.push_str(" * ");
                }
                first = false;
                self.expr_text_with(names, b, true, fma, out);
            }
        }
        if den > 1 {
            out.push(')');
        }
    }
}

/// The statements `e` reads.
pub(super) fn locals_of(e: &LExpr, out: &mut Vec<usize>) {
    match e {
        LExpr::Leaf(Leaf::Local(i)) => out.push(*i),
        LExpr::Leaf(_) => {}
        LExpr::Sum { terms, .. } => terms.iter().for_each(|(_, t)| locals_of(t, out)),
        LExpr::Prod(f) => f.iter().for_each(|(b, _)| locals_of(b, out)),
    }
}

/// `|v|` as the literal of [`lit`] (the same text as its token).
fn push_lit(out: &mut String, v: f64, p: &Printer<'_>) {
    let _ = write!(out, "{}", lit(v, p.precision));
}

/// Whether a statement of `len` bytes stays on one line at indentation `indent`.
fn fits(indent: usize, len: usize) -> bool {
    len <= MARGIN.saturating_sub(indent).max(MIN_SPACE)
}

/// prettyplease's formatting of the statement `code` at indentation `indent` (a multiple of 4,
/// at least 4), one string per line with the indentation. `None` if `code` does not parse (a
/// generator bug, reported by the caller).
fn format_long(indent: usize, code: &str) -> Option<Vec<String>> {
    let depth = indent / 4;
    let mut src = String::from("fn f() {");
    for _ in 1..depth {
        src.push('{');
    }
    src.push_str(code);
    for _ in 0..depth {
        src.push('}');
    }
    let file: syn::File = syn::parse_str(&src).ok()?;
    let text = prettyplease::unparse(&file);
    let lines: Vec<&str> = text.lines().collect();
    let inner = lines.get(depth..lines.len().checked_sub(depth)?)?;
    Some(inner.iter().map(|l| (*l).to_owned()).collect())
}

/// A raw line at indentation `at`; a tuple pattern or value that does not fit (`let (k1, k2,
/// …) = {`, `(k1, k2, …)`) gets one name per line with a trailing comma, as rustfmt and
/// prettyplease break tuples.
fn push_raw(out: &mut String, at: usize, code: &str) {
    let pad = |out: &mut String, n: usize| out.extend(std::iter::repeat_n(' ', n));
    let split = code
        .find('(')
        .zip(code.rfind(')'))
        .filter(|_| !fits(at, code.len()));
    let Some((open, close)) = split else {
        pad(out, at);
        out.push_str(code);
        out.push('\n');
        return;
    };
    pad(out, at);
    out.push_str(&code[..=open]);
    out.push('\n');
    for name in code[open + 1..close].split(", ") {
        pad(out, at + 4);
        out.push_str(name);
        out.push_str(",\n");
    }
    pad(out, at);
    out.push_str(&code[close..]);
    out.push('\n');
}

/// The block number of a placeholder line (`__kanegen_block!(7);` → 7), if it is one.
fn placeholder_number(trimmed: &str) -> Option<usize> {
    trimmed
        .strip_prefix(PLACEHOLDER)?
        .strip_suffix(");")?
        .parse()
        .ok()
}

/// `src` (formatted) with every placeholder line replaced by its block, at the placeholder's
/// indentation. Errors name a statement that does not parse (a generator bug).
pub(super) fn splice(src: &str, blocks: &[Block]) -> Result<String, String> {
    let extra: usize = blocks.iter().map(|b| b.len_at(16)).sum();
    let mut out = String::with_capacity(src.len() + extra);
    for line in src.lines() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        let Some(block) = placeholder_number(trimmed).and_then(|n| blocks.get(n)) else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        for l in &block.lines {
            let at = indent + 4 * l.depth;
            if l.raw {
                push_raw(&mut out, at, &l.code);
                continue;
            }
            if fits(at, l.code.len()) {
                out.extend(std::iter::repeat_n(' ', at));
                out.push_str(&l.code);
            } else {
                let lines = format_long(at, &l.code)
                    .ok_or_else(|| format!("statement `{}` does not parse", l.code))?;
                out.push_str(&lines.join("\n"));
            }
            if !l.label.is_empty() {
                out.push_str(" // ");
                out.push_str(&l.label);
            }
            out.push('\n');
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
