//! `kanegen` command line: inspect and emit the generated dynamics of a robot description.
//!
//! ```text
//! kanegen show    <model>                  the validated model: frame tree, speeds, parameters
//! kanegen stats   <model> [options]        K/D counts and op counts per generated function
//! kanegen listing <model> [options]        the substitution listing in the reports' style
//! kanegen emit    <model> [options] [--out FILE]   the generated Rust (stdout or FILE)
//! ```
//!
//! `<model>` is a TOML description or a URDF file (`.urdf`, imported with the default
//! `UrdfOptions` unless the URDF options below are given). Run `kanegen --help` for the options.
#![forbid(unsafe_code)]

use std::path::Path;
use std::process::ExitCode;

use kanegen::model::{Model, UrdfImport, UrdfOptions, WheeledBaseSpec};
use kanegen::{Builder, FunctionSet};

const USAGE: &str = "usage: kanegen <show|stats|listing|emit> <model.toml|model.urdf> [options]

  show     print the validated model: frame tree, speeds, parameters
  stats    print K/D variable counts and operation counts per generated function
  listing  print the substitution listing (K/D variables) in the reports' style
  emit     print the generated Rust module, or write it to --out FILE (only if changed)

options (stats, listing, emit):
  --baked                 fold the model file's parameter values in as constants
  --functions LIST        the generated functions, comma-separated (default: `default`;
                          `all`, or names: mass_matrix,coriolis,gravity,inverse_dynamics,coriolis_matrix)
  --no-coriolis-matrix    leave out the Coriolis matrix C(q, u)
  --f32                   emit an f32 module (emit only)
  --out FILE              write the module to FILE (emit only)

URDF import options (.urdf models; see kanegen_model::UrdfOptions):
  --wheeled LEFT_JOINT,RIGHT_JOINT,BODY_LINK   a two-wheeled inverted-pendulum base
  --up X,Y,Z              the body axis that points up at zero pitch (with --wheeled; default 0,0,1)
  --radius R              wheel radius in m (required with --wheeled)
  --track L               distance between the wheel contact points (default: from the joints)
  --pitch-name NAME       name of the pitch coordinate (default: pitch)
  --drop-links A,B        links to leave out (e.g. Krang's gripper plates)
  --name NAME             the model (and wrapper type) name (default: <robot name>)";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("{msg}");
            ExitCode::FAILURE
        }
    }
}

/// The parsed command line.
#[derive(Default)]
struct Args {
    positional: Vec<String>,
    baked: bool,
    functions: Option<FunctionSet>,
    no_coriolis_matrix: bool,
    f32: bool,
    out: Option<String>,
    wheeled: Option<[String; 3]>,
    up: Option<[f64; 3]>,
    radius: Option<f64>,
    track: Option<f64>,
    pitch_name: Option<String>,
    drop_links: Vec<String>,
    name: Option<String>,
}

fn numbers<const N: usize>(option: &str, s: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{option} expects {N} comma-separated numbers, got `{s}`"))?;
    v.try_into()
        .map_err(|_| format!("{option} expects {N} comma-separated numbers, got `{s}`"))
}

fn parse(args: Vec<String>) -> Result<Option<Args>, String> {
    let mut a = Args::default();
    let mut it = args.into_iter();
    while let Some(arg) = it.next() {
        let mut value = |what: &str| it.next().ok_or(format!("{arg} needs {what}"));
        match arg.as_str() {
            "-h" | "--help" => return Ok(None),
            "--baked" => a.baked = true,
            "--no-coriolis-matrix" => a.no_coriolis_matrix = true,
            "--f32" => a.f32 = true,
            "--out" => a.out = Some(value("a file name")?),
            "--functions" => {
                a.functions = Some(
                    value("a list of functions")?
                        .parse()
                        .map_err(|e| format!("{e}"))?,
                )
            }
            "--wheeled" => {
                let v = value("LEFT_JOINT,RIGHT_JOINT,BODY_LINK")?;
                let parts: Vec<String> = v.split(',').map(|s| s.trim().to_owned()).collect();
                a.wheeled = Some(parts.try_into().map_err(|_| {
                    format!("--wheeled expects LEFT_JOINT,RIGHT_JOINT,BODY_LINK, got `{v}`")
                })?);
            }
            "--up" => a.up = Some(numbers::<3>("--up", &value("X,Y,Z")?)?),
            "--radius" => a.radius = Some(numbers::<1>("--radius", &value("a number")?)?[0]),
            "--track" => a.track = Some(numbers::<1>("--track", &value("a number")?)?[0]),
            "--pitch-name" => a.pitch_name = Some(value("a name")?),
            "--drop-links" => {
                let v = value("a list of links")?;
                a.drop_links = v.split(',').map(|s| s.trim().to_owned()).collect();
            }
            "--name" => a.name = Some(value("a name")?),
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n\n{USAGE}")),
            _ => a.positional.push(arg),
        }
    }
    Ok(Some(a))
}

impl Args {
    /// The URDF import options given on the command line.
    fn urdf_options(&self) -> Result<UrdfOptions, String> {
        let mut o = match &self.wheeled {
            Some([left, right, body]) => {
                let radius = self
                    .radius
                    .ok_or("--wheeled needs --radius R (the wheel radius in m)")?;
                let mut base = WheeledBaseSpec::new(
                    left.as_str(),
                    right.as_str(),
                    body.as_str(),
                    self.up.unwrap_or([0.0, 0.0, 1.0]),
                    radius,
                );
                base.track = self.track;
                if let Some(p) = &self.pitch_name {
                    base.pitch_name = p.clone();
                }
                UrdfOptions::wheeled(base)
            }
            None => {
                if self.up.is_some()
                    || self.radius.is_some()
                    || self.track.is_some()
                    || self.pitch_name.is_some()
                {
                    return Err("--up, --radius, --track and --pitch-name need --wheeled".into());
                }
                UrdfOptions::default()
            }
        };
        o = o.drop_links(self.drop_links.iter().cloned());
        o.name = self.name.clone();
        Ok(o)
    }

    fn has_urdf_options(&self) -> bool {
        self.wheeled.is_some()
            || self.up.is_some()
            || self.radius.is_some()
            || self.track.is_some()
            || self.pitch_name.is_some()
            || !self.drop_links.is_empty()
            || self.name.is_some()
    }
}

fn run(args: Vec<String>) -> Result<(), String> {
    let Some(args) = parse(args)? else {
        println!("{USAGE}");
        return Ok(());
    };
    let [cmd, path] = args.positional.as_slice() else {
        return Err(USAGE.to_owned());
    };
    if !["show", "stats", "listing", "emit"].contains(&cmd.as_str()) {
        return Err(format!("unknown command `{cmd}`\n\n{USAGE}"));
    }
    let urdf = kanegen::is_urdf(Path::new(path));
    if !urdf && args.has_urdf_options() {
        return Err(format!(
            "URDF import options apply to .urdf models only (`{path}` is TOML)"
        ));
    }
    if cmd != "emit" && (args.out.is_some() || args.f32) {
        return Err(format!("--out and --f32 apply to `emit` only\n\n{USAGE}"));
    }
    let urdf_options = args.urdf_options()?;
    if cmd == "show" {
        let model = if urdf {
            UrdfImport::read(path, &urdf_options).map(|i| i.model)
        } else {
            Model::from_toml_file(path)
        };
        print!("{}", model.map_err(|e| format!("error: {e}"))?);
        return Ok(());
    }
    let mut builder = if urdf {
        Builder::urdf(path, urdf_options)
    } else {
        Builder::new(path)
    }
    .baked(args.baked);
    if let Some(set) = args.functions {
        builder = builder.functions(set);
    }
    if args.no_coriolis_matrix {
        builder = builder.coriolis_matrix(false);
    }
    if args.f32 {
        builder = builder.precision(kanegen::Precision::F32);
    }
    let start = std::time::Instant::now();
    let g = builder.generate().map_err(|e| format!("error: {e}"))?;
    let elapsed = start.elapsed();
    match cmd.as_str() {
        "stats" => {
            print!("{}", kanegen::stats(&g));
            println!("generation time: {:.0} ms", elapsed.as_secs_f64() * 1e3);
        }
        "listing" => print!("{}", kanegen::listing(&g)),
        _ => match &args.out {
            Some(f) => {
                let written = kanegen::write_if_changed(Path::new(f), &g.source)
                    .map_err(|e| format!("error: {e}"))?;
                eprintln!("{f}: {}", if written { "written" } else { "unchanged" });
            }
            None => print!("{}", g.source),
        },
    }
    Ok(())
}
