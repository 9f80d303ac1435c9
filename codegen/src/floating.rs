//! What the generator emits for a floating base ([`kanegen_model::Base::Floating`]), and the
//! typed error for the rest.
//!
//! A floating base's module has `NQ = DOF + 1` coordinates (the base's position and unit
//! quaternion first) and `DOF` speeds (the base's twist `v`, `ω` in the base frame first), laid
//! out as Pinocchio's free-flyer joint; `docs/floating-base.md` describes it. The functions of
//! [`SUPPORTED`] are derived with the base's structure (single-state and batched); asking for
//! another one or for a model with mimic joints is [`Error::FloatingBase`] (never code with
//! wrong numbers).

use crate::combined::Combined;
use crate::options::Options;
use crate::registry::FunctionId;
use crate::{Error, model};

/// The registry functions generated for a floating base.
pub const SUPPORTED: [FunctionId; 22] = [
    FunctionId::InverseDynamicsRegressor,
    FunctionId::GravityRegressor,
    FunctionId::BaseRegressor,
    FunctionId::BaseGravityRegressor,
    FunctionId::CentroidalMomentumMatrix,
    FunctionId::CentroidalMomentumBias,
    FunctionId::CentroidalInertia,
    FunctionId::InverseDynamicsDerivatives,
    FunctionId::MassMatrix,
    FunctionId::Coriolis,
    FunctionId::CoriolisMatrix,
    FunctionId::Gravity,
    FunctionId::InverseDynamics,
    FunctionId::NonlinearEffects,
    FunctionId::CenterOfMass,
    FunctionId::ComJacobian,
    FunctionId::ComBiasAcceleration,
    FunctionId::KineticEnergy,
    FunctionId::PotentialEnergy,
    FunctionId::FramePose,
    FunctionId::FrameJacobian,
    FunctionId::FrameBiasAcceleration,
];

/// The fix the errors suggest.
const FIX: &str = "leave it out for a floating base (M, c, g, τ, the Coriolis matrix, nonlinear_effects, the derivatives, the kinematics, the energies, the centroidal functions and the regressors are generated)";

/// [`Error::FloatingBase`] if `robot` has a floating base and the options ask for something
/// outside [`SUPPORTED`] or GPU kernels (`gpu`: their buffers hold DOF coordinates per state, not
/// NQ), or has mimic constraints.
pub(crate) fn check(
    robot: &model::Model,
    opts: &Options,
    combined: &[Combined],
    gpu: bool,
) -> Result<(), Error> {
    if !robot.is_floating() {
        return Ok(());
    }
    let err = |what: String, fix: &'static str| Error::FloatingBase {
        model: robot.name.clone(),
        file: robot.source.clone(),
        what,
        fix,
    };
    if let Some(f) = opts.functions.iter().find(|f| !SUPPORTED.contains(f)) {
        return Err(err(format!("function `{f}`"), FIX));
    }
    for c in combined {
        if let Some(p) = c.parts().iter().find(|p| !SUPPORTED.contains(&p.function)) {
            return Err(err(
                format!(
                    "function `{}` (part of the combined function `{}`)",
                    p.function,
                    c.name()
                ),
                FIX,
            ));
        }
    }
    if gpu {
        return Err(err(
            "GPU kernels".into(),
            "leave out `Builder::gpu` and `Builder::gpu_functions` for a floating base (the CPU functions, single-state and batched, take `q` of NQ entries)",
        ));
    }
    if !robot.mimics.is_empty() {
        return Err(err(
            "a model with mimic joints".into(),
            "import the URDF with `MimicMode::Independent` (each mimic joint its own coordinate)",
        ));
    }
    Ok(())
}
