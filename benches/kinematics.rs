//! Criterion benchmarks of Krang's generated kinematics (`krang-dynamics`, feature
//! `kinematics`) against the numeric frame passes of `kanegen-rbd` (`RbdFrame`): both hands'
//! Jacobians, both hands' pose + Jacobian + bias acceleration, and the CoM Jacobian (generated
//! only: `kanegen-rbd` has no CoM pass), with one `coriolis` call in the same run for the
//! target "both hands' Jacobians cost less than one `coriolis` call".
//!
//! Ids `kinematics/<what>/<variant>`: `hands_jacobian`, `hands_pose_jacobian_bias`,
//! `com_jacobian`, `coriolis`; variants `generated`, `rbd`. Inputs cycle through 8 random
//! states behind `black_box`; the variants are checked against each other before timing.
//!
//! ```sh
//! cargo bench --bench kinematics
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kanegen_model::Model;
use kanegen_rbd::{Rbd, RbdFrame};
use kanegen_reference::random::SplitMix64;
use krang_dynamics::{Frame, Krang};
use nalgebra::SVector;

type V = SVector<f64, 19>;

fn states() -> Vec<(V, V)> {
    let mut r = SplitMix64::new(7);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * r.next_f64();
    (0..8)
        .map(|_| {
            let q = V::from_fn(|_, _| uniform(-3.1, 3.1));
            let u = V::from_fn(|_, _| uniform(-2.0, 2.0));
            (q, u)
        })
        .collect()
}

fn kinematics(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/krang.toml");
    let model = Model::from_toml_file(path).expect("krang.toml loads");
    let params = model.param_values();
    let rbd = Rbd::<19>::new(&model, &params).expect("builds");
    let k = Krang::default();
    let hands = [
        Frame::from_name("left_hand"),
        Frame::from_name("right_hand"),
    ]
    .map(|f| f.expect("krang.toml declares the hands"));
    let rbd_hands = ["left_hand", "right_hand"].map(|n| {
        let l = model.link_index(n).expect("hand frame");
        RbdFrame::new(&model, &params, l).expect("frame")
    });
    let states = states();
    // The two implementations agree.
    for (q, u) in &states {
        for (h, f) in hands.iter().zip(&rbd_hands) {
            let dj = (k.frame_jacobian(q, *h) - rbd.frame_jacobian(q, f)).amax();
            let db =
                (k.frame_bias_acceleration(q, u, *h) - rbd.frame_bias_acceleration(q, u, f)).amax();
            let (r, p) = rbd.frame_pose(q, f);
            let pose = k.frame_pose(q, *h);
            let dp = (pose.translation.vector - p).amax()
                + (pose.rotation.to_rotation_matrix().matrix() - r).amax();
            assert!(
                dj < 1e-12 && db < 1e-10 && dp < 1e-12,
                "{dj:e} {db:e} {dp:e}"
            );
        }
    }
    let mut group = c.benchmark_group("kinematics");
    macro_rules! bench {
        ($id:expr, |$q:ident, $u:ident| $body:expr) => {
            group.bench_function($id, |b| {
                let mut i = 0;
                b.iter(|| {
                    let (q, u) = &states[i & 7];
                    i += 1;
                    let ($q, $u) = (black_box(q), black_box(u));
                    black_box($body)
                })
            });
        };
    }
    bench!("hands_jacobian/generated", |q, _u| (
        k.frame_jacobian(q, hands[0]),
        k.frame_jacobian(q, hands[1])
    ));
    bench!("hands_jacobian/rbd", |q, _u| (
        rbd.frame_jacobian(q, &rbd_hands[0]),
        rbd.frame_jacobian(q, &rbd_hands[1])
    ));
    bench!("hands_pose_jacobian_bias/generated", |q, u| hands.map(
        |h| (
            k.frame_pose(q, h),
            k.frame_jacobian(q, h),
            k.frame_bias_acceleration(q, u, h)
        )
    ));
    bench!("hands_pose_jacobian_bias/rbd", |q, u| [0, 1].map(|i| (
        rbd.frame_pose(q, &rbd_hands[i]),
        rbd.frame_jacobian(q, &rbd_hands[i]),
        rbd.frame_bias_acceleration(q, u, &rbd_hands[i])
    )));
    bench!("com_jacobian/generated", |q, _u| k.com_jacobian(q));
    bench!("coriolis/generated", |q, u| k.coriolis(q, u));
    bench!("coriolis/rbd", |q, u| rbd.coriolis(q, u));
    group.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2))
        .sample_size(50)
}

criterion_group! {
    name = benches;
    config = config();
    targets = kinematics
}
criterion_main!(benches);
