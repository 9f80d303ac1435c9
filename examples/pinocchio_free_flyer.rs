//! Free-flyer cases for the Pinocchio harness (`benches/pinocchio/run.sh`, which runs
//! `benches/pinocchio/harness_ff.cpp` on them; docs/correctness.md):
//!
//! ```text
//! cargo run --release --example pinocchio_free_flyer -- DIR
//! ```
//!
//! writes `DIR/ff-cases.txt`: Solo 12 (four point contacts at the feet) and `simple_humanoid`
//! (two point contacts at the ankles) of the URDF corpus, each exported with a free-flyer root
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

use std::process::ExitCode;

use kanegen_model::{Model, UrdfImport, UrdfOptions};
use kanegen_reference::FreeFlyer;
use kanegen_reference::random::SplitMix64;
use kanegen_runtime::contact::{
    Contact, ContactJacobian, ContactSettings, constrained_forward_dynamics,
};
use nalgebra::{DMatrix, SMatrix, SVector};

/// Random states per model.
const CASES: usize = 10;

fn load(name: &str) -> Result<Model, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus/");
    let text = std::fs::read_to_string(format!("{path}{name}.urdf")).map_err(|e| e.to_string())?;
    Ok(UrdfImport::parse(&text, name, &UrdfOptions::default())
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

fn write(dir: &str) -> Result<(), String> {
    let robots: [(&str, &[&str]); 2] = [
        ("solo12", &["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]),
        ("simple_humanoid", &["l_ankle", "r_ankle"]),
    ];
    let mut out = format!("ff-cases {}\n", robots.len() * CASES);
    let mut rng = SplitMix64::new(48);
    let mut k = 0;
    for (name, feet) in robots {
        let model = load(name)?;
        let ff = FreeFlyer::<f64>::new(&model).map_err(|e| e.to_string())?;
        let pm = kanegen::pinocchio::export_free_flyer(&model, &model.param_values())
            .map_err(|e| e.to_string())?;
        let frames: Vec<usize> = feet
            .iter()
            .map(|f| {
                model
                    .links
                    .iter()
                    .position(|l| l.name == *f)
                    .ok_or(format!("{name}: no frame {f}"))
            })
            .collect::<Result<_, _>>()?;
        let (nq, nv) = (ff.nq(), ff.dof());
        for _ in 0..CASES {
            let mut uni = |n: usize, s: f64| -> Vec<f64> {
                (0..n).map(|_| s * (2.0 * rng.next_f64() - 1.0)).collect()
            };
            let mut q = uni(nq, 1.0);
            let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
            q[3..7].iter_mut().for_each(|x| *x /= norm);
            let (u, ud) = (uni(nv, 1.0), uni(nv, 1.0));
            let mut f = uni(nv, 2.0);
            f[..6].iter_mut().for_each(|x| *x = 0.0);
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
            let (cud, lambda) = match (nv, frames.len()) {
                (18, 4) => constrained::<18, 12>(&ff, &frames, &q, &u, &f)?,
                (35, 2) => constrained::<35, 6>(&ff, &frames, &q, &u, &f)?,
                other => return Err(format!("{name}: no case for (NV, contacts) = {other:?}")),
            };
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

fn main() -> ExitCode {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: pinocchio_free_flyer DIR");
        return ExitCode::from(2);
    };
    match write(&dir) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
