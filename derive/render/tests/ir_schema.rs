//! `derive/ir_schema.json`, from which the derivation builds its IR types, is what the renderer's
//! IR types describe (`toolconf-render --ir-schema`). When it is not, this test writes it anew and
//! fails naming it, so that a change to `src/ir.rs` reaches the derivation with one more run and a
//! reviewed diff, never silently (the file is committed: Python reads it without Rust).

use std::path::Path;

#[test]
fn the_committed_ir_schema_is_what_the_ir_types_describe() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ir_schema.json");
    let described = toolconf_render::ir_schema::ir_schema().unwrap_or_else(|e| panic!("{e}"));
    let committed = std::fs::read_to_string(&file).unwrap_or_default();
    if committed != described {
        std::fs::write(&file, &described).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        panic!(
            "{} was not what derive/render/src/ir.rs describes; it has been written anew: \
             review the diff, commit it and run the tests again",
            file.display()
        );
    }
}
