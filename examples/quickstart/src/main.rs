//! Prints the mass matrix, gravity and inverse dynamics of the arm of `arm.toml`.

// The generated module (`build.rs`): `Arm`, `Params`, `DOF`, `mass_matrix`, … A binary uses
// only part of it.
#[allow(dead_code, missing_docs)]
mod arm {
    include!(concat!(env!("OUT_DIR"), "/arm.rs"));
}

use arm::{Arm, DOF, Params};
use nalgebra::SVector;

fn main() {
    let robot = Arm::new(Params::default()); // the values of arm.toml
    let q = SVector::<f64, DOF>::new(0.3, -0.5); // joint angles, rad
    let u = SVector::<f64, DOF>::new(1.0, 0.0); // joint speeds, rad/s
    let ud = SVector::<f64, DOF>::zeros(); // accelerations, rad/s²
    println!("M = {}", robot.mass_matrix(&q));
    println!("g = {}", robot.gravity(&q));
    println!("tau = {}", robot.inverse_dynamics(&q, &u, &ud)); // M u̇ + c + g
}
