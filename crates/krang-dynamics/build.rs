//! Generates the optional dynamics modules from the robot descriptions next to this file: one
//! `kanegen::Builder` chain per module, each behind its feature of the crate (Cargo compiles the
//! script with the package's `--cfg feature="..."`, read here with `cfg!`). Without features
//! this script does nothing and `kanegen` is not even a build dependency: the default module
//! (f64 Krang with M, c, g and inverse dynamics) is pre-generated in `src/generated/krang.rs`
//! (`tests/pregenerated.rs` checks it against the generator). With `coriolis-matrix`,
//! `kinematics`, `derivatives`, `regressors` or `gpu` the Krang module is generated here
//! instead, with those functions (and with `gpu`, its GPU kernels).
fn main() {
    #[cfg(any(
        feature = "coriolis-matrix",
        feature = "kinematics",
        feature = "derivatives",
        feature = "regressors",
        feature = "baked",
        feature = "f32",
        feature = "fixed-wheels",
        feature = "two-link",
        feature = "gpu"
    ))]
    modules::generate();
}

/// The generator calls, compiled only with a feature that asks for a generated module (then
/// `kanegen` is a build dependency).
#[cfg(any(
    feature = "coriolis-matrix",
    feature = "kinematics",
    feature = "derivatives",
    feature = "regressors",
    feature = "baked",
    feature = "f32",
    feature = "fixed-wheels",
    feature = "two-link",
    feature = "gpu"
))]
mod modules {
    use kanegen::{Builder, Combined, FunctionId as F, FunctionSet, Precision};

    const CORIOLIS_MATRIX: bool = cfg!(feature = "coriolis-matrix");
    const KINEMATICS: bool = cfg!(feature = "kinematics");
    const DERIVATIVES: bool = cfg!(feature = "derivatives");
    const REGRESSORS: bool = cfg!(feature = "regressors");
    const GPU: bool = cfg!(feature = "gpu");

    /// `set` if `on`, else no function.
    fn when(on: bool, set: FunctionSet) -> FunctionSet {
        if on { set } else { FunctionSet::EMPTY }
    }

    pub fn generate() {
        if CORIOLIS_MATRIX || KINEMATICS || DERIVATIVES || REGRESSORS || GPU {
            // The main module: M, c, g, τ and the functions of the features (the Coriolis
            // matrix, the kinematics and energies with c + g and two combined programs, the
            // derivatives, the regressors).
            let krang = Builder::new("krang.toml")
                .functions(
                    FunctionSet::default()
                        .union(when(
                            KINEMATICS,
                            FunctionSet::kinematics().with(F::NonlinearEffects),
                        ))
                        .union(when(REGRESSORS, FunctionSet::regressors()))
                        .union(when(GPU, FunctionSet::EMPTY.with(F::NonlinearEffects))),
                )
                .coriolis_matrix(CORIOLIS_MATRIX)
                .derivatives(DERIVATIVES)
                .mirrored_lanes(true)
                .batch_feature("batch");
            // With `gpu`: the kernels of M, c, g, τ, c + g (and C), which give forward
            // dynamics and rollouts on the device; not the kinematics, derivatives or
            // regressors (their kernels are as large as their Rust functions).
            let krang = if GPU {
                krang.gpu_functions(FunctionSet::default().with(F::NonlinearEffects))
            } else {
                krang
            };
            if KINEMATICS {
                krang
                    .combined(whole_body_terms())
                    .combined(hands_jacobians())
                    .run();
            } else {
                krang.run();
            }
        }
        if cfg!(feature = "baked") {
            Builder::new("krang.toml")
                .baked(true)
                .coriolis_matrix(CORIOLIS_MATRIX)
                .mirrored_lanes(true)
                .batch_feature("batch")
                .run();
        }
        if cfg!(feature = "f32") {
            Builder::new("krang.toml")
                .precision(Precision::F32)
                .coriolis_matrix(CORIOLIS_MATRIX)
                .mirrored_lanes(true)
                .run();
        }
        if cfg!(feature = "fixed-wheels") {
            // With `regressors`: the arm's identification example uses the fixed-wheel tree's.
            // Batched (feature `batch`): the fixed-wheel tree's batched forward dynamics
            // (`forward_batch`).
            Builder::new("krang-fixed-wheels.toml")
                .functions(
                    FunctionSet::default().union(when(REGRESSORS, FunctionSet::regressors())),
                )
                .coriolis_matrix(CORIOLIS_MATRIX)
                .derivatives(DERIVATIVES)
                .mirrored_lanes(true)
                .batch_feature("batch")
                .run();
        }
        if cfg!(feature = "two-link") {
            Builder::new("two-link.toml")
                .coriolis_matrix(CORIOLIS_MATRIX)
                .derivatives(DERIVATIVES)
                .mirrored_lanes(true)
                .run();
        }
    }

    /// Both hands' Jacobians as one generated program (`Krang::hands_jacobians`): the trunk's
    /// sines, cosines and rotations computed once, the two arms' chains two lanes at a time
    /// (what an operational-space controller of both hands reads every tick).
    fn hands_jacobians() -> Combined {
        Combined::new("hands_jacobians")
            .with_frame(F::FrameJacobian, "left_hand")
            .with_frame(F::FrameJacobian, "right_hand")
    }

    /// What a whole-body controller reads every tick at one state, as one generated program
    /// (`Krang::whole_body_terms`): M, `c + g`, the centre of mass with its Jacobian and bias
    /// acceleration, and both hands' poses, Jacobians and bias accelerations.
    fn whole_body_terms() -> Combined {
        let mut c = Combined::new("whole_body_terms")
            .with(F::MassMatrix)
            .with(F::NonlinearEffects)
            .with(F::CenterOfMass)
            .with(F::ComJacobian)
            .with(F::ComBiasAcceleration);
        for hand in ["left_hand", "right_hand"] {
            c = c
                .with_frame(F::FramePose, hand)
                .with_frame(F::FrameJacobian, hand)
                .with_frame(F::FrameBiasAcceleration, hand);
        }
        c
    }
}
