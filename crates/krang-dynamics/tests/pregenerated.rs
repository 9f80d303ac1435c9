//! The default Krang module is committed pre-generated (`src/generated/krang.rs`), so that a
//! default build of the crate runs no generator. It must be exactly what the generator makes
//! of `krang.toml` without the Coriolis matrix, with the batched functions behind the crate's
//! `batch` feature; after a change of the generator or of
//! `krang.toml`, accept the new file with
//! `KANEGEN_ACCEPT_GOLDEN=1 cargo test -p krang-dynamics --test pregenerated`.

use std::path::Path;

#[test]
fn committed_default_module_is_what_the_generator_makes_of_krang_toml() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let generated = kanegen::Builder::new(dir.join("krang.toml"))
        .coriolis_matrix(false)
        .batch_feature("batch")
        .mirrored_lanes(true)
        .generate()
        .unwrap()
        .source;
    let path = dir.join("src/generated/krang.rs");
    if std::env::var_os("KANEGEN_ACCEPT_GOLDEN").is_some() {
        kanegen::write_if_changed(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is out of date: run `KANEGEN_ACCEPT_GOLDEN=1 cargo test -p krang-dynamics --test \
         pregenerated` and commit the file",
        path.display()
    );
}
