//! Contact-constrained dynamics (`kanegen_runtime::contact`) on Solo 12 with a free-flyer root,
//! its terms from the reference recursion (`kanegen_reference::FreeFlyer`): standing still on
//! four point contacts, and impacts.

use kanegen_model::{Model, UrdfImport, UrdfOptions};
use kanegen_reference::FreeFlyer;
use kanegen_reference::random::SplitMix64;
use kanegen_runtime::contact::{
    Contact, ContactJacobian, ContactSettings, constrained_forward_dynamics, contact_impulse,
};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

const N: usize = 18;
const K: usize = 12;
const FEET: [&str; 4] = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"];

/// Solo 12 imported on a floating base (the trunk's body kept) and its free-flyer recursion.
fn solo12() -> (Model, FreeFlyer<f64>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus/solo12.urdf");
    let text = std::fs::read_to_string(path).unwrap();
    let model = UrdfImport::parse(&text, "solo12", &UrdfOptions::floating())
        .unwrap()
        .model;
    let ff = FreeFlyer::new(&model).unwrap();
    (model, ff)
}

fn foot_contacts(model: &Model) -> Vec<Contact<usize>> {
    FEET.iter()
        .map(|name| {
            let i = model.links.iter().position(|l| l.name == *name).unwrap();
            Contact::point(i)
        })
        .collect()
}

/// A crouched stance: base 0.25 m up, tilted a little, knees bent.
fn stance() -> Vec<f64> {
    let mut q = vec![0.0; N + 1];
    q[2] = 0.25;
    let (s, c) = (0.05f64.sin(), 0.05f64.cos());
    q[3..7].copy_from_slice(&[s, 0.0, 0.0, c]);
    for (leg, hip, knee) in [
        (0, 0.8, -1.6),
        (1, 0.8, -1.6),
        (2, -0.8, 1.6),
        (3, -0.8, 1.6),
    ] {
        q[7 + 3 * leg] = 0.05;
        q[8 + 3 * leg] = hip;
        q[9 + 3 * leg] = knee;
    }
    q
}

fn contacts_at(
    ff: &FreeFlyer<f64>,
    contacts: &[Contact<usize>],
    q: &[f64],
    u: &SVector<f64, N>,
) -> ContactJacobian<f64, N, K> {
    ContactJacobian::stack(contacts, u, |frame| {
        let j = ff.frame_jacobian(q, frame);
        let b = ff.frame_bias_acceleration(q, u.as_slice(), frame);
        (SMatrix::from_iterator(j.iter().copied()), b)
    })
    .unwrap()
}

fn dense<const R: usize, const C: usize>(m: &DMatrix<f64>) -> SMatrix<f64, R, C> {
    SMatrix::from_iterator(m.iter().copied())
}

#[test]
fn solo12_standing_still_has_zero_acceleration_and_its_feet_carry_its_weight() {
    let (model, ff) = solo12();
    let contacts = foot_contacts(&model);
    let q = stance();
    let u = SVector::<f64, N>::zeros();
    let m: SMatrix<f64, N, N> = dense(&ff.mass_matrix(&q));
    let h =
        SVector::<f64, N>::from_iterator(ff.nonlinear_effects(&q, u.as_slice()).iter().copied());
    let c = contacts_at(&ff, &contacts, &q, &u);
    // The foot forces that hold the base (least norm), then the joint torques that balance them.
    let jt = DMatrix::from_iterator(N, K, c.jacobian.transpose().iter().copied());
    let base = jt.rows(0, 6).into_owned();
    let h_base = DVector::from_iterator(6, h.iter().take(6).copied());
    let lambda_hold = base.svd(true, true).solve(&h_base, 1e-12).unwrap();
    let tau_joints =
        DVector::from_iterator(N - 6, h.iter().skip(6).copied()) - jt.rows(6, N - 6) * &lambda_hold;
    let mut f = SVector::<f64, N>::zeros();
    f.rows_mut(6, N - 6).copy_from(&tau_joints);

    let s = constrained_forward_dynamics(m, &h, &f, &c, &ContactSettings::default()).unwrap();
    assert!(s.ud.amax() < 1e-10, "u̇ = {}", s.ud.transpose());
    let weight = ff.total_mass() * 9.81;
    let (mut fx, mut fy, mut fz) = (0.0, 0.0, 0.0);
    for foot in 0..4 {
        fx += s.lambda[3 * foot];
        fy += s.lambda[3 * foot + 1];
        fz += s.lambda[3 * foot + 2];
    }
    assert!(
        (fz - weight).abs() < 1e-9 * weight,
        "Σλz = {fz}, weight {weight}"
    );
    assert!(fx.abs() < 1e-9 * weight && fy.abs() < 1e-9 * weight);
    for (a, b) in s.lambda.iter().zip(lambda_hold.iter()) {
        assert!((a - b).abs() < 1e-9 * weight);
    }
}

#[test]
fn solo12_under_random_torques_keeps_its_feet_still() {
    let (model, ff) = solo12();
    let contacts = foot_contacts(&model);
    let q = stance();
    let mut rng = SplitMix64::new(11);
    let u = SVector::<f64, N>::from_fn(|_, _| rng.next_f64() - 0.5);
    let m: SMatrix<f64, N, N> = dense(&ff.mass_matrix(&q));
    let h =
        SVector::<f64, N>::from_iterator(ff.nonlinear_effects(&q, u.as_slice()).iter().copied());
    let c = contacts_at(&ff, &contacts, &q, &u);
    let mut f = SVector::<f64, N>::zeros();
    f.rows_mut(6, N - 6)
        .iter_mut()
        .for_each(|x| *x = 2.0 * rng.next_f64() - 1.0);
    let s = constrained_forward_dynamics(m, &h, &f, &c, &ContactSettings::default()).unwrap();
    // The reference's inverse dynamics of u̇ is f + J_cᵀ λ: the dynamics hold.
    let tau = ff.inverse_dynamics(&q, u.as_slice(), s.ud.as_slice());
    let rhs = f + c.jacobian.transpose() * s.lambda;
    for (a, b) in tau.iter().zip(rhs.iter()) {
        assert!((a - b).abs() < 1e-9 * rhs.amax().max(1.0));
    }
    // The feet do not accelerate: J_c u̇ + J̇_c u = 0.
    assert!((c.jacobian * s.ud + c.bias).amax() < 1e-9);
}

#[test]
fn solo12_impact_stops_the_feet() {
    let (model, ff) = solo12();
    let contacts = foot_contacts(&model);
    let q = stance();
    let mut rng = SplitMix64::new(12);
    // Falling at 1 m/s, with some spin and leg motion.
    let mut u_minus = SVector::<f64, N>::from_fn(|_, _| 0.4 * (rng.next_f64() - 0.5));
    let (r, _) = ff.base_pose(&q);
    let down = r.transpose() * nalgebra::Vector3::new(0.0, 0.0, -1.0);
    u_minus.rows_mut(0, 3).copy_from(&down);
    let m: SMatrix<f64, N, N> = dense(&ff.mass_matrix(&q));
    let c = contacts_at(&ff, &contacts, &q, &u_minus);
    let plastic = contact_impulse(m, &u_minus, &c, 0.0, &ContactSettings::default()).unwrap();
    let v = c.jacobian * plastic.u_plus;
    assert!(
        v.amax() < 1e-10,
        "foot velocities after impact: {}",
        v.transpose()
    );
    // The floor pushes up: the normal impulses are positive and sum to the momentum lost.
    let normal: f64 = (0..4).map(|k| plastic.impulse[3 * k + 2]).sum();
    assert!(normal > 0.0);
    let bouncy = contact_impulse(m, &u_minus, &c, 0.5, &ContactSettings::default()).unwrap();
    let before = c.jacobian * u_minus;
    let after = c.jacobian * bouncy.u_plus;
    for k in 0..4 {
        let z = 3 * k + 2;
        assert!((after[z] + 0.5 * before[z]).abs() < 1e-10);
    }
}
