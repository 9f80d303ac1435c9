//! The kinematics and energies of the registry (opt-in functions), on Krang (wheeled base), the
//! fixed-wheel tree, the two-link model, the URDF arm and a small URDF with a prismatic joint
//! (oblique axes, tilted gravity), with random parameters and states,
//! through the derivation's and the lowering's evaluators:
//!
//! * `kinetic_energy = ½ uᵀ M u` and the reference recursion's kinetic energy;
//! * `potential_energy` equals the reference's and `∂V/∂q = g` (central differences);
//! * the centre of mass equals the mass-weighted body centres of the reference's frames;
//! * along a trajectory `q(t) = q + u t + ½ u̇ t²` (and, for the wheeled base, the ground
//!   position of frame 0 integrated from `ẋ` and `ψ`), `J u` is the time derivative of the
//!   centre of mass in the ground frame and `J u̇ + bias` its second derivative (both rotated
//!   into frame 0's axes);
//! * every body frame's pose equals the reference's frames, its Jacobian times `u` and its bias
//!   equal the reference's velocities and accelerations, and along a trajectory `J u` is the
//!   derivative of the frame's ground pose (origin and rotation) and `J u̇ + bias` the second
//!   derivative.

use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options};
use kanegen_reference::Reference;
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::{Matrix3, Vector3};

/// One model with every function, a random parameter set and its reference recursion.
struct Case {
    name: &'static str,
    model: Model,
    generated: Generated,
    params: Vec<f64>,
    reference: Reference<f64>,
    uniform: Box<dyn FnMut() -> f64>,
}

fn models_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models")
}

/// A small URDF with an oblique prismatic joint between oblique revolute joints, a fixed-joint
/// merge and a tilted gravity direction.
const SLIDER: &str = r#"<robot name="slider">
  <link name="world"/>
  <link name="post"><inertial><origin xyz="0 0.1 0.3" rpy="0.2 0.1 0"/><mass value="3"/>
    <inertia ixx="0.1" ixy="0.01" ixz="0" iyy="0.12" iyz="0" izz="0.04"/></inertial></link>
  <link name="sled"><inertial><origin xyz="0.05 0 0.02"/><mass value="1.1"/>
    <inertia ixx="0.003" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.002"/></inertial></link>
  <link name="bracket"><inertial><origin xyz="0 0.02 0"/><mass value="0.3"/>
    <inertia ixx="0.0002" ixy="0" ixz="0" iyy="0.0002" iyz="0" izz="0.0001"/></inertial></link>
  <link name="tool"><inertial><origin xyz="0 0 0.07"/><mass value="0.5"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.0005"/></inertial></link>
  <joint name="turn" type="continuous"><parent link="world"/><child link="post"/>
    <origin xyz="0.1 0 0.2" rpy="0 0 0.4"/><axis xyz="0 0.6 0.8"/></joint>
  <joint name="slide" type="prismatic"><parent link="post"/><child link="sled"/>
    <origin xyz="0 0.1 0.5" rpy="0.3 0 0"/><axis xyz="1 0 1"/>
    <limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="fix" type="fixed"><parent link="sled"/><child link="bracket"/>
    <origin xyz="0.1 0 0" rpy="0 0.5 0"/></joint>
  <joint name="tilt" type="revolute"><parent link="bracket"/><child link="tool"/>
    <origin xyz="0 0 0.05"/><axis xyz="0.8 0 0.6"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"#;

fn case(name: &'static str, seed: u64) -> Case {
    let path = models_dir().join(name);
    let model = if name == "slider.urdf" {
        let options = UrdfOptions {
            gravity_direction: [0.0, -0.6, -0.8],
            ..UrdfOptions::default()
        };
        Model::from_urdf_str(SLIDER, name, &options).expect("URDF imports")
    } else if name.ends_with(".urdf") {
        Model::from_urdf_file(&path, &UrdfOptions::default()).expect("URDF imports")
    } else {
        Model::from_toml_file(&path).expect("model loads")
    };
    // Every function but the regressors (`codegen/tests/regressors.rs`; their derivation in a
    // debug build made this test 4.6 times as long: 75 s instead of 16 s).
    let options = Options {
        functions: FunctionSet::all()
            .iter()
            .filter(|f| !FunctionSet::regressors().contains(*f))
            .collect(),
        ..Options::default()
    };
    let generated = Builder::from_model(model.clone())
        .options(options)
        .generate()
        .expect("generates");
    let mut r = SplitMix64::new(seed);
    let mut uniform: Box<dyn FnMut() -> f64> = Box::new(move || r.next_f64());
    let params = random_physical_params(&model, &mut uniform);
    let reference = Reference::with_params(&model, &params);
    Case {
        name,
        model,
        generated,
        params,
        reference,
        uniform,
    }
}

/// The models of the tests.
fn cases() -> Vec<Case> {
    [
        "krang.toml",
        "krang-fixed-wheels.toml",
        "two-link.toml",
        "singlearm.urdf",
        "slider.urdf",
    ]
    .into_iter()
    .enumerate()
    .map(|(i, name)| case(name, 100 + i as u64))
    .collect()
}

/// `max |a − b| / max(max |b|, floor)`.
fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(floor, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

impl Case {
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// A random state `(q, u, u̇)`.
    fn state(&mut self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.dof();
        let pi = std::f64::consts::PI;
        (
            uniform_vec(&mut self.uniform, n, -pi, pi),
            uniform_vec(&mut self.uniform, n, -2.0, 2.0),
            uniform_vec(&mut self.uniform, n, -5.0, 5.0),
        )
    }

    /// Function `id` through the lowered programs, checked against the derivation's evaluator.
    fn eval(&self, id: FunctionId, q: &[f64], u: &[f64], ud: &[f64]) -> Vec<f64> {
        self.eval_at(id, None, q, u, ud)
    }

    /// [`Case::eval`] for body frame `frame` of a per-frame function.
    fn eval_at(
        &self,
        id: FunctionId,
        frame: Option<usize>,
        q: &[f64],
        u: &[f64],
        ud: &[f64],
    ) -> Vec<f64> {
        // The derivation's evaluator computes every node: inputs the function does not read
        // are zeros.
        let zero = vec![0.0; self.dof()];
        let u = if u.is_empty() { &zero[..] } else { u };
        let ud = if ud.is_empty() { &zero[..] } else { ud };
        let low = self
            .generated
            .lowered
            .evaluate_at(id, frame, &self.params, q, u, ud);
        let sym = self
            .generated
            .derivation
            .evaluate_at(id, frame, &self.params, q, u, ud);
        let err = rel_err(&low, &sym, 1.0);
        assert!(
            err < 1e-11,
            "{}: {id}: lowered vs derivation {err:e}",
            self.name
        );
        low
    }

    /// The wheeled base's `(ẋ, ψ̇)` speed indices, if any.
    fn base(&self) -> Option<(usize, usize)> {
        self.model.wheeled_base().map(|w| (w.x_speed, w.psi_speed))
    }

    /// `(position of frame 0 in the ground frame, heading ψ)` at time `t` of the trajectory
    /// `q + u t + ½ u̇ t²`: `P0(t) = ∫₀ᵗ Rz(ψ(s)) [ẋ(s), 0, 0] ds` by 5-point Gauss–Legendre
    /// (exact to rounding for the small `t` of the differences).
    fn base_at(&self, q: &[f64], u: &[f64], ud: &[f64], t: f64) -> (Vector3<f64>, f64) {
        let Some((xs, ps)) = self.base() else {
            return (Vector3::zeros(), 0.0);
        };
        let psi = |s: f64| q[ps] + u[ps] * s + 0.5 * ud[ps] * s * s;
        let xd = |s: f64| u[xs] + ud[xs] * s;
        const GL: [(f64, f64); 5] = [
            (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
            (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (0.0, 0.568_888_888_888_888_9),
            (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
            (0.906_179_845_938_664, 0.236_926_885_056_189_1),
        ];
        let mut p = Vector3::zeros();
        for (x, w) in GL {
            let s = 0.5 * t * (x + 1.0);
            p += rz(psi(s)) * Vector3::new(xd(s), 0.0, 0.0) * (0.5 * t * w);
        }
        (p, psi(t))
    }

    /// A point given in frame 0 at time `t`, in the ground frame.
    fn to_ground(&self, q: &[f64], u: &[f64], ud: &[f64], t: f64, p: Vector3<f64>) -> Vector3<f64> {
        let (p0, psi) = self.base_at(q, u, ud, t);
        p0 + rz(psi) * p
    }
}

/// The heading rotation about z.
fn rz(psi: f64) -> Matrix3<f64> {
    let (s, c) = psi.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// `(q(t), u(t))` on the trajectory `q + u t + ½ u̇ t²`.
fn at(q: &[f64], u: &[f64], ud: &[f64], t: f64) -> (Vec<f64>, Vec<f64>) {
    let qt = (0..q.len())
        .map(|i| q[i] + u[i] * t + 0.5 * ud[i] * t * t)
        .collect();
    let ut = (0..u.len()).map(|i| u[i] + ud[i] * t).collect();
    (qt, ut)
}

/// First and second central differences of `f` at 0 with step `h`.
fn derivatives(h: f64, f: impl Fn(f64) -> Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (m, z, p) = (f(-h), f(0.0), f(h));
    ((p - m) / (2.0 * h), (p - 2.0 * z + m) / (h * h))
}

/// `J x` for a row-major `rows × n` Jacobian.
fn mul(j: &[f64], x: &[f64], rows: usize) -> Vec<f64> {
    let n = x.len();
    (0..rows)
        .map(|r| (0..n).map(|c| j[r * n + c] * x[c]).sum())
        .collect()
}

fn v3(x: &[f64]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

#[test]
fn kinetic_energy_is_half_u_m_u_and_the_reference() {
    for mut c in cases() {
        let n = c.dof();
        for _ in 0..20 {
            let (q, u, _) = c.state();
            let t = c.eval(FunctionId::KineticEnergy, &q, &u, &[])[0];
            let m = c.eval(FunctionId::MassMatrix, &q, &[], &[]);
            let mu = mul(&m, &u, n);
            let half_umu = 0.5 * u.iter().zip(&mu).map(|(a, b)| a * b).sum::<f64>();
            let err = (t - half_umu).abs() / half_umu.abs().max(1e-3);
            assert!(err < 1e-11, "{}: T vs ½uᵀMu {err:e}", c.name);
            let reference = c.reference.kinetic_energy(&q, &u);
            let err = (t - reference).abs() / reference.abs().max(1e-3);
            assert!(err < 1e-10, "{}: T vs reference {err:e}", c.name);
        }
    }
}

#[test]
fn potential_energy_is_the_reference_and_its_gradient_is_g() {
    for mut c in cases() {
        let n = c.dof();
        for _ in 0..10 {
            let (q, _, _) = c.state();
            let v = c.eval(FunctionId::PotentialEnergy, &q, &[], &[])[0];
            let reference = c.reference.potential_energy(&q);
            let err = (v - reference).abs() / reference.abs().max(1e-3);
            assert!(err < 1e-10, "{}: V vs reference {err:e}", c.name);
            let g = c.eval(FunctionId::Gravity, &q, &[], &[]);
            let h = 1e-5;
            let dv: Vec<f64> = (0..n)
                .map(|i| {
                    let mut qp = q.clone();
                    let mut qm = q.clone();
                    qp[i] += h;
                    qm[i] -= h;
                    let vp = c.eval(FunctionId::PotentialEnergy, &qp, &[], &[])[0];
                    let vm = c.eval(FunctionId::PotentialEnergy, &qm, &[], &[])[0];
                    (vp - vm) / (2.0 * h)
                })
                .collect();
            let err = rel_err(&dv, &g, 1e-3);
            assert!(err < 1e-7, "{}: ∂V/∂q vs g {err:e}", c.name);
        }
    }
}

#[test]
fn center_of_mass_is_the_mass_weighted_body_centres() {
    for mut c in cases() {
        for _ in 0..10 {
            let (q, _, _) = c.state();
            let com = v3(&c.eval(FunctionId::CenterOfMass, &q, &[], &[]));
            let zero = vec![0.0; c.dof()];
            let frames = c.reference.frame_states(&q, &zero, &zero);
            let (mut mass, mut moment) = (0.0, Vector3::zeros());
            for (link, s) in c.model.links.iter().zip(&frames) {
                let Some(b) = &link.body else { continue };
                let m = c.params[b.mass];
                let ms = Vector3::from_fn(|i, _| c.params[b.first_moment[i]]);
                mass += m;
                moment += s.position * m + s.rotation * ms;
            }
            // The wheels: 2 mw at the axle's ends, (0, ±L/2, 0).
            if let Some(w) = c.model.wheeled_base() {
                mass += 2.0 * c.params[w.wheel_mass];
            }
            let expected = moment / mass;
            let err = (com - expected).abs().max() / expected.abs().max().max(1e-3);
            assert!(err < 1e-11, "{}: CoM {err:e}", c.name);
        }
    }
}

#[test]
fn com_jacobian_and_bias_are_the_derivatives_of_the_ground_com() {
    for mut c in cases() {
        for _ in 0..10 {
            let (q, u, ud) = c.state();
            let ground_com = |t: f64| {
                let (qt, _) = at(&q, &u, &ud, t);
                let com = v3(&c.eval(FunctionId::CenterOfMass, &qt, &[], &[]));
                c.to_ground(&q, &u, &ud, t, com)
            };
            let (vel, acc) = derivatives(1e-3, ground_com);
            let (_, psi) = c.base_at(&q, &u, &ud, 0.0);
            let (vel, acc) = (rz(psi).transpose() * vel, rz(psi).transpose() * acc);
            let j = c.eval(FunctionId::ComJacobian, &q, &[], &[]);
            let bias = v3(&c.eval(FunctionId::ComBiasAcceleration, &q, &u, &[]));
            let ju = v3(&mul(&j, &u, 3));
            let jud = v3(&mul(&j, &ud, 3));
            let err = (ju - vel).abs().max() / vel.abs().max().max(1.0);
            assert!(err < 1e-5, "{}: J u vs d/dt CoM {err:e}", c.name);
            let err = (jud + bias - acc).abs().max() / acc.abs().max().max(1.0);
            assert!(err < 1e-4, "{}: J u̇ + bias vs d²/dt² CoM {err:e}", c.name);
        }
    }
}

/// The pose `(⁰A, ⁰p)` of frame `l` from `frame_pose` (row-major `[R | p]`).
fn pose(c: &Case, l: usize, q: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
    let x = c.eval_at(FunctionId::FramePose, Some(l), q, &[], &[]);
    let r = Matrix3::from_fn(|i, j| x[i * 4 + j]);
    (r, Vector3::new(x[3], x[7], x[11]))
}

/// `(J_v u, J_ω u)` of frame `l` for speeds `x`.
fn twist(c: &Case, l: usize, q: &[f64], x: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
    let j = c.eval_at(FunctionId::FrameJacobian, Some(l), q, &[], &[]);
    let t = mul(&j, x, 6);
    (v3(&t[..3]), v3(&t[3..]))
}

fn close(a: Vector3<f64>, b: Vector3<f64>, tol: f64) -> bool {
    (a - b).abs().max() <= tol * b.abs().max().max(1.0)
}

#[test]
fn frames_match_the_reference_recursion() {
    for mut c in cases() {
        for _ in 0..5 {
            let (q, u, ud) = c.state();
            let zero = vec![0.0; c.dof()];
            let states = c.reference.frame_states(&q, &u, &zero);
            for (l, s) in states.iter().enumerate() {
                let (r, p) = pose(&c, l, &q);
                let name = &c.model.links[l].name;
                assert!(
                    (r - s.rotation).abs().max() < 1e-12,
                    "{} {name}: rotation",
                    c.name
                );
                assert!(close(p, s.position, 1e-12), "{} {name}: position", c.name);
                let (v, w) = twist(&c, l, &q, &u);
                assert!(
                    close(v, s.rotation * s.velocity, 1e-11),
                    "{} {name}: J_v u",
                    c.name
                );
                assert!(
                    close(w, s.rotation * s.omega, 1e-11),
                    "{} {name}: J_ω u",
                    c.name
                );
                let b = c.eval_at(FunctionId::FrameBiasAcceleration, Some(l), &q, &u, &ud);
                let (a, al) = (s.rotation * s.acceleration, s.rotation * s.alpha);
                assert!(
                    close(v3(&b[..3]), a, 1e-11),
                    "{} {name}: linear bias",
                    c.name
                );
                assert!(
                    close(v3(&b[3..]), al, 1e-11),
                    "{} {name}: angular bias",
                    c.name
                );
            }
        }
    }
}

#[test]
fn frame_jacobians_and_biases_are_the_derivatives_of_the_ground_pose() {
    for mut c in cases() {
        for _ in 0..3 {
            let (q, u, ud) = c.state();
            let h = 1e-3;
            let (_, psi) = c.base_at(&q, &u, &ud, 0.0);
            let back = rz(psi).transpose();
            for l in 0..c.model.links.len() {
                let name = &c.model.links[l].name;
                // The origin in the ground frame.
                let origin = |t: f64| {
                    let (qt, _) = at(&q, &u, &ud, t);
                    c.to_ground(&q, &u, &ud, t, pose(&c, l, &qt).1)
                };
                let (vel, acc) = derivatives(h, origin);
                let (v, _) = twist(&c, l, &q, &u);
                let (jv, jw) = twist(&c, l, &q, &ud);
                let b = c.eval_at(FunctionId::FrameBiasAcceleration, Some(l), &q, &u, &[]);
                assert!(close(v, back * vel, 1e-5), "{} {name}: J_v u", c.name);
                assert!(
                    close(jv + v3(&b[..3]), back * acc, 1e-4),
                    "{} {name}: a",
                    c.name
                );
                // The rotation in the ground frame: ω× = Ṙ Rᵀ.
                let rot = |t: f64| {
                    let (qt, _) = at(&q, &u, &ud, t);
                    let (_, psi) = c.base_at(&q, &u, &ud, t);
                    rz(psi) * pose(&c, l, &qt).0
                };
                let h1 = h / 10.0;
                let wx = (rot(h1) - rot(-h1)) / (2.0 * h1) * rot(0.0).transpose();
                let omega = Vector3::new(wx[(2, 1)], wx[(0, 2)], wx[(1, 0)]);
                let (_, w) = twist(&c, l, &q, &u);
                assert!(close(w, back * omega, 1e-5), "{} {name}: J_ω u", c.name);
                // α: the derivative of the ground angular velocity.
                let ground_omega = |t: f64| {
                    let (qt, ut) = at(&q, &u, &ud, t);
                    let (_, psi) = c.base_at(&q, &u, &ud, t);
                    rz(psi) * twist(&c, l, &qt, &ut).1
                };
                // A first derivative: a smaller step (its error is O(h²), its rounding O(ε/h)).
                let (alpha, _) = derivatives(h / 10.0, ground_omega);
                assert!(
                    close(jw + v3(&b[3..]), back * alpha, 1e-5),
                    "{} {name}: α",
                    c.name
                );
            }
        }
    }
}

/// A point mass `δm` at the origin of frame `l` adds `−J_vᵀ (δm g0)` to the reference
/// recursion's generalized gravity forces: `Jᵀ f` for the force `f = δm g0` at the frame, an
/// independent check of the Jacobian's columns as generalized forces. The mass is added to the
/// body the frame is rigidly fixed to (its own, or through fixed joints a parent's: operational
/// frames and merged URDF links): `m += δm`, `MS += δm p` with `p` the frame's origin in the
/// body frame (from the reference's frame states).
#[test]
fn jacobian_transpose_maps_a_force_at_the_frame_to_generalized_forces() {
    for mut c in cases() {
        let n = c.dof();
        let g0: Vec<f64> = {
            let g = c.params[c.model.gravity.symbol];
            c.model.gravity.direction.iter().map(|d| g * d).collect()
        };
        let links = c.model.links.clone();
        for (l, link) in links.iter().enumerate() {
            // The body frame `l` is rigidly fixed to.
            let mut b = l;
            while links[b].body.is_none() {
                match &links[b].mount {
                    Some(m) if m.joint.kind == kanegen::model::JointKind::Fixed => b = m.parent,
                    _ => break,
                }
            }
            let Some(body) = &links[b].body else { continue };
            let dm = 0.7;
            let (q, _, _) = c.state();
            let zero = vec![0.0; n];
            let states = c.reference.frame_states(&q, &zero, &zero);
            let p = states[b].rotation.transpose() * (states[l].position - states[b].position);
            let mut heavier = c.params.clone();
            heavier[body.mass] += dm;
            for (k, &ms) in body.first_moment.iter().enumerate() {
                heavier[ms] += dm * p[k];
            }
            let with = Reference::with_params(&c.model, &heavier);
            let dg: Vec<f64> = (with.gravity(&q) - c.reference.gravity(&q))
                .iter()
                .copied()
                .collect();
            let j = c.eval_at(FunctionId::FrameJacobian, Some(l), &q, &[], &[]);
            let jtf: Vec<f64> = (0..n)
                .map(|col| -(0..3).map(|r| j[r * n + col] * dm * g0[r]).sum::<f64>())
                .collect();
            let err = rel_err(&jtf, &dg, 1e-3);
            assert!(err < 1e-10, "{} {}: Jᵀ f {err:e}", c.name, link.name);
        }
    }
}
