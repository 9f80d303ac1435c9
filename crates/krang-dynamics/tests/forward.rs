//! Forward dynamics: the block Cholesky of Krang's mass matrix against inverse dynamics and
//! against nalgebra's dense Cholesky, the exact zero block it relies on, and the dense
//! fallback of the fixed-wheel model.

use krang_dynamics::fixed_wheels::{self, KrangFixedWheels};
use krang_dynamics::forward::{LEFT_ARM, RIGHT_ARM};
use krang_dynamics::{
    Block, BlockCholesky, ForwardDynamicsError, Krang, MassMatrixCholesky, Params, index, solve_spd,
};
use nalgebra::{SMatrix, SVector};

/// SplitMix64: a tiny deterministic generator (no dev-dependency needed).
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    fn vector<const N: usize>(&mut self, lo: f64, hi: f64) -> SVector<f64, N> {
        SVector::from_fn(|_, _| self.uniform(lo, hi))
    }
}

const BODIES: [&str; 17] = [
    "1", "2", "3", "4l", "5l", "6l", "7l", "8l", "9l", "10l", "4r", "5r", "6r", "7r", "8r", "9r",
    "10r",
];
const INERTIAL: [&str; 10] = ["m", "MX", "MY", "MZ", "XX", "XY", "XZ", "YY", "YZ", "ZZ"];

/// The default parameters with each body scaled by a random positive factor (m, MS and J of a
/// body scaled together stay physically consistent), and random wheel constants.
fn random_params(rng: &mut Rng) -> Params {
    let mut p = Params::default();
    for body in BODIES {
        let s = rng.uniform(0.3, 3.0);
        for kind in INERTIAL {
            let name = format!("{kind}{body}");
            p.set(&name, s * p.get(&name).unwrap()).unwrap();
        }
    }
    p.R = rng.uniform(0.1, 0.4);
    p.L = rng.uniform(0.4, 1.0);
    p.mw = rng.uniform(1.0, 10.0);
    p.YYw = p.mw * p.R * p.R * rng.uniform(0.3, 1.0);
    p.ZZw = p.YYw * rng.uniform(0.5, 1.0);
    p
}

/// Random q (angles in ±π), u (±2 rad/s), τ (±50 N·m).
fn random_state<const N: usize>(
    rng: &mut Rng,
) -> (SVector<f64, N>, SVector<f64, N>, SVector<f64, N>) {
    (
        rng.vector(-std::f64::consts::PI, std::f64::consts::PI),
        rng.vector(-2.0, 2.0),
        rng.vector(-50.0, 50.0),
    )
}

/// Krang with the default parameters for the first `defaults` cases, random ones after.
fn krang_for(case: usize, defaults: usize, rng: &mut Rng) -> Krang {
    if case < defaults {
        Krang::default()
    } else {
        Krang::new(random_params(rng))
    }
}

#[test]
fn generated_mass_matrix_has_exact_zeros_between_the_arms() {
    let mut rng = Rng(1);
    for case in 0..300 {
        let k = krang_for(case, 1, &mut rng);
        let (q, _, _) = random_state::<19>(&mut rng);
        let m = k.mass_matrix(&q);
        for i in LEFT_ARM {
            for j in RIGHT_ARM {
                // Exact: the generated code never writes these entries.
                assert_eq!(m[(i, j)].to_bits(), 0.0f64.to_bits(), "M[{i},{j}]");
                assert_eq!(m[(j, i)].to_bits(), 0.0f64.to_bits(), "M[{j},{i}]");
            }
        }
        // …and every other block is generically non-zero (the structure is not emptier
        // than assumed, e.g. trunk–arm coupling is there).
        assert!(m.fixed_view::<5, 7>(0, 5).abs().max() > 0.0);
        assert!(m.fixed_view::<5, 7>(0, 12).abs().max() > 0.0);
    }
}

#[test]
fn forward_then_inverse_dynamics_round_trips() {
    let mut rng = Rng(2);
    let mut worst: f64 = 0.0;
    for case in 0..2000 {
        let k = krang_for(case, 200, &mut rng);
        let (q, u, tau) = random_state::<19>(&mut rng);
        let ud = k.forward_dynamics(&q, &u, &tau);
        let back = k.inverse_dynamics(&q, &u, &ud);
        let err = (back - tau).norm() / tau.norm();
        worst = worst.max(err);
        assert!(err <= 1e-10, "case {case}: relative error {err:e}");
    }
    eprintln!("worst relative round-trip error τ → u̇ → τ: {worst:.2e}");
}

#[test]
fn block_cholesky_agrees_with_dense_nalgebra_cholesky() {
    let mut rng = Rng(3);
    for case in 0..1000 {
        let k = krang_for(case, 100, &mut rng);
        let (q, u, tau) = random_state::<19>(&mut rng);
        let m = k.mass_matrix(&q);
        let rhs = tau - k.coriolis(&q, &u) - k.gravity(&q);
        let dense = m.cholesky().expect("M is positive definite").solve(&rhs);
        let block = k.forward_dynamics(&q, &u, &tau);
        // Different elimination orders, same answer to rounding (worst seen 1.4e-14 with
        // condition numbers of M up to 5e5).
        let rel = (block - dense).norm() / dense.norm();
        assert!(
            rel <= 1e-12,
            "case {case}: |block − dense| / |dense| = {rel:e}"
        );
        // The factor reproduces M.
        let chol = MassMatrixCholesky::new(&m).unwrap();
        let l = chol.factor();
        let llt = l * l.transpose();
        assert!(
            (llt - m).abs().max() <= 1e-13 * m.abs().max(),
            "case {case}"
        );
        // det M from the factor.
        let det = dense_det(&m);
        assert!(
            (chol.determinant() - det).abs() <= 1e-9 * det.abs(),
            "case {case}"
        );
    }
}

#[test]
fn solving_many_columns_at_once_equals_solving_each_column() {
    let mut rng = Rng(7);
    for case in 0..300 {
        let k = krang_for(case, 30, &mut rng);
        let (q, _, _) = random_state::<19>(&mut rng);
        let m = k.mass_matrix(&q);
        let chol = MassMatrixCholesky::new(&m).unwrap();
        let b = SMatrix::<f64, 19, 23>::from_fn(|_, _| rng.uniform(-10.0, 10.0));
        let mut x = b;
        chol.solve_columns_mut(&mut x);
        for j in 0..23 {
            let one = chol.solve(&b.column(j).into_owned());
            // The same operations in the same order for each column, whichever of the two
            // lanes it is solved in (the last, odd column beside zeros): the same bits.
            assert_eq!(x.column(j), one, "case {case}, column {j}");
        }
        // And it solves M X = B.
        let residual = (m * x - b).norm() / b.norm();
        assert!(residual <= 1e-10, "case {case}: residual {residual:e}");
    }
}

#[test]
fn solving_once_equals_factorising_then_solving() {
    let mut rng = Rng(8);
    for case in 0..300 {
        let k = krang_for(case, 30, &mut rng);
        let (q, _, b) = random_state::<19>(&mut rng);
        let m = k.mass_matrix(&q);
        let once = MassMatrixCholesky::solve_once(&m, &b).unwrap();
        assert_eq!(
            once,
            MassMatrixCholesky::new(&m).unwrap().solve(&b),
            "case {case}"
        );
    }
    // The same error, naming the same block, for a matrix that is not positive definite.
    let m = Krang::new(inertia_times_minus_ten(&["9r"])).mass_matrix(&SVector::zeros());
    let b = SVector::<f64, 19>::from_element(1.0);
    assert_eq!(
        MassMatrixCholesky::solve_once(&m, &b).unwrap_err(),
        MassMatrixCholesky::new(&m).unwrap_err()
    );
}

fn dense_det(m: &SMatrix<f64, 19, 19>) -> f64 {
    let l = m.cholesky().unwrap();
    l.l().diagonal().iter().map(|d| d * d).product()
}

#[test]
fn factor_is_lower_triangular_after_the_arms_first_permutation() {
    let k = Krang::default();
    let mut rng = Rng(4);
    let (q, _, _) = random_state::<19>(&mut rng);
    let l = k.mass_matrix_cholesky(&q).unwrap().factor();
    // Permutation: arms first, then the trunk.
    let order: Vec<usize> = (5..19).chain(0..5).collect();
    let lp = SMatrix::<f64, 19, 19>::from_fn(|i, j| l[(order[i], order[j])]);
    assert_eq!(lp.upper_triangle(), SMatrix::from_diagonal(&lp.diagonal()));
    // No fill-in between the arms.
    assert_eq!(l.fixed_view::<7, 7>(12, 5).abs().max(), 0.0);
    assert_eq!(l.fixed_view::<7, 7>(5, 12).abs().max(), 0.0);
}

#[test]
fn factorisation_reuses_for_many_right_hand_sides() {
    let k = Krang::default();
    let mut rng = Rng(5);
    let (q, _, _) = random_state::<19>(&mut rng);
    let m = k.mass_matrix(&q);
    let chol = k.mass_matrix_cholesky(&q).unwrap();
    let inv = SMatrix::<f64, 19, 19>::from_columns(
        &(0..19)
            .map(|j| chol.solve(&SVector::<f64, 19>::from_fn(|i, _| f64::from(i == j))))
            .collect::<Vec<_>>(),
    );
    let id = m * inv;
    assert!((id - SMatrix::<f64, 19, 19>::identity()).abs().max() < 1e-9);
}

#[test]
fn non_physical_parameters_are_reported_not_panicked() {
    // Through the array: `Params::set` refuses a negative mass.
    let mut values = Params::default().to_array();
    for kind in INERTIAL {
        let name = format!("{kind}7r");
        let i = Params::NAMES.iter().position(|n| *n == name).unwrap();
        values[i] *= -10.0;
    }
    let k = Krang::new(Params::from_array(values));
    let q = SVector::<f64, 19>::zeros();
    let u = SVector::<f64, 19>::zeros();
    let err = k.try_forward_dynamics(&q, &u, &u).unwrap_err();
    assert!(
        matches!(err, ForwardDynamicsError::NotPositiveDefinite(e) if e.block == Block::RightArm),
        "{err:?}"
    );
    assert!(err.to_string().contains("not positive definite"));
    assert!(k.forward_dynamics(&q, &u, &u).iter().all(|x| x.is_nan()));
    // NaN coordinates propagate as an error too.
    let k = Krang::default();
    let mut q = q;
    q[index::Q_IMU] = f64::NAN;
    assert!(k.try_forward_dynamics(&q, &u, &u).is_err());
}

/// The default parameters with the inertial parameters of `bodies` (`"5l"`, `"3"`, …) times −10.
fn inertia_times_minus_ten(bodies: &[&str]) -> Params {
    let mut values = Params::default().to_array();
    for (body, kind) in bodies.iter().flat_map(|b| INERTIAL.map(|k| (b, k))) {
        let name = format!("{kind}{body}");
        let i = Params::NAMES.iter().position(|n| *n == name).unwrap();
        values[i] *= -10.0;
    }
    Params::from_array(values)
}

#[test]
fn each_block_of_the_factor_reports_its_own_failure() {
    // A body's inertial parameters times -10 make the blocks it enters indefinite: an arm body
    // its arm's block (the two arms' pivots are taken together, step by step, so the arm whose
    // pivot fails at the earlier step is named, and the left one at the same step), the torso
    // the trunk's Schur complement.
    for (bodies, block) in [
        (&["5l"][..], Block::LeftArm),
        (&["9r"], Block::RightArm),
        (&["3"], Block::Trunk),
        (&["9l", "5r"], Block::RightArm),
        (&["9l", "9r"], Block::LeftArm),
    ] {
        let body = bodies.join(", ");
        let m = Krang::new(inertia_times_minus_ten(bodies)).mass_matrix(&SVector::zeros());
        let err = MassMatrixCholesky::new(&m).unwrap_err();
        assert_eq!(err.block, block, "body {body}");
    }
}

#[test]
fn fixed_wheel_block_factor_round_trips_and_agrees_with_nalgebra() {
    let mut rng = Rng(6);
    for case in 0..1000 {
        let mut p = fixed_wheels::Params::default();
        if case > 0 {
            for body in BODIES {
                let s = rng.uniform(0.3, 3.0);
                for kind in INERTIAL {
                    let name = format!("{kind}{body}");
                    p.set(&name, s * p.get(&name).unwrap()).unwrap();
                }
            }
        }
        let k = KrangFixedWheels::new(p);
        let (q, u, tau) = random_state::<17>(&mut rng);
        let ud = k.forward_dynamics(&q, &u, &tau);
        let back = k.inverse_dynamics(&q, &u, &ud);
        assert!((back - tau).norm() <= 1e-10 * tau.norm(), "case {case}");
        let m = k.mass_matrix(&q);
        let rhs = tau - k.coriolis(&q, &u) - k.gravity(&q);
        let dense = m.cholesky().unwrap().solve(&rhs);
        assert!((ud - dense).norm() <= 1e-12 * dense.norm(), "case {case}");
        // The same block factor as Krang's, with a trunk of three speeds: L Lᵀ = M.
        let chol = k.mass_matrix_cholesky(&q).unwrap();
        assert_eq!(chol, BlockCholesky::<3, 17>::new(&m).unwrap());
        let l = chol.factor();
        assert!(
            (l * l.transpose() - m).norm() <= 1e-13 * m.norm(),
            "case {case}"
        );
        // Its many-column solve, column by column the single solve's bits.
        let b = SMatrix::<f64, 17, 5>::from_fn(|i, j| m[(i, 3 * j)]);
        let mut x = b;
        chol.solve_columns_mut(&mut x);
        for j in 0..5 {
            assert_eq!(
                x.column(j),
                chol.solve(&b.column(j).into_owned()),
                "case {case}"
            );
        }
        assert!((m * x - b).norm() <= 1e-12 * b.norm(), "case {case}");
    }
}

#[test]
fn solve_spd_is_generic_and_rejects_indefinite_matrices() {
    let a = SMatrix::<f64, 3, 3>::new(4.0, 2.0, 0.0, 2.0, 3.0, 1.0, 0.0, 1.0, 2.0);
    let b = SVector::<f64, 3>::new(1.0, 2.0, 3.0);
    let x = solve_spd(&a, &b).unwrap();
    assert!((a * x - b).norm() < 1e-14);
    let indefinite = SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 1.0);
    assert_eq!(
        solve_spd(&indefinite, &SVector::<f64, 2>::zeros())
            .unwrap_err()
            .block,
        Block::Dense
    );
}

#[test]
fn upright_pitch_puts_the_centre_of_mass_above_the_axle() {
    let mut rng = Rng(7);
    for case in 0..200 {
        let k = krang_for(case, 1, &mut rng);
        let (mut q, _, _) = random_state::<19>(&mut rng);
        let up = k.upright_pitch(&q);
        q[index::Q_IMU] = up;
        let g = k.gravity(&q);
        // Equilibrium: no gravity torque about the axle …
        assert!(
            g[index::Q_IMU].abs() < 1e-9 * k.gravity(&q).norm().max(1.0),
            "case {case}"
        );
        // … and unstable (centre of mass above, not below): tilting forward makes gravity
        // accelerate the tilt (dg/dq_imu < 0 at a maximum of the potential).
        let mut qt = q;
        qt[index::Q_IMU] += 1e-4;
        assert!(k.gravity(&qt)[index::Q_IMU] < 0.0, "case {case}");
    }
}

#[test]
fn infinities_in_the_state_forces_or_parameters_are_errors_not_results() {
    let q = SVector::<f64, 19>::zeros();
    let u = SVector::<f64, 19>::zeros();
    let k = Krang::default();
    let mut tau = u;
    tau[index::QD1L] = f64::INFINITY;
    assert_eq!(
        k.try_forward_dynamics(&q, &u, &tau),
        Err(ForwardDynamicsError::NotFinite("tau"))
    );
    let mut u_inf = u;
    u_inf[index::QD_W] = f64::NEG_INFINITY;
    assert_eq!(
        k.try_forward_dynamics(&q, &u_inf, &u),
        Err(ForwardDynamicsError::NotFinite("u"))
    );
    let mut q_inf = q;
    q_inf[index::Q_TORSO] = f64::INFINITY;
    assert_eq!(
        k.try_forward_dynamics(&q_inf, &u, &u),
        Err(ForwardDynamicsError::NotFinite("q"))
    );
    // An infinite gravity passes the factorisation (M does not depend on g) and was returned as
    // Ok(inf/NaN) before: now an error, and NaNs from the infallible form.
    let mut p = Params::default();
    assert!(p.set("g", f64::INFINITY).is_err()); // set refuses it; the field does not
    p.g = f64::INFINITY;
    assert!(p.validate().is_err());
    let k = Krang::new(p);
    let err = k.try_forward_dynamics(&q, &u, &u).unwrap_err();
    assert_eq!(err, ForwardDynamicsError::NotFinite("u̇"));
    assert!(err.to_string().contains("not finite"));
    assert!(k.forward_dynamics(&q, &u, &u).iter().all(|x| x.is_nan()));
}
