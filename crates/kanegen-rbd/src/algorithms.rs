//! The hot paths: CRBA, RNEA, the gravity pass and the kinetic energy.
//!
//! Links are visited in topological order (parents first) forwards and in reverse backwards.
//! Along a chain (`parent == j − 1`, the common case) the parent's state is passed in registers
//! (`prev` forwards, `carry` backwards) instead of through the per-link arrays: a store followed
//! at once by a load of the same 3-vector, written and read with different vector widths, stalls
//! store-to-load forwarding. Branches (a parent with several children) go through the arrays.

use nalgebra::{SMatrix, SVector};

use crate::scalar::{V3, add, add6, cross, dot, inertia_shift, rot, scale, sym_mul};
use crate::{ROOT, Rbd, Scalar};

impl<const N: usize, T: Scalar> Rbd<N, T> {
    /// `sin q_j` and `cos q_j` of every revolute joint (`0`, `1` for prismatic joints) into
    /// `sn`, `cs`, computed up front in one independent (vectorizable) batch.
    #[inline(always)]
    pub(crate) fn sin_cos_all(&self, q: &SVector<T, N>, sn: &mut [T; N], cs: &mut [T; N]) {
        let mut x = [T::zero(); N];
        for (l, xj) in self.links[..self.nl].iter().zip(x.iter_mut()) {
            if !l.prismatic {
                *xj = q[l.speed];
            }
        }
        T::sin_cos_batch(&x, sn, cs);
    }

    /// The joint-space inertia matrix `M(q)` (composite-rigid-body algorithm).
    ///
    /// Composite inertias are accumulated in the link frames; each `F_j = I_j^c S_j` is taken to
    /// frame 0 once and every entry `M[k, j]` (`k` an ancestor of `j`) is the 6-term dot product
    /// `S_k · F_j` there. Each entry is computed once and mirrored.
    pub fn mass_matrix(&self, q: &SVector<T, N>) -> SMatrix<T, N, N> {
        let z = T::zero();
        let o1 = T::one();
        let nl = self.nl;
        let mut mm = SMatrix::<T, N, N>::zeros();
        let mut sn = [z; N];
        let mut cs = [z; N];
        self.sin_cos_all(q, &mut sn, &mut cs);
        // Rotation and origin of each link in frame 0; linear part (about the frame-0 origin)
        // of its motion subspace, whose angular part is `wr[j][2]` (revolute) or 0 (prismatic).
        let mut wr = [[[z; 3]; 3]; N];
        let mut wo = [[z; 3]; N];
        // Motion subspace of each link in frame 0: angular part, then linear part about the
        // frame-0 origin; slots `nl`, `nl + 1` hold the wheeled base's ẋ (linear x̂) and ψ̇
        // (angular ẑ).
        let mut sw = [[z; 6]; N];
        if self.root.wheels.is_some() {
            sw[nl] = [z, z, z, o1, z, z];
            sw[nl + 1] = [z, z, o1, z, z, z];
        }
        // Composite first moments and inertias, link frames (own body + non-chain children).
        let mut ch = [[z; 3]; N];
        let mut cj = [[z; 6]; N];
        let mut prev_w = [[o1, z, z], [z, o1, z], [z, z, o1]];
        let mut prev_o = [z; 3];
        for j in 0..nl {
            let l = &self.links[j];
            let jr = l.jr(sn[j], cs[j]);
            let p = l.trans(q);
            let (pw, po) = if l.chain {
                (prev_w, prev_o)
            } else if l.parent == ROOT {
                ([[o1, z, z], [z, o1, z], [z, z, o1]], [z; 3])
            } else {
                (wr[l.parent], wo[l.parent])
            };
            let w = l.right(&jr, &pw);
            let o = if l.offset { add(po, rot(&pw, p)) } else { po };
            let a = w[2];
            sw[j] = if l.prismatic {
                [z, z, z, a[0], a[1], a[2]]
            } else {
                let b = cross(o, a);
                [a[0], a[1], a[2], b[0], b[1], b[2]]
            };
            wr[j] = w;
            wo[j] = o;
            ch[j] = l.h;
            cj[j] = l.j;
            prev_w = w;
            prev_o = o;
        }
        let mut h0 = self.root.h;
        let mut j0 = self.root.j;
        let wheels = self.root.wheels;
        let mut carry_h = [z; 3];
        let mut carry_j = [z; 6];
        for j in (0..nl).rev() {
            let l = &self.links[j];
            let sj = l.speed;
            let h = add(ch[j], carry_h);
            let jj = add6(cj[j], carry_j);
            // F = I_c S_j, in frame 0 (moment about its origin): for a revolute joint
            // f = ẑ × h, n = J ẑ in the link frame; for a prismatic one f = m ẑ, n = h × ẑ.
            let w = &wr[j];
            let (fw, nw, d) = if l.prismatic {
                let fw = scale(w[2], l.mc);
                let nl = add(scale(w[0], h[1]), scale(w[1], -h[0]));
                (fw, add(nl, cross(wo[j], fw)), l.mc)
            } else {
                let fw = add(scale(w[0], -h[1]), scale(w[1], h[0]));
                let nl = rot(w, [jj[2], jj[4], jj[5]]);
                (fw, add(nl, cross(wo[j], fw)), jj[5])
            };
            let mdata = mm.as_mut_slice();
            mdata[sj + sj * N] = d;
            for e in &self.anc[j][..self.anc_len[j]] {
                let sk = &sw[e.k];
                let v = (sk[0] * nw[0] + sk[1] * nw[1] + sk[2] * nw[2])
                    + (sk[3] * fw[0] + sk[4] * fw[1] + sk[5] * fw[2]);
                mdata[e.upper] = v;
                mdata[e.lower] = v;
            }
            // The composite of j into its parent: rotate, then shift the reference point.
            carry_h = [z; 3];
            carry_j = [z; 6];
            if l.parent != ROOT || wheels.is_some() {
                let jr = l.jr(sn[j], cs[j]);
                let p = l.trans(q);
                let hr = l.up(&jr, h);
                let jrot = l.sym_up(&jr, &jj);
                let (mcp, half) = if l.prismatic {
                    let mp = scale(p, l.mc);
                    (mp, scale(mp, nalgebra::convert(0.5)))
                } else {
                    (l.mc_p, l.half_mc_p)
                };
                let dh = add(hr, mcp);
                let dj = add6(jrot, inertia_shift(p, hr, half));
                if l.chain {
                    carry_h = dh;
                    carry_j = dj;
                } else if l.parent == ROOT {
                    h0 = add(h0, dh);
                    j0 = add6(j0, dj);
                } else {
                    ch[l.parent] = add(ch[l.parent], dh);
                    cj[l.parent] = add6(cj[l.parent], dj);
                }
            }
        }
        if let Some(wh) = wheels {
            mm[(wh.x, wh.x)] = self.root.mc + wh.m_xx;
            mm[(wh.x, wh.psi)] = -h0[1];
            mm[(wh.psi, wh.x)] = -h0[1];
            mm[(wh.psi, wh.psi)] = j0[5] + wh.m_psipsi;
        }
        mm
    }

    /// Recursive Newton–Euler. `UD`: include `u̇`; `GRAV`: include gravity.
    ///
    /// One function of ~125 lines on purpose: the forward and backward passes share per-link
    /// temporaries that the optimiser keeps in registers, and this is the benchmark baseline
    /// whose speed docs/performance.md reports (helpers would need `#[inline(always)]` and
    /// re-measurement to be an equal baseline).
    #[inline(always)]
    fn rnea<const UD: bool, const GRAV: bool>(
        &self,
        q: &SVector<T, N>,
        u: &SVector<T, N>,
        ud: &SVector<T, N>,
    ) -> SVector<T, N> {
        let z = T::zero();
        let nl = self.nl;
        let mut tau = SVector::<T, N>::zeros();
        let mut sn = [z; N];
        let mut cs = [z; N];
        self.sin_cos_all(q, &mut sn, &mut cs);
        let mut w = [[z; 3]; N];
        let mut al = [[z; 3]; N];
        let mut ac = [[z; 3]; N];
        let mut f = [[z; 3]; N];
        let mut n = [[z; 3]; N];
        let grav = if GRAV { self.root.grav } else { [z; 3] };
        let (w0, al0, a0) = match &self.root.wheels {
            Some(wh) => {
                let (xd, psid) = (u[wh.x], u[wh.psi]);
                let (xdd, psidd) = if UD { (ud[wh.x], ud[wh.psi]) } else { (z, z) };
                (
                    [z, z, psid],
                    [z, z, psidd],
                    [xdd + grav[0], xd * psid + grav[1], grav[2]],
                )
            }
            None => ([z; 3], [z; 3], grav),
        };
        let mut prev = (w0, al0, a0);
        for j in 0..nl {
            let l = &self.links[j];
            let sj = l.speed;
            let jr = l.jr(sn[j], cs[j]);
            let (wp, alp, ap) = if l.chain {
                prev
            } else if l.parent == ROOT {
                (w0, al0, a0)
            } else {
                (w[l.parent], al[l.parent], ac[l.parent])
            };
            // Acceleration of origin j, parent frame.
            let ap = if l.offset {
                let p = l.trans(q);
                add(ap, add(cross(alp, p), cross(wp, cross(wp, p))))
            } else {
                ap
            };
            let ww = l.down(&jr, wp);
            let aa = l.down(&jr, alp);
            let mut acc = l.down(&jr, ap);
            let uj = u[sj];
            let udj = if UD { ud[sj] } else { z };
            let (om, alpha) = if l.prismatic {
                // a += 2 u ω×ẑ + u̇ ẑ
                let uu = uj + uj;
                acc = [acc[0] + uu * ww[1], acc[1] - uu * ww[0], acc[2] + udj];
                (ww, aa)
            } else {
                // ω = ω' + u ẑ, α = α' + u ω'×ẑ + u̇ ẑ
                (
                    [ww[0], ww[1], ww[2] + uj],
                    [aa[0] + uj * ww[1], aa[1] - uj * ww[0], aa[2] + udj],
                )
            };
            // Inertial force and moment about the origin: f = m a + α×h + ω×(ω×h),
            // n = J α + ω×(J ω) + h×a.
            let jw = sym_mul(&l.j, om);
            f[j] = add(
                scale(acc, l.m),
                add(cross(alpha, l.h), cross(om, cross(om, l.h))),
            );
            n[j] = add(add(sym_mul(&l.j, alpha), cross(om, jw)), cross(l.h, acc));
            w[j] = om;
            al[j] = alpha;
            ac[j] = acc;
            prev = (om, alpha, acc);
        }
        let mut f0 = [z; 3];
        let mut n0 = [z; 3];
        let wheeled = self.root.wheels.is_some();
        if wheeled {
            let rt = &self.root;
            let jw = sym_mul(&rt.j, w0);
            f0 = add(
                scale(a0, rt.m),
                add(cross(al0, rt.h), cross(w0, cross(w0, rt.h))),
            );
            n0 = add(add(sym_mul(&rt.j, al0), cross(w0, jw)), cross(rt.h, a0));
        }
        let mut carry_f = [z; 3];
        let mut carry_n = [z; 3];
        for j in (0..nl).rev() {
            let l = &self.links[j];
            let fj = add(f[j], carry_f);
            let nj = add(n[j], carry_n);
            tau[l.speed] = if l.prismatic { fj[2] } else { nj[2] };
            carry_f = [z; 3];
            carry_n = [z; 3];
            if l.parent == ROOT && !wheeled {
                continue;
            }
            let jr = l.jr(sn[j], cs[j]);
            let fr = l.up(&jr, fj);
            let mut nr = l.up(&jr, nj);
            if l.offset {
                nr = add(nr, cross(l.trans(q), fr));
            }
            if l.chain {
                carry_f = fr;
                carry_n = nr;
            } else if l.parent == ROOT {
                f0 = add(f0, fr);
                n0 = add(n0, nr);
            } else {
                f[l.parent] = add(f[l.parent], fr);
                n[l.parent] = add(n[l.parent], nr);
            }
        }
        if let Some(wh) = &self.root.wheels {
            let (xdd, psidd) = if UD { (ud[wh.x], ud[wh.psi]) } else { (z, z) };
            tau[wh.x] = f0[0] + wh.m_xx * xdd;
            tau[wh.psi] = n0[2] + wh.m_psipsi * psidd;
        }
        tau
    }

    /// Inverse dynamics `τ(q, u, u̇) = M(q) u̇ + c(q, u) + g(q)` (recursive Newton–Euler).
    pub fn inverse_dynamics(
        &self,
        q: &SVector<T, N>,
        u: &SVector<T, N>,
        ud: &SVector<T, N>,
    ) -> SVector<T, N> {
        self.rnea::<true, true>(q, u, ud)
    }

    /// The velocity-product terms `c(q, u)` (Coriolis and centrifugal; RNEA with `u̇ = 0` and no
    /// gravity; includes the base's `ẋψ̇` centripetal term).
    pub fn coriolis(&self, q: &SVector<T, N>, u: &SVector<T, N>) -> SVector<T, N> {
        self.rnea::<false, false>(q, u, u)
    }

    /// The gravity terms `g(q)` (`u = u̇ = 0`): the gravity vector rotated down the tree, then
    /// `τ_j = ẑ·(h_j^c × a_j)` with the composite first moment `h_j^c` of the subtree about
    /// origin `j` (subtree masses are precomputed).
    pub fn gravity(&self, q: &SVector<T, N>) -> SVector<T, N> {
        let z = T::zero();
        let nl = self.nl;
        let mut tau = SVector::<T, N>::zeros();
        let mut sn = [z; N];
        let mut cs = [z; N];
        self.sin_cos_all(q, &mut sn, &mut cs);
        let mut ac = [[z; 3]; N];
        let mut ch = [[z; 3]; N];
        let g0 = self.root.grav;
        let mut prev = g0;
        for j in 0..nl {
            let l = &self.links[j];
            let ap = if l.chain {
                prev
            } else if l.parent == ROOT {
                g0
            } else {
                ac[l.parent]
            };
            let a = l.down(&l.jr(sn[j], cs[j]), ap);
            ac[j] = a;
            ch[j] = l.h;
            prev = a;
        }
        let mut h0 = self.root.h;
        let wheeled = self.root.wheels.is_some();
        let mut carry = [z; 3];
        for j in (0..nl).rev() {
            let l = &self.links[j];
            let h = add(ch[j], carry);
            let a = ac[j];
            tau[l.speed] = if l.prismatic {
                l.mc * a[2]
            } else {
                h[0] * a[1] - h[1] * a[0]
            };
            carry = [z; 3];
            if l.parent == ROOT && !wheeled {
                continue;
            }
            let mcp = if l.prismatic {
                scale(l.trans(q), l.mc)
            } else {
                l.mc_p
            };
            let dh = add(l.up(&l.jr(sn[j], cs[j]), h), mcp);
            if l.chain {
                carry = dh;
            } else if l.parent == ROOT {
                h0 = add(h0, dh);
            } else {
                ch[l.parent] = add(ch[l.parent], dh);
            }
        }
        if let Some(wh) = &self.root.wheels {
            tau[wh.x] = self.root.mc * g0[0];
            tau[wh.psi] = h0[0] * g0[1] - h0[1] * g0[0];
        }
        tau
    }

    /// Kinetic energy `½ uᵀ M(q) u`, summed body by body from the link velocities (wheels
    /// included).
    pub fn kinetic_energy(&self, q: &SVector<T, N>, u: &SVector<T, N>) -> T {
        let z = T::zero();
        let half: T = nalgebra::convert(0.5);
        let mut w = [[z; 3]; N];
        let mut v = [[z; 3]; N];
        let (w0, v0) = match &self.root.wheels {
            Some(wh) => ([z, z, u[wh.psi]], [u[wh.x], z, z]),
            None => ([z; 3], [z; 3]),
        };
        let body = |m: T, h: V3<T>, j: &[T; 6], w: V3<T>, v: V3<T>| {
            let hvw = dot(h, cross(v, w));
            m * dot(v, v) + dot(w, sym_mul(j, w)) + (hvw + hvw)
        };
        let rt = &self.root;
        let mut e2 = body(rt.m, rt.h, &rt.j, w0, v0);
        if let Some(wh) = &rt.wheels {
            let (xd, psid) = (u[wh.x], u[wh.psi]);
            e2 += wh.m_xx * xd * xd + wh.m_psipsi * psid * psid;
        }
        let mut sn = [z; N];
        let mut cs = [z; N];
        self.sin_cos_all(q, &mut sn, &mut cs);
        for j in 0..self.nl {
            let l = &self.links[j];
            let jr = l.jr(sn[j], cs[j]);
            let p = l.trans(q);
            let (wp, vp) = if l.parent == ROOT {
                (w0, v0)
            } else {
                (w[l.parent], v[l.parent])
            };
            let mut wj = l.down(&jr, wp);
            let mut vj = l.down(&jr, add(vp, cross(wp, p)));
            if l.prismatic {
                vj[2] += u[l.speed];
            } else {
                wj[2] += u[l.speed];
            }
            e2 += body(l.m, l.h, &l.j, wj, vj);
            w[j] = wj;
            v[j] = vj;
        }
        half * e2
    }
}
