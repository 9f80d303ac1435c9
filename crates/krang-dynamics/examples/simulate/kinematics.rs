//! Forward kinematics from the model description (for the potential energy).

use kanegen_model::{JointKind, Model};
use nalgebra::{Matrix3, SVector, Vector3};

use super::Res;

struct FkLink {
    parent: Option<usize>,
    rotation: Matrix3<f64>,
    axis: Vector3<f64>,
    translation: Vector3<f64>,
    coordinate: Option<usize>,
    /// `(m, MS)` of the body in this frame.
    body: Option<(f64, Vector3<f64>)>,
}

/// Frames of `krang.toml` with the parameter values of a [`Krang`].
pub struct Kinematics {
    links: Vec<FkLink>,
    gravity: Vector3<f64>,
}

impl Kinematics {
    /// Loads `krang.toml` (next to this crate's manifest) and takes the lengths and inertial
    /// parameters from `params`.
    pub fn new(params: &krang_dynamics::Params) -> Res<Self> {
        let model = Model::from_toml_file(concat!(env!("CARGO_MANIFEST_DIR"), "/krang.toml"))?;
        let value = |id: usize| -> Res<f64> {
            let name = &model.params[id].name;
            params
                .get(name)
                .ok_or_else(|| format!("parameter {name} not in Params").into())
        };
        let mut links = Vec::new();
        for link in &model.links {
            let (rotation, axis, translation, coordinate) = match link.joint() {
                None => (
                    Matrix3::identity(),
                    Vector3::zeros(),
                    Vector3::zeros(),
                    None,
                ),
                Some(j) => {
                    let r = j.rotation;
                    let mut t = Vector3::zeros();
                    for (k, s) in j.translation.iter().enumerate() {
                        t[k] = match s.symbol {
                            Some(p) => s.coef * value(p)?,
                            None => s.coef,
                        };
                    }
                    let coordinate = match j.kind {
                        JointKind::Revolute { speed } => Some(speed),
                        JointKind::Fixed => None,
                        JointKind::Prismatic { .. } => {
                            return Err("prismatic joint in krang.toml".into());
                        }
                    };
                    (
                        Matrix3::from_fn(|i, k| r[i][k]),
                        Vector3::from(j.axis),
                        t,
                        coordinate,
                    )
                }
            };
            let body = match &link.body {
                None => None,
                Some(b) => Some((
                    value(b.mass)?,
                    Vector3::new(
                        value(b.first_moment[0])?,
                        value(b.first_moment[1])?,
                        value(b.first_moment[2])?,
                    ),
                )),
            };
            links.push(FkLink {
                parent: link.parent(),
                rotation,
                axis,
                translation,
                coordinate,
                body,
            });
        }
        let gravity = Vector3::from(model.gravity.direction) * value(model.gravity.symbol)?;
        Ok(Self { links, gravity })
    }

    /// Rotation and origin of every frame in frame 0.
    fn frames(&self, q: &SVector<f64, 19>) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        let mut out: Vec<(Matrix3<f64>, Vector3<f64>)> = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let local = match l.coordinate {
                Some(c) => {
                    // Rot(e, θ) = 1 + sin θ [e]× + (1 − cos θ) [e]×².
                    let k = l.axis.cross_matrix();
                    let (s, c) = q[c].sin_cos();
                    l.rotation * (Matrix3::identity() + k * s + k * k * (1.0 - c))
                }
                None => l.rotation,
            };
            out.push(match l.parent {
                None => (Matrix3::identity(), Vector3::zeros()),
                Some(p) => {
                    let (rp, pp) = out[p];
                    (rp * local, pp + rp * l.translation)
                }
            });
        }
        out
    }

    /// `(Σ m, Σ (m ⁰P + ⁰A MS))`: total mass and first moment in frame 0 (wheels excluded:
    /// their centres are on the axle, at frame 0's height).
    fn first_moment(&self, q: &SVector<f64, 19>) -> (f64, Vector3<f64>) {
        let mut mass = 0.0;
        let mut ms = Vector3::zeros();
        for (l, (r, p)) in self.links.iter().zip(self.frames(q)) {
            if let Some((m, msb)) = l.body {
                mass += m;
                ms += p * m + r * msb;
            }
        }
        (mass, ms)
    }

    /// Potential energy `V = −Σ g0·(m ⁰P + ⁰A MS)` relative to the axle height.
    pub fn potential(&self, q: &SVector<f64, 19>) -> f64 {
        -self.gravity.dot(&self.first_moment(q).1)
    }

    /// Centre of mass in frame 0 (heading frame at the axle midpoint, z up).
    pub fn centre_of_mass(&self, q: &SVector<f64, 19>) -> Vector3<f64> {
        let (m, ms) = self.first_moment(q);
        ms / m
    }
}
