//! Any bytes as a URDF: the import (fixed base, and a two-wheeled base declared on joints `jwl`,
//! `jwr` and link `l0`) returns a model or a typed error and never panics, hangs or overflows
//! the stack; a small model that loads also generates.
#![no_main]

use kanegen_model::{Model, UrdfOptions, WheeledBaseSpec};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let wheeled = UrdfOptions::wheeled(WheeledBaseSpec::new(
        "jwl",
        "jwr",
        "l0",
        [0.0, 0.0, 1.0],
        0.2,
    ));
    for options in [UrdfOptions::default(), wheeled] {
        if let Ok(model) = Model::from_urdf_str(text, "fuzz.urdf", &options)
            && model.dof() <= 8
        {
            kanegen::Builder::from_model(model)
                .generate()
                .expect("a model the loader accepts generates");
        }
    }
});
