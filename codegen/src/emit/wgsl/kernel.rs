//! The WGSL module of one float type: the bindings, the per-invocation state, one `_eval`
//! function and one compute entry point per lowered registry function, the `precompute` entry
//! point (parameter-only values, once per parameter set), and, where the module has the mass
//! matrix and the velocity and gravity terms, `forward_dynamics` (an unrolled Cholesky solve
//! in registers) and `rollout` (semi-implicit Euler steps on the device).

use std::fmt::Write as _;

use super::print::{BadConstant, Float, Mimic, body, sin_cos_fn};
use crate::lower::{FunctionProgram, Lowered, Program};
use crate::registry::{FunctionId, Inputs, Shape};

/// Invocations per workgroup of every per-state entry point.
pub const WORKGROUP_SIZE: u32 = 64;

/// One per-state entry point: its name, inputs and dense result size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Entry {
    /// The entry point's name (the Rust function's: `mass_matrix`, `frame_pose_tool`).
    pub(super) name: String,
    /// Its state inputs.
    pub(super) inputs: Inputs,
    /// Rows of the dense result.
    pub(super) rows: usize,
    /// Columns of the dense result.
    pub(super) cols: usize,
}

/// What the kernels of a module are made from.
pub(super) struct Source<'a> {
    /// The lowered programs.
    pub(super) low: &'a Lowered,
    /// The functions that get kernels (those of `low.functions` in the selected set).
    pub(super) functions: Vec<&'a FunctionProgram>,
    /// The entry point of each of `functions`, in order.
    pub(super) entries: Vec<Entry>,
    /// The dependent speeds.
    pub(super) mimics: Vec<Mimic>,
    /// Number of speeds, dependent ones included (the state arrays' length).
    pub(super) speeds: usize,
    /// The programs whose sum is the bias `h = c + g` of forward dynamics, and the mass
    /// matrix's program: `None` when the module lacks them.
    pub(super) dynamics: Option<(usize, Vec<usize>)>,
}

impl Source<'_> {
    /// The index in `functions` of the function `id` (no frame).
    fn find(functions: &[&FunctionProgram], id: FunctionId) -> Option<usize> {
        functions
            .iter()
            .position(|f| f.id == id && f.frame.is_none())
    }

    /// The programs forward dynamics reads: M and h = c + g, from `nonlinear_effects`, from
    /// `coriolis` and `gravity`, or from `inverse_dynamics` at zero acceleration.
    pub(super) fn dynamics_of(fs: &[&FunctionProgram]) -> Option<(usize, Vec<usize>)> {
        let m = Self::find(fs, FunctionId::MassMatrix)?;
        let bias = if let Some(h) = Self::find(fs, FunctionId::NonlinearEffects) {
            vec![h]
        } else if let (Some(c), Some(g)) = (
            Self::find(fs, FunctionId::Coriolis),
            Self::find(fs, FunctionId::Gravity),
        ) {
            vec![c, g]
        } else {
            vec![Self::find(fs, FunctionId::InverseDynamics)?]
        };
        Some((m, bias))
    }
}

/// The WGSL module of `src` in `float`.
pub(super) fn module(src: &Source<'_>, float: Float) -> Result<String, BadConstant> {
    let ty = float.ty();
    let n = src.low.dof;
    let ns = src.speeds.max(1);
    let mut out = String::new();
    writeln!(
        out,
        "// Bindings shared by every entry point (one bind group, one pipeline layout).
struct Batch {{
    count: u32,
    stride: u32,
    steps: u32,
    record: u32,
    dt: f32,
    dt_lo: f32,
    pad0: u32,
    pad1: u32,
}}

@group(0) @binding(0) var<storage, read> params: array<{ty}>;
@group(0) @binding(1) var<storage, read_write> pre: array<{ty}>;
@group(0) @binding(2) var<uniform> batch: Batch;
@group(0) @binding(3) var<storage, read> in_q: array<{ty}>;
@group(0) @binding(4) var<storage, read> in_u: array<{ty}>;
@group(0) @binding(5) var<storage, read> in_x: array<{ty}>;
@group(0) @binding(6) var<storage, read_write> out: array<{ty}>;

// One state: coordinates, speeds, accelerations, and the sines and cosines of the joint
// angles (computed once per state, dependent joints' from their masters).
struct State {{
    q: array<{ty}, {ns}>,
    u: array<{ty}, {ns}>,
    a: array<{ty}, {ns}>,
    s: array<{ty}, {ns}>,
    c: array<{ty}, {ns}>,
}}
"
    )
    .expect("string");
    out.push_str(&sin_cos_fn(float));
    precompute(src, float, &mut out)?;
    for (f, e) in src.functions.iter().zip(&src.entries) {
        writeln!(
            out,
            "\nfn {}_eval(st: State) -> array<{ty}, {}> {{",
            e.name,
            outputs(&f.program)
        )
        .expect("string");
        body(&f.program, float, &src.mimics, "    ", &mut out)?;
        out.push_str("}\n");
        entry_point(src, f, e, float, &mut out)?;
    }
    if let Some((m, bias)) = &src.dynamics {
        super::solve::cholesky(&src.functions[*m].program, n, float, &mut out);
        forward_dynamics(src, *m, bias, float, &mut out)?;
    }
    Ok(out)
}

/// The number of entries a program's `_eval` returns (at least one).
fn outputs(p: &Program) -> usize {
    p.outputs.len().max(1)
}

/// `@compute fn precompute()`: the parameter-only values into `pre`, once per parameter set.
fn precompute(src: &Source<'_>, float: Float, out: &mut String) -> Result<(), BadConstant> {
    let p = &src.low.precompute;
    out.push_str("\n// The parameter-only values, once per parameter set (one invocation).\n");
    out.push_str("@compute @workgroup_size(1)\nfn precompute() {\n");
    let mut slots = p.clone();
    slots.outputs.clear();
    let mut text = String::new();
    body(&slots, float, &src.mimics, "    ", &mut text)?;
    // The statements without the `return` line `body` ends with.
    for line in text
        .lines()
        .filter(|l| !l.trim_start().starts_with("return "))
    {
        writeln!(out, "{line}").expect("string");
    }
    for (k, &i) in src.low.pre_slots.iter().enumerate() {
        writeln!(out, "    pre[{k}] = {};", p.stmts[i].name).expect("string");
    }
    out.push_str("}\n");
    Ok(())
}

/// The statements that load state `i`'s inputs (`q` always, `u`, `a` as `inputs` says) into
/// `var st: State` and compute the sines and cosines of the angles `sincos`.
fn load_state(
    src: &Source<'_>,
    inputs: Inputs,
    sincos: &[usize],
    float: Float,
    out: &mut String,
) -> Result<(), BadConstant> {
    out.push_str("    var st: State;\n");
    for j in 0..src.low.dof {
        writeln!(out, "    st.q[{j}] = in_q[{j}u * batch.stride + i];").expect("string");
    }
    if inputs.needs_u() {
        for j in 0..src.low.dof {
            writeln!(out, "    st.u[{j}] = in_u[{j}u * batch.stride + i];").expect("string");
        }
    }
    if inputs.needs_ud() {
        for j in 0..src.low.dof {
            writeln!(out, "    st.a[{j}] = in_x[{j}u * batch.stride + i];").expect("string");
        }
    }
    trig(src, sincos, float, out)
}

/// `st.s[k]`, `st.c[k]` for every angle of `sincos`, one `sin_cos` call each.
fn trig(
    src: &Source<'_>,
    sincos: &[usize],
    float: Float,
    out: &mut String,
) -> Result<(), BadConstant> {
    for &s in sincos {
        let angle = match src.mimics.iter().find(|m| m.speed == s) {
            None => format!("st.q[{s}]"),
            Some(m) => {
                let lit = |v| float.lit(v).ok_or(BadConstant(v));
                format!(
                    "{} * st.q[{}] + {}",
                    lit(m.multiplier)?,
                    m.master,
                    lit(m.offset)?
                )
            }
        };
        writeln!(
            out,
            "    let sc{s} = sin_cos({angle});\n    st.s[{s}] = sc{s}.x;\n    st.c[{s}] = sc{s}.y;"
        )
        .expect("string");
    }
    Ok(())
}

/// The header of a per-state entry point up to the bounds check.
fn entry_head(name: &str, out: &mut String) {
    writeln!(
        out,
        "\n@compute @workgroup_size({WORKGROUP_SIZE})
fn {name}(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i >= batch.count) {{
        return;
    }}"
    )
    .expect("string");
}

/// The entry point of one function: load, evaluate, store the dense result row-major, entry
/// `k` of state `i` at `out[k * stride + i]` (both triangles of a symmetric matrix, zeros
/// where the program has no entry).
fn entry_point(
    src: &Source<'_>,
    f: &FunctionProgram,
    e: &Entry,
    float: Float,
    out: &mut String,
) -> Result<(), BadConstant> {
    entry_head(&e.name, out);
    load_state(src, e.inputs, &f.program.sincos, float, out)?;
    writeln!(out, "    let r = {}_eval(st);", e.name).expect("string");
    let symmetric = f.id.spec().shape == Shape::SymmetricMatrix;
    let mut dense: Vec<Option<usize>> = vec![None; e.rows * e.cols];
    for (k, (r, c, _)) in f.program.outputs.iter().enumerate() {
        dense[r * e.cols + c] = Some(k);
        if symmetric {
            dense[c * e.cols + r] = Some(k);
        }
    }
    let zero = float.lit(0.0).expect("zero");
    for (k, d) in dense.iter().enumerate() {
        match d {
            Some(j) => writeln!(out, "    out[{k}u * batch.stride + i] = r[{j}];"),
            None => writeln!(out, "    out[{k}u * batch.stride + i] = {zero};"),
        }
        .expect("string");
    }
    out.push_str("}\n");
    Ok(())
}

/// `fn forward_dynamics_eval(st, tau)`, the `forward_dynamics` entry point (`u̇` from `q`,
/// `u`, `τ`) and the `rollout` entry point.
fn forward_dynamics(
    src: &Source<'_>,
    m: usize,
    bias: &[usize],
    float: Float,
    out: &mut String,
) -> Result<(), BadConstant> {
    let ty = float.ty();
    let n = src.low.dof;
    let fs = &src.functions;
    let mut sincos: Vec<usize> = std::iter::once(m)
        .chain(bias.iter().copied())
        .flat_map(|k| fs[k].program.sincos.iter().copied())
        .collect();
    sincos.sort_unstable();
    sincos.dedup();
    // u̇ = M⁻¹ (τ − h); the state's sines and cosines are computed by the caller.
    writeln!(
        out,
        "\nfn forward_dynamics_eval(st: State, tau: array<{ty}, {n}>) -> array<{ty}, {n}> {{"
    )
    .expect("string");
    writeln!(out, "    let m = {}_eval(st);", src.entries[m].name).expect("string");
    for (j, &b) in bias.iter().enumerate() {
        writeln!(out, "    let h{j} = {}_eval(st);", src.entries[b].name).expect("string");
    }
    // Each bias program's outputs are (row, 0) entries of a vector.
    let mut rhs: Vec<String> = (0..n).map(|j| format!("tau[{j}]")).collect();
    for (j, &b) in bias.iter().enumerate() {
        for (k, (r, _, _)) in fs[b].program.outputs.iter().enumerate() {
            write!(rhs[*r], " - h{j}[{k}]").expect("string");
        }
    }
    writeln!(
        out,
        "    return solve(m, array<{ty}, {n}>({}));\n}}",
        rhs.join(", ")
    )
    .expect("string");

    entry_head("forward_dynamics", out);
    load_state(src, Inputs::QU, &sincos, float, out)?;
    writeln!(out, "    var tau: array<{ty}, {n}>;").expect("string");
    for j in 0..n {
        writeln!(out, "    tau[{j}] = in_x[{j}u * batch.stride + i];").expect("string");
    }
    out.push_str("    let ud = forward_dynamics_eval(st, tau);\n");
    for j in 0..n {
        writeln!(out, "    out[{j}u * batch.stride + i] = ud[{j}];").expect("string");
    }
    out.push_str("}\n");

    // Rollouts: `batch.steps` steps of semi-implicit Euler (u += dt·u̇, then q += dt·u) with
    // the generalized forces of step k of state i at in_x[(k·N + j)·stride + i]; the state
    // after every step (`record` = 1: q then u, 2N entries per step) or after the last one.
    let dt = match float {
        Float::F32 => "batch.dt".to_owned(),
        Float::F64 => "f64(batch.dt) + f64(batch.dt_lo)".to_owned(),
    };
    entry_head("rollout", out);
    writeln!(
        out,
        "    let dt = {dt};\n    var q: array<{ty}, {n}>;\n    var u: array<{ty}, {n}>;"
    )
    .expect("string");
    for j in 0..n {
        writeln!(out, "    q[{j}] = in_q[{j}u * batch.stride + i];\n    u[{j}] = in_u[{j}u * batch.stride + i];").expect("string");
    }
    writeln!(
        out,
        "    for (var k = 0u; k < batch.steps; k++) {{\n    var st: State;"
    )
    .expect("string");
    for j in 0..n {
        writeln!(out, "    st.q[{j}] = q[{j}];\n    st.u[{j}] = u[{j}];").expect("string");
    }
    trig(src, &sincos, float, out)?;
    writeln!(
        out,
        "    var tau: array<{ty}, {n}>;\n    let base = k * {n}u;"
    )
    .expect("string");
    for j in 0..n {
        writeln!(
            out,
            "    tau[{j}] = in_x[(base + {j}u) * batch.stride + i];"
        )
        .expect("string");
    }
    out.push_str("    let ud = forward_dynamics_eval(st, tau);\n");
    for j in 0..n {
        writeln!(
            out,
            "    u[{j}] = u[{j}] + dt * ud[{j}];\n    q[{j}] = q[{j}] + dt * u[{j}];"
        )
        .expect("string");
    }
    writeln!(
        out,
        "    if (batch.record == 1u) {{\n    let at = k * {}u;",
        2 * n
    )
    .expect("string");
    for j in 0..n {
        writeln!(
            out,
            "    out[(at + {j}u) * batch.stride + i] = q[{j}];\n    out[(at + {}u) * batch.stride + i] = u[{j}];",
            n + j
        )
        .expect("string");
    }
    out.push_str("    }\n    }\n    if (batch.record != 1u) {\n");
    for j in 0..n {
        writeln!(
            out,
            "    out[{j}u * batch.stride + i] = q[{j}];\n    out[{}u * batch.stride + i] = u[{j}];",
            n + j
        )
        .expect("string");
    }
    out.push_str("    }\n}\n");
    Ok(())
}
