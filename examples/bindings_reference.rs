//! Reference values for the tests of the Python and C bindings (`python/tests/`): random states
//! and the Rust results of every generated function for them, for Krang (`krang-dynamics`) and
//! the 7-DOF arm of `models/singlearm.urdf`, with each model exported to Pinocchio
//! (`kanegen::pinocchio`, default parameters).
//!
//! ```sh
//! cargo run --example bindings_reference -- target/python/reference.json
//! ```
//!
//! The file is one JSON object: per robot (`"krang"`, `"arm"`) its `dof`, `frames`, a
//! parameter change (`"changed"`: a name, its new value, and the mass matrix of the first state
//! with it), the `states` (`q`, `u`, `ud`), the `results` (function name → one row-major array
//! per state; per-frame functions: frame name → arrays) and `pinocchio`, the export's text. The
//! state `"example_state"` and its M, g, τ are those the C++ example prints
//! (`examples/cpp/krang_example.cpp`: `q_i = 0.1 (i + 1)`, `u_i = 0.05 (i + 1)`, `u̇_i = 0.02 (i + 1)`).

#[allow(dead_code, missing_docs, non_snake_case)]
mod singlearm_all {
    include!(concat!(env!("OUT_DIR"), "/singlearm_all.rs"));
}

use std::fmt::Write as _;

use nalgebra::{Isometry3, SMatrix};
use serde_json::{Map, Value, json};

/// A small deterministic generator (xorshift64*): the same states on every run.
struct Rng(u64);

impl Rng {
    /// Uniform in `[r.start, r.end)`.
    fn range(&mut self, r: std::ops::Range<f64>) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        r.start + (r.end - r.start) * (x as f64 / (1u64 << 53) as f64)
    }
}

/// Random states per robot.
const STATES: usize = 12;

/// A result as a row-major array (a pose: its 4 × 4 homogeneous matrix).
trait RowMajor {
    fn row_major(&self) -> Vec<f64>;
}

impl<const R: usize, const C: usize> RowMajor for SMatrix<f64, R, C> {
    fn row_major(&self) -> Vec<f64> {
        (0..R)
            .flat_map(|r| (0..C).map(move |c| (r, c)))
            .map(|(r, c)| self[(r, c)])
            .collect()
    }
}

impl RowMajor for Isometry3<f64> {
    fn row_major(&self) -> Vec<f64> {
        self.to_homogeneous().row_major()
    }
}

impl RowMajor for f64 {
    fn row_major(&self) -> Vec<f64> {
        vec![*self]
    }
}

/// Adds `value` to the per-state list `key` of `results`.
fn push(results: &mut Map<String, Value>, key: &str, value: Vec<f64>) {
    let list = results.entry(key).or_insert_with(|| json!([]));
    list.as_array_mut().expect("a list").push(json!(value));
}

/// Adds `value` to the per-state list of frame `frame` of the per-frame function `key`.
fn push_frame(results: &mut Map<String, Value>, key: &str, frame: &str, value: Vec<f64>) {
    let per_frame = results.entry(key).or_insert_with(|| json!({}));
    let list = per_frame
        .as_object_mut()
        .expect("a map")
        .entry(frame)
        .or_insert_with(|| json!([]));
    list.as_array_mut().expect("a list").push(json!(value));
}

/// The results of the functions named `$f` (state inputs `$args`) of `$robot` for one state.
macro_rules! record {
    ($results:ident, $robot:ident, $args:tt, [$($f:ident),*]) => {
        $(push(&mut $results, stringify!($f), $robot.$f $args.row_major());)*
    };
}

/// The results of the per-frame functions of `$robot` for every frame of `$frame`.
macro_rules! record_frames {
    ($results:ident, $robot:ident, $frame:ty, $q:ident, $u:ident) => {
        for fr in <$frame>::ALL {
            let name = fr.name();
            push_frame(
                &mut $results,
                "frame_pose",
                name,
                $robot.frame_pose(&$q, fr).row_major(),
            );
            let j = $robot.frame_jacobian(&$q, fr).row_major();
            push_frame(&mut $results, "frame_jacobian", name, j);
            let a = $robot.frame_bias_acceleration(&$q, &$u, fr).row_major();
            push_frame(&mut $results, "frame_bias_acceleration", name, a);
        }
    };
}

/// Krang: the functions of `python/krang_dynamics` (M, c, g, τ, C, kinematics, c + g).
fn krang(rng: &mut Rng) -> Value {
    use krang_dynamics::{DOF, Frame, Krang, Params};
    let robot = Krang::new(Params::default());
    let mut states = Vec::new();
    let mut results = Map::new();
    for _ in 0..STATES {
        let q = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-1.5..1.5));
        let u = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-1.0..1.0));
        let ud = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-1.0..1.0));
        states.push(json!({"q": q.as_slice(), "u": u.as_slice(), "ud": ud.as_slice()}));
        record!(
            results,
            robot,
            (&q),
            [
                mass_matrix,
                gravity,
                center_of_mass,
                com_jacobian,
                potential_energy
            ]
        );
        record!(
            results,
            robot,
            (&q, &u),
            [
                coriolis,
                coriolis_matrix,
                com_bias_acceleration,
                kinetic_energy,
                nonlinear_effects
            ]
        );
        record!(results, robot, (&q, &u, &ud), [inverse_dynamics]);
        record_frames!(results, robot, Frame, q, u);
    }
    // The C++ example's state.
    let s = |k: f64| nalgebra::SVector::<f64, DOF>::from_fn(|i, _| k * (i + 1) as f64);
    let (q, u, ud) = (s(0.1), s(0.05), s(0.02));
    let example = json!({
        "q": q.as_slice(), "u": u.as_slice(), "ud": ud.as_slice(),
        "M": robot.mass_matrix(&q).row_major(),
        "g": robot.gravity(&q).row_major(),
        "tau": robot.inverse_dynamics(&q, &u, &ud).row_major(),
    });
    let mut p = Params::default();
    let (name, value) = ("m4l", p.get("m4l").expect("Krang has m4l") * 1.25);
    p.set(name, value).expect("a positive mass");
    let q0: Vec<f64> = serde_json::from_value(states[0]["q"].clone()).expect("numbers");
    let changed = Krang::new(p).mass_matrix(&nalgebra::SVector::from_column_slice(&q0));
    json!({
        "dof": DOF,
        "frames": Frame::NAMES,
        "changed": {"name": name, "value": value, "mass_matrix": changed.row_major()},
        "states": states,
        "results": results,
        "example_state": example,
        "pinocchio": export("crates/krang-dynamics/krang.toml"),
    })
}

/// The arm: every registry function.
fn arm(rng: &mut Rng) -> Value {
    use singlearm_all::{DOF, Frame, Params, SingleArm};
    let robot = SingleArm::new(Params::default());
    let mut states = Vec::new();
    let mut results = Map::new();
    for _ in 0..STATES {
        let q = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-3.0..3.0));
        let u = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-2.0..2.0));
        let ud = nalgebra::SVector::<f64, DOF>::from_fn(|_, _| rng.range(-2.0..2.0));
        states.push(json!({"q": q.as_slice(), "u": u.as_slice(), "ud": ud.as_slice()}));
        record!(
            results,
            robot,
            (&q),
            [
                mass_matrix,
                gravity,
                center_of_mass,
                com_jacobian,
                potential_energy,
                gravity_regressor,
                base_gravity_regressor,
                centroidal_momentum_matrix,
                centroidal_inertia
            ]
        );
        record!(
            results,
            robot,
            (&q, &u),
            [
                coriolis,
                coriolis_matrix,
                com_bias_acceleration,
                kinetic_energy,
                nonlinear_effects,
                centroidal_momentum_bias
            ]
        );
        record!(
            results,
            robot,
            (&q, &u, &ud),
            [
                inverse_dynamics,
                inverse_dynamics_derivatives,
                inverse_dynamics_regressor,
                base_regressor
            ]
        );
        record_frames!(results, robot, Frame, q, u);
    }
    let mut p = Params::default();
    let name = Params::NAMES
        .iter()
        .find(|n| n.starts_with("m_"))
        .expect("a mass");
    let value = p.get(name).expect("listed") * 1.5;
    p.set(name, value).expect("a positive mass");
    let q0: Vec<f64> = serde_json::from_value(states[0]["q"].clone()).expect("numbers");
    let changed = SingleArm::new(p).mass_matrix(&nalgebra::SVector::from_column_slice(&q0));
    json!({
        "dof": DOF,
        "frames": Frame::NAMES,
        "changed": {"name": name, "value": value, "mass_matrix": changed.row_major()},
        "states": states,
        "results": results,
        "pinocchio": export("models/singlearm.urdf"),
    })
}

/// The Pinocchio export of `model` (relative to the workspace root) with its default
/// parameters, in the text format of `kanegen::pinocchio`.
fn export(model: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(model);
    let m = if kanegen::is_urdf(&path) {
        kanegen::model::UrdfImport::read(&path, &Default::default())
            .expect("the arm imports")
            .model
    } else {
        kanegen::model::Model::from_toml_file(&path).expect("the model loads")
    };
    let pm = kanegen::pinocchio::export(&m, &m.param_values()).expect("the model exports");
    pm.to_text()
}

fn main() {
    let Some(out) = std::env::args().nth(1) else {
        eprintln!("usage: bindings_reference OUT.json");
        std::process::exit(2);
    };
    let mut rng = Rng(0x5eed_b1d5);
    let value = json!({"krang": krang(&mut rng), "arm": arm(&mut rng)});
    let mut text = String::new();
    let _ = write!(text, "{value}");
    if let Some(dir) = std::path::Path::new(&out).parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = std::fs::write(&out, text) {
        eprintln!("error: cannot write {out}: {e}");
        std::process::exit(1);
    }
}
