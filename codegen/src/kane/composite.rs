//! Composite (subtree) mass, first moment and inertia, accumulated backward.

use kanegen_model::{Joint, JointKind};

use super::algebra::{AXES, M3, V3};
use super::ctx::Ctx;
use crate::expr::{Atom, ExprId, VarKind};

/// Composite (subtree) inertial quantities of a frame, in that frame.
#[derive(Clone, Debug)]
pub(super) struct Composite {
    pub(super) mass: ExprId,
    pub(super) first_moment: V3,
    /// `[XX, XY, XZ, YY, YZ, ZZ]` about the frame origin (empty if not computed).
    pub(super) inertia: Option<[ExprId; 6]>,
}

impl Ctx<'_> {
    /// With `columns`, the mass-matrix column of every joint is formed as soon as the composite
    /// of its subtree is complete (see [`Ctx::mass_matrix_column`]).
    pub(super) fn composites(
        &mut self,
        with_inertia: bool,
        mut columns: Option<&mut Vec<(usize, usize, ExprId)>>,
    ) -> Vec<Composite> {
        let links = self.model.links.len();
        let zero = self.ar.zero();
        let mut comp: Vec<Composite> = (0..links)
            .map(|_| Composite {
                mass: zero,
                first_moment: [zero; 3],
                inertia: if with_inertia { Some([zero; 6]) } else { None },
            })
            .collect();
        for l in 0..links {
            if let Some((m, ms, j)) = self.body(l) {
                comp[l] = Composite {
                    mass: m,
                    first_moment: ms,
                    inertia: with_inertia.then_some(j),
                };
            }
        }
        let model = self.model;
        for (c, _, mount) in model.mounted_links().rev() {
            let parent = mount.parent;
            let name = self.link_name(c).to_owned();
            let pname = self.link_name(parent).to_owned();
            // Finalise the child's composite as substitution variables.
            let child = comp[c].clone();
            let mass = self.ar.subst(child.mass, VarKind::D, &format!("mC{name}"));
            let msc = self.subst3(child.first_moment, VarKind::D, &format!("MSC{name}"));
            let inertia = child.inertia.map(|j| {
                let labels = ["xx", "xy", "xz", "yy", "yz", "zz"];
                let mut out = j;
                for (k, x) in out.iter_mut().enumerate() {
                    *x = self
                        .ar
                        .subst(*x, VarKind::D, &format!("JC{name}.{}", labels[k]));
                }
                out
            });
            comp[c] = Composite {
                mass,
                first_moment: msc,
                inertia,
            };
            let empty = self.ar.is_zero(mass) && msc.iter().all(|x| self.ar.is_zero(*x));
            let r = self.rotation(c, &mount.joint);
            let p = self.position(c, &mount.joint);
            // First moment moved to the parent frame: R·MS + m·p. (Formed before the column
            // of M, which may share these terms, so that they carry the composite's label.)
            let u = self.rot_up(&r, &msc);
            let u = self.subst3(u, VarKind::D, &format!("MSC{name} in {pname}"));
            if let Some(entries) = columns.as_deref_mut() {
                let composite = comp[c].clone();
                self.mass_matrix_column(c, &mount.joint, &composite, entries);
            }
            if empty {
                continue;
            }
            let mp = self.scale3(mass, &p);
            let add = self.add3(&u, &mp);
            let new_mass = self.ar.add(comp[parent].mass, mass);
            let new_ms = self.add3(&comp[parent].first_moment, &add);
            let mut new_inertia = comp[parent].inertia;
            if let (Some(jc), Some(acc)) = (inertia, new_inertia.as_mut()) {
                let joint = &mount.joint;
                self.add_inertia_to_parent(joint, &r, &p, mass, &u, &jc, &name, "JC", acc);
            }
            comp[parent] = Composite {
                mass: new_mass,
                first_moment: new_ms,
                inertia: new_inertia,
            };
        }
        let name = self.link_name(0).to_owned();
        let root = comp[0].clone();
        comp[0] = Composite {
            mass: self.ar.subst(root.mass, VarKind::D, &format!("mC{name}")),
            first_moment: self.subst3(root.first_moment, VarKind::D, &format!("MSC{name}")),
            inertia: root
                .inertia
                .map(|j| j.map(|x| self.ar.subst(x, VarKind::D, &format!("JC{name}")))),
        };
        comp
    }

    /// Add to `acc` (`[XX, XY, XZ, YY, YZ, ZZ]` about the parent's origin, in the parent's
    /// frame) the inertia `jc` of a child about its own origin, with mass `mass` and first moment
    /// `u` already rotated into the parent's frame (`u = R·MS`): `R J Rᵀ` (see
    /// [`Ctx::rotate_inertia`]) plus the parallel-axis
    /// terms `−(u pᵀ + p uᵀ) + 2 (p·u) 1 + m (|p|² 1 − p pᵀ)`. Linear in `(m, MS, J)`: with
    /// `mass = 0` it carries any matrix of the form `[[A, [b]×], [−[b]×, 0]]` (inertia rates).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add_inertia_to_parent(
        &mut self,
        joint: &Joint,
        r: &M3,
        p: &V3,
        mass: ExprId,
        u: &V3,
        jc: &[ExprId; 6],
        name: &str,
        prefix: &str,
        acc: &mut [ExprId; 6],
    ) {
        let zero = self.ar.zero();
        let rjr = self.rotate_inertia(joint, r, jc, &format!("{prefix}{name}"));
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        // −(u pᵀ + p uᵀ) + 2 (p·u) I  and  m (|p|² I − p pᵀ)
        let pu = self.dot(p, u);
        let two_pu = self.ar.scale(pu, 2.0);
        let pp = self.dot(p, p);
        for (k, &(a, b)) in idx.iter().enumerate() {
            let rjr = rjr[k];
            let upa = self.ar.mul(u[a], p[b]);
            let pua = self.ar.mul(p[a], u[b]);
            let cross = self.ar.add(upa, pua);
            let cross = self.ar.neg(cross);
            let ppab = self.ar.mul(p[a], p[b]);
            let mterm = if a == b {
                let d = self.ar.sub(pp, ppab);
                self.ar.mul(mass, d)
            } else {
                let d = self.ar.neg(ppab);
                self.ar.mul(mass, d)
            };
            let diag = if a == b { two_pu } else { zero };
            acc[k] = self.ar.sum([acc[k], rjr, cross, diag, mterm]);
        }
    }

    /// `R J Rᵀ` for the rotation `r = iAj` of the child frame of `joint` and a symmetric `j`
    /// (`[XX, XY, XZ, YY, YZ, ZZ]`). For a revolute joint about a coordinate axis whose constant
    /// part `iAj(0)` is a signed permutation (every joint of Krang), the rotation about the axis
    /// uses double angles: in the plane `(i, j)` normal to the axis, with `d = Jii − Jjj` and
    /// `w = d sin²q + Jij sin 2q`, `J'ii = Jii − w`, `J'jj = Jjj + w`,
    /// `J'ij = Jij cos 2q + d sin q cos q` (15 operations instead of 33); otherwise it is
    /// computed in two stages, `T = J Rᵀ` (variables `{label}·Aᵀ`) and `R T`.
    pub(super) fn rotate_inertia(
        &mut self,
        joint: &Joint,
        r: &M3,
        j: &[ExprId; 6],
        label: &str,
    ) -> [ExprId; 6] {
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        let jm = Self::sym(j);
        let signed_permutation = joint.rotation.iter().all(|row| {
            row.iter().filter(|x| **x != 0.0).count() == 1
                && row.iter().all(|x| [-1.0, 0.0, 1.0].contains(x))
        });
        let axis = (0..3).find(|&k| joint.axis[k].abs() == 1.0);
        if let (JointKind::Revolute { speed: s }, true, Some(k)) =
            (joint.kind, signed_permutation, axis)
        {
            let sigma = joint.axis[k];
            let (i, jx) = ((k + 1) % 3, (k + 2) % 3);
            let (ss, sc, s2, c2) = self.double_angle(s);
            let s2 = self.ar.scale(s2, sigma);
            let sc = self.ar.scale(sc, sigma);
            let sn = self.ar.atom(Atom::Sin(s as u32));
            let sn = self.ar.scale(sn, sigma);
            let cs = self.ar.atom(Atom::Cos(s as u32));
            // d = Jii − Jjj, w = d s² + Jij sin 2q: J'ii = Jii − w, J'jj = Jjj + w,
            // J'ij = Jij cos 2q + d s c.
            let d = self.ar.sub(jm[i][i], jm[jx][jx]);
            let d = self.ar.subst(
                d,
                VarKind::D,
                &format!("{label}: J{0}{0} − J{1}{1}", AXES[i], AXES[jx]),
            );
            let dss = self.ar.mul(d, ss);
            let js2 = self.ar.mul(jm[i][jx], s2);
            let w = self.ar.add(dss, js2);
            let w = self.ar.subst(
                w,
                VarKind::D,
                &format!(
                    "{label} rotated about {}: J{1}{1} − J'{1}{1}",
                    AXES[k], AXES[i]
                ),
            );
            let mut jp = [[self.ar.zero(); 3]; 3];
            jp[i][i] = self.ar.sub(jm[i][i], w);
            jp[jx][jx] = self.ar.add(jm[jx][jx], w);
            let jc2 = self.ar.mul(jm[i][jx], c2);
            let dsc = self.ar.mul(d, sc);
            jp[i][jx] = self.ar.add(jc2, dsc);
            jp[jx][i] = jp[i][jx];
            // The axis column: J'ik = c Jik − s Jjk, J'jk = s Jik + c Jjk, J'kk = Jkk.
            let t1 = self.ar.mul(cs, jm[i][k]);
            let t2 = self.ar.mul(sn, jm[jx][k]);
            jp[i][k] = self.ar.sub(t1, t2);
            let t1 = self.ar.mul(sn, jm[i][k]);
            let t2 = self.ar.mul(cs, jm[jx][k]);
            jp[jx][k] = self.ar.add(t1, t2);
            jp[k][i] = jp[i][k];
            jp[k][jx] = jp[jx][k];
            jp[k][k] = jm[k][k];
            // The constant signed permutation: exact, no operations.
            let a0: M3 = joint.rotation.map(|row| row.map(|x| self.ar.constant(x)));
            return idx.map(|(ra, rb)| {
                let mut terms = Vec::new();
                for m in 0..3 {
                    for n in 0..3 {
                        let am = self.ar.mul(a0[ra][m], a0[rb][n]);
                        terms.push(self.ar.mul(am, jp[m][n]));
                    }
                }
                self.ar.sum(terms)
            });
        }
        let zero = self.ar.zero();
        let mut t = [[zero; 3]; 3];
        for (a, row) in t.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                let terms: Vec<ExprId> = (0..3).map(|k| self.ar.mul(jm[a][k], r[b][k])).collect();
                let s = self.ar.sum(terms);
                *x = self
                    .ar
                    .subst(s, VarKind::D, &format!("{label}·Aᵀ({},{})", a + 1, b + 1));
            }
        }
        idx.map(|(a, b)| {
            let terms: Vec<ExprId> = (0..3).map(|i| self.ar.mul(r[a][i], t[i][b])).collect();
            self.ar.sum(terms)
        })
    }

    /// `(sin² q, sin q cos q, sin 2q, cos 2q)` of the coordinate of speed `s` as K variables
    /// (`s s`, `s c`, `2 s c`, `1 − 2 s²`).
    pub(super) fn double_angle(&mut self, s: usize) -> (ExprId, ExprId, ExprId, ExprId) {
        let sn = self.ar.atom(Atom::Sin(s as u32));
        let cs = self.ar.atom(Atom::Cos(s as u32));
        let coord = self.model.speeds[s].coordinate.clone();
        let ss = self.ar.mul(sn, sn);
        let ss = self.ar.subst(ss, VarKind::K, &format!("sin² {coord}"));
        let sc = self.ar.mul(sn, cs);
        let sc = self
            .ar
            .subst(sc, VarKind::K, &format!("sin {coord} cos {coord}"));
        let s2 = self.ar.scale(sc, 2.0);
        let s2 = self.ar.subst(s2, VarKind::K, &format!("sin 2{coord}"));
        let one = self.ar.one();
        let two_ss = self.ar.scale(ss, 2.0);
        let c2 = self.ar.sub(one, two_ss);
        let c2 = self.ar.subst(c2, VarKind::K, &format!("cos 2{coord}"));
        (ss, sc, s2, c2)
    }
}
