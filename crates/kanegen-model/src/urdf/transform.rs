//! Rigid transforms, URDF rpy angles and their snapping to multiples of π/2, and the import notes
//! (which record the snaps).

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Matrix3, Vector3};

use crate::ir::Length;

/// A rigid transform: the pose of a frame in another (rotation `r`, origin `p`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Tf {
    /// Rotation: the frame's axes (columns) in the outer frame.
    pub(super) r: Matrix3<f64>,
    /// The frame's origin in the outer frame.
    pub(super) p: Vector3<f64>,
}

impl Tf {
    /// The identity.
    pub(super) fn identity() -> Self {
        Self {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self ∘ b`: b's pose given in this frame.
    pub(super) fn then(&self, b: &Tf) -> Tf {
        Tf {
            r: self.r * b.r,
            p: self.r * b.p + self.p,
        }
    }

    /// The inverse transform.
    pub(super) fn inverse(&self) -> Tf {
        let rt = self.r.transpose();
        Tf {
            r: rt,
            p: -(rt * self.p),
        }
    }
}

/// Removes floating-point dust from composed rotations and translations.
pub(super) fn clean(x: f64) -> f64 {
    const EPS: f64 = 1e-15;
    if x.abs() < EPS {
        0.0
    } else if (x - 1.0).abs() < EPS {
        1.0
    } else if (x + 1.0).abs() < EPS {
        -1.0
    } else {
        x
    }
}

/// Snaps up to this size are counted in one note rather than listed (`3.1416` is 7.3·10⁻⁶ off π).
const SMALL_SNAP: f64 = 1e-4;

/// Import notes under construction.
#[derive(Default)]
pub(super) struct Notes {
    lines: Vec<String>,
    small_snaps: usize,
}

impl Notes {
    /// Adds a line.
    pub(super) fn push(&mut self, line: String) {
        self.lines.push(line);
    }

    /// The lines, with the count of small snaps first.
    pub(super) fn finish(mut self) -> Vec<String> {
        if self.small_snaps > 0 {
            self.lines.insert(
                0,
                format!(
                    "{} rotation angles within {SMALL_SNAP:e} rad of a multiple of π/2 (such as 3.1416 or 1.5708) snapped to it",
                    self.small_snaps
                ),
            );
        }
        self.lines
    }
}

/// `k·π/2` written as a fraction of π (`π/2`, `-π`, `3π/2`).
fn fmt_half_pi(k: i64) -> String {
    match k {
        0 => "0".into(),
        _ if k % 2 == 0 => match k / 2 {
            1 => "π".into(),
            -1 => "-π".into(),
            n => format!("{n}π"),
        },
        1 => "π/2".into(),
        -1 => "-π/2".into(),
        _ => format!("{k}π/2"),
    }
}

/// `(cos a, sin a)`, exact for multiples of π/2 and for angles snapped to them.
fn cos_sin(a: f64, snap: Option<f64>, what: &str, notes: &mut Notes) -> (f64, f64) {
    let k = (a / FRAC_PI_2).round();
    let exact = k * FRAC_PI_2;
    let delta = a - exact;
    if delta == 0.0 || snap.is_some_and(|t| delta.abs() <= t) {
        let k = k as i64;
        if delta.abs() > SMALL_SNAP {
            notes.push(format!(
                "{what}: {a} snapped to {} (by {delta:.2e} rad)",
                fmt_half_pi(k)
            ));
        } else if delta != 0.0 {
            notes.small_snaps += 1;
        }
        return match k.rem_euclid(4) {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 0.0),
            _ => (0.0, -1.0),
        };
    }
    (a.cos(), a.sin())
}

/// URDF rpy: `R = Rz(y) · Ry(p) · Rx(r)`.
pub(super) fn rpy_matrix(
    rpy: [f64; 3],
    snap: Option<f64>,
    what: &str,
    notes: &mut Notes,
) -> Matrix3<f64> {
    let names = ["roll", "pitch", "yaw"];
    let cs: Vec<(f64, f64)> = (0..3)
        .map(|i| cos_sin(rpy[i], snap, &format!("{what} rpy {}", names[i]), notes))
        .collect();
    let (cr, sr) = cs[0];
    let (cp, sp) = cs[1];
    let (cy, sy) = cs[2];
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    (rz * ry * rx).map(clean)
}

/// A URDF `<origin>` as a transform (its rpy snapped as [`rpy_matrix`] does).
pub(super) fn pose_tf(
    pose: &urdf_rs::Pose,
    snap: Option<f64>,
    what: &str,
    notes: &mut Notes,
) -> Tf {
    Tf {
        r: rpy_matrix(pose.rpy.0, snap, what, notes),
        p: Vector3::from(pose.xyz.0),
    }
}

/// Are all three numbers finite?
pub(super) fn finite3(v: [f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A rotation as IR rows, dust removed.
pub(super) fn rows(r: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| clean(r[(i, j)])))
}

/// A translation as IR lengths (plain numbers), dust removed.
pub(super) fn numbers(v: Vector3<f64>) -> [Length; 3] {
    [v.x, v.y, v.z].map(|x| Length::number(clean(x)))
}
