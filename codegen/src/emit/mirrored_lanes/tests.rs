//! Mirrored lanes in generated source: what the emitted two-lane statements look like.

use crate::emit::EmitOptions;
use crate::options::Options;
use kanegen_model::Model;

fn krang_source(isa_dispatch: bool) -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let model = Model::from_toml_file(root.join("models/krang.toml")).expect("loads");
    let emit = EmitOptions {
        isa_dispatch,
        mirrored_lanes: true,
        ..EmitOptions::default()
    };
    crate::generate_with(model, Options::default(), &emit)
        .expect("generates")
        .source
}

#[test]
fn paired_statements_are_printed_once_over_two_lanes_in_both_dispatch_forms() {
    for dispatch in [true, false] {
        let src = krang_source(dispatch);
        assert!(src.contains("use kanegen_runtime::pair::F64x2;"));
        // A lane statement, its scalars taken out where read, a mirrored leaf pair.
        assert!(src.contains("lanes.mul_add("));
        assert!(src.contains(".lo();") && src.contains(".hi();"));
        assert!(src.contains("F64x2::new(s_q7l, s_q7r)"));
        let call = if dispatch {
            "kanegen_runtime::isa::dispatch_pair_with("
        } else {
            "kanegen_runtime::isa::native_pair()"
        };
        assert!(src.contains(call), "dispatch {dispatch}");
    }
}
