//! Generates the arm's dynamics module from its URDF (written to `$OUT_DIR/singlearm.rs`).
use kanegen::model::UrdfOptions;

fn main() {
    kanegen::Builder::urdf("../../models/singlearm.urdf", UrdfOptions::default()).run();
}
