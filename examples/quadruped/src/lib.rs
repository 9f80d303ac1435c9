//! Solo 12 standing on four point contacts and moving its centre of mass along a horizontal
//! circle: a whole-body inverse-dynamics QP ([`wbc`], solved with `clarabel`) picks joint
//! torques at every millisecond, and the contact-constrained forward dynamics of
//! `kanegen_runtime::contact` simulates the robot under them ([`sim`]). The dynamics come
//! through a small trait, [`robot::WholeBodyModel`] (M, h, contact Jacobians and their bias,
//! centroidal momentum matrix and bias, centre of mass, integration on the configuration space),
//! implemented by the generated module of Solo 12 on a floating base ([`generated::Solo`], through
//! [`impl_whole_body_model!`]; the example runs on it) and by the free-flyer reference recursion
//! ([`robot::ReferenceSolo`], which the tests compare the generated run with). The guide's chapter is
//! `docs/contacts.md`.

pub mod generated;
pub mod robot;
pub mod sim;
pub mod wbc;
