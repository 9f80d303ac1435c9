//! Helpers shared by the integration tests: model loading, a deterministic random source,
//! random physical parameters and states, and an independent (non-recursive) kinetic energy.
#![allow(dead_code)]

use std::path::PathBuf;

use kanegen_model::{Base, JointKind, Model, ParamKind};
use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};

/// The three shipped models with their number of speeds.
pub const MODELS: [(&str, usize); 3] = [("two-link", 2), ("krang-fixed-wheels", 17), ("krang", 19)];

/// Loads `models/<name>.toml` from the workspace.
pub fn load_model(name: &str) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(format!("{name}.toml"));
    Model::from_toml_file(&path).unwrap_or_else(|e| panic!("loading {}: {e}", path.display()))
}

/// SplitMix64: a tiny deterministic generator for test data.
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Uniform in `[0, 1)`.
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    /// A vector uniform in `[lo, hi)ᴺ`.
    pub fn vec<const N: usize>(&mut self, lo: f64, hi: f64) -> SVector<f64, N> {
        SVector::from_fn(|_, _| self.range(lo, hi))
    }

    /// A uniformly random rotation (the reference crate's Shoemake construction).
    pub fn rotation(&mut self) -> Matrix3<f64> {
        kanegen_reference::random::random_rotation(&mut || self.next())
    }
}

/// Random but physically valid parameters: lengths in [0.05, 0.6], g in [8, 11], each body a
/// random mass, centre of mass and positive-definite central inertia (triangle inequality
/// holds), converted to Khalil's form about the frame origin; positive wheel constants.
pub fn random_params(model: &Model, rng: &mut Rng) -> Vec<f64> {
    let mut p = model.param_values();
    for (i, par) in model.params.iter().enumerate() {
        p[i] = match par.kind {
            ParamKind::Length => rng.range(0.05, 0.6),
            ParamKind::Gravity => rng.range(8.0, 11.0),
            ParamKind::Wheel => rng.range(0.05, 1.0),
            ParamKind::Inertial => p[i],
        };
    }
    for link in &model.links {
        let Some(b) = &link.body else { continue };
        let m = rng.range(0.5, 10.0);
        let s = Vector3::new(
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
        );
        // Central second moments -> principal inertias (always satisfy the triangle inequality).
        let (sx, sy, sz) = (
            rng.range(0.001, 0.1),
            rng.range(0.001, 0.1),
            rng.range(0.001, 0.1),
        );
        let d = Matrix3::from_diagonal(&Vector3::new(sy + sz, sx + sz, sx + sy)) * m;
        let r = rng.rotation();
        let ig = r * d * r.transpose();
        let j = ig + (Matrix3::identity() * s.norm_squared() - s * s.transpose()) * m;
        p[b.mass] = m;
        for k in 0..3 {
            p[b.first_moment[k]] = m * s[k];
        }
        let vals = [
            j[(0, 0)],
            j[(0, 1)],
            j[(0, 2)],
            j[(1, 1)],
            j[(1, 2)],
            j[(2, 2)],
        ];
        for k in 0..6 {
            p[b.inertia[k]] = vals[k];
        }
    }
    p
}

/// `max |a − b| / max(max |b|, floor)`.
pub fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let d = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let s = b.iter().map(|y| y.abs()).fold(0.0, f64::max);
    d / s.max(floor)
}

/// Rotation by `angle` about the unit axis `e` (Rodrigues).
fn axis_angle(e: [f64; 3], angle: f64) -> Matrix3<f64> {
    let e = Vector3::from(e);
    let k = e.cross_matrix();
    Matrix3::identity() + k * angle.sin() + k * k * (1.0 - angle.cos())
}

/// A moving joint on the path from the base to a link: world axis, world origin, kind (with the
/// speed).
type PathJoint = (Vector3<f64>, Vector3<f64>, JointKind);

/// The kinetic energy computed directly, body by body, without any recursion: each link's
/// pose in frame 0 from the product of its joints' 4×4 transforms (raw model frames), its
/// velocity from the joint-axis sum `ω = ω0 + Σ u_j ê_j`, `v_O = v0 + ω0×O + Σ u_j ê_j×(O − O_j)`
/// (revolute) or `+ u_j ê_j` (prismatic), then `½ m v_G² + ½ ωᵀ I_G ω`; the two wheels each
/// contribute translation (`v = ẋ ∓ L ψ̇ / 2`), spin about the axle (`θ̇ = v / R`) and yaw.
pub fn direct_kinetic_energy(model: &Model, params: &[f64], q: &[f64], u: &[f64]) -> f64 {
    let n = model.links.len();
    let (w0, v0) = match &model.base {
        Base::Wheeled(w) => (
            Vector3::new(0.0, 0.0, u[w.psi_speed]),
            Vector3::new(u[w.x_speed], 0.0, 0.0),
        ),
        Base::Fixed => (Vector3::zeros(), Vector3::zeros()),
        // The base twist (v, ω) in frame 0 (speeds 0..6).
        Base::Floating => (
            Vector3::new(u[3], u[4], u[5]),
            Vector3::new(u[0], u[1], u[2]),
        ),
    };
    // Pose of each link in frame 0, and the list of joints on its path (axis, origin, speed, kind).
    let mut rot = vec![Matrix3::identity(); n];
    let mut org = vec![Vector3::zeros(); n];
    let mut path: Vec<Vec<PathJoint>> = vec![Vec::new(); n];
    for (k, _, mount) in model.mounted_links() {
        let (pi, j) = (mount.parent, &mount.joint);
        let a0 = Matrix3::from_fn(|r, c| j.rotation[r][c]);
        let p0 = Vector3::from_fn(|r, _| j.translation[r].eval(params));
        let e = Vector3::from(j.axis);
        let (a, p) = match j.kind {
            JointKind::Revolute { speed } => (a0 * axis_angle(j.axis, q[speed]), p0),
            JointKind::Prismatic { speed } => (a0, p0 + a0 * e * q[speed]),
            JointKind::Fixed => (a0, p0),
        };
        rot[k] = rot[pi] * a;
        org[k] = org[pi] + rot[pi] * p;
        let mut pth = path[pi].clone();
        if j.speed().is_some() {
            pth.push((rot[k] * e, org[k], j.kind));
        }
        path[k] = pth;
    }
    let mut ke = 0.0;
    for k in 0..n {
        let Some(b) = &model.links[k].body else {
            continue;
        };
        let mut w = w0;
        let mut v = v0 + w0.cross(&org[k]);
        for (e, o, kind) in &path[k] {
            match *kind {
                JointKind::Revolute { speed } => {
                    w += e * u[speed];
                    v += e.cross(&(org[k] - o)) * u[speed];
                }
                JointKind::Prismatic { speed } => v += e * u[speed],
                JointKind::Fixed => {}
            }
        }
        let m = params[b.mass];
        let s_local = Vector3::from_fn(|r, _| params[b.first_moment[r]]) / m;
        let [xx, xy, xz, yy, yz, zz] = b.inertia.map(|i| params[i]);
        let j = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
        let ig_local =
            j - (Matrix3::identity() * s_local.norm_squared() - s_local * s_local.transpose()) * m;
        let ig = rot[k] * ig_local * rot[k].transpose();
        let vg = v + w.cross(&(rot[k] * s_local));
        ke += 0.5 * m * vg.norm_squared() + 0.5 * w.dot(&(ig * w));
    }
    if let Base::Wheeled(wb) = &model.base {
        let (r, l, mw, yy, zz) = (
            params[wb.radius],
            params[wb.track],
            params[wb.wheel_mass],
            params[wb.wheel_axle_inertia],
            params[wb.wheel_diametral_inertia],
        );
        let (xd, psid) = (u[wb.x_speed], u[wb.psi_speed]);
        for side in [-1.0, 1.0] {
            let vw = xd + side * 0.5 * l * psid;
            ke += 0.5 * mw * vw * vw + 0.5 * yy * (vw / r).powi(2) + 0.5 * zz * psid * psid;
        }
    }
    ke
}

/// `DMatrix` from an `SMatrix` (for comparisons with the reference crate's dynamic results).
pub fn to_dmatrix<const N: usize>(m: &nalgebra::SMatrix<f64, N, N>) -> DMatrix<f64> {
    DMatrix::from_fn(N, N, |i, j| m[(i, j)])
}

/// `DVector` from an `SVector`.
pub fn to_dvector<const N: usize>(v: &SVector<f64, N>) -> DVector<f64> {
    DVector::from_column_slice(v.as_slice())
}
