//! `select --models M --task-file F --json` gives each tool's predicted cost, the numbers
//! `confidence --model M --params … --task-file F --json` gives for that tool alone.

mod common;

use common::toolconf_json as toolconf;
use serde_json::Value;

#[test]
fn select_on_a_task_file_gives_each_tools_prediction() {
    let task = "examples/tasks/panda_touch_point.toml";
    let v = toolconf(&[
        "select",
        "--models",
        "panda",
        "--task-file",
        task,
        "--tools",
        "3",
        "--seed",
        "4",
        "--json",
    ]);
    let tools = v["tools"].as_array().unwrap();
    assert_eq!(tools.len(), 3);
    for t in tools {
        let names = [
            "tool_mass",
            "tool_com_x",
            "tool_com_y",
            "tool_com_z",
            "tool_ixx",
            "tool_iyy",
            "tool_izz",
            "tool_ixy",
            "tool_ixz",
            "tool_iyz",
            "tool_tip_x",
            "tool_tip_y",
            "tool_tip_z",
        ];
        let params: Vec<String> = names
            .iter()
            .map(|n| format!("{}", t["arm"][n].as_f64().unwrap()))
            .collect();
        let alone = toolconf(&[
            "confidence",
            "--model",
            "panda",
            "--params",
            &params.join(","),
            "--task-file",
            task,
            "--json",
        ]);
        for key in [
            "predicted_task_error",
            "predicted_free_energy",
            "predicted_cost_j",
        ] {
            let (a, b) = (t[key].as_f64().unwrap(), alone[key].as_f64().unwrap());
            assert!(
                (a / b - 1.0).abs() < 1e-12,
                "{key}: select {a}, confidence {b}"
            );
        }
        assert_eq!(t["prediction_note"], Value::Null);
    }
    let builtin = toolconf(&["select", "--task", "velocity", "--tools", "2", "--json"]);
    assert!(builtin["tools"][0].get("predicted_task_error").is_none());
}
