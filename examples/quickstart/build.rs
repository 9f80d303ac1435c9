//! Generates the arm's dynamics into `$OUT_DIR/arm.rs` (once, and again when `arm.toml` changes).
fn main() {
    kanegen::Builder::new("arm.toml").run();
}
