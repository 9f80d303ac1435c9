//! Human-readable reports of a generation: `kanegen stats` (K/D and op counts per function) and
//! `kanegen listing` (the substitution listing in the reports' style).

use std::fmt::Write as _;

use crate::Generated;
use crate::expr::{Atom, ExprId, VarKind};
use crate::lower::Program;
use crate::lower::lanes::LanePlan;
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
        "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6} {:>6} {:>6}",
        "function",
        "K",
        "D",
        "temps",
        "adds",
        "muls",
        "divs",
        "sin/cos",
        "flops",
        "fma",
        "live",
        "lanes"
    );
    let mut row = |name: &str, p: &Program, lanes: Option<&LanePlan>| {
        let temps = p.stmts.len() - p.k_vars - p.d_vars;
        let lanes = lanes.map_or("-".to_owned(), |l| l.lane_pairs().to_string());
        let _ = writeln!(
            s,
            "{:<18} {:>6} {:>6} {:>6} {:>6} {:>6} {:>5} {:>8} {:>8} {:>6} {:>6} {:>6}",
            name,
            p.k_vars,
            p.d_vars,
            temps,
            p.ops.adds,
            p.ops.muls,
            p.ops.divs,
            p.ops.sincos,
            p.ops.flops(),
            p.ops.fmas,
            p.max_live(),
            lanes
        );
    };
    if d.options.params.is_runtime() {
        row("precompute (once)", &g.lowered.precompute, None);
    }
    for f in &g.lowered.functions {
        row(&f.program.name, &f.program, f.lanes.as_ref());
    }
    for c in &g.lowered.combined {
        row(&c.program.name, &c.program, None);
    }
    if let Some(l) = &g.lowered.derivative_loop {
        row("  looped: setup", &l.program, l.lanes.as_ref());
        let _ = writeln!(
            s,
            "  looped: loop     {} steps up, workspace {} values; {} flops in the loop (dense 4-wide transforms), {} in all (the emitted form)",
            l.plan.steps(),
            l.plan.workspace,
            l.plan.flops(),
            l.program.ops.flops() + l.plan.flops(),
        );
    }
    // What the loop-form regressors run instead of their straight-line rows above.
    for f in &g.lowered.functions {
        if let Some(lp) = &f.looped {
            let _ = writeln!(
                s,
                "{} runs in loop form: {} flops straight-line (every link's motion), {} (speed, body) pairs in a loop of {} flops: {} flops per call",
                f.id.name(),
                lp.program.ops.flops(),
                lp.tables.pairs(),
                lp.tables.flops(),
                lp.flops()
            );
        }
    }
    s.push_str(&base_parameters(g));
    s
}

/// The base parameters of the module's base regressors, in the reports' style: one line per
/// base parameter with its grouping (`XXR4l = XX4l - YY4l`), then the parameters that do not
/// act at all. Empty without base regressors.
pub fn base_parameters(g: &Generated) -> String {
    let mut s = String::new();
    let reg = &g.derivation.regressors;
    for (base, params, what) in [
        (&reg.base, &reg.inertial, "inverse-dynamics regressor"),
        (&reg.base_beta, &reg.beta, "gravity regressor"),
    ] {
        let Some(b) = base else { continue };
        let grouped = b.groups.iter().filter(|g| g.len() > 1).count();
        let _ = writeln!(
            s,
            "base parameters of the {what}: {} of {} ({} grouped, {} without effect; \
             rank of {} stacked random states, grouping checked on 10 others to {:.1e})",
            b.names.len(),
            params.len(),
            grouped,
            b.unidentifiable.len(),
            b.states,
            b.check_residual
        );
        let ex = &b.exactness;
        match &ex.skipped {
            Some(why) => {
                let _ = writeln!(
                    s,
                    "  coefficients: numbers for the model file's geometry (exact check skipped: {why})"
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "  coefficients: exact expressions of the geometry; {} of {} dependencies \
                     verified exactly (modular arithmetic, {} random points, every leaf random)",
                    ex.verified, ex.dependencies, ex.points
                );
            }
        }
        if !ex.numeric_only.is_empty() {
            let _ = writeln!(
                s,
                "  not exact (numbers for the model file's geometry, checked numerically above; \
                 rounded constants in the model, e.g. URDF origins and rpy rotations, defeat \
                 an exact check): {}",
                ex.numeric_only.join(" ")
            );
        }
        for (i, name) in b.names.iter().enumerate() {
            let text = match b.symbolic.get(i) {
                Some(group) => crate::kane::symbolic_group_text(&g.model, params, name, group),
                None => crate::kane::group_text(&g.model, params, name, &b.groups[i]),
            };
            let _ = writeln!(s, "  {text}");
        }
        if !b.unidentifiable.is_empty() {
            let names: Vec<&str> = b
                .unidentifiable
                .iter()
                .map(|&i| g.model.params[params[i]].name.as_str())
                .collect();
            let _ = writeln!(s, "  without effect: {}", names.join(" "));
        }
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
    let base = base_parameters(g);
    if !base.is_empty() {
        let _ = writeln!(s, "\n% ---- base parameters ----");
        for line in base.lines() {
            let _ = writeln!(s, "% {}", line.trim_start());
        }
    }
    s
}
