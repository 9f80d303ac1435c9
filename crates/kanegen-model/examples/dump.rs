//! Print a model: `cargo run -p kanegen-model --example dump -- models/two-link.toml`.
fn main() {
    let path = std::env::args().nth(1).expect("usage: dump <model.toml>");
    match kanegen_model::Model::from_toml_file(&path) {
        Ok(m) => print!("{m}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
