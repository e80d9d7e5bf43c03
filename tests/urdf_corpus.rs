//! The tool reader (`toolconf tool --urdf`, crates/tool-urdf/) against the corpus
//! both URDF readers share (tests/fixtures/urdf/, cases.json): each file accepted or refused as
//! listed, a refusal one line naming the file and holding the listed phrase. The derivation's
//! reader is run on the same files by derive/tests/test_urdf_corpus.py, so that the two agree on
//! what a URDF is. And a FIFO with no writer is refused at once, not waited on.

use std::path::Path;

use toolconf_tool_urdf::{tool_from_urdf_file, Request};

fn request() -> Request {
    Request {
        root: "base".into(),
        tip: "flange".into(),
        opening: Some(0.0),
        ..Request::default()
    }
}

#[test]
fn each_file_is_accepted_or_refused_as_listed() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/urdf");
    let cases: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(corpus.join("cases.json")).unwrap()).unwrap();
    let cases = cases["cases"].as_array().unwrap();
    assert!(cases.len() > 10);
    for case in cases {
        let file = case["file"].as_str().unwrap();
        let path = corpus.join(file);
        let result = tool_from_urdf_file(&path, &request());
        if case["accepted"].as_bool().unwrap() {
            let tool = result.unwrap_or_else(|e| panic!("{file}: refused: {e}"));
            assert_eq!(tool.mass, 1.5, "{file}");
            continue;
        }
        let message = result
            .err()
            .unwrap_or_else(|| panic!("{file}: accepted"))
            .to_string();
        assert!(
            message.starts_with(&path.display().to_string()),
            "{message}"
        );
        assert!(!message.contains('\n'), "{message}");
        let phrase = case["tool"].as_str().unwrap();
        assert!(
            message.contains(phrase),
            "{file}: {message} does not say '{phrase}'"
        );
    }
}

#[cfg(unix)]
#[test]
fn a_fifo_with_no_writer_is_refused_at_once() {
    let dir = std::env::temp_dir().join(format!("toolconf-urdf-fifo-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("tool.urdf");
    let status = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(status.success());
    let started = std::time::Instant::now();
    let e = tool_from_urdf_file(&fifo, &request())
        .unwrap_err()
        .to_string();
    assert!(started.elapsed().as_secs() < 5);
    assert!(e.contains("is a FIFO, not a URDF file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
