//! `kanegen` command line: inspect and emit the generated dynamics of a robot description.
//!
//! ```text
//! kanegen show    <model>                  the validated model: frame tree, speeds, parameters
//! kanegen stats   <model> [options]        K/D counts and op counts per generated function
//! kanegen listing <model> [options]        the substitution listing in the reports' style
//! kanegen emit    <model> [options] [--out FILE]   the generated Rust (stdout or FILE)
//! kanegen python  <model> [options] --out DIR      a Python extension crate (PyO3, maturin)
//! kanegen c       <model> [options] --out DIR      a C library crate (static library, header)
//! ```
//!
//! `<model>` is a TOML description or a URDF file (`.urdf`, imported with the default
//! `UrdfOptions` unless the URDF options below are given). Run `kanegen --help` for the options.
//!
//! The command line is checked completely before any work: an unknown command, an unknown
//! option, an option the command does not take or a missing or extra argument is an error
//! (exit status 2). Output to a closed pipe (`kanegen stats m.toml | head -1`) ends quietly.
#![forbid(unsafe_code)]

#[path = "cli_show.rs"]
mod show;

use std::io::Write as _;
use std::path::Path;
use std::process::ExitCode;

use kanegen::model::{Model, UrdfImport, UrdfOptions, WheeledBaseSpec};
use kanegen::{Builder, FunctionSet};

/// The reminder after a command-line error.
const SHORT_USAGE: &str =
    "usage: kanegen <show|stats|listing|emit|python|c> <model.toml|model.urdf> [options]
(`kanegen --help` lists the commands and the options each one takes)";

const USAGE: &str =
    "usage: kanegen <show|stats|listing|emit|python|c> <model.toml|model.urdf> [options]

  show     print the validated model: frame tree, speeds, parameters
  stats    print K/D variable counts and operation counts per generated function
  listing  print the substitution listing (K/D variables) in the reports' style
  emit     print the generated Rust module, or write it to --out FILE (only if changed)
  python   write a Python extension crate (PyO3, built with maturin) into --out DIR
  c        write a C library crate (static library, header by cbindgen) into --out DIR

options (stats, listing, emit, python, c; `show` takes only the URDF import options):
  --baked                 fold the model file's parameter values in as constants
  --functions LIST        the generated functions: comma-separated names and groups (listed
                          below; default: `default`)
  --no-coriolis-matrix    leave out the Coriolis matrix C(q, u)
  --mirrored-lanes        compute mirrored subtrees (two identical arms) in two SIMD lanes
  --f32                   emit an f32 module (emit only)
  --batch                 also emit the batched functions: L states per call in SIMD lanes
                          (`mass_matrix_batch`, `…_batch_soa`, …; f64 modules; emit only)
  --batch-feature NAME    --batch, each batched item behind `#[cfg(feature = \"NAME\")]` of the
                          crate that includes the module (emit only)
  --out FILE              write the module to FILE (emit), the crate into the directory FILE
                          (python, c: required)
  --module NAME           the Python module or C library name (python, c; default: the model
                          file's stem)
  --kanegen-path DIR      take the kanegen crates from the checkout DIR instead of the git
                          repository (python, c)

URDF import options (.urdf models; see kanegen_model::UrdfOptions):
  --floating              a floating (free-flyer) base at the URDF root (the default when the
                          root is a bare `world` link whose one joint is `floating`)
  --wheeled LEFT_JOINT,RIGHT_JOINT,BODY_LINK   a two-wheeled inverted-pendulum base
  --up X,Y,Z              the body axis that points up at zero pitch (with --wheeled; default 0,0,1)
  --radius R              wheel radius in m (required with --wheeled)
  --track L               distance between the wheel contact points (default: from the joints)
  --pitch-name NAME       name of the pitch coordinate (default: pitch)
  --drop-links A,B        links to leave out (e.g. Krang's gripper plates)
  --name NAME             the model (and wrapper type) name (default: <robot name>)";

/// How the command failed.
enum Failure {
    /// A bad command line: the message and the usage (exit status 2).
    Usage(String),
    /// The command failed: the message (exit status 1).
    Error(String),
}

impl From<String> for Failure {
    fn from(msg: String) -> Self {
        Failure::Usage(msg)
    }
}

impl From<&str> for Failure {
    fn from(msg: &str) -> Self {
        Failure::Usage(msg.to_owned())
    }
}

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Usage(msg)) => {
            eprintln!("error: {msg}\n{SHORT_USAGE}");
            ExitCode::from(2)
        }
        Err(Failure::Error(msg)) => {
            eprintln!("{msg}");
            ExitCode::FAILURE
        }
    }
}

/// Write `text` to standard output. A closed pipe (the reader, such as `head`, has exited) is
/// not an error: the output is simply not wanted any more.
fn output(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Failure::Error(format!(
            "error: writing to standard output: {e}"
        ))),
        _ => Ok(()),
    }
}

/// The `--functions` part of `--help`, from the registry (so that it names every function the
/// generator has): the groups with their members, then every name.
fn functions_help() -> String {
    let groups = [
        ("default", FunctionSet::default()),
        ("kinematics", FunctionSet::kinematics()),
        ("regressors", FunctionSet::regressors()),
        ("centroidal", FunctionSet::centroidal()),
    ];
    let mut text = String::from(
        "functions (--functions LIST, comma-separated; each name is a generated function):\n",
    );
    for (name, set) in groups {
        text += &wrapped(
            &format!("  {name:<11}"),
            &set.to_string().replace(',', ", "),
        );
    }
    text += "  all        every function below\n";
    text + &wrapped(
        "  names      ",
        &FunctionSet::all().to_string().replace(',', ", "),
    )
}

/// `items` after `head`, broken after a comma so that no line is longer than 96 characters, the
/// lines after the first indented as far as `head`.
fn wrapped(head: &str, items: &str) -> String {
    let indent = " ".repeat(head.chars().count());
    let mut text = String::new();
    let mut line = head.to_owned();
    for word in items.split_inclusive(' ') {
        if line.chars().count() + word.trim_end().chars().count() > 96 && line.trim() != head.trim()
        {
            text += line.trim_end();
            text.push('\n');
            line.clone_from(&indent);
        }
        line += word;
    }
    text + line.trim_end() + "\n"
}

/// What `stats` prints after its table: the columns, and what to run next.
const STATS_LEGEND: &str = "
columns (per call of each generated function; `precompute` runs once per parameter set):
  K        substitution variables for kinematic quantities (rotations, velocities,
           accelerations), as in the Krang reports
  D        substitution variables for inertial and gravity terms (forces, moments, M entries)
  temps    other named intermediate values of the straight-line code
  adds, muls, divs   floating-point additions (and subtractions), multiplications, divisions
  sin/cos  joint angles whose sine and cosine are needed (computed together in one batched call)
  flops    adds + muls + divs
  fma      multiply-adds fused in the x86-64-v3 copy (each one of the muls and one of the
           adds above, executed as one instruction there: flops - fma instructions)
  live     the most intermediate values alive at once (register pressure: x86-64 has 16
           vector registers, more live values spill to the stack)
  lanes    statement pairs computed in two lanes, one per mirrored subtree (--mirrored-lanes;
           `-`: none)
next:
  kanegen listing MODEL                 the K/D substitution listing of every function
  kanegen emit MODEL --out FILE         the generated Rust module
  kanegen stats MODEL --functions LIST  other functions (names and groups: kanegen --help)
  kanegen stats MODEL --baked           with the parameter values folded in
";

fn run(args: Vec<String>) -> Result<(), Failure> {
    let Some(args) = parse(args)? else {
        return output(&format!("{USAGE}\n\n{}", functions_help()));
    };
    let (cmd, path) = (args.command, args.model.as_str());
    let urdf = kanegen::is_urdf(Path::new(path));
    if !urdf && args.has_urdf_options() {
        return Err(
            format!("URDF import options apply to .urdf models only (`{path}` is TOML)").into(),
        );
    }
    let urdf_options = args.urdf_options()?;
    let error = |e: &dyn std::fmt::Display| Failure::Error(format!("error: {e}"));
    if cmd == Command::Show {
        let model = if urdf {
            UrdfImport::read(path, &urdf_options).map(|i| i.model)
        } else {
            Model::from_toml_file(path)
        };
        return output(&show::model(&model.map_err(|e| error(&e))?));
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
    builder = builder.mirrored_lanes(args.mirrored_lanes);
    if let Some(feature) = args.batch_feature.clone() {
        builder = builder.batch_feature(feature);
    } else if args.batch {
        builder = builder.batch(true);
    }
    if matches!(cmd, Command::Python | Command::C) {
        return bindings(cmd, &args, &builder);
    }
    let start = std::time::Instant::now();
    let g = builder.generate().map_err(|e| error(&e))?;
    let elapsed = start.elapsed();
    // The URDF import decisions that change the numbers, one line per kind (as a build prints
    // them after `cargo:warning=`); every note is in the generated file's header.
    for line in g.warnings() {
        eprintln!("warning: {line}");
    }
    match cmd {
        Command::Stats => output(&format!(
            "{}generation time: {:.0} ms\n{STATS_LEGEND}",
            kanegen::stats(&g),
            elapsed.as_secs_f64() * 1e3
        )),
        Command::Listing => output(&kanegen::listing(&g)),
        _ => match &args.out {
            Some(f) => {
                let written =
                    kanegen::write_if_changed(Path::new(f), &g.source).map_err(|e| error(&e))?;
                eprintln!("{f}: {}", if written { "written" } else { "unchanged" });
                Ok(())
            }
            None => output(&g.source),
        },
    }
}

/// `kanegen python` and `kanegen c`: the bindings crate written into `--out DIR`.
fn bindings(cmd: Command, args: &Args, builder: &Builder) -> Result<(), Failure> {
    let Some(dir) = &args.out else {
        return Err(format!("`{}` needs --out DIR (the crate's directory)", cmd.name()).into());
    };
    let options = kanegen::bindings::BindingsOptions {
        name: args.module.clone(),
        kanegen: match &args.kanegen_path {
            Some(p) => kanegen::bindings::KanegenSource::Path(p.into()),
            None => kanegen::bindings::KanegenSource::default(),
        },
    };
    let written = if cmd == Command::Python {
        builder.python_crate(dir, &options)
    } else {
        builder.c_crate(dir, &options)
    }
    .map_err(|e| Failure::Error(format!("error: {e}")))?;
    for path in written {
        eprintln!("{}", path.display());
    }
    Ok(())
}

/// The command.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Command {
    Show,
    Stats,
    Listing,
    Emit,
    Python,
    C,
}

impl Command {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "show" => Command::Show,
            "stats" => Command::Stats,
            "listing" => Command::Listing,
            "emit" => Command::Emit,
            "python" => Command::Python,
            "c" => Command::C,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Command::Show => "show",
            Command::Stats => "stats",
            Command::Listing => "listing",
            Command::Emit => "emit",
            Command::Python => "python",
            Command::C => "c",
        }
    }

    /// Whether the command takes `option` (one of the options of [`parse`]).
    fn takes(self, option: &str) -> bool {
        const URDF: [&str; 8] = [
            "--floating",
            "--wheeled",
            "--up",
            "--radius",
            "--track",
            "--pitch-name",
            "--drop-links",
            "--name",
        ];
        const GENERATOR: [&str; 4] = [
            "--baked",
            "--functions",
            "--no-coriolis-matrix",
            "--mirrored-lanes",
        ];
        URDF.contains(&option)
            || (self != Command::Show && GENERATOR.contains(&option))
            || (self == Command::Emit
                && ["--f32", "--out", "--batch", "--batch-feature"].contains(&option))
            || (matches!(self, Command::Python | Command::C)
                && ["--out", "--module", "--kanegen-path"].contains(&option))
    }
}

/// The parsed command line.
struct Args {
    command: Command,
    model: String,
    baked: bool,
    functions: Option<FunctionSet>,
    no_coriolis_matrix: bool,
    mirrored_lanes: bool,
    f32: bool,
    batch: bool,
    batch_feature: Option<String>,
    out: Option<String>,
    floating: bool,
    module: Option<String>,
    kanegen_path: Option<String>,
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

/// The command line, checked completely: `None` for `--help`. The command comes first, so that
/// an unknown command is reported before anything else; every option must be one the command
/// takes.
fn parse(args: Vec<String>) -> Result<Option<Args>, String> {
    if args.iter().any(|a| a == "-h" || a == "--help") {
        return Ok(None);
    }
    let mut it = args.into_iter();
    let command = match it.next() {
        None => return Err("no command given".into()),
        Some(c) => Command::parse(&c).ok_or_else(|| {
            if c.starts_with('-') {
                format!("expected a command before `{c}`")
            } else {
                format!("unknown command `{c}`")
            }
        })?,
    };
    let mut a = Args {
        command,
        model: String::new(),
        baked: false,
        functions: None,
        no_coriolis_matrix: false,
        mirrored_lanes: false,
        f32: false,
        batch: false,
        batch_feature: None,
        out: None,
        floating: false,
        module: None,
        kanegen_path: None,
        wheeled: None,
        up: None,
        radius: None,
        track: None,
        pitch_name: None,
        drop_links: Vec::new(),
        name: None,
    };
    while let Some(arg) = it.next() {
        if !arg.starts_with('-') {
            if !a.model.is_empty() {
                return Err(format!("unexpected argument `{arg}` (one model file)"));
            }
            a.model = arg;
            continue;
        }
        if !is_option(&arg) {
            return Err(format!("unknown option `{arg}`"));
        }
        if !command.takes(&arg) {
            return Err(format!("`{}` does not take `{arg}`", command.name()));
        }
        let value = if FLAGS.contains(&arg.as_str()) {
            None
        } else {
            it.next()
        };
        a.set(&arg, value)?;
    }
    if a.model.is_empty() {
        return Err(format!("`{}` needs a model file", command.name()));
    }
    Ok(Some(a))
}

/// The options that take no value.
const FLAGS: [&str; 6] = [
    "--floating",
    "--baked",
    "--no-coriolis-matrix",
    "--mirrored-lanes",
    "--f32",
    "--batch",
];

/// Whether `arg` is one of the options of the command line.
fn is_option(arg: &str) -> bool {
    [
        Command::Show,
        Command::Stats,
        Command::Listing,
        Command::Emit,
        Command::Python,
        Command::C,
    ]
    .iter()
    .any(|c| c.takes(arg))
}

impl Args {
    /// Apply option `arg` with its value (`None` for the flags, which take none).
    fn set(&mut self, arg: &str, value: Option<String>) -> Result<(), String> {
        let value = || value.clone().ok_or(format!("{arg} needs a value"));
        match arg {
            "--floating" => self.floating = true,
            "--baked" => self.baked = true,
            "--no-coriolis-matrix" => self.no_coriolis_matrix = true,
            "--mirrored-lanes" => self.mirrored_lanes = true,
            "--f32" => self.f32 = true,
            "--batch" => self.batch = true,
            "--batch-feature" => {
                let name = value()?;
                if name.is_empty() || name.starts_with('-') {
                    return Err(format!(
                        "--batch-feature needs a cargo feature name, got `{name}`"
                    ));
                }
                self.batch_feature = Some(name);
            }
            "--out" => self.out = Some(value()?),
            "--module" => self.module = Some(value()?),
            "--kanegen-path" => self.kanegen_path = Some(value()?),
            "--functions" => {
                let set: FunctionSet = value()?.parse().map_err(|e| format!("{e}"))?;
                if set.is_empty() {
                    return Err("--functions names no function (give names or groups, e.g. \
                                `--functions default,frame_pose`; `kanegen --help` lists them)"
                        .into());
                }
                self.functions = Some(set);
            }
            "--wheeled" => {
                let v = value()?;
                let parts: Vec<String> = v.split(',').map(|s| s.trim().to_owned()).collect();
                self.wheeled = Some(parts.try_into().map_err(|_| {
                    format!("--wheeled expects LEFT_JOINT,RIGHT_JOINT,BODY_LINK, got `{v}`")
                })?);
            }
            "--up" => self.up = Some(numbers::<3>("--up", &value()?)?),
            "--radius" => self.radius = Some(numbers::<1>("--radius", &value()?)?[0]),
            "--track" => self.track = Some(numbers::<1>("--track", &value()?)?[0]),
            "--pitch-name" => self.pitch_name = Some(value()?),
            "--drop-links" => {
                self.drop_links = value()?.split(',').map(|s| s.trim().to_owned()).collect();
            }
            "--name" => self.name = Some(value()?),
            _ => return Err(format!("unknown option `{arg}`")),
        }
        Ok(())
    }

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
                if self.floating {
                    return Err(
                        "--floating and --wheeled exclude each other: a model has one base".into(),
                    );
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
                if self.floating {
                    UrdfOptions::floating()
                } else {
                    UrdfOptions::default()
                }
            }
        };
        o = o.drop_links(self.drop_links.iter().cloned());
        o.name = self.name.clone();
        Ok(o)
    }

    fn has_urdf_options(&self) -> bool {
        self.floating
            || self.wheeled.is_some()
            || self.up.is_some()
            || self.radius.is_some()
            || self.track.is_some()
            || self.pitch_name.is_some()
            || !self.drop_links.is_empty()
            || self.name.is_some()
    }
}
