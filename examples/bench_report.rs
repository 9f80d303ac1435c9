//! Markdown table of the `dynamics` benchmarks (`benches/dynamics.rs`): for each model, function ×
//! {generated, baked, rbd, naive} in ns per call (criterion's median point estimate), the speedups
//! of the generated code over `kanegen-rbd` and over the naive recursion, and the generated
//! code's operation counts (as printed by `kanegen stats`, baked counts in parentheses).
//!
//! ```sh
//! cargo bench --bench dynamics
//! cargo run --release --example bench_report               # reads target/criterion
//! cargo run --release --example bench_report -- --dir DIR  # another criterion directory
//! ```
//!
//! On a shared machine, save several runs and take the minimum of their medians:
//!
//! ```sh
//! for r in a b c; do cargo bench --bench dynamics -- --save-baseline $r; done
//! cargo run --release --example bench_report -- --baselines a,b,c
//! ```
//!
//! Only the standard library, `serde_json` and `kanegen` (for the op counts: every model is
//! generated again, in well under a second).
#![forbid(unsafe_code)]

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use kanegen::lower::OpCount;
use kanegen::model::{UrdfOptions, WheeledBaseSpec};
use kanegen::{Generated, Options, ParamMode};

/// The benchmark functions, in table order.
const FUNCTIONS: [&str; 4] = ["mass_matrix", "coriolis", "gravity", "inverse_dynamics"];

/// The benchmark variants, in column order.
const VARIANTS: [&str; 4] = ["generated", "baked", "rbd", "naive"];

/// How a model is generated (for the op counts).
enum Source {
    Toml(&'static str),
    Urdf(&'static str, fn() -> UrdfOptions),
}

/// One benchmarked model.
struct Bench {
    /// First component of the benchmark ids.
    key: &'static str,
    title: &'static str,
    source: Source,
    /// Is there a `baked` variant?
    baked: bool,
}

fn krang_urdf_options() -> UrdfOptions {
    // As in build.rs.
    let mut base = WheeledBaseSpec::new("JLWheel", "JRWheel", "Base", [0.0, 1.0, 0.0], 0.25);
    base.pitch_name = "imu".into();
    UrdfOptions::wheeled(base).drop_links(["lgPlate1", "lgPlate2", "rgPlate1", "rgPlate2"])
}

const BENCHES: [Bench; 4] = [
    Bench {
        key: "krang",
        title: "Golem Krang, 19 speeds (`models/krang.toml`)",
        source: Source::Toml("models/krang.toml"),
        baked: true,
    },
    Bench {
        key: "krang_fixed_wheels",
        title: "Krang on fixed wheels, 17 speeds (`models/krang-fixed-wheels.toml`)",
        source: Source::Toml("models/krang-fixed-wheels.toml"),
        baked: false,
    },
    Bench {
        key: "arm",
        title: "7-DOF arm (`models/singlearm.urdf`)",
        source: Source::Urdf("models/singlearm.urdf", UrdfOptions::default),
        baked: true,
    },
    Bench {
        key: "krang_urdf",
        title: "Krang from URDF, 19 speeds (`models/Krang.urdf`, wheeled base)",
        source: Source::Urdf("models/Krang.urdf", krang_urdf_options),
        baked: false,
    },
];

const USAGE: &str = "usage: bench_report [--dir CRITERION_DIR] [--baselines NAME,NAME,...]

  --dir        criterion's output directory (default: $CARGO_TARGET_DIR/criterion or target/criterion)
  --baselines  criterion baselines to read (default: new, the latest run); with several, the
               minimum of their medians (runs saved with `cargo bench -- --save-baseline NAME`)";

fn main() -> ExitCode {
    match args().and_then(|(dir, baselines)| run(&dir, &baselines)) {
        Ok(table) => {
            print!("{table}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `(criterion directory, baselines)` from the command line.
fn args() -> Result<(PathBuf, Vec<String>), String> {
    let mut dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("criterion");
    let mut baselines = vec!["new".to_owned()];
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--dir" => dir = it.next().ok_or(USAGE)?.into(),
            "--baselines" => {
                baselines = it
                    .next()
                    .ok_or(USAGE)?
                    .split(',')
                    .map(str::to_owned)
                    .collect()
            }
            _ => return Err(USAGE.to_owned()),
        }
    }
    Ok((dir, baselines))
}

fn run(dir: &Path, baselines: &[String]) -> Result<String, String> {
    let mut medians = BTreeMap::new();
    collect(dir, baselines, &mut medians)?;
    if medians.is_empty() {
        return Err(format!(
            "no criterion results ({}) under {} (run `cargo bench --bench dynamics` first)",
            baselines.join(", "),
            dir.display()
        ));
    }
    let mut out = String::new();
    for b in &BENCHES {
        let runtime = generate(b, ParamMode::Runtime)?;
        let baked = if b.baked {
            Some(generate(b, ParamMode::Baked)?)
        } else {
            None
        };
        table(&mut out, b, &runtime, baked.as_ref(), &medians);
    }
    let sin_cos = ["batched", "generated", "std", "rbd"]
        .map(|v| medians.get(&format!("overhead/sin_cos_x17/{v}")).copied());
    if sin_cos.iter().any(Option::is_some) {
        let _ = writeln!(
            out,
            "17 × `sin_cos` (Krang's joint angles), ns: generated code's batched routine {}, \
             its scalar routine (one call per joint) {}, standard library {}, kanegen-rbd's \
             batched kernel {}.\n",
            ns(sin_cos[0]),
            ns(sin_cos[1]),
            ns(sin_cos[2]),
            ns(sin_cos[3])
        );
    }
    Ok(out)
}

/// Every `<dir>/**/<baseline>/{benchmark,estimates}.json`: full benchmark id → median (ns),
/// the minimum over `baselines`.
fn collect(
    dir: &Path,
    baselines: &[String],
    medians: &mut BTreeMap<String, f64>,
) -> Result<(), String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if !path.is_dir() || name == "report" || baselines.iter().any(|b| name == b.as_str()) {
            continue;
        }
        let mut found = false;
        for baseline in baselines {
            let (bench, est) = (
                path.join(baseline).join("benchmark.json"),
                path.join(baseline).join("estimates.json"),
            );
            if !(bench.is_file() && est.is_file()) {
                continue;
            }
            found = true;
            let id = read_json(&bench)?["full_id"]
                .as_str()
                .ok_or_else(|| format!("{}: no full_id", bench.display()))?
                .to_owned();
            let median = read_json(&est)?["median"]["point_estimate"]
                .as_f64()
                .ok_or_else(|| format!("{}: no median.point_estimate", est.display()))?;
            let m = medians.entry(id).or_insert(f64::INFINITY);
            *m = m.min(median);
        }
        if !found {
            collect(&path, baselines, medians)?;
        }
    }
    Ok(())
}

fn read_json(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

fn generate(b: &Bench, params: ParamMode) -> Result<Generated, String> {
    let options = Options {
        params,
        ..Options::default()
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    match &b.source {
        Source::Toml(p) => kanegen::Builder::new(root.join(p))
            .options(options)
            .generate(),
        Source::Urdf(p, urdf) => kanegen::Builder::urdf(root.join(p), urdf())
            .options(options)
            .generate(),
    }
    .map_err(|e| format!("{}: {e}", b.key))
}

fn ops(g: &Generated, function: &str) -> Option<OpCount> {
    let id = kanegen::FunctionId::from_name(function)?;
    g.lowered.function(id).map(|p| p.ops)
}

/// One model's table.
fn table(
    out: &mut String,
    b: &Bench,
    runtime: &Generated,
    baked: Option<&Generated>,
    medians: &BTreeMap<String, f64>,
) {
    let _ = writeln!(out, "**{}** (`{}/…`)\n", b.title, b.key);
    let _ = writeln!(
        out,
        "| function | adds | muls | sin/cos | generated (ns) | baked (ns) | rbd (ns) | naive (ns) \
         | generated vs rbd | generated vs naive |"
    );
    let _ = writeln!(out, "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|");
    for f in FUNCTIONS {
        let (r, k) = (ops(runtime, f), baked.and_then(|g| ops(g, f)));
        let count = |field: fn(&OpCount) -> usize| match (r, k) {
            (Some(r), Some(k)) => format!("{} ({})", field(&r), field(&k)),
            (Some(r), None) => field(&r).to_string(),
            _ => "—".into(),
        };
        let t = VARIANTS.map(|v| medians.get(&format!("{}/{f}/{v}", b.key)).copied());
        let speedup = |other: Option<f64>| match (t[0], other) {
            (Some(g), Some(o)) => format!("{:.1}×", o / g),
            _ => "—".into(),
        };
        let _ = writeln!(
            out,
            "| `{f}` | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            count(|o| o.adds),
            count(|o| o.muls),
            count(|o| o.sincos),
            ns(t[0]),
            ns(t[1]),
            ns(t[2]),
            ns(t[3]),
            speedup(t[2]),
            speedup(t[3]),
        );
    }
    let note = if baked.is_some() {
        "Op counts per call of the generated code with runtime parameters (baked in parentheses)."
    } else {
        "Op counts per call of the generated code (runtime parameters)."
    };
    let _ = writeln!(out, "\n{note}\n");
}

/// A median in ns, or a dash.
fn ns(t: Option<f64>) -> String {
    match t {
        Some(t) if t < 100.0 => format!("{t:.1}"),
        Some(t) => format!("{t:.0}"),
        None => "—".into(),
    }
}
