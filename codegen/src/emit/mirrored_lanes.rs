//! The statement block of a function whose statements are paired (arms in lanes, see
//! [`crate::lower::lanes`]): each lane pair printed once over `F64x2`, the left subtree's
//! expression with every leaf that differs between the subtrees given in both lanes:
//!
//! ```text
//! let d275_d7 = lanes.mul_add(-d272_d4, F64x2::new(s_q6l, s_q6r), F64x2::new(p.ZZ10l, p.ZZ10r) * F64x2::new(c_q6l, c_q6r)); // N(M col 10l) at 8l.y | N(M col 10r) at 8r.y
//! let d275 = d275_d7.lo();
//! let d7 = d275_d7.hi();
//! ```
//!
//! Shared values (the trunk's statements, shared parameters, constants) are `f64` operands,
//! applied to both lanes. A lane's scalar is taken out (`.lo()`, `.hi()`) only where a scalar
//! statement or a result entry reads it; a packed pair (two scalar statements that lane
//! statements read) is put in lanes right after the later of the two.

use super::print::Printer;
use super::text::{Block, LeafNames, locals_of as reads};
use crate::lower::mirrored_lanes::{LaneLeaves, LanePlan, Role};
use crate::lower::{Leaf, Program};

/// The name of the lane value of the pair `(left, right)`: `d5_d90`.
fn lane_name(p: &Program, left: usize, right: usize) -> String {
    format!("{}_{}", p.stmts[left].name, p.stmts[right].name)
}

/// The block of `p`'s statements in two lanes by `plan` (see the module docs), with
/// `after[0]` before the first statement and `after[i + 1]` right after statement `i` (the
/// stores of [`Printer::statement_block`]).
pub(super) fn lane_block(
    printer: &Printer<'_>,
    names: &LeafNames,
    leaves: &LaneLeaves,
    p: &Program,
    plan: &LanePlan,
    after: Vec<Vec<String>>,
) -> Block {
    let n = p.stmts.len();
    // The pair and the lane of every paired statement: (left, right, is it the high lane).
    let mut packed_pair = vec![None; n];
    for &(l, r) in &plan.packed {
        packed_pair[l] = Some((l, r, false));
        packed_pair[r] = Some((l, r, true));
    }
    let pair_of = |k: usize| -> Option<(usize, usize, bool)> {
        match plan.roles[k] {
            Role::Left => Some((k, k + 1, false)),
            Role::Right => Some((k - 1, k, true)),
            Role::Scalar => packed_pair[k],
        }
    };
    // Which statements a scalar reads (so their lane values are taken out), and which packed
    // pairs a lane statement reads (so they are formed).
    let mut scalar_read = vec![false; n];
    let mut pack_read = vec![false; n];
    let mut buf = Vec::new();
    for (k, s) in p.stmts.iter().enumerate() {
        buf.clear();
        reads(&s.expr, &mut buf);
        match plan.roles[k] {
            Role::Scalar => buf.iter().for_each(|&r| scalar_read[r] = true),
            Role::Left => buf.iter().for_each(|&r| {
                if let Some((l, _, _)) = pair_of(r) {
                    pack_read[l] = true;
                }
            }),
            Role::Right => {}
        }
    }
    for (_, _, e) in &p.outputs {
        buf.clear();
        reads(e, &mut buf);
        buf.iter().for_each(|&r| scalar_read[r] = true);
    }
    // Packed pairs, formed after the later of their two statements.
    let mut packs_after: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    for &(l, r) in &plan.packed {
        if pack_read[l] {
            packs_after[l.max(r)].push((l, r));
        }
    }
    let plain_leaf = |l: &Leaf| {
        let mut s = String::new();
        printer.leaf_text(names, l, &mut s);
        s
    };
    let lane_leaf = |l: &Leaf| -> Option<String> {
        match *l {
            Leaf::Local(k) => {
                let (left, right, high) = pair_of(k)?;
                let name = lane_name(p, left, right);
                Some(if high { format!("{name}.swap()") } else { name })
            }
            Leaf::Const(_) => None,
            other => {
                let m = leaves.leaf(other)?;
                (m != other)
                    .then(|| format!("F64x2::new({}, {})", plain_leaf(&other), plain_leaf(&m)))
            }
        }
    };
    let lane_printer = Printer {
        lane: Some(&lane_leaf),
        ..*printer
    };
    let mut block = Block::default();
    let mut after = after.into_iter();
    for code in after.next().unwrap_or_default() {
        block.push(code, "");
    }
    let mut code = String::new();
    let mut k = 0;
    while k < n {
        let s = &p.stmts[k];
        code.clear();
        let last = if plan.roles[k] == Role::Left {
            let right = &p.stmts[k + 1];
            let name = lane_name(p, k, k + 1);
            code.push_str(&format!("let {name} = "));
            lane_printer.expr_text_with(names, &s.expr, false, true, &mut code);
            code.push(';');
            let label = if right.comment == s.comment {
                s.comment.clone()
            } else {
                format!("{} | {}", s.comment, right.comment)
            };
            block.push(code.clone(), &label);
            for (j, lane) in [(k, "lo"), (k + 1, "hi")] {
                if scalar_read[j] {
                    let scalar = &p.stmts[j].name;
                    block.push(format!("let {scalar} = {name}.{lane}();"), "");
                }
            }
            for store in after.next().unwrap_or_default() {
                block.push(store, "");
            }
            k + 1
        } else {
            code.push_str(&format!("let {} = ", s.name));
            printer.expr_text_with(names, &s.expr, false, true, &mut code);
            code.push(';');
            block.push(code.clone(), &s.comment);
            k
        };
        for store in after.next().unwrap_or_default() {
            block.push(store, "");
        }
        for packs in &packs_after[k..=last] {
            for &(l, r) in packs {
                let (ln, rn) = (&p.stmts[l].name, &p.stmts[r].name);
                block.push(
                    format!("let {} = F64x2::new({ln}, {rn});", lane_name(p, l, r)),
                    "",
                );
            }
        }
        k = last + 1;
    }
    block
}

#[cfg(test)]
mod tests;
