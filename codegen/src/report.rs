//! Human-readable reports of a generation: `kanegen stats` (K/D and op counts per function) and
//! `kanegen listing` (the substitution listing in the reports' style).

use std::fmt::Write as _;

use crate::Generated;
use crate::expr::{Atom, ExprId, VarKind};
use crate::lower::Program;
use crate::registry::{Dim, Shape};

/// A per-function summary: K/D counts and op counts, as printed by `kanegen stats`.
pub fn stats(g: &Generated) -> String {
    let mut s = String::new();
    let d = &g.derivation;
    let vars = d.arena.vars();
    let k = vars.iter().filter(|v| v.kind == VarKind::K).count();
    let _ = writeln!(
        s,
        "model {} ({}): {} speeds, {} bodies, {} parameters; parameters {}",
        g.model.name,
        g.model.source,
        g.model.independent_dof(),
        g.model.body_count(),
        g.model.params.len(),
        if d.options.params.is_runtime() {
            "at run time"
        } else {
            "baked"
        }
    );
    let _ = writeln!(
        s,
        "derivation: {} expression nodes, {} substitution variables ({} K, {} D)",
        d.arena.len(),
        vars.len(),
        k,
        vars.len() - k
    );
    let _ = writeln!(
        s,
        "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6}",
        "function", "K", "D", "temps", "adds", "muls", "divs", "sin/cos", "flops", "live"
    );
    let mut row = |name: &str, p: &Program| {
        let temps = p.stmts.len() - p.k_vars - p.d_vars;
        let _ = writeln!(
            s,
            "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6}",
            name,
            p.k_vars,
            p.d_vars,
            temps,
            p.ops.adds,
            p.ops.muls,
            p.ops.divs,
            p.ops.sincos,
            p.ops.flops(),
            p.max_live()
        );
    };
    if d.options.params.is_runtime() {
        row("precompute (once)", &g.lowered.precompute);
    }
    for f in &g.lowered.functions {
        row(&f.program.name, &f.program);
    }
    s
}

/// The substitution listing of a model in the reports' style, function by function.
pub fn listing(g: &Generated) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "% Substitution listing of `{}` (kanegen {}). K: kinematic, D: inertial/gravity.",
        g.model.name,
        crate::emit::GENERATOR_VERSION
    );
    let d = &g.derivation;
    let mut shown = vec![false; d.arena.vars().len()];
    for f in &d.functions {
        let spec = f.id.spec();
        let roots: Vec<ExprId> = f.entries.iter().map(|e| e.2).collect();
        let needed = d.arena.reachable_vars(&roots);
        match f.frame {
            Some(l) => writeln!(s, "\n% ---- {} [{}] ----", spec.name, d.frame_names[l]),
            None => writeln!(s, "\n% ---- {} ----", spec.name),
        }
        .expect("writing to a String");
        for (i, info) in d.arena.vars().iter().enumerate() {
            if needed[i] && !shown[i] {
                shown[i] = true;
                let _ = writeln!(
                    s,
                    "{} = {};  % {}",
                    d.arena.atom_name(Atom::Var(i as u32)),
                    d.arena.display(info.def),
                    info.label
                );
            }
        }
        for &(r, c, e) in &f.entries {
            let lhs = match spec.shape {
                Shape::Scalar => spec.symbol.to_owned(),
                Shape::Vector
                | Shape::Dense {
                    cols: Dim::Fixed(1),
                    ..
                } => format!("{}({})", spec.symbol, r + 1),
                _ => format!("{}({},{})", spec.symbol, r + 1, c + 1),
            };
            let _ = writeln!(s, "{lhs} = {};", d.arena.display(e));
        }
    }
    s
}
