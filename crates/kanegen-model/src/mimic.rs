//! Mimic joints: a joint whose coordinate is an affine function of another joint's,
//! `q_dep = a · q_master + b` (URDF `<mimic joint multiplier offset>`), kept as an exact
//! constraint in reduced coordinates.
//!
//! A constrained [`Model`] is the unconstrained tree (one coordinate and speed per moving joint)
//! plus the list [`Model::mimics`]: the dependent speeds are the last ones of
//! [`Model::speeds`]. With the constant map `T` (`u_all = T u`, `T[dep, master] = a`, identity on
//! the independent speeds; `Ṫ = 0`), Kane's equations in the independent speeds are
//! `M = Tᵀ M_all T`, `c = Tᵀ c_all(q_all, T u)`, `g = Tᵀ g_all`, `τ = Tᵀ τ_all`, `C = Tᵀ C_all T`,
//! Jacobians `J_all T`: what the generator emits. Code that ignores [`Model::mimics`] (the
//! reference recursion, `kanegen-rbd`) sees the unconstrained tree; [`Model::expand_coordinates`],
//! [`Model::expand_speeds`], [`Model::project_forces`] and [`Model::project_matrix`] convert
//! between the two.

use std::collections::HashMap;

use crate::error::ModelErrorKind as K;
use crate::ir::{Base, JointKind, Model};

/// One mimic constraint: speed `speed` (dependent) follows speed `master` (independent):
/// `q[speed] = multiplier · q[master] + offset`, `u[speed] = multiplier · u[master]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Mimic {
    /// Index of the dependent speed in [`Model::speeds`] (`≥ Model::independent_dof()`).
    pub speed: usize,
    /// Index of the independent speed it follows (`< Model::independent_dof()`).
    pub master: usize,
    /// The factor `a` (URDF `multiplier`, default 1).
    pub multiplier: f64,
    /// The offset `b` (URDF `offset`, default 0), in the unit of the dependent joint.
    pub offset: f64,
}

/// What the URDF import does with `<mimic>` joints ([`UrdfOptions::mimic`](crate::UrdfOptions::mimic)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MimicMode {
    /// An exact constraint in reduced coordinates: the joint has no speed of its own in
    /// generated code (the default; what the mechanism does).
    #[default]
    Exact,
    /// An independent coordinate with its own speed, the `<mimic>` ignored (Pinocchio's and
    /// RBDL's behaviour: the controller is then responsible for the coupling).
    Independent,
    /// A fixed joint at the position it has when its master is at zero (`offset`).
    Fixed,
}

/// A `<mimic>` as written: the dependent joint, its master, the multiplier and the offset.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MimicSpec {
    pub(crate) joint: String,
    pub(crate) master: String,
    pub(crate) multiplier: f64,
    pub(crate) offset: f64,
}

impl Model {
    /// The constraint of speed `s`, if it is a dependent (mimic) speed.
    pub fn mimic_of(&self, s: usize) -> Option<&Mimic> {
        self.mimics.iter().find(|m| m.speed == s)
    }

    /// Per speed of the tree, `(independent speed, factor)`: the column of `T` (`u_all = T u`)
    /// that has its one nonzero entry. An independent speed is `(itself, 1)`.
    pub fn constraint_map(&self) -> Vec<(usize, f64)> {
        let mut map: Vec<(usize, f64)> = (0..self.dof()).map(|s| (s, 1.0)).collect();
        for m in &self.mimics {
            map[m.speed] = (m.master, m.multiplier);
        }
        map
    }

    /// All coordinates of the tree from the independent ones (`q.len() == independent_dof()`):
    /// `q_dep = a · q_master + b` appended.
    pub fn expand_coordinates(&self, q: &[f64]) -> Vec<f64> {
        let mut out = q[..self.independent_dof()].to_vec();
        out.extend(
            self.mimics
                .iter()
                .map(|m| m.multiplier * q[m.master] + m.offset),
        );
        out
    }

    /// All speeds (or accelerations) of the tree from the independent ones: `T u`.
    pub fn expand_speeds(&self, u: &[f64]) -> Vec<f64> {
        let mut out = u[..self.independent_dof()].to_vec();
        out.extend(self.mimics.iter().map(|m| m.multiplier * u[m.master]));
        out
    }

    /// Generalized forces of the tree projected onto the independent speeds: `Tᵀ f`.
    pub fn project_forces(&self, f: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.independent_dof()];
        for (s, (i, a)) in self.constraint_map().into_iter().enumerate() {
            out[i] += a * f[s];
        }
        out
    }

    /// A row-major `dof × dof` matrix of the tree (M, C) projected: the row-major
    /// `independent_dof × independent_dof` matrix `Tᵀ A T`.
    pub fn project_matrix(&self, a: &[f64]) -> Vec<f64> {
        let (n_all, n) = (self.dof(), self.independent_dof());
        let map = self.constraint_map();
        let mut out = vec![0.0; n * n];
        for (r, &(ri, ra)) in map.iter().enumerate() {
            for (c, &(ci, ca)) in map.iter().enumerate() {
                out[ri * n + ci] += ra * ca * a[r * n_all + c];
            }
        }
        out
    }

    /// The model with the mimic constraints `specs` (dependent joint, master joint, factor,
    /// offset, as written in the file). Mimics of mimics are composed; a dependent joint that is
    /// not a moving joint of the model (dropped, a wheel) is skipped with a note.
    pub(crate) fn with_mimics(
        mut self,
        specs: &[MimicSpec],
        notes: &mut Vec<String>,
    ) -> Result<Model, K> {
        if specs.is_empty() {
            return Ok(self);
        }
        let speed_of_joint: HashMap<&str, usize> = self
            .mounted_links()
            .filter_map(|(_, _, m)| m.joint.speed().map(|s| (m.joint.name.as_str(), s)))
            .collect();
        let by_joint: HashMap<&str, &MimicSpec> =
            specs.iter().map(|s| (s.joint.as_str(), s)).collect();
        let bad = |joint: &str, detail: String| K::UrdfBadMimic {
            joint: joint.to_owned(),
            detail,
        };
        // (dependent speed, independent master speed, a, b), composed through chains.
        let mut resolved: Vec<(usize, usize, f64, f64)> = Vec::new();
        for spec in specs {
            let Some(&dep) = speed_of_joint.get(spec.joint.as_str()) else {
                notes.push(format!(
                    "<mimic> of joint `{}` ignored: the joint is not a moving joint of the model (dropped, fixed or part of the wheeled base)",
                    spec.joint
                ));
                continue;
            };
            let (mut a, mut b) = (spec.multiplier, spec.offset);
            if !(a.is_finite() && b.is_finite()) {
                return Err(bad(
                    &spec.joint,
                    format!("multiplier {a} and offset {b} must be finite numbers"),
                ));
            }
            let mut master = spec.master.as_str();
            let mut steps = 0;
            while let Some(next) = by_joint.get(master) {
                steps += 1;
                if steps > specs.len() {
                    return Err(bad(
                        &spec.joint,
                        format!(
                            "the mimic joints form a cycle through `{master}`; make one of them independent (remove its <mimic>)"
                        ),
                    ));
                }
                // q = a (a' q'' + b') + b
                b += a * next.offset;
                a *= next.multiplier;
                master = next.master.as_str();
            }
            let Some(&m) = speed_of_joint.get(master) else {
                return Err(bad(
                    &spec.joint,
                    format!(
                        "its master joint `{master}` is not a moving joint of the model (missing, fixed, dropped or a wheel joint); name a revolute, continuous or prismatic joint, or set UrdfOptions::mimic to Independent or Fixed"
                    ),
                ));
            };
            if m == dep {
                return Err(bad(&spec.joint, "the joint mimics itself".into()));
            }
            notes.push(format!(
                "mimic joint `{}`: q = {a} · q(`{master}`) {} {} (exact constraint, no speed of its own)",
                spec.joint,
                if b < 0.0 { '-' } else { '+' },
                b.abs()
            ));
            resolved.push((dep, m, a, b));
        }
        // New order: the independent speeds as they were, then the dependent ones.
        let n_all = self.speeds.len();
        let mut is_dep = vec![false; n_all];
        for r in &resolved {
            is_dep[r.0] = true;
        }
        let mut new_index = vec![0; n_all];
        let mut order: Vec<usize> = (0..n_all).filter(|&s| !is_dep[s]).collect();
        order.extend(resolved.iter().map(|r| r.0));
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new;
        }
        self.speeds = order.iter().map(|&s| self.speeds[s].clone()).collect();
        for link in &mut self.links {
            if let Some(m) = &mut link.mount {
                m.joint.kind = match m.joint.kind {
                    JointKind::Revolute { speed } => JointKind::Revolute {
                        speed: new_index[speed],
                    },
                    JointKind::Prismatic { speed } => JointKind::Prismatic {
                        speed: new_index[speed],
                    },
                    JointKind::Fixed => JointKind::Fixed,
                };
            }
        }
        if let Base::Wheeled(w) = &mut self.base {
            w.x_speed = new_index[w.x_speed];
            w.psi_speed = new_index[w.psi_speed];
        }
        self.mimics = resolved
            .into_iter()
            .map(|(dep, m, a, b)| Mimic {
                speed: new_index[dep],
                master: new_index[m],
                multiplier: a,
                offset: b,
            })
            .collect();
        Ok(self)
    }
}
