//! Dynamics straight from a URDF as written, for tests: forward kinematics from the urdf-rs
//! structures (nothing of the importer), potential and kinetic energy, and the comparison of a
//! generated module's g and M with them.
#![allow(dead_code)]

use kanegen::{Builder, FunctionId, Options};
use kanegen_model::Model;

use super::common::{random_state, rel_err, rng};

/// Forward kinematics straight from the URDF as written (urdf-rs structures, nothing of the
/// importer): per link with an `<inertial>`, its mass, centre of mass and rotation of its
/// inertial frame in the root frame, and its inertia in that frame; joint values by the
/// model's coordinate names (`q_<joint>`).
pub struct RawUrdf {
    robot: urdf_rs::Robot,
    /// Index into q of each joint (`None`: fixed).
    coordinate: Vec<Option<usize>>,
}

pub type Pose = (nalgebra::Matrix3<f64>, nalgebra::Vector3<f64>);

fn rpy(p: &urdf_rs::Pose) -> Pose {
    let [r, pi, y] = p.rpy.0;
    (
        *nalgebra::Rotation3::from_euler_angles(r, pi, y).matrix(),
        nalgebra::Vector3::from(p.xyz.0),
    )
}

impl RawUrdf {
    pub fn new(text: &str, model: &Model) -> Self {
        let robot = urdf_rs::read_from_string(text).unwrap();
        let coordinate = robot
            .joints
            .iter()
            .map(|j| {
                let name = format!("q_{}", kanegen_model::sanitize_identifier(&j.name));
                model.speeds.iter().position(|s| s.coordinate == name)
            })
            .collect();
        Self { robot, coordinate }
    }

    /// Link poses (rotation, origin) in the root frame at `q`, by link name.
    pub fn poses(&self, q: &[f64]) -> std::collections::HashMap<&str, Pose> {
        let mut poses = std::collections::HashMap::new();
        let children: std::collections::HashSet<&str> = self
            .robot
            .joints
            .iter()
            .map(|j| j.child.link.as_str())
            .collect();
        for l in &self.robot.links {
            if !children.contains(l.name.as_str()) {
                poses.insert(
                    l.name.as_str(),
                    (nalgebra::Matrix3::identity(), nalgebra::Vector3::zeros()),
                );
            }
        }
        while poses.len() < self.robot.links.len() {
            for (j, c) in self.robot.joints.iter().zip(&self.coordinate) {
                let Some(&(rp, pp)) = poses.get(j.parent.link.as_str()) else {
                    continue;
                };
                if poses.contains_key(j.child.link.as_str()) {
                    continue;
                }
                let (ro, po) = rpy(&j.origin);
                let axis = nalgebra::Vector3::from(j.axis.xyz.0).normalize();
                let v = c.map_or(0.0, |i| q[i]);
                let (rj, pj) = match j.joint_type {
                    urdf_rs::JointType::Prismatic => (nalgebra::Matrix3::identity(), axis * v),
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => (
                        *nalgebra::Rotation3::from_axis_angle(
                            &nalgebra::Unit::new_normalize(axis),
                            v,
                        )
                        .matrix(),
                        nalgebra::Vector3::zeros(),
                    ),
                    _ => (nalgebra::Matrix3::identity(), nalgebra::Vector3::zeros()),
                };
                let r = rp * ro;
                poses.insert(j.child.link.as_str(), (r * rj, pp + rp * po + r * pj));
            }
        }
        poses
    }

    /// Potential energy (g = 9.81 along −z of the root frame).
    pub fn potential(&self, q: &[f64]) -> f64 {
        let poses = self.poses(q);
        self.robot
            .links
            .iter()
            .map(|l| {
                let (r, p) = poses[l.name.as_str()];
                let c = p + r * nalgebra::Vector3::from(l.inertial.origin.xyz.0);
                l.inertial.mass.value * 9.81 * c.z
            })
            .sum()
    }

    /// Kinetic energy at `q` moving with `u` (= q̇): velocities by central differences of the
    /// poses along `u`.
    pub fn kinetic(&self, q: &[f64], u: &[f64], h: f64) -> f64 {
        let at = |s: f64| -> Vec<f64> { q.iter().zip(u).map(|(q, u)| q + s * u).collect() };
        let (p0, pp, pm) = (self.poses(q), self.poses(&at(h)), self.poses(&at(-h)));
        self.robot
            .links
            .iter()
            .map(|l| {
                let i = &l.inertial;
                let com = nalgebra::Vector3::from(i.origin.xyz.0);
                let (ri, _) = rpy(&i.origin);
                let t = &i.inertia;
                let ic = nalgebra::Matrix3::new(
                    t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
                );
                let name = l.name.as_str();
                let (r0, _) = p0[name];
                let c = |(r, p): Pose| p + r * com;
                let v = (c(pp[name]) - c(pm[name])) / (2.0 * h);
                let rdot = (pp[name].0 - pm[name].0) / (2.0 * h);
                let w = rdot * r0.transpose();
                let omega = nalgebra::Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
                let iw = r0 * ri * ic * ri.transpose() * r0.transpose();
                0.5 * i.mass.value * v.norm_squared() + 0.5 * omega.dot(&(iw * omega))
            })
            .sum()
    }

    /// Worst relative errors over `draws` random states of the generated g against the
    /// gradient of [`potential`](Self::potential) and of ½ uᵀ M u against
    /// [`kinetic`](Self::kinetic) (the model's own parameters; fixed base).
    pub fn energy_errors(&self, model: &Model, draws: usize, seed: u64) -> (f64, f64) {
        let g = Builder::from_model(model.clone())
            .options(Options {
                functions: [FunctionId::MassMatrix, FunctionId::Gravity]
                    .into_iter()
                    .collect(),
                ..Options::default()
            })
            .generate()
            .expect("generates");
        let p = model.param_values();
        // Mimic joints: the generated functions take the independent coordinates; the raw
        // file's energies are taken at the whole tree's expanded state.
        let n = model.independent_dof();
        let mut r = rng(seed);
        let (mut worst_g, mut worst_t) = (0.0f64, 0.0f64);
        for _ in 0..draws {
            let (q, u, _) = random_state(&mut r, n);
            let gravity = g.lowered.evaluate(FunctionId::Gravity, &p, &q, &u, &u);
            let h = 1e-5;
            let grad: Vec<f64> = (0..n)
                .map(|i| {
                    let mut a = q.clone();
                    let mut b = q.clone();
                    a[i] += h;
                    b[i] -= h;
                    (self.potential(&model.expand_coordinates(&a))
                        - self.potential(&model.expand_coordinates(&b)))
                        / (2.0 * h)
                })
                .collect();
            worst_g = worst_g.max(rel_err(&gravity, &grad, 1.0));
            let m = g.lowered.evaluate(FunctionId::MassMatrix, &p, &q, &u, &u);
            let t: f64 = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|k| 0.5 * u[i] * m[i * n + k] * u[k])
                        .sum::<f64>()
                })
                .sum();
            let raw_t = self.kinetic(
                &model.expand_coordinates(&q),
                &model.expand_speeds(&u),
                1e-5,
            );
            worst_t = worst_t.max((t - raw_t).abs() / t.abs().max(1e-3));
        }
        (worst_g, worst_t)
    }
}
