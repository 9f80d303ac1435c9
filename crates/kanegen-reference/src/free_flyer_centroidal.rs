//! Centroidal momentum of a [`FreeFlyer`]: the momentum `h_G = A_G(q) u` summed body by body
//! (linear momentum, then angular momentum about the centre of mass, world axes: Pinocchio's
//! `ccrba` `Ag`), its matrix `A_G` by partial velocities, and the bias `Ȧ_G u` as the sum of the
//! bodies' inertia forces at `u̇ = 0` reduced to the centre of mass.

use nalgebra::{DMatrix, RealField, Vector3, Vector6};

use crate::free_flyer::FreeFlyer;

fn stack<T: RealField + Copy>(a: Vector3<T>, b: Vector3<T>) -> Vector6<T> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

impl<T: RealField + Copy> FreeFlyer<T> {
    /// `(linear momentum, angular momentum about the world point c)` of velocities given per
    /// frame as `(ω_k, v_k)` in frame `k`, with the frames' world poses of `q`.
    fn momentum_about(
        &self,
        q: &[T],
        velocities: &[(Vector3<T>, Vector3<T>)],
        c: &Vector3<T>,
    ) -> Vector6<T> {
        let zero = vec![T::zero(); self.dof()];
        let states = self.frame_states(q, &zero, &zero);
        let (mut lin, mut ang) = (Vector3::zeros(), Vector3::zeros());
        for ((b, s), (w, v)) in self.bodies.iter().zip(&states).zip(velocities) {
            let Some(b) = b else { continue };
            let ms = b.first_moment;
            // Linear momentum m v_G = m v_O + ω × MS; angular about O: J_O ω + MS × v_O.
            let p = s.rotation * (v * b.mass + w.cross(&ms));
            let h_o = s.rotation * (b.inertia * w + ms.cross(v));
            lin += p;
            ang += h_o + (s.position - c).cross(&p);
        }
        stack(lin, ang)
    }

    /// The centroidal momentum `h_G = [Σ mₖ v_Gₖ; Σ (Iₖ ωₖ + mₖ (cₖ − c) × v_Gₖ)]` in world
    /// axes, summed over the bodies.
    pub fn centroidal_momentum(&self, q: &[T], u: &[T]) -> Vector6<T> {
        let zero = vec![T::zero(); self.dof()];
        let states = self.frame_states(q, u, &zero);
        let vel: Vec<_> = states.iter().map(|s| (s.omega, s.velocity)).collect();
        self.momentum_about(q, &vel, &self.center_of_mass(q))
    }

    /// The centroidal momentum matrix `A_G(q)` (6 × DOF): column `r` is the centroidal
    /// momentum of the partial velocities of speed `r`, so that `h_G = A_G u`.
    pub fn centroidal_momentum_matrix(&self, q: &[T]) -> DMatrix<T> {
        let c = self.center_of_mass(q);
        let partials = self.partials(q);
        let mut a = DMatrix::zeros(6, self.dof());
        for (r, p) in partials.iter().enumerate() {
            a.set_column(r, &self.momentum_about(q, p, &c));
        }
        a
    }

    /// `Ȧ_G u`: the rate of the centroidal momentum at `u̇ = 0`, `Σ (Fₖ; Nₖ + (pₖ − c) × Fₖ)`
    /// over the bodies' inertia forces `Fₖ` and moments `Nₖ` about their frame origins (world
    /// axes). The moment of the momenta about the moving centre of mass, `Σ (v_Gₖ − v_G) × mₖ
    /// v_Gₖ`, vanishes.
    pub fn centroidal_momentum_bias(&self, q: &[T], u: &[T]) -> Vector6<T> {
        let zero = vec![T::zero(); self.dof()];
        let states = self.frame_states(q, u, &zero);
        let c = self.center_of_mass(q);
        let (mut lin, mut ang) = (Vector3::zeros(), Vector3::zeros());
        for (load, s) in self.loads(&states, false).iter().zip(&states) {
            let Some((f, n)) = load else { continue };
            let fw = s.rotation * f;
            lin += fw;
            ang += s.rotation * n + (s.position - c).cross(&fw);
        }
        stack(lin, ang)
    }
}
