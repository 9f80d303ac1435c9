//! Generates Solo 12 on a floating base (written to `$OUT_DIR/solo12.rs`): the mass matrix, the
//! nonlinear effects, the frame kinematics, the centre of mass and the centroidal functions the
//! whole-body controller and the contact simulation use.
use kanegen::model::UrdfOptions;
use kanegen::{FunctionId as F, FunctionSet};

fn main() {
    let functions = FunctionSet::default()
        .iter()
        .filter(|f| *f == F::MassMatrix)
        .chain([
            F::NonlinearEffects,
            F::CenterOfMass,
            F::FramePose,
            F::FrameJacobian,
            F::FrameBiasAcceleration,
            F::CentroidalMomentumMatrix,
            F::CentroidalMomentumBias,
        ])
        .collect::<FunctionSet>();
    kanegen::Builder::urdf("../../tests/corpus/solo12.urdf", UrdfOptions::floating())
        .functions(functions)
        .output("solo12.rs")
        .run();
}
