//! The command line as a user runs it: output shape, and bad input as exit status 2.

use std::process::Command;

use serde_json::Value;

fn toolconf(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(args)
        .output()
        .expect("run toolconf")
}

#[test]
fn confidence_json_has_the_documented_keys() {
    let out = toolconf(&[
        "confidence",
        "--arm",
        "0.3,0.4,0.5,0.2",
        "--task",
        "velocity",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for key in ["a", "b", "pi_u", "logdet", "task", "arm"] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["a"].as_array().unwrap().len(), 4);
    assert!(v["a"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r.as_array().unwrap().len() == 4));
    assert_eq!(v["b"].as_array().unwrap().len(), 4);
    assert!(v["b"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r.as_array().unwrap().len() == 2));
    assert_eq!(v["task"], "velocity");
    assert_eq!(v["arm"]["l1"], 0.5);
    let pi = &v["pi_u"];
    assert_eq!(pi[0][1], pi[1][0]);
    let det = pi[0][0].as_f64().unwrap() * pi[1][1].as_f64().unwrap()
        - pi[0][1].as_f64().unwrap().powi(2);
    assert!((v["logdet"].as_f64().unwrap() - det.ln()).abs() < 1e-12);
}

#[test]
fn confidence_text_names_every_part() {
    let out = toolconf(&["confidence", "--arm", "0.3,0.4,0.5,0.2", "--task", "1"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for part in [
        "A = ",
        "B = ",
        "dtheta/dU",
        "dtheta_dot/dU",
        "dtheta_ddot/dU",
        "Pi^U",
        "ln|Pi^U|",
    ] {
        assert!(text.contains(part), "missing {part} in\n{text}");
    }
}

#[test]
fn bad_input_exits_2_with_a_message_naming_the_value() {
    for (args, needle) in [
        (
            vec![
                "confidence",
                "--arm",
                "0.3,-0.4,0.5,0.2",
                "--task",
                "velocity",
            ],
            "m2 = -0.4",
        ),
        (
            vec![
                "confidence",
                "--arm",
                "0.3,nan,0.5,0.2",
                "--task",
                "velocity",
            ],
            "m2 = NaN",
        ),
        (
            vec!["confidence", "--arm", "0.3,0.4,0.5", "--task", "velocity"],
            "got 3 values",
        ),
        (
            vec!["confidence", "--arm", "0.3,0.4,0.5,0.2", "--task", "jump"],
            "unknown task 'jump'",
        ),
        (vec!["confidence", "--arm", "0.3,0.4,0.5,0.2"], "--task"),
    ] {
        let out = toolconf(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(needle),
            "{args:?}: stderr lacks '{needle}':\n{err}"
        );
        assert!(out.stdout.is_empty());
    }
}
