//! Criterion benchmarks of Krang's generated kinematics (`krang-dynamics`, feature
//! `kinematics`) against the numeric passes of `kanegen-rbd` (`RbdFrame`, `Rbd::com_jacobian`):
//! both hands' Jacobians, both hands' pose + Jacobian + bias acceleration, and the CoM Jacobian,
//! with one `coriolis` call in the same run for the target "both hands' Jacobians cost less than
//! one `coriolis` call"; and a whole-body controller's terms at one state (M, c + g, the CoM, its
//! Jacobian and bias, both hands' pose, Jacobian and bias) as the combined `whole_body_terms`
//! against the eleven separate calls, with the 17-angle `sin_cos_n` every call computes.
//!
//! Ids `kinematics/<what>/<variant>`: `hands_jacobian`, `hands_pose_jacobian_bias`,
//! `com_jacobian`, `coriolis` (variants `generated`, `rbd`; `hands_jacobian` also `combined`,
//! the one-program `Krang::hands_jacobians`), `whole_body` (`combined`, `separate`),
//! `sin_cos_17/generated`. Inputs cycle through 8 random
//! states behind `black_box`; the variants are checked against each other before timing.
//!
//! Also `arm_end/pose_jacobian/{generated,rbd,k}`: the end link of the URDF arm
//! (`models/singlearm.urdf`), its pose and Jacobian, generated, by `kanegen-rbd` and by the `k`
//! crate (`SerialChain::set_joint_positions_unchecked`, `update_transforms`, `k::jacobian`)
//! loaded from the same file.
//!
//! ```sh
//! cargo bench --bench kinematics
//! ```

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kanegen_model::{AngleSnap, Model, UrdfOptions};
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
    // The two implementations agree; the combined call equals the separate ones (bit for bit
    // in the baseline copy, `crates/krang-dynamics/tests/kinematics.rs`; here, in the
    // dispatched copy, which fuses multiply-adds, to rounding).
    macro_rules! close {
        ($a:expr, $b:expr) => {{
            let (a, b) = ($a, $b);
            let d = (a - b).amax();
            assert!(d <= 1e-12 * b.amax().max(1.0), "{}: {d:e}", stringify!($a));
        }};
    }
    for (q, u) in &states {
        let dc = (k.com_jacobian(q) - rbd.com_jacobian(q)).amax();
        assert!(dc < 1e-12, "CoM Jacobian: {dc:e}");
        let w = k.whole_body_terms(q, u);
        close!(w.mass_matrix, k.mass_matrix(q));
        close!(w.nonlinear_effects, k.nonlinear_effects(q, u));
        close!(w.com_jacobian, k.com_jacobian(q));
        close!(w.frame_jacobian_right_hand, k.frame_jacobian(q, hands[1]));
        let j = k.hands_jacobians(q);
        close!(j.frame_jacobian_left_hand, k.frame_jacobian(q, hands[0]));
        close!(j.frame_jacobian_right_hand, k.frame_jacobian(q, hands[1]));
        close!(
            w.frame_bias_acceleration_left_hand,
            k.frame_bias_acceleration(q, u, hands[0])
        );
    }
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
    bench!("hands_jacobian/combined", |q, _u| k.hands_jacobians(q));
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
    bench!("com_jacobian/rbd", |q, _u| rbd.com_jacobian(q));
    // A whole-body controller's terms at one state: one combined call against the separate
    // calls (M, c + g, CoM, its Jacobian and bias, both hands' pose, Jacobian and bias).
    bench!("whole_body/combined", |q, u| k.whole_body_terms(q, u));
    bench!("whole_body/separate", |q, u| (
        k.mass_matrix(q),
        k.nonlinear_effects(q, u),
        k.center_of_mass(q),
        k.com_jacobian(q),
        k.com_bias_acceleration(q, u),
        hands.map(|h| (
            k.frame_pose(q, h),
            k.frame_jacobian(q, h),
            k.frame_bias_acceleration(q, u, h)
        ))
    ));
    // The trigonometry one call computes: 17 angles (what sharing only sin/cos would save
    // per call after the first).
    bench!("sin_cos_17/generated", |q, _u| {
        let a: [f64; 17] = core::array::from_fn(|i| q[i + 2]);
        kanegen_runtime::trig::sin_cos_n(a)
    });
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
    targets = kinematics, arm
}
criterion_main!(benches);

/// The 7-DOF arm of `models/singlearm.urdf` with every registry function (generated by the root
/// package's `build.rs`).
#[allow(missing_docs, dead_code, clippy::all)]
mod arm_all {
    include!(concat!(env!("OUT_DIR"), "/singlearm_all.rs"));
}

/// The arm's end link `L7_EFF`: pose and Jacobian (generated, `kanegen-rbd`, and the `k`
/// crate's forward kinematics and Jacobian from the same URDF).
fn arm(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/singlearm.urdf");
    let model = Model::from_urdf_file(path, &UrdfOptions::default()).expect("singlearm.urdf loads");
    let params = model.param_values();
    let rbd = Rbd::<7>::new(&model, &params).expect("builds");
    let end = model.link_index("L7_EFF").expect("end link");
    let rbd_end = RbdFrame::new(&model, &params, end).expect("frame");
    let generated = arm_all::SingleArm::new(arm_all::Params::default());
    let gen_end = arm_all::Frame::from_name("L7_EFF").expect("end frame");
    // `k` takes the URDF's angles as written; the generated module snaps rounded multiples of
    // π/2 (`3.1416` → π, AngleSnap::Rounded): `k` is checked against the same URDF imported
    // without snapping.
    let unsnapped = UrdfOptions {
        snap_angles: AngleSnap::Off,
        ..UrdfOptions::default()
    };
    let exact = Model::from_urdf_file(path, &unsnapped).expect("singlearm.urdf loads");
    let exact_params = exact.param_values();
    let rbd_exact = Rbd::<7>::new(&exact, &exact_params).expect("builds");
    let exact_end = RbdFrame::new(&exact, &exact_params, end).expect("frame");
    let chain = k::Chain::<f64>::from_urdf_file(path).expect("k loads the URDF");
    let k_end = chain.find_link("L7_EFF").expect("k finds the end link");
    let serial = k::SerialChain::from_end(k_end);
    let mut r = SplitMix64::new(9);
    let states: Vec<SVector<f64, 7>> = (0..8)
        .map(|_| SVector::from_fn(|_, _| -2.0 + 4.0 * r.next_f64()))
        .collect();
    for q in &states {
        serial.set_joint_positions_unchecked(q.as_slice());
        serial.update_transforms();
        let kj = k::jacobian(&serial);
        let kt = k_end.world_transform().expect("updated");
        let ej = rbd_exact.frame_jacobian(q, &exact_end);
        let (_, ep) = rbd_exact.frame_pose(q, &exact_end);
        let dj = (0..6)
            .flat_map(|i| (0..7).map(move |j| (i, j)))
            .map(|(i, j)| (kj[(i, j)] - ej[(i, j)]).abs())
            .fold(0.0, f64::max);
        let dp = (0..3)
            .map(|i| (kt.translation.vector[i] - ep[i]).abs())
            .fold(0.0, f64::max);
        assert!(dj < 1e-12 && dp < 1e-12, "k vs rbd: {dj:e} {dp:e}");
        let gj = generated.frame_jacobian(q, gen_end);
        let rj = rbd.frame_jacobian(q, &rbd_end);
        assert!((rj - gj).amax() < 1e-12);
    }
    let mut group = c.benchmark_group("arm_end");
    let mut i = 0;
    group.bench_function("pose_jacobian/generated", |b| {
        b.iter(|| {
            let q = black_box(&states[i & 7]);
            i += 1;
            black_box((
                generated.frame_pose(q, gen_end),
                generated.frame_jacobian(q, gen_end),
            ))
        })
    });
    group.bench_function("pose_jacobian/rbd", |b| {
        b.iter(|| {
            let q = black_box(&states[i & 7]);
            i += 1;
            black_box((rbd.frame_pose(q, &rbd_end), rbd.frame_jacobian(q, &rbd_end)))
        })
    });
    group.bench_function("pose_jacobian/k", |b| {
        b.iter(|| {
            let q = black_box(&states[i & 7]);
            i += 1;
            serial.set_joint_positions_unchecked(q.as_slice());
            serial.update_transforms();
            black_box((k_end.world_transform(), k::jacobian(&serial)))
        })
    });
    group.finish();
}
