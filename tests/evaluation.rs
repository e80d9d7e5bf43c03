//! `toolconf reproduce --model`: the paper's evaluation on a model, a task written here (not one
//! of the repository's) and a sampled population, end to end through the binary: every file,
//! every figure with its data, a verdict per claim by its rule, no NaN, the same bytes on 1 and
//! 2 threads; and, through the runtime, the two properties the evaluation's tasks rest on: a
//! relative tip goal starts every tool at the same distance, and a goal-only tip task moves the
//! Panda's catalogue.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::read_tools;
use toolconf_model::registry::{AnyTool, ModelKind};

fn fresh_dir(name: &str) -> PathBuf {
    common::fresh_dir(&format!("evaluation-{name}"))
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn toolconf(args: &[&str], threads: usize) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .expect("run toolconf");
    common::assert_ok_with(&out, &format!("toolconf {args:?} failed:\n"));
    out
}

/// A tip task no file of the repository states: the UR5 touching a point 6 cm up and 3 cm
/// sideways of each tool's own tip, its precisions from the robot's scales, a ΔT of its own.
const TASK: &str = "kind = \"tip_position\"\n\
description = \"UR5: lift the tip 6 cm and move it 3 cm sideways\"\n\
[goal]\ntip_offset = [0.0, 0.03, 0.06]\n\
[episode]\nperturbation = [-12.0, -12.0, -12.0, -2.0, -2.0, -2.0]\n";

fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    common::folder_files(dir)
}

fn count(text: &str, needle: &str) -> usize {
    text.matches(needle).count()
}

#[test]
fn an_evaluation_on_a_users_task_writes_every_file_figure_and_verdict() {
    let dir = fresh_dir("ur5");
    let task = dir.join("lift.toml");
    std::fs::write(&task, TASK).unwrap();
    let (one, two) = (dir.join("one"), dir.join("two"));
    let run = |out: &Path, threads| {
        let args = [
            "reproduce",
            "--model",
            "ur5",
            "--task-file",
            task.to_str().unwrap(),
            "--sample",
            "24",
            "--seed",
            "5",
            "--quick",
            "--json",
            "--out",
            out.to_str().unwrap(),
        ];
        toolconf(&args, threads)
    };
    let output = run(&one, 1);
    run(&two, 2);
    let json: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(json["model"], "ur5");
    assert_eq!(json["goal"], "relative");
    assert_eq!(json["perturbation"].as_array().unwrap().len(), 6);
    assert_eq!(
        json["perturbation_source"],
        "the task's [episode] perturbation"
    );
    for key in [
        "confidence_predicts_task_error",
        "confidence_predicts_reliability",
        "free_energy_choices_less_sensitive",
    ] {
        let verdict = json["verdicts"][key]["verdict"].as_str().unwrap();
        assert!(
            ["holds", "reversed", "no relation"].contains(&verdict),
            "{key}: {verdict}"
        );
    }
    let (first, second) = (files(&one), files(&two));
    every_file_finite_and_thread_independent(&first, &second);
    let svg = |f: &str| std::str::from_utf8(&first[f]).unwrap().to_string();
    // Every panel has its data: the tools' dots, the runs' lines, the grid's cells, the boxes.
    assert!(count(&svg("fig2_confidence_vs_error.svg"), "<circle") >= 24);
    assert!(count(&svg("fig4_perturbation_change.svg"), "<circle") >= 24);
    assert!(count(&svg("fig3_trajectories.svg"), "<polyline") >= 3 * 4);
    assert!(count(&svg("fig5_perturbation_sweep.svg"), "<circle") >= 6 * 10);
    assert!(count(&svg("fig6_selection_grid.svg"), "<rect") > 4 * 3);
    assert!(count(&svg("fig7_benchmark.svg"), "<rect") > 9);
    let md = std::str::from_utf8(&first["report.md"]).unwrap();
    for claim in ["a", "b", "c"] {
        assert_eq!(
            count(md, &format!("**Verdict ({claim}): ")),
            1,
            "claim {claim}"
        );
    }
    assert!(
        md.contains("relative: an offset of [0, 0.03, 0.06] m"),
        "the goal's kind"
    );
    assert!(md.contains("**ΔT** per joint [N m]: [−12.0, −12.0, −12.0, −2.00, −2.00, −2.00]"));
    let html = std::str::from_utf8(&first["report.html"]).unwrap();
    assert_eq!(count(html, "<svg"), 6, "every figure inline");
    // The fig7 trials' rows and choices agree with each other.
    let choices = std::str::from_utf8(&first["fig7_choices.csv"]).unwrap();
    assert_eq!(choices.lines().count(), 1 + 6 * 3);
}

/// Exactly the evaluation's files, no NaN or infinite cell in any, and each but the reports
/// the same with one and with two threads.
fn every_file_finite_and_thread_independent(
    first: &BTreeMap<String, Vec<u8>>,
    second: &BTreeMap<String, Vec<u8>>,
) {
    let mut names: Vec<&str> = toolconf_report::evaluation::FILES.to_vec();
    names.sort_unstable();
    assert_eq!(first.keys().map(String::as_str).collect::<Vec<_>>(), names);
    for (name, bytes) in first {
        let text = std::str::from_utf8(bytes).unwrap();
        // The 3-D view's inlined three.js is code, where NaN is a word; its data is checked.
        let text = match text.split_once("<script type=\"module\">") {
            Some((before, after)) => before.to_string() + after.split_once("</script>").unwrap().1,
            None => text.to_string(),
        };
        let text = text.as_str();
        assert!(!text.contains("NaN"), "{name} holds NaN");
        if name.ends_with(".csv") {
            for cell in text.lines().skip(1).flat_map(|l| l.split(',')) {
                assert!(
                    cell.parse::<f64>().map_or(true, f64::is_finite),
                    "{name}: {cell}"
                );
            }
        }
        if !name.starts_with("report.") {
            assert!(
                bytes == &second[name],
                "{name} differs between 1 and 2 threads"
            );
        }
    }
}

/// `reproduce --model` without a sample draws `select --models`'s tools: the fig2 rows are
/// select's tools, with select's numbers, for the same seed (ΔT = 0 for both).
#[test]
fn the_population_and_its_numbers_are_selects() {
    let dir = fresh_dir("select");
    let out = dir.join("out");
    let task = repo("examples/tasks/ur5_touch_point.toml");
    let task = task.to_str().unwrap();
    toolconf(
        &[
            "reproduce",
            "--model",
            "ur5",
            "--task-file",
            task,
            "--sample",
            "8",
            "--seed",
            "3",
            "--quick",
            "--out",
            out.to_str().unwrap(),
        ],
        2,
    );
    let select = toolconf(
        &[
            "select",
            "--models",
            "ur5",
            "--task-file",
            task,
            "--tools",
            "8",
            "--seed",
            "3",
            "--json",
        ],
        2,
    );
    let select: Value = serde_json::from_slice(&select.stdout).unwrap();
    let fig2 = std::fs::read_to_string(out.join("fig2_confidence_vs_error.csv")).unwrap();
    let header: Vec<&str> = fig2.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for (line, tool) in fig2
        .lines()
        .skip(1)
        .zip(select["tools"].as_array().unwrap())
    {
        let cells: Vec<&str> = line.split(',').collect();
        for key in ["logdet", "task_error", "free_energy", "cost_j"] {
            let ours: f64 = cells[col(key)].parse().unwrap();
            assert_eq!(ours, tool[key].as_f64().unwrap(), "{key}");
        }
        let mass: f64 = cells[col("tool_mass")].parse().unwrap();
        assert_eq!(mass, tool["arm"]["tool_mass"].as_f64().unwrap());
    }
}

/// With a relative goal every tool starts at the same distance |offset| from its goal (to the
/// rounding of its rest tip, the goal being y(q0) + offset); with the absolute point they
/// start centimetres apart.
#[test]
fn a_relative_tip_goal_starts_every_tool_at_the_same_distance() {
    let relative =
        TaskSpec::from_file(&repo("examples/tasks/panda_touch_point_relative.toml")).unwrap();
    let absolute = TaskSpec::from_file(&repo("examples/tasks/panda_touch_point.toml")).unwrap();
    let mut tools: Vec<AnyTool> = Vec::new();
    read_tools(&repo("examples/tools/panda_tools.csv"), |row| {
        tools.push(row?.tool);
        Ok(())
    })
    .unwrap();
    tools.extend(toolconf::select::mixed::draw_mixed_tools(&[ModelKind::Panda], 40, 11).unwrap());
    let offset = (0.05f64 * 0.05 + 0.03 * 0.03 + 0.04 * 0.04).sqrt();
    let start = |spec: &TaskSpec, tool: &AnyTool| {
        let trace = ModelTasks::new(spec).trace(tool).unwrap();
        let d: Vec<f64> = (0..3).map(|j| trace.value[j][0] - trace.goal[j]).collect();
        let scale = (0..3).map(|j| trace.value[j][0].abs()).fold(0.0, f64::max);
        ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(), scale)
    };
    for tool in &tools {
        let (d, scale) = start(&relative, tool);
        // Each component of y(q0) + offset − y(q0) is the offset to within half an ulp of y.
        assert!(
            (d - offset).abs() <= 4.0 * f64::EPSILON * scale,
            "{tool}: {d} vs {offset}"
        );
    }
    let spread: Vec<f64> = tools.iter().map(|t| start(&absolute, t).0).collect();
    let (lo, hi) = spread
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi - lo > 0.05, "the absolute point: {lo}..{hi} m");
}

/// `rank` of the Panda's catalogue on the task file `text` (in a fresh folder `name`), on two
/// threads, with `extra` arguments.
fn rank_panda_catalogue(name: &str, text: &str, extra: &[&str]) -> Output {
    let task = fresh_dir(name).join("task.toml");
    std::fs::write(&task, text).unwrap();
    let tools = repo("examples/tools/panda_tools.csv");
    let args = [
        "rank",
        "--tools",
        tools.to_str().unwrap(),
        "--task",
        task.to_str().unwrap(),
    ];
    toolconf(&[&args[..], extra].concat(), 2)
}

/// A tip task file that states only its goal gets its precisions from the robot's own scales,
/// and moves the Panda's catalogue towards the point (the paper's unit precisions would not:
/// progress 0.0003).
#[test]
fn a_goal_only_tip_task_moves_the_panda_catalogue() {
    let task = "kind = \"tip_position\"\n[goal]\ntip = [0.36, 0.03, 0.39]\n";
    let out = rank_panda_catalogue("goal-only", task, &["--json"]);
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut progress: Vec<f64> = common::each_tool(&json, |t| t["progress"].as_f64().unwrap());
    progress.sort_by(f64::total_cmp);
    let median = progress[progress.len() / 2];
    assert!(median >= 0.5, "median progress {median}: {progress:?}");
    assert_eq!(
        json["notes"].as_array().unwrap().len(),
        0,
        "{}",
        json["notes"]
    );
}

/// The paper's unit precisions barely move a real arm: the output says so, and which precision
/// to raise.
#[test]
fn a_task_that_barely_moves_the_tools_says_which_precision_to_raise() {
    let task = "kind = \"tip_position\"\n[goal]\ntip = [0.36, 0.03, 0.39]\n[precision]\ntip = 100\ntip_dot = 50\nu = 1\n";
    let out = rank_panda_catalogue("barely", task, &[]);
    let text = String::from_utf8_lossy(&out.stdout);
    let note = text
        .lines()
        .find(|l| l.starts_with("note: the task barely moved the tools"))
        .expect(&text);
    assert!(note.contains("raise precision.tip"), "{note}");
}
