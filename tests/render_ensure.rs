//! The generated crate is exactly what its committed IR renders to: every file of `generated/`
//! that the renderer writes (the models' sources and reports, the registry), byte for byte,
//! rustfmt included, and no file that neither the render nor the derivation makes. Checked
//! without Python, from the IR alone (the drift check, `make drift-check`, also re-derives the
//! IR); a hand edit of `generated/`, or a change to templates/ or derive/render not re-rendered,
//! fails here naming the file, its first differing line, and the command that fixes it.

use std::path::{Path, PathBuf};

use toolconf_render::{check_crate, crate_irs, render_crate, Package};

const FIX: &str = "run `make render` (re-renders generated/ from its committed IR, no Python: \
                   cargo run -p toolconf-render -- --crate generated), review the diff and commit \
                   it; if the IR itself is stale, `make derive`";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Renders the IRs in `folder` through the repository's templates and compares with `folder`.
fn problems(folder: &Path, package: &Package) -> Vec<String> {
    let irs = crate_irs(folder).unwrap_or_else(|e| panic!("{e}"));
    assert!(!irs.is_empty(), "{}: no IR", folder.display());
    let (read, files) = render_crate(&irs, &root().join("templates"), package)
        .unwrap_or_else(|e| panic!("rendering {}: {e}", folder.display()));
    check_crate(folder, &read, &files)
}

#[test]
fn generated_is_what_its_ir_renders_to() {
    let found = problems(&root().join("generated"), &Package::in_repository());
    assert!(
        found.is_empty(),
        "generated/ is not what its IR renders to:\n  {}\n{FIX}",
        found.join("\n  ")
    );
}

/// A scratch crate: the fixture's IR and vectors, and what they render to.
fn scratch_crate(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "toolconf-render-ensure-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for file in ["pendulum.json", "pendulum.vectors.json"] {
        std::fs::copy(root().join("tests/fixtures").join(file), dir.join(file)).unwrap();
    }
    let irs = crate_irs(&dir).unwrap();
    let (_, files) = render_crate(&irs, &root().join("templates"), &Package::in_repository())
        .unwrap_or_else(|e| panic!("{e}"));
    for f in files {
        let path = dir.join(&f.path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, f.contents).unwrap();
    }
    dir
}

#[test]
fn a_hand_edit_a_missing_file_and_a_stale_one_are_named() {
    let dir = scratch_crate("edits");
    let package = Package::in_repository();
    assert_eq!(problems(&dir, &package), Vec::<String>::new());

    // One character of one line of the model's source, by hand.
    let source = dir.join("src/pendulum.rs");
    let text = std::fs::read_to_string(&source).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("pub const DOF"))
        .unwrap()
        + 1;
    std::fs::write(
        &source,
        text.replace("pub const DOF: usize = 1;", "pub const DOF: usize = 2;"),
    )
    .unwrap();
    std::fs::remove_file(dir.join("src/tasks.rs")).unwrap();
    std::fs::write(dir.join("src/old_model.rs"), "").unwrap();

    let found = problems(&dir, &package);
    assert_eq!(found.len(), 3, "{found:#?}");
    let edited = found
        .iter()
        .find(|p| p.contains("src/pendulum.rs"))
        .expect("the edit");
    assert!(
        edited.contains(&format!("first at line {line}:"))
            && edited.contains("committed: pub const DOF: usize = 2;")
            && edited.contains("rendered:  pub const DOF: usize = 1;"),
        "{edited}"
    );
    assert!(
        found
            .iter()
            .any(|p| p.contains("src/tasks.rs: cannot read it")),
        "{found:#?}"
    );
    assert!(found.iter().any(|p| p.contains("src/old_model.rs: neither the render nor the derivation makes it")), "{found:#?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
