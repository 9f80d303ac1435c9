//! Agreement with the official reference recursion (`kanegen-reference`, a naive Kane's-method
//! implementation): `M`, `c`, `g` and `τ` on 250 random states per model, for default
//! parameters, this crate's random parameters and the reference's own random physical
//! parameters, to 1e-10 relative (max |difference| / max |reference entry|).

mod common;

use std::f64::consts::PI;

use common::{Rng, load_model, random_params, rel_err};
use kanegen_model::Model;
use kanegen_rbd::Rbd;
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params};

const STATES: usize = 250;
const TOL: f64 = 1e-10;

fn compare<const N: usize>(model: &Model, seed: u64) {
    let mut rng = Rng::new(seed);
    let mut theirs = SplitMix64::new(seed ^ 0x5EED);
    let mut worst = [0.0f64; 4];
    for case in 0..STATES {
        let params = match case % 3 {
            0 => model.param_values(),
            1 => random_params(model, &mut rng),
            _ => random_physical_params(model, &mut || theirs.next_f64()),
        };
        let rbd = Rbd::<N>::new(model, &params).expect("builds");
        let reference = Reference::<f64>::with_params(model, &params);
        let q = rng.vec::<N>(-PI, PI);
        let u = rng.vec::<N>(-2.0, 2.0);
        let ud = rng.vec::<N>(-3.0, 3.0);
        let (qs, us, uds) = (q.as_slice(), u.as_slice(), ud.as_slice());

        let m = rbd.mass_matrix(&q);
        let m_ref = reference.mass_matrix(qs);
        let g_ref = reference.gravity(qs);
        let checks = [
            ("M", rel_err(m.as_slice(), m_ref.as_slice(), 1e-300)),
            (
                "c",
                rel_err(
                    rbd.coriolis(&q, &u).as_slice(),
                    reference.coriolis(qs, us).as_slice(),
                    1e-300,
                ),
            ),
            (
                "g",
                rel_err(rbd.gravity(&q).as_slice(), g_ref.as_slice(), 1e-300),
            ),
            (
                "tau",
                rel_err(
                    rbd.inverse_dynamics(&q, &u, &ud).as_slice(),
                    reference.inverse_dynamics(qs, us, uds).as_slice(),
                    1e-300,
                ),
            ),
        ];
        for (i, (what, e)) in checks.into_iter().enumerate() {
            worst[i] = worst[i].max(e);
            assert!(
                e < TOL,
                "{} case {case}: {what} differs from kanegen-reference, rel err {e:.3e}",
                model.name
            );
        }
    }
    println!(
        "{}: worst rel err M {:.1e}, c {:.1e}, g {:.1e}, tau {:.1e}",
        model.name, worst[0], worst[1], worst[2], worst[3]
    );
}

#[test]
fn two_link_matches_kanegen_reference() {
    compare::<2>(&load_model("two-link"), 11);
}

#[test]
fn krang_fixed_wheels_matches_kanegen_reference() {
    compare::<17>(&load_model("krang-fixed-wheels"), 12);
}

#[test]
fn krang_matches_kanegen_reference() {
    compare::<19>(&load_model("krang"), 13);
}
