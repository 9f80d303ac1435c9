//! Any bytes as a TOML model description: a model or a typed error, never a panic; a small
//! model that loads also generates.
#![no_main]

use kanegen_model::Model;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = Model::from_toml_str(text, "fuzz.toml")
        && model.dof() <= 8
    {
        kanegen::Builder::from_model(model)
            .generate()
            .expect("a model the loader accepts generates");
    }
});
