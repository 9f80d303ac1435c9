//! The centre-of-mass pass (`center_of_mass`, `com_jacobian`) against the reference recursion's
//! frame states, on Krang (wheeled base: the wheels are point masses on the axle), the
//! fixed-wheel tree and the URDF arm, with random physical parameters and states: the centre of
//! mass is `Σ m_k (p_k + R_k S_k) / m`, and `J u` is the mass-weighted velocity of the bodies'
//! centres, `Σ m_k R_k (v_k + ω_k × S_k) / m` (plus the wheels' `2 mw ẋ x̂`), to 1e-11.

mod common;

use std::f64::consts::PI;

use common::{Rng, load_model};
use kanegen_model::Model;
use kanegen_rbd::Rbd;
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params};
use nalgebra::Vector3;

fn close(a: Vector3<f64>, b: Vector3<f64>) -> bool {
    (a - b).abs().max() <= 1e-11 * b.abs().max().max(1.0)
}

fn compare<const N: usize>(model: &Model, seed: u64) {
    let mut rng = Rng::new(seed);
    let mut theirs = SplitMix64::new(seed ^ 0x5EED);
    for _ in 0..10 {
        let params = random_physical_params(model, &mut || theirs.next_f64());
        let rbd = Rbd::<N>::new(model, &params).expect("builds");
        let reference = Reference::<f64>::with_params(model, &params);
        let q = rng.vec::<N>(-PI, PI);
        let u = rng.vec::<N>(-2.0, 2.0);
        let zero = vec![0.0; N];
        let states = reference.frame_states(q.as_slice(), u.as_slice(), &zero);
        // Σ m_k r_Gk and Σ m_k v_Gk over the bodies, in frame 0 (axes and origin).
        let (mut mass, mut moment, mut momentum) = (0.0, Vector3::zeros(), Vector3::zeros());
        for (link, s) in model.links.iter().zip(&states) {
            let Some(b) = &link.body else { continue };
            let m = params[b.mass];
            let ms = Vector3::from_fn(|r, _| params[b.first_moment[r]]);
            mass += m;
            moment += m * s.position + s.rotation * ms;
            momentum += s.rotation * (m * s.velocity + s.omega.cross(&ms));
        }
        if let Some(w) = model.wheeled_base() {
            let mw2 = 2.0 * params[w.wheel_mass];
            mass += mw2;
            momentum += Vector3::new(mw2 * u[w.x_speed], 0.0, 0.0);
        }
        let com = rbd.center_of_mass(&q);
        assert!(close(com, moment / mass), "{}: centre of mass", model.name);
        let j = rbd.com_jacobian(&q);
        assert!(close(j * u, momentum / mass), "{}: J u", model.name);
    }
}

#[test]
fn com_pass_matches_the_reference_bodies() {
    compare::<19>(&load_model("krang"), 1);
    compare::<17>(&load_model("krang-fixed-wheels"), 2);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/singlearm.urdf");
    let arm = Model::from_urdf_file(path, &Default::default()).expect("URDF imports");
    compare::<7>(&arm, 3);
}
