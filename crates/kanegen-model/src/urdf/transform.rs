//! Rigid transforms, URDF rpy angles and their snapping to multiples of π/2 ([`AngleSnap`]), and
//! the import notes (which list every snap).

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Matrix3, Vector3};

use super::options::AngleSnap;
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

/// Import notes under construction.
#[derive(Default)]
pub(super) struct Notes {
    lines: Vec<String>,
}

impl Notes {
    /// Adds a line.
    pub(super) fn push(&mut self, line: String) {
        self.lines.push(line);
    }

    /// The lines, in the order they were added.
    pub(super) fn finish(self) -> Vec<String> {
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

/// The number of decimals of `a` as written: of its shortest decimal that reads back as `a`
/// (`3.1416` → 4; trailing zeros of the file do not count).
fn written_decimals(a: f64) -> usize {
    let written = format!("{a}");
    written.find('.').map_or(0, |dot| written.len() - dot - 1)
}

/// Whether `a`, as written, is `exact` correctly rounded to the same number of decimals, at
/// least two (`3.14`, `3.1416`, `-1.5708` for π, π, −π/2; not `3.1415`, nor `1.5`).
fn is_rounded_decimal_of(a: f64, exact: f64) -> bool {
    let d = written_decimals(a);
    d >= 2 && format!("{exact:.d$}") == format!("{a}")
}

/// `(cos a, sin a)`, exact for multiples of π/2 and for angles snapped to them (each snap noted).
fn cos_sin(a: f64, snap: AngleSnap, what: &str, notes: &mut Notes) -> (f64, f64) {
    let k = (a / FRAC_PI_2).round();
    let exact = k * FRAC_PI_2;
    let delta = a - exact;
    let why = match snap {
        _ if delta == 0.0 => Some(String::new()),
        AngleSnap::Rounded if k != 0.0 && is_rounded_decimal_of(a, exact) => Some(format!(
            " ({a} is {} rounded to {} decimals; {delta:.2e} rad)",
            fmt_half_pi(k as i64),
            written_decimals(a)
        )),
        AngleSnap::Within(t) if delta.abs() <= t => {
            Some(format!(" (within {t:e} rad; {delta:.2e} rad)"))
        }
        _ => None,
    };
    let Some(why) = why else {
        return (a.cos(), a.sin());
    };
    let k = k as i64;
    if delta != 0.0 {
        notes.push(format!("{what}: {a} snapped to {}{why}", fmt_half_pi(k)));
    }
    match k.rem_euclid(4) {
        0 => (1.0, 0.0),
        1 => (0.0, 1.0),
        2 => (-1.0, 0.0),
        _ => (0.0, -1.0),
    }
}

/// URDF rpy: `R = Rz(y) · Ry(p) · Rx(r)`.
pub(super) fn rpy_matrix(
    rpy: [f64; 3],
    snap: AngleSnap,
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
pub(super) fn pose_tf(pose: &urdf_rs::Pose, snap: AngleSnap, what: &str, notes: &mut Notes) -> Tf {
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
