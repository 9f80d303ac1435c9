//! The Rust side of the Pinocchio comparison (`benches/pinocchio/run.sh`, docs/performance.md): writes Krang (`models/krang.toml`) as a Pinocchio tree with test cases, times the
//! generated functions, and prints the combined table.
//!
//! ```sh
//! cargo run --release --example pinocchio_side_by_side -- write DIR   # DIR/cases.txt
//! cargo run --release --example pinocchio_side_by_side -- time DIR    # appends DIR/kanegen-times.txt
//! cargo run --release --example pinocchio_side_by_side -- report DIR  # table from both time files
//! cargo run --release --example pinocchio_side_by_side -- export MODEL FILE  # any model, defaults
//! ```
//!
//! `export` writes any description (TOML, or URDF with the default import options) with its
//! default parameters in the `kanegen::pinocchio` text format, for use with one's own harness.
//!
//! `cases.txt` holds [`CASES`] cases, each one parameter set (case 0: the defaults of
//! `krang.toml`, then random physical parameters), the model exported for it by
//! `kanegen::pinocchio` (text format in that module's documentation), one random state `q, u, u̇`
//! and the generated code's `M, c, g, τ, C, ∂τ/∂q, ∂τ/∂u` for it (shortest round-trip decimals,
//! exact):
//!
//! ```text
//! cases <n> dof <dof>
//! case <i>
//! <the model in the kanegen-pinocchio text format, ending with `end`>
//! q <dof numbers>    u …    ud …
//! M <dof² numbers, by rows>    c …    g …    tau …    C <dof², by rows>
//! dtau_dq <dof², by rows>    dtau_du <dof², by rows>
//! fd <dof numbers: the generated forward dynamics u̇ = FD(q, u, τ) of that τ>
//! ```
//!
//! The C++ harness (`benches/pinocchio/harness.cpp`) builds a `pinocchio::Model` per case,
//! compares, and times Pinocchio with case 0's parameters on the states of all cases (and, when
//! `run.sh` is given `CODEGEN=1`, `benches/pinocchio/codegen.cpp` does the same for Pinocchio's
//! CppADCodeGen code); `time` times the generated code (`krang_dynamics::Krang`, runtime
//! parameters, the workspace's features: the Coriolis matrix and the derivatives among them) in
//! the same way: per function, [`ROUNDS`] rounds of [`CALLS`] calls cycling
//! through the states, the fastest round's mean ns per call. Each run appends one line per
//! function (`name ns`) to the times files; `report` takes the smallest figure of each.
#![forbid(unsafe_code)]

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[path = "support/times.rs"]
mod times;

use kanegen_model::Model;
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use krang_dynamics::{Krang, Params};
use nalgebra::{SMatrix, SVector};
use times::{append, best_times};

/// Number of cases (parameter sets with one state each).
const CASES: usize = 100;
/// Calls per timing round.
const CALLS: usize = 2000;
/// Timing rounds per function (the fastest counts).
const ROUNDS: usize = 200;

type V = SVector<f64, 19>;

/// One case: parameter values (indexed like `Model::params`) and a state.
struct Case {
    params: Vec<f64>,
    q: Vec<f64>,
    u: Vec<f64>,
    ud: Vec<f64>,
}

fn krang_model() -> Result<Model, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/krang.toml");
    Model::from_toml_file(&path).map_err(|e| e.to_string())
}

/// The cases: deterministic (seeded), so `write` and `time` see the same states.
fn cases(model: &Model) -> Vec<Case> {
    let mut rng = SplitMix64::new(2026);
    let mut uniform = move || rng.next_f64();
    let n = model.dof();
    (0..CASES)
        .map(|i| {
            let params = if i == 0 {
                model.param_values()
            } else {
                random_physical_params(model, &mut uniform)
            };
            Case {
                params,
                q: uniform_vec(&mut uniform, n, -std::f64::consts::PI, std::f64::consts::PI),
                u: uniform_vec(&mut uniform, n, -2.0, 2.0),
                ud: uniform_vec(&mut uniform, n, -5.0, 5.0),
            }
        })
        .collect()
}

fn krang(params: &[f64]) -> Result<Krang, String> {
    let array: [f64; 185] = params
        .try_into()
        .map_err(|_| format!("{} parameters, Krang has 185", params.len()))?;
    Ok(Krang::new(Params::from_array(array)))
}

fn line(out: &mut String, tag: &str, xs: impl IntoIterator<Item = f64>) {
    out.push_str(tag);
    for x in xs {
        let _ = write!(out, " {x:?}");
    }
    out.push('\n');
}

fn rows(m: &SMatrix<f64, 19, 19>) -> impl Iterator<Item = f64> + '_ {
    (0..19).flat_map(move |r| (0..19).map(move |c| m[(r, c)]))
}

fn write(dir: &Path) -> Result<(), String> {
    let model = krang_model()?;
    let mut out = format!("cases {CASES} dof {}\n", model.dof());
    for (i, case) in cases(&model).iter().enumerate() {
        let pm = kanegen::pinocchio::export(&model, &case.params).map_err(|e| e.to_string())?;
        let k = krang(&case.params)?;
        let (q, u, ud) = (
            V::from_column_slice(&case.q),
            V::from_column_slice(&case.u),
            V::from_column_slice(&case.ud),
        );
        let _ = writeln!(out, "case {i}");
        out.push_str(&pm.to_text());
        line(&mut out, "q", case.q.iter().copied());
        line(&mut out, "u", case.u.iter().copied());
        line(&mut out, "ud", case.ud.iter().copied());
        line(&mut out, "M", rows(&k.mass_matrix(&q)));
        line(&mut out, "c", k.coriolis(&q, &u).iter().copied());
        line(&mut out, "g", k.gravity(&q).iter().copied());
        let tau = k.inverse_dynamics(&q, &u, &ud);
        line(&mut out, "tau", tau.iter().copied());
        line(&mut out, "C", rows(&k.coriolis_matrix(&q, &u)));
        let (dq, du) = k.inverse_dynamics_partials(&q, &u, &ud);
        line(&mut out, "dtau_dq", rows(&dq));
        line(&mut out, "dtau_du", rows(&du));
        line(
            &mut out,
            "fd",
            k.forward_dynamics(&q, &u, &tau).iter().copied(),
        );
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join("cases.txt");
    std::fs::write(&path, out).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {} ({CASES} cases)", path.display());
    Ok(())
}

/// The fastest round's ns per call of `f` over the states.
fn time_one(states: &[(V, V, V)], mut f: impl FnMut(&V, &V, &V)) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..ROUNDS {
        let start = Instant::now();
        for i in 0..CALLS {
            let (q, u, ud) = &states[i % states.len()];
            f(black_box(q), black_box(u), black_box(ud));
        }
        best = best.min(start.elapsed().as_nanos() as f64 / CALLS as f64);
    }
    best
}

fn time(dir: &Path) -> Result<(), String> {
    let model = krang_model()?;
    let all = cases(&model);
    let k = krang(&all[0].params)?;
    let states: Vec<(V, V, V)> = all
        .iter()
        .map(|c| {
            (
                V::from_column_slice(&c.q),
                V::from_column_slice(&c.u),
                V::from_column_slice(&c.ud),
            )
        })
        .collect();
    // Forward dynamics of each state's τ = ID(q, u, u̇) (the harness solves the same).
    let fd_states: Vec<(V, V, V)> = states
        .iter()
        .map(|(q, u, ud)| (*q, *u, k.inverse_dynamics(q, u, ud)))
        .collect();
    let k = &k;
    // The `_into` forms write into a matrix the caller keeps, as Pinocchio writes `data.M`, `data.C`.
    let (mut m_out, mut c_out, mut d_out) = (
        SMatrix::<f64, 19, 19>::zeros(),
        SMatrix::<f64, 19, 19>::zeros(),
        SMatrix::<f64, 19, 38>::zeros(),
    );
    // And the derivatives into a workspace kept across calls, as Pinocchio keeps `data`.
    let mut d_ws = krang_dynamics::DerivativesWorkspace::new();
    let mut fd_ws = krang_dynamics::ForwardDynamicsDerivativesWorkspace::new();
    let results = [
        (
            "mass_matrix",
            time_one(&states, |q, _, _| {
                black_box(black_box(k).mass_matrix(q));
            }),
        ),
        (
            "coriolis",
            time_one(&states, |q, u, _| {
                black_box(black_box(k).coriolis(q, u));
            }),
        ),
        (
            "gravity",
            time_one(&states, |q, _, _| {
                black_box(black_box(k).gravity(q));
            }),
        ),
        (
            "inverse_dynamics",
            time_one(&states, |q, u, ud| {
                black_box(black_box(k).inverse_dynamics(q, u, ud));
            }),
        ),
        (
            "coriolis_matrix",
            time_one(&states, |q, u, _| {
                black_box(black_box(k).coriolis_matrix(q, u));
            }),
        ),
        (
            "mass_matrix_into",
            time_one(&states, |q, _, _| {
                black_box(k).mass_matrix_into(q, black_box(&mut m_out));
            }),
        ),
        (
            "coriolis_matrix_into",
            time_one(&states, |q, u, _| {
                black_box(k).coriolis_matrix_into(q, u, black_box(&mut c_out));
            }),
        ),
        (
            "inverse_dynamics_derivatives",
            time_one(&states, |q, u, ud| {
                black_box(black_box(k).inverse_dynamics_derivatives(q, u, ud));
            }),
        ),
        (
            "inverse_dynamics_derivatives_into",
            time_one(&states, |q, u, ud| {
                black_box(k).inverse_dynamics_derivatives_into(q, u, ud, black_box(&mut d_out));
            }),
        ),
        (
            "inverse_dynamics_derivatives_with",
            time_one(&states, |q, u, ud| {
                black_box(black_box(k).inverse_dynamics_derivatives_with(
                    q,
                    u,
                    ud,
                    black_box(&mut d_ws),
                ));
            }),
        ),
        (
            "forward_dynamics",
            time_one(&fd_states, |q, u, tau| {
                black_box(black_box(k).forward_dynamics(q, u, tau));
            }),
        ),
        (
            "forward_dynamics_derivatives",
            time_one(&fd_states, |q, u, tau| {
                black_box(black_box(k).forward_dynamics_derivatives(q, u, tau));
            }),
        ),
        (
            "forward_dynamics_derivatives_with",
            time_one(&fd_states, |q, u, tau| {
                black_box(black_box(k).forward_dynamics_derivatives_with(
                    q,
                    u,
                    tau,
                    black_box(&mut fd_ws),
                ));
            }),
        ),
    ];
    let mut text = String::new();
    for (name, ns) in results {
        println!("kanegen {name:<18} {ns:9.1} ns");
        let _ = writeln!(text, "{name} {ns}");
    }
    append(&dir.join("kanegen-times.txt"), &text)
}

/// One row of the table: our label and times-file key, Pinocchio's label and key.
type Row = (&'static str, &'static str, &'static str, &'static str);

/// The rows of the comparison, in the order printed.
const ROWS: [Row; 14] = [
    (
        "`mass_matrix` (M)",
        "mass_matrix",
        "`crba` (M, upper triangle)",
        "crba",
    ),
    (
        "`coriolis` (c)",
        "coriolis",
        "`nonLinearEffects` (c + g)",
        "nle",
    ),
    (
        "`gravity` (g)",
        "gravity",
        "`computeGeneralizedGravity`",
        "gravity",
    ),
    (
        "`inverse_dynamics` (τ)",
        "inverse_dynamics",
        "`rnea`",
        "rnea",
    ),
    (
        "`coriolis_matrix` (C)",
        "coriolis_matrix",
        "`computeCoriolisMatrix`",
        "coriolis_matrix",
    ),
    (
        "`mass_matrix_into` (M, into a kept matrix)",
        "mass_matrix_into",
        "`crba` (M, upper triangle)",
        "crba",
    ),
    (
        "`coriolis_matrix_into` (C, into a kept matrix)",
        "coriolis_matrix_into",
        "`computeCoriolisMatrix`",
        "coriolis_matrix",
    ),
    (
        "`inverse_dynamics_derivatives` (∂τ/∂q, ∂τ/∂u)",
        "inverse_dynamics_derivatives",
        "`computeRNEADerivatives` (∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M)",
        "rnea_derivatives",
    ),
    (
        "`inverse_dynamics_derivatives_into` (into a kept matrix)",
        "inverse_dynamics_derivatives_into",
        "`computeRNEADerivatives` (∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M)",
        "rnea_derivatives",
    ),
    (
        "`inverse_dynamics_derivatives_with` (into a kept `DerivativesWorkspace`)",
        "inverse_dynamics_derivatives_with",
        "`computeRNEADerivatives` (∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M)",
        "rnea_derivatives",
    ),
    (
        "`forward_dynamics` (u̇, block Cholesky)",
        "forward_dynamics",
        "`crba` + `nonLinearEffects` + Eigen `LLT` on the 19 speeds",
        "fd_reduced",
    ),
    (
        "`forward_dynamics` (u̇, block Cholesky)",
        "forward_dynamics",
        "`aba` (20 speeds: the base without its rolling constraint, other dynamics)",
        "aba",
    ),
    (
        "`forward_dynamics_derivatives` (u̇, ∂u̇/∂q, ∂u̇/∂u, M⁻¹)",
        "forward_dynamics_derivatives",
        "`computeABADerivatives` (∂u̇/∂q, ∂u̇/∂v, M⁻¹; 20 speeds as `aba`)",
        "aba_derivatives",
    ),
    (
        "`forward_dynamics_derivatives_with` (into a kept workspace)",
        "forward_dynamics_derivatives_with",
        "`computeABADerivatives` (∂u̇/∂q, ∂u̇/∂v, M⁻¹; 20 speeds as `aba`)",
        "aba_derivatives",
    ),
];

/// Prefix of the times-file keys of Pinocchio's CppADCodeGen code (`codegen.cpp`).
const GENERATED: &str = "cg_";

/// Prints one markdown table: per row our time, theirs (`prefix` + their key) and the ratio.
/// Rows whose Pinocchio key is missing are left out when `optional`.
fn table(
    ours: &BTreeMap<String, f64>,
    pin: &BTreeMap<String, f64>,
    header: &str,
    prefix: &str,
    optional: bool,
) -> Result<(), String> {
    println!(
        "| kanegen (Rust) | ns | {header} | ns | Pinocchio / kanegen |\n|---|--:|---|--:|--:|"
    );
    for (our_label, our_key, pin_label, pin_key) in ROWS {
        let pin_key = format!("{prefix}{pin_key}");
        let (Some(a), Some(b)) = (ours.get(our_key), pin.get(&pin_key)) else {
            if optional && ours.contains_key(our_key) {
                continue;
            }
            return Err(format!("no time for `{our_key}` or `{pin_key}`"));
        };
        println!(
            "| {our_label} | {a:.0} | {pin_label} | {b:.0} | {:.1}× |",
            b / a
        );
    }
    Ok(())
}

fn report(dir: &Path) -> Result<(), String> {
    let (ours, our_runs) = best_times(&dir.join("kanegen-times.txt"))?;
    let (pin, pin_runs) = best_times(&dir.join("pinocchio-times.txt"))?;
    table(&ours, &pin, "Pinocchio (C++)", "", false)?;
    if pin.keys().any(|k| k.starts_with(GENERATED)) {
        println!();
        table(
            &ours,
            &pin,
            "Pinocchio's generated code (CppADCodeGen, C)",
            GENERATED,
            true,
        )?;
    }
    println!();
    for (key, into) in [
        ("inverse_dynamics_derivatives_into", "a kept matrix"),
        ("inverse_dynamics_derivatives_with", "a kept workspace"),
    ] {
        if let (Some(d), Some(t)) = (ours.get(key), ours.get("inverse_dynamics")) {
            println!(
                "kanegen: both derivative matrices, into {into}, take {:.1}× one `inverse_dynamics` call",
                d / t
            );
        }
    }
    println!(
        "\n(best of {our_runs} kanegen and {pin_runs} Pinocchio runs; each figure the fastest round of {ROUNDS} × {CALLS} calls)"
    );
    Ok(())
}

/// Writes `model` (TOML or URDF) with its default parameters in the export's text format.
fn export(model: &Path, file: &Path) -> Result<(), String> {
    let m = if model
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
    {
        Model::from_urdf_file(model, &kanegen_model::UrdfOptions::default())
    } else {
        Model::from_toml_file(model)
    }
    .map_err(|e| e.to_string())?;
    let pm = kanegen::pinocchio::export(&m, &m.param_values()).map_err(|e| e.to_string())?;
    std::fs::write(file, pm.to_text()).map_err(|e| format!("{}: {e}", file.display()))?;
    println!(
        "wrote {} ({} joints, {} bodies, nq {}, nv {})",
        file.display(),
        pm.joints.len(),
        pm.bodies.len(),
        pm.nq,
        pm.nv
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: pinocchio_side_by_side <write|time|report> DIR | export MODEL FILE";
    let result = match args.as_slice() {
        [cmd, model, file] if cmd == "export" => export(Path::new(model), Path::new(file)),
        [cmd, dir] => {
            let dir = PathBuf::from(dir);
            match cmd.as_str() {
                "write" => write(&dir),
                "time" => time(&dir),
                "report" => report(&dir),
                _ => Err(usage.to_owned()),
            }
        }
        _ => Err(usage.to_owned()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
