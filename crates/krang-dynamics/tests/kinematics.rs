//! Krang's generated kinematics and energies (the opt-in registry functions enabled in
//! `build.rs`): the centre of mass above the axle at the upright pitch, `T = ½ uᵀ M u`,
//! `∂V/∂q = g`, and a hand's Jacobian against its pose. (Derivative identities with the base's
//! motion, on every frame and several models: `codegen/tests/kinematics.rs`.)

use krang_dynamics::{DOF, Frame, Krang, index};
use nalgebra::SVector;

type V = SVector<f64, DOF>;

/// Deterministic, varied states: `(q, u)`.
fn states() -> impl Iterator<Item = (V, V)> {
    (0..20).map(|k| {
        let k = f64::from(k);
        let q = V::from_fn(|i, _| (1.3 * i as f64 + 0.7 * k).sin() * 2.5);
        let u = V::from_fn(|i, _| (0.9 * i as f64 - 1.1 * k).cos() * 1.5);
        (q, u)
    })
}

#[test]
fn the_centre_of_mass_is_above_the_axle_at_the_upright_pitch() {
    let k = Krang::default();
    for (mut q, _) in states() {
        q[index::Q_IMU] = k.upright_pitch(&q);
        let com = k.center_of_mass(&q);
        assert!(com.x.abs() < 1e-12, "{com}");
        assert!(com.z > 0.0, "{com}");
    }
}

#[test]
fn energies_are_half_u_m_u_and_the_potential_of_g() {
    let k = Krang::default();
    for (q, u) in states() {
        let t = k.kinetic_energy(&q, &u);
        let half_umu = 0.5 * u.dot(&(k.mass_matrix(&q) * u));
        assert!((t - half_umu).abs() < 1e-12 * half_umu.abs().max(1.0));
        let g = k.gravity(&q);
        let h = 1e-6;
        for i in 0..DOF {
            let (mut qp, mut qm) = (q, q);
            qp[i] += h;
            qm[i] -= h;
            let dv = (k.potential_energy(&qp) - k.potential_energy(&qm)) / (2.0 * h);
            assert!((dv - g[i]).abs() < 1e-6 * g.amax().max(1.0), "row {i}");
        }
    }
}

#[test]
fn a_hand_frame_moves_with_its_jacobian() {
    let k = Krang::default();
    let hand = Frame::from_name("10l").expect("Krang has the frame 10l");
    assert_eq!(hand.name(), "10l");
    assert!(Frame::ALL.contains(&hand));
    for (q, mut u) in states() {
        // Frame 0 at rest, so that the pose relative to it is the pose in the ground.
        u[index::X] = 0.0;
        u[index::PSI] = 0.0;
        let h = 1e-6;
        let p = |t: f64| k.frame_pose(&(q + u * t), hand).translation.vector;
        let v = (p(h) - p(-h)) / (2.0 * h);
        let ju = k.frame_jacobian(&q, hand) * u;
        assert!((ju.fixed_rows::<3>(0) - v).amax() < 1e-7, "{ju} {v}");
    }
}

#[test]
fn the_hands_sit_at_the_gripper_offset_from_the_wrists() {
    let k = Krang::default();
    for (name, wrist) in [("left_hand", Frame::F10l), ("right_hand", Frame::F10r)] {
        let hand = Frame::from_name(name).expect("Krang has the hand frames");
        assert_eq!(hand.name(), name);
        for (q, u) in states() {
            let w = k.frame_pose(&q, wrist);
            let h = k.frame_pose(&q, hand);
            // krang.toml: [0, 0, 0.17315] in frame 10, the wrist's axes.
            let expected = w * nalgebra::Point3::new(0.0, 0.0, 0.17315);
            assert!((h.translation.vector - expected.coords).amax() < 1e-12);
            assert!(
                (h.rotation.to_rotation_matrix().matrix()
                    - w.rotation.to_rotation_matrix().matrix())
                .amax()
                    < 1e-12
            );
            // Same angular velocity as the wrist; linear velocity v_w + ω × r.
            let (jh, jw) = (
                k.frame_jacobian(&q, hand) * u,
                k.frame_jacobian(&q, wrist) * u,
            );
            let omega = jw.fixed_rows::<3>(3).into_owned();
            assert!((jh.fixed_rows::<3>(3) - omega).amax() < 1e-12);
            let r = h.translation.vector - w.translation.vector;
            let v = jw.fixed_rows::<3>(0) + omega.cross(&r);
            assert!((jh.fixed_rows::<3>(0) - v).amax() < 1e-10);
        }
    }
}

/// Parameters away from the defaults (every value scaled by its own factor in [0.8, 1.2]).
fn varied_params(seed: f64) -> krang_dynamics::Params {
    let mut v = krang_dynamics::Params::default().to_array();
    for (i, x) in v.iter_mut().enumerate() {
        *x *= 1.0 + 0.2 * (1.7 * i as f64 + seed).sin();
    }
    krang_dynamics::Params::from_array(v)
}

/// Held while a test selects instruction sets (the selection is global to the process and the
/// tests run in parallel threads).
static ISA_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Runs `check(exact)` once with each instruction set this CPU has selected, `exact` for the
/// baseline copy (whose sums are the plain ones), then selects the detected one again.
fn for_each_isa(mut check: impl FnMut(bool)) {
    use krang_dynamics::isa::{self, Isa};
    let _isa = ISA_LOCK
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let best = isa::detected();
    for which in Isa::ALL.into_iter().filter(|i| isa::available(*i)) {
        isa::select(which).expect("available");
        check(which == Isa::Baseline);
    }
    isa::select(best).expect("detected");
}

/// `a` equals `b` bit for bit if `exact`, else to 10⁻¹² of `b`'s largest entry.
macro_rules! same {
    ($a:expr, $b:expr, $exact:expr) => {{
        let (a, b) = ($a, $b);
        if $exact {
            assert_eq!(a, b);
        } else {
            assert!((a - b).amax() <= 1e-12 * b.amax().max(1.0), "{a} {b}");
        }
    }};
}

/// Bit for bit in the baseline copy; in the x86-64-v3 copy, which fuses multiply-adds, a
/// product that is a shared statement in one program and inline in the other is fused in only
/// one of them, so there the parts agree to 10⁻¹² of each result's largest entry. The module
/// is generated with mirrored lanes (docs/batched-and-dispatch.md, "Arms in lanes"): the combined program and the
/// separate M, `c + g` and centre-of-mass functions are paired alike and agree bit for bit,
/// but the right hand's bias acceleration, a per-frame function with no mirror inside it,
/// keeps the derivation's order separately while the combined program adds its sums in the
/// left hand's order: that part agrees to 10⁻¹² in both copies.
#[test]
fn whole_body_terms_equal_the_separate_functions_bit_for_bit_in_the_baseline_copy() {
    let [l, r] = ["left_hand", "right_hand"].map(|n| Frame::from_name(n).expect("hand frame"));
    for_each_isa(|exact| {
        for (s, (q, u)) in states().enumerate() {
            let k = Krang::new(varied_params(s as f64));
            let w = k.whole_body_terms(&q, &u);
            same!(w.mass_matrix, k.mass_matrix(&q), exact);
            same!(w.nonlinear_effects, k.nonlinear_effects(&q, &u), exact);
            same!(w.center_of_mass, k.center_of_mass(&q), exact);
            same!(w.com_jacobian, k.com_jacobian(&q), exact);
            same!(
                w.com_bias_acceleration,
                k.com_bias_acceleration(&q, &u),
                exact
            );
            same!(
                w.frame_pose_left_hand.to_homogeneous(),
                k.frame_pose(&q, l).to_homogeneous(),
                exact
            );
            same!(w.frame_jacobian_left_hand, k.frame_jacobian(&q, l), exact);
            same!(
                w.frame_bias_acceleration_left_hand,
                k.frame_bias_acceleration(&q, &u, l),
                exact
            );
            same!(
                w.frame_pose_right_hand.to_homogeneous(),
                k.frame_pose(&q, r).to_homogeneous(),
                exact
            );
            same!(w.frame_jacobian_right_hand, k.frame_jacobian(&q, r), exact);
            // Paired with the left hand's in the combined program only (see above).
            same!(
                w.frame_bias_acceleration_right_hand,
                k.frame_bias_acceleration(&q, &u, r),
                false
            );
        }
    });
}

/// `hands_jacobians` (both hands' Jacobians as one program, the arms two lanes at a time) equals
/// the two separate `frame_jacobian` calls: bit for bit in the baseline copy, to 10⁻¹² of the
/// largest entry in the copies that fuse multiply-adds (as `whole_body_terms` above).
#[test]
fn hands_jacobians_equal_the_two_separate_frame_jacobians() {
    for_each_isa(|exact| {
        for (s, (q, _)) in states().enumerate() {
            let k = Krang::new(varied_params(s as f64));
            let j = k.hands_jacobians(&q);
            same!(
                j.frame_jacobian_left_hand,
                k.frame_jacobian(&q, Frame::LeftHand),
                exact
            );
            same!(
                j.frame_jacobian_right_hand,
                k.frame_jacobian(&q, Frame::RightHand),
                exact
            );
        }
    });
}

#[test]
fn nonlinear_effects_are_inverse_dynamics_at_zero_acceleration() {
    for (s, (q, u)) in states().enumerate() {
        let k = Krang::new(varied_params(s as f64));
        let h = k.nonlinear_effects(&q, &u);
        let tau = k.inverse_dynamics(&q, &u, &V::zeros());
        let cg = k.coriolis(&q, &u) + k.gravity(&q);
        assert!((h - tau).amax() < 1e-12 * tau.amax().max(1.0), "{h} {tau}");
        assert!((h - cg).amax() < 1e-12 * tau.amax().max(1.0));
    }
}
