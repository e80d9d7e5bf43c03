//! `derive/ir_schema.json`, from which the derivation builds its IR types, is what the renderer's
//! IR types describe (`toolconf-render --ir-schema`). When it is not, this test writes it anew and
//! fails naming it, so that a change to `src/ir.rs` reaches the derivation with one more run and a
//! reviewed diff, never silently (the file is committed: Python reads it without Rust).

use std::path::Path;

#[test]
fn the_committed_ir_schema_is_what_the_ir_types_describe() {
    let derive = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("derive/");
    let file = derive.join("ir_schema.json");
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

#[test]
fn fields_keep_their_order_and_say_whether_they_are_left_out_when_empty() {
    let text = toolconf_render::ir_schema::ir_schema().unwrap_or_else(|e| panic!("{e}"));
    // Read back in the text's order: serde_json's own map would sort the keys.
    let keys = |object: &str| -> Vec<String> {
        let start = text.find(&format!("\"{object}\": {{")).expect(object);
        let properties = start + text[start..].find("\"properties\": {").expect("properties");
        let end = properties + text[properties..].find("\n      }").expect("their end");
        let lines = text[properties..end]
            .lines()
            .filter(|l| l.starts_with("        \""));
        lines
            .map(|l| l.trim().split('"').nth(1).unwrap().to_string())
            .collect()
    };
    // ir.rs's order, which is not the alphabet's.
    assert_eq!(
        keys("Entry"),
        ["row", "col", "rust"],
        "Entry's fields out of order"
    );
    assert_eq!(
        keys("Formulation"),
        ["name", "doc", "chosen_by"],
        "Formulation's fields out of order"
    );
    let schema: serde_json::Value = serde_json::from_str(&text).unwrap();
    let required = |def: &str| schema["$defs"][def]["required"].clone();
    // `rust` is left out when empty; `closed` is always written, `null` when empty.
    assert_eq!(required("Entry"), serde_json::json!(["row", "col"]));
    assert_eq!(
        required("GradientReport"),
        serde_json::json!(["reference", "values", "closed"])
    );
    assert_eq!(
        schema["properties"]["schema"]["const"],
        toolconf_render::IR_SCHEMA
    );
}
