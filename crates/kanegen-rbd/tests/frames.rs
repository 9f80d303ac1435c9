//! The frame passes (`frame_pose`, `frame_jacobian`, `frame_bias_acceleration`) against the
//! reference recursion's frame states, for every frame (body frames, Krang's operational hand
//! frames, URDF links merged by fixed joints) of Krang, the fixed-wheel tree and the URDF arm,
//! with random physical parameters and states: the pose, `J u` (the frame's velocity and angular
//! velocity) and the bias (its acceleration and angular acceleration at `u̇ = 0`), to 1e-11.

mod common;

use std::f64::consts::PI;

use common::{Rng, load_model};
use kanegen_model::Model;
use kanegen_rbd::{Rbd, RbdFrame};
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params};
use nalgebra::{Matrix3, Vector3};

fn close(a: Vector3<f64>, b: Vector3<f64>) -> bool {
    (a - b).abs().max() <= 1e-11 * b.abs().max().max(1.0)
}

fn compare<const N: usize>(model: &Model, seed: u64) {
    let mut rng = Rng::new(seed);
    let mut theirs = SplitMix64::new(seed ^ 0xF4A3);
    for _ in 0..10 {
        let params = random_physical_params(model, &mut || theirs.next_f64());
        let rbd = Rbd::<N>::new(model, &params).expect("builds");
        let reference = Reference::<f64>::with_params(model, &params);
        let q = rng.vec::<N>(-PI, PI);
        let u = rng.vec::<N>(-2.0, 2.0);
        let zero = vec![0.0; N];
        let states = reference.frame_states(q.as_slice(), u.as_slice(), &zero);
        for (l, s) in states.iter().enumerate() {
            let name = &model.links[l].name;
            let f = RbdFrame::new(model, &params, l).expect("frame");
            let (r, p) = rbd.frame_pose(&q, &f);
            let rot_err: f64 = (r - s.rotation).abs().max();
            assert!(
                rot_err < 1e-12,
                "{} {name}: rotation {rot_err:e}",
                model.name
            );
            assert!(close(p, s.position), "{} {name}: position", model.name);
            let ju = rbd.frame_jacobian(&q, &f) * u;
            let rs: Matrix3<f64> = s.rotation;
            let (v, w) = (
                ju.fixed_rows::<3>(0).into_owned(),
                ju.fixed_rows::<3>(3).into_owned(),
            );
            assert!(close(v, rs * s.velocity), "{} {name}: J_v u", model.name);
            assert!(close(w, rs * s.omega), "{} {name}: J_ω u", model.name);
            let b = rbd.frame_bias_acceleration(&q, &u, &f);
            let (a, al) = (
                b.fixed_rows::<3>(0).into_owned(),
                b.fixed_rows::<3>(3).into_owned(),
            );
            assert!(close(a, rs * s.acceleration), "{} {name}: a", model.name);
            assert!(close(al, rs * s.alpha), "{} {name}: α", model.name);
        }
    }
}

#[test]
fn frame_passes_match_the_reference_frame_states() {
    let krang = load_model("krang");
    assert!(krang.link_index("left_hand").is_some());
    compare::<19>(&krang, 1);
    compare::<17>(&load_model("krang-fixed-wheels"), 2);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/singlearm.urdf");
    let arm = Model::from_urdf_file(path, &Default::default()).expect("URDF imports");
    assert!(
        arm.link_index("Bracket").is_some(),
        "merged link kept as a frame"
    );
    compare::<7>(&arm, 3);
}
