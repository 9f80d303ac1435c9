//! The centre of mass and its Jacobian, the numeric baseline of the generated `center_of_mass`
//! and `com_jacobian`, with their conventions: positions in frame 0, velocities relative to the
//! ground in frame 0's axes (for a wheeled base the `ẋ` column is `[1, 0, 0]` and the `ψ̇` column
//! `ẑ × r_G`), the wheels point masses `mw` at `(0, ±L/2, 0)` (they add `2 mw` to the total mass
//! and nothing to the first moment about frame 0's origin).
//!
//! One forward pass forms each moving link's rotation `W_j` and origin `o_j` in frame 0 and its
//! body's first moment about frame 0's origin, `m_j o_j + W_j h_j`; one backward pass sums them
//! over subtrees (`S_j`). Column `j` of the Jacobian is then `e_j × (S_j − mC_j o_j) / m` for a
//! revolute joint (`e_j = W_j ẑ`, `mC_j` the subtree's mass) and `mC_j e_j / m` for a prismatic
//! one: the partial velocity `Σ_k m_k (v_Gk)_j / m` of the centre of mass.

use nalgebra::{SMatrix, SVector, Vector3};

use crate::scalar::{V3, add, cross, rot, scale};
use crate::{ROOT, Rbd, Scalar};

impl<const N: usize, T: Scalar> Rbd<N, T> {
    /// The centre of mass of the whole robot (wheels included) in frame 0.
    pub fn center_of_mass(&self, q: &SVector<T, N>) -> Vector3<T> {
        let (g, _) = self.com_pass(q, false);
        Vector3::new(g[0], g[1], g[2])
    }

    /// The Jacobian of the centre of mass: its velocity relative to the ground, in frame 0's
    /// axes, is `J u` (as the generated `com_jacobian`).
    pub fn com_jacobian(&self, q: &SVector<T, N>) -> SMatrix<T, 3, N> {
        self.com_pass(q, true).1
    }

    /// The centre of mass and (with `jacobian`) its Jacobian.
    #[inline(always)]
    fn com_pass(&self, q: &SVector<T, N>, jacobian: bool) -> (V3<T>, SMatrix<T, 3, N>) {
        let z = T::zero();
        let o1 = T::one();
        let nl = self.nl;
        let mut sn = [z; N];
        let mut cs = [z; N];
        self.sin_cos_all(q, &mut sn, &mut cs);
        let identity = [[o1, z, z], [z, o1, z], [z, z, o1]];
        // Per moving link: the joint axis and origin in frame 0, and the first moment of its
        // body (then of its subtree) about frame 0's origin.
        let mut axis = [[z; 3]; N];
        let mut origin = [[z; 3]; N];
        let mut first = [[z; 3]; N];
        let mut rotation = [identity; N];
        for j in 0..nl {
            let l = &self.links[j];
            let (wp, op) = if l.parent == ROOT {
                (identity, [z; 3])
            } else {
                (rotation[l.parent], origin[l.parent])
            };
            let o = if l.offset {
                add(op, rot(&wp, l.trans(q)))
            } else {
                op
            };
            let w = l.right(&l.jr(sn[j], cs[j]), &wp);
            first[j] = add(scale(o, l.m), rot(&w, l.h));
            axis[j] = w[2];
            origin[j] = o;
            rotation[j] = w;
        }
        let wheels = self.root.wheels.as_ref();
        let inv = o1 / (self.root.mc + wheels.map_or(z, |w| w.mass));
        let mut jac = SMatrix::<T, 3, N>::zeros();
        let mut h0 = self.root.h;
        for j in (0..nl).rev() {
            let l = &self.links[j];
            let s = first[j];
            if jacobian {
                let col = if l.prismatic {
                    scale(axis[j], l.mc * inv)
                } else {
                    let d = add(s, scale(origin[j], -l.mc));
                    scale(cross(axis[j], d), inv)
                };
                for (r, x) in col.into_iter().enumerate() {
                    jac[(r, l.speed)] = x;
                }
            }
            if l.parent == ROOT {
                h0 = add(h0, s);
            } else {
                first[l.parent] = add(first[l.parent], s);
            }
        }
        let g = scale(h0, inv);
        if let (true, Some(w)) = (jacobian, wheels) {
            jac[(0, w.x)] = o1;
            jac[(0, w.psi)] = -g[1];
            jac[(1, w.psi)] = g[0];
        }
        (g, jac)
    }
}
