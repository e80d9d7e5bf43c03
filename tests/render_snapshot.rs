//! The renderer's output for a small fixed IR (tests/fixtures/pendulum.json, a one-link pendulum)
//! is pinned by insta snapshots: any change to templates/ or to the renderer shows up as a
//! reviewed snapshot diff (`cargo insta review`).

use std::path::Path;

use toolconf_render::{load_templates, read_ir, render};

#[test]
fn pendulum_fixture_renders_to_the_reviewed_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let ir = read_ir(&root.join("tests/fixtures/pendulum.json")).expect("fixture IR");
    let templates = load_templates(&root.join("templates")).expect("templates");
    let files = render(&ir, &templates).expect("render");
    let names: Vec<&str> = files.iter().map(|f| f.file_name.as_str()).collect();
    assert_eq!(names, ["pendulum.rs", "pendulum.md"]);
    for file in files {
        insta::assert_snapshot!(file.file_name.clone(), file.contents);
    }
}

#[test]
fn rendered_rust_is_rustfmt_stable() {
    // The renderer formats its output; formatting it again must change nothing, or
    // `make derive` would not be byte-identical run to run.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let generated =
        std::fs::read_to_string(root.join("generated/src/arm2.rs")).expect("generated/src/arm2.rs");
    assert_eq!(
        toolconf_render::rustfmt(&generated).expect("rustfmt"),
        generated
    );
}

#[test]
fn unknown_schema_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.json");
    std::fs::write(&path, r#"{"schema": 99, "model": {"name": "x"}}"#).unwrap();
    let err = read_ir(&path).unwrap_err().to_string();
    assert!(err.contains("schema"), "{err}");
}
