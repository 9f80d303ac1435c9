//! Generates the optional dynamics modules from the robot descriptions next to this file: one
//! generator call per module, each behind its feature of the crate (Cargo compiles the script
//! with `--cfg feature="..."` and sets `CARGO_FEATURE_<NAME>`, `-` as `_`). Without features
//! this script does nothing and `kanegen` is not even a build dependency: the default module
//! (f64 Krang with M, c, g and inverse dynamics) is pre-generated in `src/generated/krang.rs`
//! (`tests/pregenerated.rs` checks it against the generator). With `coriolis-matrix`,
//! `kinematics` or `regressors` the Krang module is generated here instead, with those functions.
fn main() {
    #[cfg(any(
        feature = "coriolis-matrix",
        feature = "kinematics",
        feature = "derivatives",
        feature = "regressors",
        feature = "baked",
        feature = "f32",
        feature = "fixed-wheels",
        feature = "two-link"
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
    feature = "two-link"
))]
mod modules {
    use kanegen::{DerivativesForm, FunctionId, FunctionSet, RegressorForm};

    pub fn generate() {
        let enabled =
            |feature: &str| std::env::var_os(format!("CARGO_FEATURE_{feature}")).is_some();
        let coriolis_matrix = enabled("CORIOLIS_MATRIX");
        let kinematics = enabled("KINEMATICS");
        let derivatives = enabled("DERIVATIVES");
        let regressors = enabled("REGRESSORS");
        // For measurements only: `KANEGEN_DERIVATIVES_FORM=straight-line` (or `looped`) overrides
        // the generator's choice of the derivatives' form (README, "Derivatives: the looped form").
        let form = form_from_env(
            "KANEGEN_DERIVATIVES_FORM",
            [
                ("straight-line", DerivativesForm::StraightLine),
                ("looped", DerivativesForm::Looped),
            ],
            DerivativesForm::Auto,
        );
        let builder = |model: &str| {
            kanegen::Builder::new(model)
                .coriolis_matrix(coriolis_matrix)
                .derivatives_form(form)
                .mirrored_lanes(true)
        };
        if coriolis_matrix || kinematics || derivatives || regressors {
            // The main module, with the Coriolis matrix and/or the kinematics and energies (centre
            // of mass, frames, T, V).
            let mut functions = FunctionSet::default().without(FunctionId::CoriolisMatrix);
            if coriolis_matrix {
                functions = functions.with(FunctionId::CoriolisMatrix);
            }
            if kinematics {
                functions = functions
                    .union(FunctionSet::kinematics())
                    .with(FunctionId::NonlinearEffects);
            }
            if derivatives {
                functions = functions.with(FunctionId::InverseDynamicsDerivatives);
            }
            if regressors {
                functions = functions.union(FunctionSet::regressors());
            }
            let mut main = kanegen::Builder::new("krang.toml")
                .functions(functions)
                .regressor_form(regressor_form())
                .derivatives_form(form)
                .mirrored_lanes(true)
                .batch_feature("batch");
            if kinematics {
                main = main
                    .combined(whole_body_terms())
                    .combined(hands_jacobians());
            }
            main.run();
        }
        if enabled("BAKED") {
            builder("krang.toml")
                .baked(true)
                .batch_feature("batch")
                .run();
        }
        if enabled("F32") {
            builder("krang.toml")
                .precision(kanegen::Precision::F32)
                .run();
        }
        if enabled("FIXED_WHEELS") {
            // With `regressors`: the arm's identification example uses the fixed-wheel tree's.
            let mut functions = FunctionSet::default();
            if !coriolis_matrix {
                functions = functions.without(FunctionId::CoriolisMatrix);
            }
            if derivatives {
                functions = functions.with(FunctionId::InverseDynamicsDerivatives);
            }
            if regressors {
                functions = functions.union(FunctionSet::regressors());
            }
            // Batched (feature `batch`): the fixed-wheel tree's batched forward dynamics
            // (`forward_batch`).
            builder("krang-fixed-wheels.toml")
                .functions(functions)
                .batch_feature("batch")
                .run();
        }
        if enabled("TWO_LINK") {
            builder("two-link.toml").derivatives(derivatives).run();
        }
    }

    /// The regressors' code shape: `KANEGEN_REGRESSOR_FORM=straight-line` (or `loop`) overrides the
    /// generator's choice, to measure one form against the other (README, "Regressors: the loop
    /// form"); unset, the generator's rule (the loop form for Krang).
    fn regressor_form() -> RegressorForm {
        form_from_env(
            "KANEGEN_REGRESSOR_FORM",
            [
                ("straight-line", RegressorForm::StraightLine),
                ("loop", RegressorForm::Loop),
            ],
            RegressorForm::Auto,
        )
    }

    /// For measurements only: the code shape named by the environment variable `var` (one of
    /// `forms`), or `auto` (the generator's rule) when it is unset or names none of them.
    fn form_from_env<T: Copy>(var: &str, forms: [(&str, T); 2], auto: T) -> T {
        println!("cargo:rerun-if-env-changed={var}");
        let value = std::env::var(var).unwrap_or_default();
        forms
            .iter()
            .find(|(name, _)| *name == value)
            .map_or(auto, |&(_, form)| form)
    }

    /// Both hands' Jacobians as one generated program (`Krang::hands_jacobians`): the trunk's
    /// sines, cosines and rotations computed once, the two arms' chains two lanes at a time
    /// (what an operational-space controller of both hands reads every tick).
    fn hands_jacobians() -> kanegen::combined::Combined {
        use kanegen::FunctionId as F;
        let mut c = kanegen::combined::Combined::new("hands_jacobians");
        for hand in ["left_hand", "right_hand"] {
            c = c.with_frame(F::FrameJacobian, hand);
        }
        c
    }

    /// What a whole-body controller reads every tick at one state, as one generated program
    /// (`Krang::whole_body_terms`): M, `c + g`, the centre of mass with its Jacobian and bias
    /// acceleration, and both hands' poses, Jacobians and bias accelerations.
    fn whole_body_terms() -> kanegen::combined::Combined {
        use kanegen::FunctionId as F;
        let mut c = kanegen::combined::Combined::new("whole_body_terms")
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
