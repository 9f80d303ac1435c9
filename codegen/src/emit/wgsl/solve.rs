//! `fn solve(m, b) -> x`: `M x = b` by an unrolled Cholesky factorisation `M = L Lᵀ` and two
//! triangular solves, every entry of `L` a named value in registers. Entries that are zero in
//! the mass matrix's program and stay zero in `L` (no fill-in) are left out at generation
//! time.

use std::fmt::Write as _;

use super::print::Float;
use crate::lower::Program;

/// Appends `fn solve(m: array<T, E>, b: array<T, n>) -> array<T, n>` for the mass matrix
/// program `mass` (outputs: its upper triangle `(row ≤ col)`, in program order).
// Index loops over the triangle of L read as the formulas are written.
#[allow(clippy::needless_range_loop)]
pub(super) fn cholesky(mass: &Program, n: usize, float: Float, out: &mut String) {
    let ty = float.ty();
    let entries = mass.outputs.len().max(1);
    // index[r][c] (r ≥ c): the program output of M[r][c], if any.
    let mut index = vec![vec![None; n]; n];
    for (k, (r, c, _)) in mass.outputs.iter().enumerate() {
        let (hi, lo) = if r >= c { (*r, *c) } else { (*c, *r) };
        index[hi][lo] = Some(k);
    }
    // nonzero[i][j] (i ≥ j): L[i][j] may be nonzero.
    let mut nonzero = vec![vec![false; n]; n];
    writeln!(
        out,
        "\n// M x = b by M = L Lᵀ, unrolled; l_i_j = L[i][j], inv_j = 1 / L[j][j].
fn solve(m: array<{ty}, {entries}>, b: array<{ty}, {n}>) -> array<{ty}, {n}> {{"
    )
    .expect("string");
    let one = float.lit(1.0).expect("one");
    for j in 0..n {
        for i in j..n {
            let ks: Vec<usize> = (0..j).filter(|&k| nonzero[i][k] && nonzero[j][k]).collect();
            let a = index[i][j].map(|k| format!("m[{k}]"));
            if a.is_none() && ks.is_empty() && i != j {
                continue;
            }
            nonzero[i][j] = true;
            let mut e = a.unwrap_or_else(|| float.lit(0.0).expect("zero"));
            for k in ks {
                write!(e, " - l_{i}_{k} * l_{j}_{k}").expect("string");
            }
            if i == j {
                writeln!(
                    out,
                    "    let l_{j}_{j} = sqrt({e});\n    let inv_{j} = {one} / l_{j}_{j};"
                )
                .expect("string");
            } else {
                writeln!(out, "    let l_{i}_{j} = ({e}) * inv_{j};").expect("string");
            }
        }
    }
    // L y = b, then Lᵀ x = y.
    for i in 0..n {
        let mut e = format!("b[{i}]");
        for k in (0..i).filter(|&k| nonzero[i][k]) {
            write!(e, " - l_{i}_{k} * y_{k}").expect("string");
        }
        writeln!(out, "    let y_{i} = ({e}) * inv_{i};").expect("string");
    }
    for i in (0..n).rev() {
        let mut e = format!("y_{i}");
        for k in (i + 1..n).filter(|&k| nonzero[k][i]) {
            write!(e, " - l_{k}_{i} * x_{k}").expect("string");
        }
        writeln!(out, "    let x_{i} = ({e}) * inv_{i};").expect("string");
    }
    let xs: Vec<String> = (0..n).map(|i| format!("x_{i}")).collect();
    writeln!(out, "    return array<{ty}, {n}>({});\n}}", xs.join(", ")).expect("string");
}
