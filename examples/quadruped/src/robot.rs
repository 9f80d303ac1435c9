//! The dynamics the controller and the simulator use, as one trait, and its implementations:
//! the generated module (`generated`, the example's dynamics) and the free-flyer reference
//! recursion ([`ReferenceSolo`], the independent check of the generated run in tests/circle.rs).

use kanegen_model::{Model, UrdfImport, UrdfOptions};
use kanegen_reference::FreeFlyer;
use nalgebra::{SMatrix, SVector, Vector3};

/// Coordinates of Solo 12 with a free-flyer base: position, quaternion, 12 joints.
pub const NQ: usize = 19;
/// Speeds: base twist (6), 12 joints.
pub const DOF: usize = 18;
/// A configuration `[x, y, z, qx, qy, qz, qw, joints]`.
pub type Q = SVector<f64, NQ>;
/// Speeds `[v, ω (base frame), joint speeds]`.
pub type U = SVector<f64, DOF>;

/// What the whole-body controller and the simulation need of a floating-base robot, with the
/// names and conventions of the generated functions (docs/kinematics.md): frame Jacobians and
/// bias accelerations with rows 0–2 linear, 3–5 angular, world axes; centroidal momentum
/// linear then angular about the centre of mass, world axes.
pub trait WholeBodyModel {
    /// How a frame is named (a generated `Frame`, a link index).
    type Frame: Copy;
    /// The frame called `name`.
    fn frame(&self, name: &str) -> Option<Self::Frame>;
    /// `M(q)`.
    fn mass_matrix(&self, q: &Q) -> SMatrix<f64, DOF, DOF>;
    /// `h(q, u) = c + g`.
    fn nonlinear_effects(&self, q: &Q, u: &U) -> U;
    /// The frame's origin in the world.
    fn frame_position(&self, q: &Q, frame: Self::Frame) -> Vector3<f64>;
    /// The frame's Jacobian (6 × DOF).
    fn frame_jacobian(&self, q: &Q, frame: Self::Frame) -> SMatrix<f64, 6, DOF>;
    /// The frame's classical acceleration at `u̇ = 0`.
    fn frame_bias_acceleration(&self, q: &Q, u: &U, frame: Self::Frame) -> SVector<f64, 6>;
    /// `A_G(q)` (6 × DOF).
    fn centroidal_momentum_matrix(&self, q: &Q) -> SMatrix<f64, 6, DOF>;
    /// `Ȧ_G u`.
    fn centroidal_momentum_bias(&self, q: &Q, u: &U) -> SVector<f64, 6>;
    /// The centre of mass in the world.
    fn center_of_mass(&self, q: &Q) -> Vector3<f64>;
    /// `q ⊕ u dt`.
    fn integrate(&self, q: &Q, u: &U, dt: f64) -> Q;
}

/// Solo 12 (`tests/corpus/solo12.urdf`, imported on a floating base) on the free-flyer reference
/// recursion of `kanegen-reference`; frames are indices into the model's links.
#[derive(Debug, Clone)]
pub struct ReferenceSolo {
    model: Model,
    ff: FreeFlyer<f64>,
}

impl ReferenceSolo {
    /// Loads the corpus file of the repository.
    pub fn load() -> Result<Self, Box<dyn std::error::Error>> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/corpus/solo12.urdf"
        );
        // A floating import: the trunk (`base_link`) keeps its body, which a fixed import drops.
        let model = UrdfImport::read(path, &UrdfOptions::floating())?.model;
        let ff = FreeFlyer::new(&model)?;
        Ok(Self { model, ff })
    }
}

fn fixed<const R: usize, const C: usize>(m: &nalgebra::DMatrix<f64>) -> SMatrix<f64, R, C> {
    SMatrix::from_iterator(m.iter().copied())
}

impl WholeBodyModel for ReferenceSolo {
    type Frame = usize;

    fn frame(&self, name: &str) -> Option<usize> {
        self.model.links.iter().position(|l| l.name == name)
    }

    fn mass_matrix(&self, q: &Q) -> SMatrix<f64, DOF, DOF> {
        fixed(&self.ff.mass_matrix(q.as_slice()))
    }

    fn nonlinear_effects(&self, q: &Q, u: &U) -> U {
        U::from_iterator(
            self.ff
                .nonlinear_effects(q.as_slice(), u.as_slice())
                .iter()
                .copied(),
        )
    }

    fn frame_position(&self, q: &Q, frame: usize) -> Vector3<f64> {
        self.ff.frame_pose(q.as_slice(), frame).1
    }

    fn frame_jacobian(&self, q: &Q, frame: usize) -> SMatrix<f64, 6, DOF> {
        fixed(&self.ff.frame_jacobian(q.as_slice(), frame))
    }

    fn frame_bias_acceleration(&self, q: &Q, u: &U, frame: usize) -> SVector<f64, 6> {
        self.ff
            .frame_bias_acceleration(q.as_slice(), u.as_slice(), frame)
    }

    fn centroidal_momentum_matrix(&self, q: &Q) -> SMatrix<f64, 6, DOF> {
        fixed(&self.ff.centroidal_momentum_matrix(q.as_slice()))
    }

    fn centroidal_momentum_bias(&self, q: &Q, u: &U) -> SVector<f64, 6> {
        self.ff.centroidal_momentum_bias(q.as_slice(), u.as_slice())
    }

    fn center_of_mass(&self, q: &Q) -> Vector3<f64> {
        self.ff.center_of_mass(q.as_slice())
    }

    fn integrate(&self, q: &Q, u: &U, dt: f64) -> Q {
        Q::from_vec(kanegen_reference::se3::integrate(
            q.as_slice(),
            u.as_slice(),
            dt,
        ))
    }
}

/// `blockdiag(R, R) m`: a 6-row matrix with rows 0–2 and 3–5 rotated by `R`.
pub fn rotate_rows<const C: usize>(
    r: &nalgebra::Matrix3<f64>,
    m: &SMatrix<f64, 6, C>,
) -> SMatrix<f64, 6, C> {
    let mut out = *m;
    for c in 0..C {
        for b in 0..2 {
            let v = r * m.fixed_view::<3, 1>(3 * b, c);
            out.fixed_view_mut::<3, 1>(3 * b, c).copy_from(&v);
        }
    }
    out
}

/// Implements [`WholeBodyModel`] for a generated floating-base robot type `$robot` with frame
/// enum `$frame` by forwarding to its generated methods of the same names (`mass_matrix`,
/// `nonlinear_effects`, `frame_pose`, `frame_jacobian`, `frame_bias_acceleration`,
/// `centroidal_momentum_matrix`, `centroidal_momentum_bias`, `center_of_mass`, `integrate`) and
/// `Frame::from_name`. The generated Jacobians and bias accelerations are in the base frame's
/// axes (docs/floating-base.md): they are rotated to the world's by the base rotation of `q`.
/// The module must be generated with a floating base and the functions `mass_matrix`,
/// `nonlinear_effects`, `center_of_mass`, `frame_pose`, `frame_jacobian`,
/// `frame_bias_acceleration`, `centroidal_momentum_matrix` and `centroidal_momentum_bias`.
#[macro_export]
macro_rules! impl_whole_body_model {
    ($robot:ty, $frame:ty) => {
        impl $crate::robot::WholeBodyModel for $robot {
            type Frame = $frame;
            fn frame(&self, name: &str) -> Option<$frame> {
                <$frame>::from_name(name)
            }
            fn mass_matrix(&self, q: &$crate::robot::Q) -> nalgebra::SMatrix<f64, 18, 18> {
                <$robot>::mass_matrix(self, q)
            }
            fn nonlinear_effects(
                &self,
                q: &$crate::robot::Q,
                u: &$crate::robot::U,
            ) -> $crate::robot::U {
                <$robot>::nonlinear_effects(self, q, u)
            }
            fn frame_position(
                &self,
                q: &$crate::robot::Q,
                frame: $frame,
            ) -> nalgebra::Vector3<f64> {
                <$robot>::frame_pose(self, q, frame).translation.vector
            }
            fn frame_jacobian(
                &self,
                q: &$crate::robot::Q,
                frame: $frame,
            ) -> nalgebra::SMatrix<f64, 6, 18> {
                $crate::robot::rotate_rows(
                    &$crate::robot::base_rotation(q),
                    &<$robot>::frame_jacobian(self, q, frame),
                )
            }
            fn frame_bias_acceleration(
                &self,
                q: &$crate::robot::Q,
                u: &$crate::robot::U,
                frame: $frame,
            ) -> nalgebra::SVector<f64, 6> {
                $crate::robot::rotate_rows(
                    &$crate::robot::base_rotation(q),
                    &<$robot>::frame_bias_acceleration(self, q, u, frame),
                )
            }
            fn centroidal_momentum_matrix(
                &self,
                q: &$crate::robot::Q,
            ) -> nalgebra::SMatrix<f64, 6, 18> {
                <$robot>::centroidal_momentum_matrix(self, q)
            }
            fn centroidal_momentum_bias(
                &self,
                q: &$crate::robot::Q,
                u: &$crate::robot::U,
            ) -> nalgebra::SVector<f64, 6> {
                <$robot>::centroidal_momentum_bias(self, q, u)
            }
            fn center_of_mass(&self, q: &$crate::robot::Q) -> nalgebra::Vector3<f64> {
                <$robot>::center_of_mass(self, q)
            }
            fn integrate(
                &self,
                q: &$crate::robot::Q,
                u: &$crate::robot::U,
                dt: f64,
            ) -> $crate::robot::Q {
                <$robot>::integrate(self, q, u, dt)
            }
        }
    };
}

/// The base rotation (base → world) of `q`: its unit quaternion `q[3..7]`, `(x, y, z, w)`.
pub fn base_rotation(q: &Q) -> nalgebra::Matrix3<f64> {
    nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(q[6], q[3], q[4], q[5]))
        .to_rotation_matrix()
        .into_inner()
}
