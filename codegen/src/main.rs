//! `kanegen` command line: inspect and emit the generated dynamics of a robot description.
//!
//! ```text
//! kanegen show    <model>                  the validated model: frame tree, speeds, parameters
//! kanegen stats   <model> [--baked]        K/D counts and op counts per generated function
//! kanegen listing <model> [--baked]        the substitution listing in the reports' style
//! kanegen emit    <model> [--baked] [--out FILE]   the generated Rust (stdout or FILE)
//! ```
//!
//! `--no-coriolis-matrix` leaves out the Coriolis matrix (as `Builder::coriolis_matrix(false)`).
#![forbid(unsafe_code)]

use std::process::ExitCode;

use kanegen::{Options, ParamMode};

const USAGE: &str = "usage: kanegen <show|stats|listing|emit> <model.toml> [--baked] [--no-coriolis-matrix] [--out FILE]

  show     print the validated model: frame tree, speeds, parameters
  stats    print K/D variable counts and operation counts per generated function
  listing  print the substitution listing (K/D variables) in the reports' style
  emit     print the generated Rust module, or write it to --out FILE (only if changed)

  --baked  fold the model file's parameter values in as constants
  --no-coriolis-matrix  leave out the Coriolis matrix C(q, u)";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("{msg}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Vec<String>) -> Result<(), String> {
    let mut positional = Vec::new();
    let mut baked = false;
    let mut coriolis_matrix = true;
    let mut out = None;
    let mut it = args.into_iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--baked" => baked = true,
            "--no-coriolis-matrix" => coriolis_matrix = false,
            "--out" => out = Some(it.next().ok_or("--out needs a file name")?),
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n\n{USAGE}")),
            _ => positional.push(a),
        }
    }
    let [cmd, path] = positional.as_slice() else {
        return Err(USAGE.to_owned());
    };
    let options = Options {
        params: if baked {
            ParamMode::Baked
        } else {
            ParamMode::Runtime
        },
        coriolis_matrix,
    };
    if cmd == "show" {
        let m = kanegen::model::Model::from_toml_file(path).map_err(|e| format!("error: {e}"))?;
        print!("{m}");
        return Ok(());
    }
    let start = std::time::Instant::now();
    let g = kanegen::generate(path, options).map_err(|e| format!("error: {e}"))?;
    let elapsed = start.elapsed();
    match cmd.as_str() {
        "stats" => {
            print!("{}", kanegen::stats(&g));
            println!("generation time: {:.0} ms", elapsed.as_secs_f64() * 1e3);
        }
        "listing" => print!("{}", kanegen::listing(&g)),
        "emit" => match out {
            Some(f) => {
                let written = kanegen::emit::write_if_changed(std::path::Path::new(&f), &g.source)
                    .map_err(|e| format!("error: {e}"))?;
                eprintln!("{f}: {}", if written { "written" } else { "unchanged" });
            }
            None => print!("{}", g.source),
        },
        other => return Err(format!("unknown command `{other}`\n\n{USAGE}")),
    }
    Ok(())
}
