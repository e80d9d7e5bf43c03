//! `design` by the predicted task error, end to end: on the Panda's touch task and its design
//! file, the designed tool's simulated task error (design's own verification) is below that of
//! the tool `design` by confidence gives, and the prediction at the design is within 10 % of
//! the simulation.

mod common;

use std::process::Command;

use serde_json::Value;

fn design(objective: &str, dir: &std::path::Path) -> Value {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("examples/design/panda_tip_length.toml")).unwrap();
    let text = text
        .replace(
            "objective = \"confidence\"",
            &format!("objective = \"{objective}\""),
        )
        .replace(
            "samples = 20000",
            "samples = 200\nsimulate = 1\nvalidation = 0",
        );
    let file = dir.join(format!("{objective}.toml"));
    std::fs::write(&file, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .current_dir(root)
        .args([
            "design",
            "--model",
            "panda",
            "--task",
            "examples/tasks/panda_touch_point.toml",
            "--design",
            file.to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    common::json_ok(&out)
}

fn simulated_task_error(v: &Value) -> f64 {
    let design = &v["verification"][0];
    assert_eq!(design["tool"], "design");
    design["task_error"].as_f64().unwrap()
}

#[test]
fn the_predicted_design_does_the_touch_task_better_than_the_confidence_design() {
    let dir = tempfile::tempdir().unwrap();
    let by_confidence = design("confidence", dir.path());
    let by_prediction = design("predicted_task_error", dir.path());
    assert_eq!(by_prediction["objective"], "predicted_task_error");
    assert!(by_confidence.get("predicted_optimum").is_none());
    let (c, p) = (
        simulated_task_error(&by_confidence),
        simulated_task_error(&by_prediction),
    );
    assert!(p < c, "predicted design {p:e}, confidence design {c:e}");
    let predicted = by_prediction["predicted_optimum"]["value"]
        .as_f64()
        .unwrap();
    assert!(
        (predicted / p - 1.0).abs() < 0.1,
        "predicted {predicted:e}, simulated {p:e}"
    );
    assert_eq!(by_prediction["predicted_optimum"]["converged"], true);
}
