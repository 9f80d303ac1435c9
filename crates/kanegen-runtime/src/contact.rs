//! Contact-constrained dynamics: forward dynamics of a robot whose frames are held by contacts,
//! and contact impulses for impacts. Allocation-free, fixed sizes (`N` speeds, `K` constraint
//! rows), `no_std`; the guide's chapter is `docs/contacts.md`.
//!
//! A contact is a frame of the robot ([`Contact`]) held either at a point (3 rows: its origin
//! does not move, [`ContactKind::Point`]) or rigidly (6 rows: neither its origin nor its
//! orientation, [`ContactKind::Frame`]). Their rows stack into [`ContactJacobian`]: `J_c`
//! (`K × N`) from the frame Jacobians (rows 0–2 the origin's velocity, 3–5 the angular velocity,
//! world axes, as generated `frame_jacobian`) and `J̇_c u` from the frame bias accelerations
//! (classical, as generated `frame_bias_acceleration`). Then
//!
//! * [`constrained_forward_dynamics`] solves
//!   `M u̇ + h = f + J_cᵀ λ`, `J_c u̇ + J̇_c u = 0` for `(u̇, λ)`, with `f = Sᵀ τ` the generalized
//!   actuation (zero on a floating base's six speeds);
//! * [`contact_impulse`] solves `M Δu = J_cᵀ Λ`, `J_c u⁺ = −e J_c u⁻` for `(u⁺, Λ)`.
//!
//! Both go through the Cholesky factor of `M` (the runtime's dense factor and its dispatched
//! substitutions) and the Schur complement `J_c M⁻¹ J_cᵀ` (`K × K`, factorised by Cholesky):
//! `λ = (J_c M⁻¹ J_cᵀ + ρ 1)⁻¹ (γ − J_c M⁻¹ (f − h))`, `u̇ = M⁻¹ (f − h + J_cᵀ λ)`, with
//! `γ = −J̇_c u − k_d J_c u − k_p e` ([`ContactSettings`]: the damping `ρ` regularises redundant
//! contacts, the Baumgarte gains `k_p`, `k_d` pull drifting contacts back). With `ρ = 0` the
//! solution is exact and `J_c` must have full row rank; with `ρ > 0`, `J_c u̇ − γ = −ρ λ`.
//!
//! ```
//! use kanegen_runtime::contact::{ContactJacobian, ContactSettings, constrained_forward_dynamics};
//! use kanegen_runtime::nalgebra::{SMatrix, SVector};
//!
//! // A point mass (2 speeds, x and z) resting on the floor: one contact row along z.
//! let m = SMatrix::<f64, 2, 2>::from_diagonal(&SVector::from([2.0, 2.0]));
//! let h = SVector::from([0.0, 2.0 * 9.81]); // gravity
//! let contacts = ContactJacobian::<f64, 2, 1> {
//!     jacobian: SMatrix::from_row_slice(&[0.0, 1.0]),
//!     ..ContactJacobian::zeros()
//! };
//! let f = SVector::from([1.0, 0.0]); // pushed along x
//! let s = constrained_forward_dynamics(m, &h, &f, &contacts, &ContactSettings::default()).unwrap();
//! assert!((s.ud[0] - 0.5).abs() < 1e-12 && s.ud[1].abs() < 1e-12);
//! assert!((s.lambda[0] - 2.0 * 9.81).abs() < 1e-12); // the floor carries the weight
//! ```

use core::fmt;

use nalgebra::{RealField, SMatrix, SVector};

use crate::dynamics::DenseFactor;
use crate::tree_factor::TreeFactor;

/// What a contact holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContactKind {
    /// The frame's origin does not move (3 rows: the linear rows of its Jacobian). A foot's
    /// point contact.
    Point,
    /// Neither the frame's origin nor its orientation moves (6 rows). A flat foot or a grasp.
    Frame,
}

impl ContactKind {
    /// Constraint rows: 3 or 6.
    pub const fn rows(self) -> usize {
        match self {
            ContactKind::Point => 3,
            ContactKind::Frame => 6,
        }
    }
}

/// A contact: a frame of the robot (whatever its frame functions take: a generated `Frame`, a
/// link index) and what it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Contact<F> {
    /// The frame in contact.
    pub frame: F,
    /// Point or frame contact.
    pub kind: ContactKind,
}

impl<F> Contact<F> {
    /// A point contact at `frame`'s origin.
    pub const fn point(frame: F) -> Self {
        Self {
            frame,
            kind: ContactKind::Point,
        }
    }

    /// A rigid (6-D) contact of `frame`.
    pub const fn frame(frame: F) -> Self {
        Self {
            frame,
            kind: ContactKind::Frame,
        }
    }
}

/// Regularisation and stabilisation of [`constrained_forward_dynamics`] and
/// [`contact_impulse`]. The default is exact: no damping, no Baumgarte terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSettings<T> {
    /// `ρ ≥ 0` added to the diagonal of `J_c M⁻¹ J_cᵀ`: makes redundant contacts (more rows
    /// than the motion they can constrain, e.g. four rigid feet) solvable, at the price of a
    /// constraint error `J_c u̇ − γ = −ρ λ`. Pinocchio's `constraintDynamics` `mu`.
    pub damping: T,
    /// `k_p`: the acceleration target gains `−k_p e` for a contact position error `e`
    /// ([`ContactJacobian::position_error`]).
    pub baumgarte_position: T,
    /// `k_d`: the acceleration target gains `−k_d J_c u` (a contact that slides is slowed).
    pub baumgarte_velocity: T,
}

impl<T: RealField + Copy> Default for ContactSettings<T> {
    fn default() -> Self {
        Self {
            damping: T::zero(),
            baumgarte_position: T::zero(),
            baumgarte_velocity: T::zero(),
        }
    }
}

/// Why a contact problem has no solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactError {
    /// `M` is not positive definite (non-physical parameters, or a NaN).
    MassMatrixNotPositiveDefinite,
    /// `J_c M⁻¹ J_cᵀ + ρ 1` is not positive definite: the contact rows are dependent (`J_c`
    /// lacks full row rank). Remove redundant contacts or set [`ContactSettings::damping`].
    DependentContacts,
    /// The contacts' rows do not add up to `K`.
    RowCount {
        /// `K`.
        expected: usize,
        /// The rows of the contacts given.
        given: usize,
    },
}

impl fmt::Display for ContactError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::MassMatrixNotPositiveDefinite => write!(
                f,
                "the mass matrix is not positive definite; check the robot's parameters (masses and inertias must be physical)"
            ),
            Self::DependentContacts => write!(
                f,
                "the contact constraints are dependent (J_c M⁻¹ J_cᵀ is singular); remove redundant contacts or set ContactSettings::damping > 0"
            ),
            Self::RowCount { expected, given } => write!(
                f,
                "the contacts have {given} constraint rows but K = {expected}; point contacts have 3 rows, frame contacts 6"
            ),
        }
    }
}

impl core::error::Error for ContactError {}

/// The stacked contact constraints at one state: `J_c`, `J̇_c u`, and for the Baumgarte terms
/// `J_c u` and a position error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactJacobian<T: RealField + Copy, const N: usize, const K: usize> {
    /// `J_c` (`K × N`).
    pub jacobian: SMatrix<T, K, N>,
    /// `J̇_c u`: the contact frames' classical accelerations at `u̇ = 0`.
    pub bias: SVector<T, K>,
    /// `J_c u`: the contact frames' velocities (used by [`ContactSettings::baumgarte_velocity`]).
    pub velocity: SVector<T, K>,
    /// A position error per row, e.g. the feet's drift from where they touched down (used by
    /// [`ContactSettings::baumgarte_position`]); zero unless set.
    pub position_error: SVector<T, K>,
}

impl<T: RealField + Copy, const N: usize, const K: usize> ContactJacobian<T, N, K> {
    /// All zeros.
    pub fn zeros() -> Self {
        Self {
            jacobian: SMatrix::zeros(),
            bias: SVector::zeros(),
            velocity: SVector::zeros(),
            position_error: SVector::zeros(),
        }
    }

    /// The rows of `contacts`, in order, from each contact frame's Jacobian (6 × N) and bias
    /// acceleration (6) as `kinematics(frame)` returns them (rows 0–2 linear, 3–5 angular,
    /// world axes: generated `frame_jacobian` and `frame_bias_acceleration`); `velocity` is
    /// `J_c u`. Fails if the contacts' rows do not add up to `K`.
    pub fn stack<F: Copy>(
        contacts: &[Contact<F>],
        u: &SVector<T, N>,
        mut kinematics: impl FnMut(F) -> (SMatrix<T, 6, N>, SVector<T, 6>),
    ) -> Result<Self, ContactError> {
        let given: usize = contacts.iter().map(|c| c.kind.rows()).sum();
        if given != K {
            return Err(ContactError::RowCount { expected: K, given });
        }
        let mut out = Self::zeros();
        let mut row = 0;
        for c in contacts {
            let (j, b) = kinematics(c.frame);
            for r in 0..c.kind.rows() {
                out.jacobian.set_row(row, &j.row(r));
                out.bias[row] = b[r];
                row += 1;
            }
        }
        out.velocity = out.jacobian * u;
        Ok(out)
    }
}

/// The solution of [`constrained_forward_dynamics`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstrainedAcceleration<T: RealField + Copy, const N: usize, const K: usize> {
    /// `u̇`.
    pub ud: SVector<T, N>,
    /// `λ`: the contact forces (and moments, for frame contacts) in world axes, in the order of
    /// the stacked rows, acting on the robot.
    pub lambda: SVector<T, K>,
}

/// The solution of [`contact_impulse`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactImpulse<T: RealField + Copy, const N: usize, const K: usize> {
    /// `u⁺`, the speeds after the impact.
    pub u_plus: SVector<T, N>,
    /// `Λ`, the contact impulses (world axes, rows as stacked).
    pub impulse: SVector<T, K>,
}

/// `M⁻¹` (through `factor`) of `J_cᵀ`, and the factor of `J_c M⁻¹ J_cᵀ + ρ 1`.
fn schur<T: RealField + Copy, const N: usize, const K: usize>(
    factor: &DenseFactor<T, N>,
    jc: &SMatrix<T, K, N>,
    damping: T,
) -> Result<(SMatrix<T, N, K>, nalgebra::Cholesky<T, nalgebra::Const<K>>), ContactError> {
    let mut minv_jt = jc.transpose();
    factor.solve_columns([&mut minv_jt], [T::one()]);
    let mut s = jc * minv_jt;
    // Symmetric by construction up to rounding: average the two triangles.
    let half: T = nalgebra::convert(0.5);
    s = (s + s.transpose()) * half;
    for i in 0..K {
        s[(i, i)] += damping;
    }
    let chol = s.cholesky().ok_or(ContactError::DependentContacts)?;
    Ok((minv_jt, chol))
}

/// Forward dynamics under contacts: `(u̇, λ)` with `M u̇ + h = f + J_cᵀ λ` and
/// `J_c u̇ = γ − ρ λ`, `γ = −J̇_c u − k_d J_c u − k_p e` (module docs). `m` is `M(q)`, `h` the
/// nonlinear effects `c(q, u) + g(q)`, `f` the generalized actuation `Sᵀ τ` (plus any known
/// external generalized force).
///
/// Errors: `M` not positive definite, or dependent contacts with zero damping.
pub fn constrained_forward_dynamics<T: RealField + Copy, const N: usize, const K: usize>(
    m: SMatrix<T, N, N>,
    h: &SVector<T, N>,
    f: &SVector<T, N>,
    contacts: &ContactJacobian<T, N, K>,
    settings: &ContactSettings<T>,
) -> Result<ConstrainedAcceleration<T, N, K>, ContactError> {
    let factor = DenseFactor::new(m).ok_or(ContactError::MassMatrixNotPositiveDefinite)?;
    let free = factor.solve(&(f - h));
    let (minv_jt, chol) = schur(&factor, &contacts.jacobian, settings.damping)?;
    let gamma = -contacts.bias
        - contacts.velocity * settings.baumgarte_velocity
        - contacts.position_error * settings.baumgarte_position;
    let lambda = chol.solve(&(gamma - contacts.jacobian * free));
    Ok(ConstrainedAcceleration {
        ud: free + minv_jt * lambda,
        lambda,
    })
}

/// Contact impulses of an impact: `(u⁺, Λ)` with `M (u⁺ − u⁻) = J_cᵀ Λ` and
/// `J_c u⁺ = −e J_c u⁻ − ρ Λ` (`e = 0`: the contacts stop, plastic impact; `e = 1`: they bounce
/// back elastically). Uses `contacts.jacobian` only.
///
/// Errors as [`constrained_forward_dynamics`].
pub fn contact_impulse<T: RealField + Copy, const N: usize, const K: usize>(
    m: SMatrix<T, N, N>,
    u_minus: &SVector<T, N>,
    contacts: &ContactJacobian<T, N, K>,
    restitution: T,
    settings: &ContactSettings<T>,
) -> Result<ContactImpulse<T, N, K>, ContactError> {
    let factor = DenseFactor::new(m).ok_or(ContactError::MassMatrixNotPositiveDefinite)?;
    let (minv_jt, chol) = schur(&factor, &contacts.jacobian, settings.damping)?;
    let v = contacts.jacobian * u_minus;
    let impulse = chol.solve(&(-v * (T::one() + restitution)));
    Ok(ContactImpulse {
        u_plus: u_minus + minv_jt * impulse,
        impulse,
    })
}

/// `W = L⁻ᵀ J_cᵀ` (`M = Lᵀ D L`, `factor`), the pivots' reciprocals `D⁻¹`, and the Cholesky
/// factor of `J_c M⁻¹ J_cᵀ + ρ 1 = Wᵀ D⁻¹ W + ρ 1`. A contact's rows of `J_c` are zero off the
/// speeds that move its frame, and so are their columns of `W` (the substitution skips them, and
/// so does the product, [`gram`]).
#[allow(clippy::type_complexity)]
fn tree_schur<T: RealField + Copy, const N: usize, const K: usize>(
    factor: &TreeFactor<T, N>,
    jc: &SMatrix<T, K, N>,
    damping: T,
) -> Result<(SMatrix<T, N, K>, SVector<T, N>, SmallCholesky<T, K>), ContactError> {
    let mut w = jc.transpose();
    for c in w.data.0.iter_mut() {
        factor.solve_transposed_unit_array(c);
    }
    let d_inv = factor.pivots().map(|d| T::one() / d);
    let wt = w.transpose();
    let mut s = SMatrix::<T, K, K>::zeros();
    crate::isa::dispatch_fused_with(
        &mut s.data.0,
        #[inline(always)]
        |s| gram::<T, N, K, false>(&wt.data.0, &w.data.0, &d_inv.data.0[0], s),
        #[inline(always)]
        |s| gram::<T, N, K, true>(&wt.data.0, &w.data.0, &d_inv.data.0[0], s),
    );
    for i in 0..K {
        s[(i, i)] += damping;
    }
    let chol = SmallCholesky::new(&s).ok_or(ContactError::DependentContacts)?;
    Ok((w, d_inv, chol))
}

/// The Cholesky factor `S = L Lᵀ` of a small symmetric positive definite matrix (the `K × K`
/// Schur complement), rows of `L` stored contiguously: plain loops over fixed sizes. With it the
/// factored constrained forward dynamics of Solo 12 on four point contacts took 1.51 µs, with
/// nalgebra's generic `Cholesky` 1.70 µs (6 Dec 2026, Intel Xeon Processor, 2 vCPUs).
struct SmallCholesky<T, const K: usize> {
    /// `l[i][k] = L(i, k)`, `k ≤ i`.
    l: [[T; K]; K],
    /// `1 / L(i, i)`.
    inv_diag: [T; K],
}

impl<T: RealField + Copy, const K: usize> SmallCholesky<T, K> {
    /// `None` when a pivot is not positive (or NaN). Reads the lower triangle of `s`.
    fn new(s: &SMatrix<T, K, K>) -> Option<Self> {
        let mut l = [[T::zero(); K]; K];
        let mut inv_diag = [T::zero(); K];
        for i in 0..K {
            for j in 0..=i {
                let mut acc = s[(i, j)];
                for (a, b) in l[i][..j].iter().zip(&l[j][..j]) {
                    acc -= *a * *b;
                }
                if i == j {
                    if acc.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
                        return None;
                    }
                    let d = acc.sqrt();
                    l[i][i] = d;
                    inv_diag[i] = T::one() / d;
                } else {
                    l[i][j] = acc * inv_diag[j];
                }
            }
        }
        Some(Self { l, inv_diag })
    }

    /// `S⁻¹ b`.
    fn solve(&self, b: &SVector<T, K>) -> SVector<T, K> {
        let mut x = *b;
        for i in 0..K {
            let mut acc = x[i];
            for (a, b) in self.l[i][..i].iter().zip(x.iter()) {
                acc -= *a * *b;
            }
            x[i] = acc * self.inv_diag[i];
        }
        for i in (0..K).rev() {
            let mut acc = x[i];
            for (row, b) in self.l[i + 1..].iter().zip(x.iter().skip(i + 1)) {
                acc -= row[i] * *b;
            }
            x[i] = acc * self.inv_diag[i];
        }
        x
    }
}

/// `S = Wᵀ D⁻¹ W`, column `b` at a time: `S(:, b) = Σ_i W(i, :)ᵀ D⁻¹_i W(i, b)` over the rows
/// `i` where `W(i, b) ≠ 0`, each term a `K`-long multiply-add over a column of `Wᵀ` (`wt`), which
/// the compiler vectorises.
#[inline(always)]
fn gram<T: RealField + Copy, const N: usize, const K: usize, const FUSED: bool>(
    wt: &[[T; K]; N],
    w: &[[T; N]; K],
    d_inv: &[T; N],
    s: &mut [[T; K]; K],
) {
    for (sb, wb) in s.iter_mut().zip(w) {
        for i in 0..N {
            if wb[i] == T::zero() {
                continue;
            }
            let x = wb[i] * d_inv[i];
            for (sab, wia) in sb.iter_mut().zip(&wt[i]) {
                *sab = if FUSED {
                    wia.mul_add(x, *sab)
                } else {
                    *sab + *wia * x
                };
            }
        }
    }
}

/// [`constrained_forward_dynamics`] through a factor of `M` along the tree
/// ([`TreeFactor`], e.g. `Multibody::mass_matrix_factor`): `z = L⁻ᵀ (f − h)`,
/// `W = L⁻ᵀ J_cᵀ`, `λ = (Wᵀ D⁻¹ W + ρ 1)⁻¹ (γ − Wᵀ D⁻¹ z)`, `u̇ = L⁻¹ D⁻¹ (z + W λ)` (as
/// Pinocchio's `constraintDynamics` uses its sparse factor). The same solution as the dense
/// form, to rounding, for less work where `M` has the tree's zeros.
///
/// Errors: dependent contacts with zero damping ([`ContactError::DependentContacts`]); a factor
/// exists only for a positive definite `M`.
pub fn constrained_forward_dynamics_factored<
    T: RealField + Copy,
    const N: usize,
    const K: usize,
>(
    factor: &TreeFactor<T, N>,
    h: &SVector<T, N>,
    f: &SVector<T, N>,
    contacts: &ContactJacobian<T, N, K>,
    settings: &ContactSettings<T>,
) -> Result<ConstrainedAcceleration<T, N, K>, ContactError> {
    let (w, d_inv, chol) = tree_schur(factor, &contacts.jacobian, settings.damping)?;
    let mut z = f - h;
    factor.solve_transposed_unit(&mut z);
    let gamma = -contacts.bias
        - contacts.velocity * settings.baumgarte_velocity
        - contacts.position_error * settings.baumgarte_position;
    let lambda = chol.solve(&(gamma - w.tr_mul(&z.component_mul(&d_inv))));
    let mut ud = z + w * lambda;
    factor.finish_solve(&mut ud);
    Ok(ConstrainedAcceleration { ud, lambda })
}

/// [`contact_impulse`] through a factor of `M` along the tree ([`TreeFactor`]):
/// `Λ = −(1 + e) (Wᵀ D⁻¹ W + ρ 1)⁻¹ J_c u⁻`, `u⁺ = u⁻ + L⁻¹ D⁻¹ W Λ`.
///
/// Errors as [`constrained_forward_dynamics_factored`].
pub fn contact_impulse_factored<T: RealField + Copy, const N: usize, const K: usize>(
    factor: &TreeFactor<T, N>,
    u_minus: &SVector<T, N>,
    contacts: &ContactJacobian<T, N, K>,
    restitution: T,
    settings: &ContactSettings<T>,
) -> Result<ContactImpulse<T, N, K>, ContactError> {
    let (w, _, chol) = tree_schur(factor, &contacts.jacobian, settings.damping)?;
    let v = contacts.jacobian * u_minus;
    let impulse = chol.solve(&(-v * (T::one() + restitution)));
    let mut du = w * impulse;
    factor.finish_solve(&mut du);
    Ok(ContactImpulse {
        u_plus: u_minus + du,
        impulse,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tree_factor::tests::source;

    const N: usize = 18;
    const K: usize = 12;

    fn problem(
        seed: u64,
    ) -> (
        SMatrix<f64, N, N>,
        SVector<f64, N>,
        SVector<f64, N>,
        ContactJacobian<f64, N, K>,
    ) {
        let mut r = source(seed);
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| r());
        let m = a * a.transpose() + SMatrix::identity() * 0.5;
        let h = SVector::from_fn(|_, _| 10.0 * r());
        let f = SVector::from_fn(|_, _| 10.0 * r());
        let mut c = ContactJacobian::zeros();
        c.jacobian = SMatrix::from_fn(|_, _| r());
        c.bias = SVector::from_fn(|_, _| r());
        c.velocity = SVector::from_fn(|_, _| r());
        c.position_error = SVector::from_fn(|_, _| 0.01 * r());
        (m, h, f, c)
    }

    fn scale<const R: usize>(v: &SVector<f64, R>) -> f64 {
        v.amax().max(1.0)
    }

    #[test]
    fn the_solution_satisfies_the_dynamics_and_the_constraints() {
        for seed in 0..20 {
            let (m, h, f, c) = problem(seed);
            let s =
                constrained_forward_dynamics(m, &h, &f, &c, &ContactSettings::default()).unwrap();
            let dynamics = m * s.ud + h - f - c.jacobian.transpose() * s.lambda;
            assert!(dynamics.amax() < 1e-10 * scale(&(f - h)), "{dynamics}");
            let constraint = c.jacobian * s.ud + c.bias;
            assert!(constraint.amax() < 1e-10 * scale(&c.bias), "{constraint}");
        }
    }

    #[test]
    fn damping_and_baumgarte_terms_enter_the_constraint_rows() {
        let settings = ContactSettings {
            damping: 1e-3,
            baumgarte_position: 100.0,
            baumgarte_velocity: 20.0,
        };
        for seed in 0..10 {
            let (m, h, f, c) = problem(seed);
            let s = constrained_forward_dynamics(m, &h, &f, &c, &settings).unwrap();
            let dynamics = m * s.ud + h - f - c.jacobian.transpose() * s.lambda;
            assert!(dynamics.amax() < 1e-10 * scale(&(f - h)));
            let gamma = -c.bias - c.velocity * 20.0 - c.position_error * 100.0;
            let constraint = c.jacobian * s.ud - gamma + s.lambda * 1e-3;
            assert!(constraint.amax() < 1e-10 * scale(&gamma), "{constraint}");
        }
    }

    #[test]
    fn impulses_satisfy_the_impact_law() {
        for seed in 0..10 {
            let (m, _, u, c) = problem(seed);
            for e in [0.0, 0.5] {
                let s = contact_impulse(m, &u, &c, e, &ContactSettings::default()).unwrap();
                let momentum = m * (s.u_plus - u) - c.jacobian.transpose() * s.impulse;
                assert!(momentum.amax() < 1e-10 * scale(&(m * u)));
                let after = c.jacobian * s.u_plus + c.jacobian * u * e;
                assert!(after.amax() < 1e-10 * scale(&(c.jacobian * u)));
            }
        }
    }

    /// The factored forms through a dense factor (the chain) and through the tree of a
    /// quadruped (its `M` and `J_c` with the tree's zeros: each contact on one leg) agree with
    /// the dense forms.
    #[test]
    fn factored_forms_agree_with_the_dense_ones() {
        use crate::tree_factor::chain_parents;
        let settings = ContactSettings {
            damping: 1e-4,
            baumgarte_position: 10.0,
            baumgarte_velocity: 2.0,
        };
        let mut tree = chain_parents::<N>();
        for leg in 0..4 {
            tree[6 + 3 * leg] = Some(5);
        }
        let different_legs = |i: usize, j: usize| {
            let leg = |k: usize| (k >= 6).then(|| (k - 6) / 3);
            matches!((leg(i), leg(j)), (Some(a), Some(b)) if a != b)
        };
        for seed in 0..10 {
            let (m, h, f, mut c) = problem(seed);
            let mut mt = m;
            for i in 0..N {
                for j in 0..N {
                    if different_legs(i, j) {
                        mt[(i, j)] = 0.0;
                    }
                }
                mt[(i, i)] += 20.0;
            }
            // Contact rows 3l..3l+3 move only the base and leg l.
            for r in 0..K {
                for j in 6..N {
                    if (j - 6) / 3 != r / 3 {
                        c.jacobian[(r, j)] = 0.0;
                    }
                }
            }
            for (m, parents) in [(m, chain_parents()), (mt, tree)] {
                let factor = TreeFactor::new(&m, &parents).unwrap();
                for settings in [ContactSettings::default(), settings] {
                    let a = constrained_forward_dynamics(m, &h, &f, &c, &settings).unwrap();
                    let b = constrained_forward_dynamics_factored(&factor, &h, &f, &c, &settings)
                        .unwrap();
                    assert!((a.ud - b.ud).amax() < 1e-9 * scale(&a.ud), "{seed}");
                    assert!((a.lambda - b.lambda).amax() < 1e-9 * scale(&a.lambda));
                    let a = contact_impulse(m, &f, &c, 0.3, &settings).unwrap();
                    let b = contact_impulse_factored(&factor, &f, &c, 0.3, &settings).unwrap();
                    assert!((a.u_plus - b.u_plus).amax() < 1e-9 * scale(&a.u_plus));
                    assert!((a.impulse - b.impulse).amax() < 1e-9 * scale(&a.impulse));
                }
            }
        }
    }

    #[test]
    fn dependent_contacts_are_an_error_unless_damped() {
        let (m, h, f, mut c) = problem(3);
        let first = c.jacobian.row(0).into_owned();
        c.jacobian.set_row(1, &first);
        let exact = constrained_forward_dynamics(m, &h, &f, &c, &ContactSettings::default());
        assert_eq!(exact.unwrap_err(), ContactError::DependentContacts);
        let factor = TreeFactor::new(&m, &crate::tree_factor::chain_parents()).unwrap();
        let exact =
            constrained_forward_dynamics_factored(&factor, &h, &f, &c, &ContactSettings::default());
        assert_eq!(exact.unwrap_err(), ContactError::DependentContacts);
        let damped = ContactSettings {
            damping: 1e-6,
            ..ContactSettings::default()
        };
        assert!(constrained_forward_dynamics_factored(&factor, &h, &f, &c, &damped).is_ok());
        let damped = ContactSettings {
            damping: 1e-6,
            ..ContactSettings::default()
        };
        assert!(constrained_forward_dynamics(m, &h, &f, &c, &damped).is_ok());
        let not_spd = -m;
        let err = constrained_forward_dynamics(not_spd, &h, &f, &c, &damped).unwrap_err();
        assert_eq!(err, ContactError::MassMatrixNotPositiveDefinite);
    }

    #[test]
    fn stacking_takes_three_rows_per_point_and_six_per_frame() {
        let u = SVector::<f64, 4>::from([1.0, 2.0, 3.0, 4.0]);
        let kin = |f: usize| {
            (
                SMatrix::<f64, 6, 4>::from_fn(|r, c| (100 * f + 10 * r + c) as f64),
                SVector::<f64, 6>::from_fn(|r, _| (100 * f + r) as f64),
            )
        };
        let contacts = [Contact::point(1), Contact::frame(2)];
        let c = ContactJacobian::<f64, 4, 9>::stack(&contacts, &u, kin).unwrap();
        assert_eq!(c.jacobian[(2, 3)], 123.0);
        assert_eq!(c.jacobian[(3, 0)], 200.0);
        assert_eq!(c.jacobian[(8, 1)], 251.0);
        assert_eq!(c.bias[4], 201.0);
        assert_eq!(c.velocity, c.jacobian * u);
        let wrong = ContactJacobian::<f64, 4, 6>::stack(&contacts, &u, kin).unwrap_err();
        assert_eq!(
            wrong,
            ContactError::RowCount {
                expected: 6,
                given: 9
            }
        );
    }
}
