//! Print a model: `cargo run -p kanegen-model --example dump -- models/two-link.toml`.
//!
//! A `.urdf` file is imported with `UrdfOptions::default()` (fixed base) and the import notes are
//! printed too; `--drop LINK` (repeatable) drops links, `--drop-absurd` drops absurd inertias.
use kanegen_model::{AbsurdInertia, Model, UrdfImport, UrdfOptions};

fn main() {
    let mut args = std::env::args().skip(1);
    let mut path = None;
    let mut options = UrdfOptions::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--drop" => options.drop_links.push(args.next().expect("--drop LINK")),
            "--drop-absurd" => options.absurd_inertia = AbsurdInertia::Drop,
            _ => path = Some(a),
        }
    }
    let path =
        path.expect("usage: dump <model.toml | robot.urdf> [--drop LINK]... [--drop-absurd]");
    let result = if path.ends_with(".urdf") {
        UrdfImport::read(&path, &options).map(|i| {
            for n in &i.notes {
                println!("note: {n}");
            }
            i.model
        })
    } else {
        Model::from_toml_file(&path)
    };
    match result {
        Ok(m) => print!("{m}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
