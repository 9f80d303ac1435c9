//! Free-flyer side of the Pinocchio comparison (`benches/pinocchio/run.sh`, which runs
//! `benches/pinocchio/harness_ff.cpp` on what this writes; docs/correctness.md and
//! docs/performance.md):
//!
//! ```text
//! cargo run --release --example pinocchio_free_flyer -- write DIR
//! cargo run --release --example pinocchio_free_flyer -- time DIR
//! cargo run --release --example pinocchio_free_flyer -- report DIR
//! ```
//!
//! `write` writes `DIR/ff-cases.txt`: Solo 12 (four point contacts at the feet) and
//! `simple_humanoid` (two point contacts at the ankles) of the URDF corpus, imported on a floating
//! base (`UrdfOptions::floating`) and exported as a Pinocchio model with a free-flyer root
//! (`kanegen::pinocchio::export_free_flyer`), at random states (default parameters), with the
//! free-flyer reference recursion's (`kanegen_reference::FreeFlyer`) M, nonlinear effects, g, τ,
//! centroidal momentum matrix and bias, ∂τ/∂q (tangent space) and ∂τ/∂u, and the
//! contact-constrained forward dynamics of `kanegen_runtime::contact` (u̇, λ) for random joint
//! torques. Format, all in the free flyer's coordinates (`q`: NQ entries, the rest NV):
//!
//! ```text
//! ff-cases <n>
//! ff-case <k> nq <NQ> nv <NV> contacts <C>
//! <the model in kanegen::pinocchio's text format, `kanegen-pinocchio 1` … `end`>
//! contact <frame name> <joint> <R by rows: 9> <p: 3>     (C lines)
//! q … u … ud … M (NV × NV, by rows) nle … g … tau … Ag (6 × NV) dhg (6) dtau_dq … dtau_du …
//! f (actuation, NV) cud (u̇ under contacts, NV) lambda (3C, world axes)
//! ```
//!
//! `time` checks the generated modules of both robots (this package's build script generates
//! them, `solo12_floating.rs` and `simple_humanoid_floating.rs`, and their baked forms, with the
//! parameter values folded in as Pinocchio's generated code folds them) against the same
//! reference on the same states, then times them and appends `robot/function ns` lines to
//! `DIR/kanegen-ff-times.txt`, keyed by the model's name (the harness appends Pinocchio's to
//! `DIR/pinocchio-ff-times.txt`).
//! `report` prints one Markdown table per robot, the best of the runs of each side.

use std::hint::black_box;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

#[path = "support/times.rs"]
mod times;

use kanegen_model::{Model, UrdfImport, UrdfOptions};
use kanegen_reference::FreeFlyer;
use kanegen_reference::random::SplitMix64;
use kanegen_runtime::contact::{
    ConstrainedAcceleration, Contact, ContactJacobian, ContactSettings,
    constrained_forward_dynamics, constrained_forward_dynamics_factored,
};
use kanegen_runtime::tree_factor::{TreeFactor, chain_parents};
use nalgebra::{DMatrix, SMatrix, SVector};
use times::{append, best_times};

#[allow(dead_code)]
mod solo {
    include!(concat!(env!("OUT_DIR"), "/solo12_floating.rs"));
}

#[allow(dead_code)]
mod humanoid {
    include!(concat!(env!("OUT_DIR"), "/simple_humanoid_floating.rs"));
}

#[allow(dead_code)]
mod solo_baked {
    include!(concat!(env!("OUT_DIR"), "/solo12_floating_baked.rs"));
}

#[allow(dead_code)]
mod humanoid_baked {
    include!(concat!(
        env!("OUT_DIR"),
        "/simple_humanoid_floating_baked.rs"
    ));
}

/// Random states per model.
const CASES: usize = 10;

/// Calls per timed round (a tenth of them for the derivatives).
const CALLS: usize = 2000;

/// Timed rounds per function: the fastest is kept.
const ROUNDS: usize = 100;

/// The robots: corpus file, contact frames.
const ROBOTS: [(&str, &[&str]); 2] = [
    ("solo12", &["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]),
    ("simple_humanoid", &["l_ankle", "r_ankle"]),
];

fn load(name: &str) -> Result<Model, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus/");
    let text = std::fs::read_to_string(format!("{path}{name}.urdf")).map_err(|e| e.to_string())?;
    Ok(UrdfImport::parse(&text, name, &UrdfOptions::floating())
        .map_err(|e| e.to_string())?
        .model)
}

fn numbers(out: &mut String, tag: &str, xs: impl IntoIterator<Item = f64>) {
    out.push_str(tag);
    for x in xs {
        out.push_str(&format!(" {x:?}"));
    }
    out.push('\n');
}

fn rows(out: &mut String, tag: &str, m: &DMatrix<f64>) {
    let t = m.transpose();
    numbers(out, tag, t.iter().copied());
}

/// `(u̇, λ)` of `kanegen_runtime::contact` with `N` speeds and `K` contact rows.
fn constrained<const N: usize, const K: usize>(
    ff: &FreeFlyer<f64>,
    frames: &[usize],
    q: &[f64],
    u: &[f64],
    f: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let contacts: Vec<Contact<usize>> = frames.iter().map(|&i| Contact::point(i)).collect();
    let uv = SVector::<f64, N>::from_column_slice(u);
    let c = ContactJacobian::<f64, N, K>::stack(&contacts, &uv, |frame| {
        let j = ff.frame_jacobian(q, frame);
        (
            SMatrix::from_iterator(j.iter().copied()),
            ff.frame_bias_acceleration(q, u, frame),
        )
    })
    .map_err(|e| e.to_string())?;
    let m = SMatrix::<f64, N, N>::from_iterator(ff.mass_matrix(q).iter().copied());
    let h = SVector::<f64, N>::from_iterator(ff.nonlinear_effects(q, u).iter().copied());
    let fv = SVector::<f64, N>::from_column_slice(f);
    let s = constrained_forward_dynamics(m, &h, &fv, &c, &ContactSettings::default())
        .map_err(|e| e.to_string())?;
    Ok((s.ud.as_slice().to_vec(), s.lambda.as_slice().to_vec()))
}

/// A state of the comparison: `q` (NQ), `u`, `u̇` and the actuation `f` (zero on the base).
struct State {
    q: Vec<f64>,
    u: Vec<f64>,
    ud: Vec<f64>,
    f: Vec<f64>,
}

/// The [`CASES`] random states of the comparison for a model of `nq` coordinates and `nv`
/// speeds, from `rng`.
fn states(rng: &mut SplitMix64, nq: usize, nv: usize) -> Vec<State> {
    (0..CASES)
        .map(|_| {
            let mut uni = |n: usize, s: f64| -> Vec<f64> {
                (0..n).map(|_| s * (2.0 * rng.next_f64() - 1.0)).collect()
            };
            let mut q = uni(nq, 1.0);
            let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[3..7].iter_mut().for_each(|x| *x /= norm);
            let (u, ud) = (uni(nv, 1.0), uni(nv, 1.0));
            let mut f = uni(nv, 2.0);
            f[..6].iter_mut().for_each(|x| *x = 0.0);
            State { q, u, ud, f }
        })
        .collect()
}

/// The contact frames' link indices in `model`.
fn contact_links(model: &Model, feet: &[&str]) -> Result<Vec<usize>, String> {
    feet.iter()
        .map(|f| {
            model
                .links
                .iter()
                .position(|l| l.name == *f)
                .ok_or(format!("{}: no frame {f}", model.name))
        })
        .collect()
}

fn write(dir: &str) -> Result<(), String> {
    let mut out = format!("ff-cases {}\n", ROBOTS.len() * CASES);
    let mut rng = SplitMix64::new(48);
    let mut k = 0;
    for (name, feet) in ROBOTS {
        let model = load(name)?;
        let ff = FreeFlyer::<f64>::new(&model).map_err(|e| e.to_string())?;
        let pm = kanegen::pinocchio::export_free_flyer(&model, &model.param_values())
            .map_err(|e| e.to_string())?;
        let frames = contact_links(&model, feet)?;
        let (nq, nv) = (ff.nq(), ff.dof());
        for State { q, u, ud, f } in states(&mut rng, nq, nv) {
            out.push_str(&format!(
                "ff-case {k} nq {nq} nv {nv} contacts {}\n",
                frames.len()
            ));
            out.push_str(&pm.to_text());
            for &i in &frames {
                let p = &pm.frames[i];
                out.push_str(&format!("contact {} {}", p.name, p.joint));
                numbers(
                    &mut out,
                    "",
                    p.rotation.into_iter().flatten().chain(p.translation),
                );
            }
            numbers(&mut out, "q", q.iter().copied());
            numbers(&mut out, "u", u.iter().copied());
            numbers(&mut out, "ud", ud.iter().copied());
            rows(&mut out, "M", &ff.mass_matrix(&q));
            numbers(
                &mut out,
                "nle",
                ff.nonlinear_effects(&q, &u).iter().copied(),
            );
            numbers(&mut out, "g", ff.gravity(&q).iter().copied());
            numbers(
                &mut out,
                "tau",
                ff.inverse_dynamics(&q, &u, &ud).iter().copied(),
            );
            rows(&mut out, "Ag", &ff.centroidal_momentum_matrix(&q));
            numbers(
                &mut out,
                "dhg",
                ff.centroidal_momentum_bias(&q, &u).iter().copied(),
            );
            let (dq, du) = ff.inverse_dynamics_derivatives(&q, &u, &ud);
            rows(&mut out, "dtau_dq", &dq);
            rows(&mut out, "dtau_du", &du);
            let (cud, lambda) = reference_constrained(&ff, &frames, &q, &u, &f)?;
            numbers(&mut out, "f", f.iter().copied());
            numbers(&mut out, "cud", cud);
            numbers(&mut out, "lambda", lambda);
            k += 1;
        }
    }
    let path = format!("{dir}/ff-cases.txt");
    std::fs::write(&path, out).map_err(|e| format!("{path}: {e}"))?;
    println!("{path}: {k} free-flyer cases");
    Ok(())
}

/// [`constrained`] for the robots of [`ROBOTS`] (their speed and contact-row counts).
fn reference_constrained(
    ff: &FreeFlyer<f64>,
    frames: &[usize],
    q: &[f64],
    u: &[f64],
    f: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), String> {
    match (ff.dof(), frames.len()) {
        (18, 4) => constrained::<18, 12>(ff, frames, q, u, f),
        (35, 2) => constrained::<35, 6>(ff, frames, q, u, f),
        other => Err(format!("no case for (NV, contacts) = {other:?}")),
    }
}

/// The fastest round's ns per call of `f(i)`, `i` counting the calls.
fn time_ns(calls: usize, mut f: impl FnMut(usize)) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..ROUNDS {
        let start = Instant::now();
        for i in 0..calls {
            f(black_box(i));
        }
        best = best.min(start.elapsed().as_nanos() as f64 / calls as f64);
    }
    best
}

/// Largest difference relative to the largest entry of `want`.
fn rel_err(got: &[f64], want: &[f64]) -> f64 {
    let scale = want.iter().fold(1e-300_f64, |m, x| m.max(x.abs()));
    got.iter()
        .zip(want)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()))
        / scale
}

/// The timings of the functions both forms of a module have (M into a kept matrix, c, h, g, τ
/// and the derivatives) on the states `$st(i)`, keys prefixed by `$prefix`.
macro_rules! shared_rows {
    ($r:expr, $prefix:expr, $st:expr, $m_out:expr, $d_out:expr) => {{
        let (r, st, m_out, d_out) = ($r, $st, $m_out, $d_out);
        vec![
            (
                format!("{}mass_matrix_into", $prefix),
                time_ns(CALLS, |i| {
                    black_box(r).mass_matrix_into(&st(i).0, black_box(&mut *m_out));
                }),
            ),
            (
                format!("{}coriolis", $prefix),
                time_ns(CALLS, |i| {
                    black_box(black_box(r).coriolis(&st(i).0, &st(i).1));
                }),
            ),
            (
                format!("{}nonlinear_effects", $prefix),
                time_ns(CALLS, |i| {
                    black_box(black_box(r).nonlinear_effects(&st(i).0, &st(i).1));
                }),
            ),
            (
                format!("{}gravity", $prefix),
                time_ns(CALLS, |i| {
                    black_box(black_box(r).gravity(&st(i).0));
                }),
            ),
            (
                format!("{}inverse_dynamics", $prefix),
                time_ns(CALLS, |i| {
                    let (q, u, ud, _) = st(i);
                    black_box(black_box(r).inverse_dynamics(q, u, ud));
                }),
            ),
            (
                format!("{}inverse_dynamics_derivatives_into", $prefix),
                time_ns(CALLS / 10, |i| {
                    let (q, u, ud, _) = st(i);
                    black_box(r).inverse_dynamics_derivatives_into(
                        q,
                        u,
                        ud,
                        black_box(&mut *d_out),
                    );
                }),
            ),
        ]
    }};
}

/// Checks and times the generated module `$m` (wrapper `$robot`, `$k` contact rows) of the
/// corpus robot `$name` with contact frames `$feet`; appends to `$text`.
macro_rules! time_robot {
    ($m:ident, $baked:ident, $robot:ident, $k:literal, $name:expr, $feet:expr, $text:expr) => {{
        use $m::{DOF, Frame, NQ, $robot};
        type Q = SVector<f64, NQ>;
        type U = SVector<f64, DOF>;
        let (name, feet): (&str, &[&str]) = ($name, $feet);
        let model = load(name)?;
        let reference = FreeFlyer::<f64>::new(&model).map_err(|e| e.to_string())?;
        let robot = $robot::default();
        let frames: Vec<Frame> = feet
            .iter()
            .map(|f| Frame::from_name(f).ok_or(format!("{name}: no generated frame {f}")))
            .collect::<Result<_, _>>()?;
        let links = contact_links(&model, feet)?;
        let contacts: Vec<Contact<Frame>> = frames.iter().map(|&f| Contact::point(f)).collect();
        // The whole constrained forward dynamics from the generated functions: M factored along
        // the tree (`mass_matrix_factor`), h, and the feet's Jacobians and bias accelerations, which are in the base frame's axes. The
        // constraint rows are solved in those axes (the same equations, rotated per contact);
        // λ is rotated to the world's at the end.
        let constrained = |q: &Q,
                           u: &U,
                           f: &U|
         -> Result<ConstrainedAcceleration<f64, DOF, $k>, String> {
            let c = ContactJacobian::<f64, DOF, $k>::stack(&contacts, u, |frame| {
                (
                    robot.frame_jacobian(q, frame),
                    robot.frame_bias_acceleration(q, u, frame),
                )
            })
            .map_err(|e| e.to_string())?;
            let factor = kanegen_runtime::Multibody::mass_matrix_factor(&robot, q)
                .ok_or(format!("{name}: M not positive definite"))?;
            let h = robot.nonlinear_effects(q, u);
            let mut s = constrained_forward_dynamics_factored(
                &factor,
                &h,
                f,
                &c,
                &ContactSettings::default(),
            )
            .map_err(|e| e.to_string())?;
            let r0 = kanegen_reference::se3::quaternion_to_rotation([q[3], q[4], q[5], q[6]]);
            for k in 0..$k / 3 {
                let l = r0 * s.lambda.fixed_rows::<3>(3 * k);
                s.lambda.fixed_rows_mut::<3>(3 * k).copy_from(&l);
            }
            Ok(s)
        };
        let mut rng = SplitMix64::new(48);
        let states: Vec<(Q, U, U, U)> = states(&mut rng, NQ, DOF)
            .into_iter()
            .map(|s| {
                (
                    Q::from_column_slice(&s.q),
                    U::from_column_slice(&s.u),
                    U::from_column_slice(&s.ud),
                    U::from_column_slice(&s.f),
                )
            })
            .collect();
        // The generated code against the reference on the timed states.
        let mut worst = 0.0_f64;
        for (q, u, ud, f) in &states {
            let (qs, us, uds) = (q.as_slice(), u.as_slice(), ud.as_slice());
            let tau = robot.inverse_dynamics(q, u, ud);
            worst = worst.max(rel_err(
                tau.as_slice(),
                reference.inverse_dynamics(qs, us, uds).as_slice(),
            ));
            worst = worst.max(rel_err(
                robot.mass_matrix(q).as_slice(),
                reference.mass_matrix(qs).as_slice(),
            ));
            let fd = kanegen_runtime::Multibody::forward_dynamics(&robot, q, u, &tau)
                .ok_or(format!("{name}: M not positive definite"))?;
            worst = worst.max(rel_err(fd.as_slice(), uds));
            let s = constrained(q, u, f)?;
            let (cud, lambda) = reference_constrained(&reference, &links, qs, us, f.as_slice())?;
            worst = worst.max(rel_err(s.ud.as_slice(), &cud));
            worst = worst.max(rel_err(s.lambda.as_slice(), &lambda));
        }
        println!(
            "{name}: generated vs the reference recursion (τ, M, forward dynamics, constrained u̇ and λ): {worst:.1e}"
        );
        if worst > 1e-9 {
            return Err(format!("{name}: the generated code differs from the reference by {worst:e}"));
        }
        let n = states.len();
        let st = |i: usize| &states[i % n];
        let robot = &robot;
        let taus: Vec<U> = states
            .iter()
            .map(|(q, u, ud, _)| robot.inverse_dynamics(q, u, ud))
            .collect();
        let mut m_out = SMatrix::<f64, DOF, DOF>::zeros();
        let mut d_out = SMatrix::<f64, DOF, { 2 * DOF }>::zeros();
        let mut rows: Vec<(String, f64)> = vec![
            ("mass_matrix".into(), time_ns(CALLS, |i| {
                black_box(black_box(robot).mass_matrix(&st(i).0));
            })),
            ("centroidal_momentum_matrix".into(), time_ns(CALLS, |i| {
                black_box(black_box(robot).centroidal_momentum_matrix(&st(i).0));
            })),
            ("forward_dynamics".into(), time_ns(CALLS, |i| {
                let (q, u, _, _) = st(i);
                black_box(kanegen_runtime::Multibody::forward_dynamics(
                    black_box(robot),
                    q,
                    u,
                    &taus[i % n],
                ));
            })),
            // The same through a dense factorisation (the factor of a type without
            // SPEED_PARENTS: every speed the previous one's child), for scale.
            ("forward_dynamics_dense".into(), time_ns(CALLS, |i| {
                let (q, u, _, _) = st(i);
                let bias = black_box(robot).inverse_dynamics(q, u, &U::zeros());
                let m = robot.mass_matrix(q);
                let factor = TreeFactor::new(&m, &chain_parents()).expect("M positive definite");
                black_box(factor.solve(&(taus[i % n] - bias)));
            })),
            ("constrained_forward_dynamics".into(), time_ns(CALLS, |i| {
                let (q, u, _, f) = st(i);
                black_box(constrained(black_box(q), u, f).ok());
            })),
        ];
        rows.extend(shared_rows!(robot, "", st, &mut m_out, &mut d_out));
        // The baked module (parameter values folded in), checked on the same states.
        let baked = $baked::$robot::default();
        let mut worst = 0.0_f64;
        for (q, u, ud, _) in &states {
            let d = robot.inverse_dynamics_derivatives(q, u, ud);
            let db = baked.inverse_dynamics_derivatives(q, u, ud);
            worst = worst.max(rel_err(db.as_slice(), d.as_slice()));
            let h = robot.nonlinear_effects(q, u);
            worst = worst.max(rel_err(baked.nonlinear_effects(q, u).as_slice(), h.as_slice()));
            let m = robot.mass_matrix(q);
            worst = worst.max(rel_err(baked.mass_matrix(q).as_slice(), m.as_slice()));
        }
        if worst > 1e-9 {
            return Err(format!("{name}: the baked module differs by {worst:e}"));
        }
        rows.extend(shared_rows!(&baked, BAKED, st, &mut m_out, &mut d_out));
        // Keyed by the model's name, as the harness keys Pinocchio's times.
        for (function, ns) in rows {
            println!("kanegen {}/{function:<34} {ns:9.1} ns", model.name);
            $text.push_str(&format!("{}/{function} {ns}\n", model.name));
        }
    }};
}

fn time(dir: &str) -> Result<(), String> {
    let mut text = String::new();
    time_robot!(solo, solo_baked, Solo, 12, ROBOTS[0].0, ROBOTS[0].1, text);
    time_robot!(
        humanoid,
        humanoid_baked,
        SimpleHumanoid,
        6,
        ROBOTS[1].0,
        ROBOTS[1].1,
        text
    );
    append(&Path::new(dir).join("kanegen-ff-times.txt"), &text)
}

/// One row of the tables: our label and key, Pinocchio's label and key (`harness_ff.cpp`).
const ROWS: [(&str, &str, &str, &str); 10] = [
    ("M `mass_matrix`", "mass_matrix", "`crba`", "crba"),
    (
        "M `mass_matrix_into` (a kept matrix)",
        "mass_matrix_into",
        "`crba`",
        "crba",
    ),
    (
        "c `coriolis`",
        "coriolis",
        "`nonLinearEffects` (c + g)",
        "nle",
    ),
    (
        "c + g `nonlinear_effects`",
        "nonlinear_effects",
        "`nonLinearEffects`",
        "nle",
    ),
    (
        "g `gravity`",
        "gravity",
        "`computeGeneralizedGravity`",
        "gravity",
    ),
    ("τ `inverse_dynamics`", "inverse_dynamics", "`rnea`", "rnea"),
    (
        "A_G `centroidal_momentum_matrix`",
        "centroidal_momentum_matrix",
        "`ccrba`",
        "ccrba",
    ),
    (
        "∂τ/∂q, ∂τ/∂u `inverse_dynamics_derivatives_into`",
        "inverse_dynamics_derivatives_into",
        "`computeRNEADerivatives`",
        "rnea_derivatives",
    ),
    (
        "u̇ `forward_dynamics` (M factored along the tree)",
        "forward_dynamics",
        "`aba`",
        "aba",
    ),
    (
        "u̇, λ under the contacts (M factored, h, the feet's J and J̇u, `contact::constrained_forward_dynamics_factored`)",
        "constrained_forward_dynamics",
        "`constraintDynamics` (3-D contacts)",
        "constraint_dynamics",
    ),
];

/// Prefix of the keys of Pinocchio's CppADCodeGen code (`benches/pinocchio/codegen.cpp`).
const GENERATED: &str = "cg_";

/// Prefix of the keys of kanegen's baked modules.
const BAKED: &str = "baked_";

fn report(dir: &str) -> Result<(), String> {
    let dir = Path::new(dir);
    let (ours, our_runs) = best_times(&dir.join("kanegen-ff-times.txt"))?;
    let (pin, pin_runs) = best_times(&dir.join("pinocchio-ff-times.txt"))?;
    for (file, feet) in ROBOTS {
        let name = load(file)?.name;
        println!("\n{name} (floating base, {} point contacts):\n", feet.len());
        println!("| kanegen (Rust) | ns | Pinocchio (C++) | ns | Pinocchio / kanegen |");
        println!("|---|--:|---|--:|--:|");
        for (our_label, our_key, pin_label, pin_key) in ROWS {
            let (ok, pk) = (format!("{name}/{our_key}"), format!("{name}/{pin_key}"));
            let (Some(a), Some(b)) = (ours.get(&ok), pin.get(&pk)) else {
                return Err(format!("no time for `{ok}` or `{pk}`"));
            };
            println!(
                "| {our_label} | {a:.0} | {pin_label} | {b:.0} | {:.1}× |",
                b / a
            );
        }
        if let (Some(tree), Some(dense)) = (
            ours.get(&format!("{name}/forward_dynamics")),
            ours.get(&format!("{name}/forward_dynamics_dense")),
        ) {
            println!(
                "\n`forward_dynamics` through a dense factorisation instead of the tree's: {dense:.0} ns ({:.1}× the tree's)",
                dense / tree
            );
        }
        // Pinocchio's CppADCodeGen code (`CODEGEN=1`), where it was timed. It folds the
        // parameter values in, as kanegen's baked modules do.
        if pin.contains_key(&format!("{name}/{GENERATED}crba")) {
            println!(
                "\n| kanegen (Rust) | run-time parameters, ns | baked, ns | Pinocchio's generated code (CppADCodeGen, C) | ns | Pinocchio / kanegen (run-time) | Pinocchio / kanegen (baked) |"
            );
            println!("|---|--:|--:|---|--:|--:|--:|");
            for (our_label, our_key, pin_label, pin_key) in ROWS {
                let ok = format!("{name}/{our_key}");
                let bk = format!("{name}/{BAKED}{our_key}");
                let pk = format!("{name}/{GENERATED}{pin_key}");
                if let (Some(a), Some(c), Some(b)) = (ours.get(&ok), ours.get(&bk), pin.get(&pk)) {
                    println!(
                        "| {our_label} | {a:.0} | {c:.0} | {pin_label} | {b:.0} | {:.1}× | {:.1}× |",
                        b / a,
                        b / c
                    );
                }
            }
        }
    }
    println!(
        "\n(best of {our_runs} kanegen and {pin_runs} Pinocchio runs; each figure the fastest round of {ROUNDS} rounds)"
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.as_slice() {
        [cmd, dir] if cmd == "write" => write(dir),
        [cmd, dir] if cmd == "time" => time(dir),
        [cmd, dir] if cmd == "report" => report(dir),
        _ => {
            eprintln!("usage: pinocchio_free_flyer <write|time|report> DIR");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
