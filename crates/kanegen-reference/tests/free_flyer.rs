//! The free-flyer reference recursion (`FreeFlyer`) against identities, finite differences along
//! SE(3) trajectories and the closed-form Newton–Euler equations of a single rigid body, on a
//! quadruped (Solo 12) and a humanoid (`simple_humanoid`, 29 joints) of the URDF corpus.

use kanegen_model::{Model, UrdfImport, UrdfOptions};
use kanegen_reference::random::SplitMix64;
use kanegen_reference::se3::{difference, integrate, quaternion_to_rotation};
use kanegen_reference::{FreeFlyer, FreeFlyerError};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3, Vector6};

fn corpus(name: &str) -> Model {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/corpus/");
    let text = std::fs::read_to_string(format!("{path}{name}.urdf")).unwrap();
    UrdfImport::parse(&text, name, &UrdfOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .model
}

fn robots() -> Vec<(Model, FreeFlyer<f64>)> {
    ["solo12", "simple_humanoid"]
        .into_iter()
        .map(|name| {
            let m = corpus(name);
            let ff = FreeFlyer::new(&m).unwrap();
            (m, ff)
        })
        .collect()
}

fn uniform(rng: &mut SplitMix64, n: usize, scale: f64) -> Vec<f64> {
    (0..n)
        .map(|_| scale * (2.0 * rng.next_f64() - 1.0))
        .collect()
}

/// A random configuration: base anywhere within a metre, a random unit quaternion, joints in
/// [−1, 1] rad.
fn random_q(ff: &FreeFlyer<f64>, rng: &mut SplitMix64) -> Vec<f64> {
    let mut q = uniform(rng, ff.nq(), 1.0);
    let n = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
    q[3..7].iter_mut().for_each(|x| *x /= n);
    q
}

fn rel(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

fn rel_v(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

#[test]
fn layout_is_pinocchios_free_flyer() {
    for (m, ff) in robots() {
        assert_eq!(ff.dof(), 6 + m.dof(), "{}", m.name);
        assert_eq!(ff.nq(), ff.dof() + 1);
        let q = ff.neutral();
        assert_eq!(q[6], 1.0);
        assert!(q.iter().enumerate().all(|(i, &x)| i == 6 || x == 0.0));
    }
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_tau_is_affine_in_ud() {
    let mut rng = SplitMix64::new(1);
    for (m, ff) in robots() {
        for _ in 0..3 {
            let q = random_q(&ff, &mut rng);
            let u = uniform(&mut rng, ff.dof(), 1.0);
            let ud = uniform(&mut rng, ff.dof(), 1.0);
            let mm = ff.mass_matrix(&q);
            assert!(rel(&mm, &mm.transpose()) < 1e-12, "{}", m.name);
            assert!(mm.clone().cholesky().is_some(), "{}: M not SPD", m.name);
            let tau = ff.inverse_dynamics(&q, &u, &ud);
            let affine = &mm * DVector::from_column_slice(&ud) + ff.nonlinear_effects(&q, &u);
            assert!(rel_v(&tau, &affine) < 1e-11, "{}", m.name);
            let h = ff.coriolis(&q, &u) + ff.gravity(&q);
            assert!(rel_v(&h, &ff.nonlinear_effects(&q, &u)) < 1e-11);
        }
    }
}

#[test]
fn kinetic_energy_is_half_u_m_u() {
    let mut rng = SplitMix64::new(2);
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = DVector::from_vec(uniform(&mut rng, ff.dof(), 1.0));
        let half = 0.5 * u.dot(&(ff.mass_matrix(&q) * &u));
        let t = ff.kinetic_energy(&q, u.as_slice());
        assert!((t - half).abs() < 1e-11 * half.abs().max(1.0), "{}", m.name);
    }
}

#[test]
fn gravity_is_the_tangent_gradient_of_the_potential_energy() {
    let mut rng = SplitMix64::new(3);
    let h = 1e-6;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let g = ff.gravity(&q);
        let fd = DVector::from_fn(ff.dof(), |i, _| {
            let mut d = vec![0.0; ff.dof()];
            d[i] = h;
            let plus = ff.potential_energy(&integrate(&q, &d, 1.0));
            let minus = ff.potential_energy(&integrate(&q, &d, -1.0));
            (plus - minus) / (2.0 * h)
        });
        assert!(rel_v(&fd, &g) < 1e-7, "{}: {}", m.name, rel_v(&fd, &g));
    }
}

#[test]
fn frame_velocities_are_jacobian_times_u_along_se3_trajectories() {
    let mut rng = SplitMix64::new(4);
    let h = 1e-6;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = uniform(&mut rng, ff.dof(), 1.0);
        for frame in [0, m.links.len() / 2, m.links.len() - 1] {
            let v = ff.frame_jacobian(&q, frame) * DVector::from_column_slice(&u);
            let (r1, p1) = ff.frame_pose(&integrate(&q, &u, h), frame);
            let (r0, p0) = ff.frame_pose(&integrate(&q, &u, -h), frame);
            let lin = (p1 - p0) / (2.0 * h);
            // ω× = Ṙ Rᵀ.
            let (rm, _) = ff.frame_pose(&q, frame);
            let w = (r1 - r0) / (2.0 * h) * rm.transpose();
            let ang = Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
            let fd = DVector::from_iterator(6, lin.iter().chain(ang.iter()).copied());
            assert!(rel_v(&v, &fd) < 1e-7, "{} frame {frame}", m.name);
        }
    }
}

#[test]
fn frame_bias_acceleration_is_the_acceleration_at_zero_ud() {
    let mut rng = SplitMix64::new(5);
    let h = 1e-5;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = uniform(&mut rng, ff.dof(), 1.0);
        let frame = m.links.len() - 1;
        // u̇ = 0 keeps u constant: d/dt (J(q(t)) u) along q(t) = q ⊕ t u.
        let vel = |t: f64| {
            ff.frame_jacobian(&integrate(&q, &u, t), frame) * DVector::from_column_slice(&u)
        };
        let fd = (vel(h) - vel(-h)) / (2.0 * h);
        let bias = ff.frame_bias_acceleration(&q, &u, frame);
        let bias = DVector::from_column_slice(bias.as_slice());
        assert!(
            rel_v(&bias, &fd) < 1e-6,
            "{}: {}",
            m.name,
            rel_v(&bias, &fd)
        );
    }
}

#[test]
fn centroidal_momentum_matrix_times_u_is_the_total_momentum() {
    let mut rng = SplitMix64::new(6);
    let h = 1e-6;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = uniform(&mut rng, ff.dof(), 1.0);
        let ag = ff.centroidal_momentum_matrix(&q);
        let hg = &ag * DVector::from_column_slice(&u);
        let sum = ff.centroidal_momentum(&q, &u);
        assert!(rel_v(&hg, &DVector::from_column_slice(sum.as_slice())) < 1e-11);
        // Linear momentum = total mass × velocity of the centre of mass.
        let c1 = ff.center_of_mass(&integrate(&q, &u, h));
        let c0 = ff.center_of_mass(&integrate(&q, &u, -h));
        let mv = (c1 - c0) / (2.0 * h) * ff.total_mass();
        assert!(
            (hg.rows(0, 3) - mv).amax() < 1e-7 * mv.amax().max(1.0),
            "{}",
            m.name
        );
        // The angular momentum about the centre of mass does not depend on where the base is:
        // A_G of a rigid motion of the whole robot (joints at rest) is that of one body.
        let mut u_base = u.clone();
        u_base[6..].iter_mut().for_each(|x| *x = 0.0);
        let hb = &ag * DVector::from_column_slice(&u_base);
        let mm = ff.mass_matrix(&q);
        let ub = DVector::from_column_slice(&u_base);
        let t = 0.5 * ub.dot(&(&mm * &ub));
        // T = ½ m |v_G|² + ½ ω·L_G for a rigid motion.
        let (rb, _) = ff.base_pose(&q);
        let w = rb * Vector3::new(u[3], u[4], u[5]);
        let lin = Vector3::new(hb[0], hb[1], hb[2]);
        let ang = Vector3::new(hb[3], hb[4], hb[5]);
        let t_hg = 0.5 * lin.dot(&lin) / ff.total_mass() + 0.5 * w.dot(&ang);
        assert!(
            (t - t_hg).abs() < 1e-10 * t.max(1.0),
            "{}: {t} vs {t_hg}",
            m.name
        );
    }
}

#[test]
fn centroidal_momentum_bias_is_the_rate_of_momentum_at_zero_ud() {
    let mut rng = SplitMix64::new(7);
    let h = 1e-5;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = uniform(&mut rng, ff.dof(), 1.0);
        let ud = DVector::from_column_slice(&u);
        let hg = |t: f64| ff.centroidal_momentum_matrix(&integrate(&q, &u, t)) * &ud;
        let fd = (hg(h) - hg(-h)) / (2.0 * h);
        let bias = ff.centroidal_momentum_bias(&q, &u);
        let bias = DVector::from_column_slice(bias.as_slice());
        assert!(
            rel_v(&bias, &fd) < 1e-6,
            "{}: {}",
            m.name,
            rel_v(&bias, &fd)
        );
    }
}

#[test]
fn tangent_derivatives_match_central_differences_on_se3() {
    let mut rng = SplitMix64::new(8);
    let h = 1e-6;
    for (m, ff) in robots() {
        let q = random_q(&ff, &mut rng);
        let u = uniform(&mut rng, ff.dof(), 1.0);
        let ud = uniform(&mut rng, ff.dof(), 1.0);
        let (dq, du) = ff.inverse_dynamics_derivatives(&q, &u, &ud);
        let n = ff.dof();
        let mut fd_q = DMatrix::zeros(n, n);
        let mut fd_u = DMatrix::zeros(n, n);
        for i in 0..n {
            let mut d = vec![0.0; n];
            d[i] = h;
            let plus = ff.inverse_dynamics(&integrate(&q, &d, 1.0), &u, &ud);
            let minus = ff.inverse_dynamics(&integrate(&q, &d, -1.0), &u, &ud);
            fd_q.set_column(i, &((plus - minus) / (2.0 * h)));
            let (mut up, mut um) = (u.clone(), u.clone());
            up[i] += h;
            um[i] -= h;
            let col =
                (ff.inverse_dynamics(&q, &up, &ud) - ff.inverse_dynamics(&q, &um, &ud)) / (2.0 * h);
            fd_u.set_column(i, &col);
        }
        assert!(
            rel(&dq, &fd_q) < 1e-6,
            "{}: ∂τ/∂q {}",
            m.name,
            rel(&dq, &fd_q)
        );
        assert!(
            rel(&du, &fd_u) < 1e-6,
            "{}: ∂τ/∂u {}",
            m.name,
            rel(&du, &fd_u)
        );
    }
}

#[test]
fn integrate_keeps_the_quaternion_unit_and_difference_inverts_it() {
    let mut rng = SplitMix64::new(9);
    let n = 12;
    for _ in 0..20 {
        let mut q0 = uniform(&mut rng, 7 + n, 1.0);
        let norm = q0[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
        q0[3..7].iter_mut().for_each(|x| *x /= norm);
        let v = uniform(&mut rng, 6 + n, 3.0);
        let q1 = integrate(&q0, &v, 0.7);
        let unit = q1[3..7].iter().map(|x| x * x).sum::<f64>();
        assert!((unit - 1.0).abs() < 1e-14);
        let back = integrate(&q0, &difference(&q0, &q1), 1.0);
        // Equal poses: the same rotation (the quaternion up to sign) and position.
        let (ra, rb) = (
            quaternion_to_rotation([q1[3], q1[4], q1[5], q1[6]]),
            quaternion_to_rotation([back[3], back[4], back[5], back[6]]),
        );
        assert!((ra - rb).amax() < 1e-12);
        for i in (0..3).chain(7..7 + n) {
            assert!((q1[i] - back[i]).abs() < 1e-12, "entry {i}");
        }
        // A twist of angle below π is recovered exactly.
        let mut small = v.clone();
        small[3..6].iter_mut().for_each(|x| *x *= 0.3);
        let d = difference(&q0, &integrate(&q0, &small, 1.0));
        for (a, b) in d.iter().zip(&small) {
            assert!((a - b).abs() < 1e-11);
        }
    }
}

/// One rigid body on the free flyer (a child joint at rest whose body is a point mass with an
/// isotropic inertia at the base origin, so that the pair is one rigid body whatever the joint
/// angle): τ of the base against the spatial Newton–Euler equations
/// `f = I V̇ + V ×* I V − f_gravity` in the body frame, with `V = (ω, v)` and the spatial inertia
/// built from `m`, `c`, `J_O`.
#[test]
fn a_single_free_body_obeys_newton_euler() {
    let toml = r#"
[model]
name = "one-body"
speeds = ["qd1"]
[base]
type = "fixed"
frame = "0"
[gravity]
symbol = "g"
direction = [0, 0, -1]
[parameters]
g = 9.81
m0 = 3.5
MX0 = 0.35
MY0 = -0.21
MZ0 = 0.7
XX0 = 0.9
XY0 = 0.02
XZ0 = -0.05
YY0 = 0.8
YZ0 = 0.03
ZZ0 = 0.6
m1 = 0.5
MX1 = 0
MY1 = 0
MZ1 = 0
XX1 = 0.01
XY1 = 0
XZ1 = 0
YY1 = 0.01
YZ1 = 0
ZZ1 = 0.01
[[joint]]
name = "q1"
type = "revolute"
parent = "0"
child = "1"
speed = "qd1"
axis = [0, 0, 1]
rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
translation = [0, 0, 0]
[[body]]
frame = "0"
[[body]]
frame = "1"
"#;
    let model = Model::from_toml_str(toml, "one-body.toml").unwrap();
    let ff = FreeFlyer::<f64>::new(&model).unwrap();
    let m = 3.5 + 0.5;
    let ms = Vector3::new(0.35, -0.21, 0.7);
    let c = ms / m;
    let j_o = Matrix3::new(0.9, 0.02, -0.05, 0.02, 0.8, 0.03, -0.05, 0.03, 0.6)
        + Matrix3::identity() * 0.01;
    let mut rng = SplitMix64::new(10);
    for _ in 0..5 {
        let mut q = random_q(&ff, &mut rng);
        q[7] = 0.4;
        let mut u = uniform(&mut rng, 7, 2.0);
        let mut ud = uniform(&mut rng, 7, 2.0);
        u[6] = 0.0;
        ud[6] = 0.0;
        let tau = ff.inverse_dynamics(&q, &u, &ud);
        let (v, w) = (
            Vector3::new(u[0], u[1], u[2]),
            Vector3::new(u[3], u[4], u[5]),
        );
        let (vd, wd) = (
            Vector3::new(ud[0], ud[1], ud[2]),
            Vector3::new(ud[3], ud[4], ud[5]),
        );
        // Spatial inertia about the origin, (angular; linear) blocks.
        let cx = c.cross_matrix();
        let inertia =
            |w: &Vector3<f64>, v: &Vector3<f64>| (j_o * w + m * cx * v, m * v - m * cx * w);
        let (n_dot, f_dot) = inertia(&wd, &vd);
        let (h_ang, h_lin) = inertia(&w, &v);
        // V ×* h for V = (ω, v): (ω × h_ang + v × h_lin, ω × h_lin).
        let n = n_dot + w.cross(&h_ang) + v.cross(&h_lin);
        let f = f_dot + w.cross(&h_lin);
        let r = quaternion_to_rotation([q[3], q[4], q[5], q[6]]);
        let g_body = r.transpose() * Vector3::new(0.0, 0.0, -9.81);
        let f = f - m * g_body;
        let n = n - c.cross(&(m * g_body));
        let expected = Vector6::new(f.x, f.y, f.z, n.x, n.y, n.z);
        let got = Vector6::from_column_slice(&tau.as_slice()[..6]);
        assert!((got - expected).amax() < 1e-12, "{got} vs {expected}");
        // The joint carries the point body's moment about z: k ω̇_z (its axis is the base's z).
        assert!((tau[6] - 0.01 * wd.z).abs() < 1e-12);
    }
}

#[test]
fn a_wheeled_base_is_refused() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/krang.toml");
    let model = Model::from_toml_file(path).unwrap();
    let err = FreeFlyer::<f64>::new(&model).unwrap_err();
    assert!(matches!(err, FreeFlyerError::WheeledBase { .. }));
    assert!(err.to_string().contains("krang"));
}
