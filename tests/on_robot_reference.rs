//! The on-robot crate's host tests compare its 1 kHz ticks with `toolconf simulate --method
//! explicit`; the numbers they compare with are recorded in
//! examples/on_robot/tests/reference/mod.rs (that crate has no toolconf runtime to run). This
//! runs the commands and checks the record is still their output, digit for digit.

mod common;

use std::process::Command;

#[path = "../examples/on_robot/tests/reference/mod.rs"]
mod reference;

fn numbers(line: &str) -> Vec<f64> {
    line.split(',').map(|v| v.parse().unwrap()).collect()
}

#[test]
fn the_on_robot_reference_is_what_simulate_prints() {
    let dir = std::env::temp_dir().join(format!(
        "toolconf-on-robot-reference-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for r in &reference::REFERENCES {
        let arm = r.arm.map(|v| v.to_string()).join(",");
        for (tight, task_error, last) in [
            (false, r.task_error, r.last),
            (true, r.tight_task_error, r.tight_last),
        ] {
            let csv = dir.join(format!("{}-{tight}.csv", r.task));
            let mut args = vec![
                "simulate", "--arm", &arm, "--task", r.task, "--method", "explicit", "--json",
            ];
            if tight {
                args.extend(["--rtol", "1e-10", "--atol", "1e-12"]);
            }
            let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
                .args(&args)
                .arg("--csv")
                .arg(&csv)
                .output()
                .unwrap();
            let json: serde_json::Value = common::json_ok(&out);
            assert_eq!(
                json["task_error"].as_f64().unwrap().to_bits(),
                task_error.to_bits(),
                "{args:?}"
            );
            let text = std::fs::read_to_string(&csv).unwrap();
            let row = numbers(text.lines().last().unwrap());
            assert_eq!(row[0], 5.0);
            for (k, v) in last.iter().enumerate() {
                assert_eq!(
                    row[1 + k].to_bits(),
                    v.to_bits(),
                    "{args:?} column {}",
                    k + 1
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
