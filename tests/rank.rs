//! `toolconf rank`, tool files and task files, as a user runs them: the example of docs/tutorials/paper-arm.md, the
//! paper's task written as a file against `simulate`, a custom task against an independent
//! fine-step integration, determinism across thread counts, and every kind of bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;
use toolconf_model::Term;

use serde_json::Value;
use toolconf_model::model::{Arm2, Arm2Tool, ClosedLoopN, TaskN};
use toolconf_model::TaskKind;

const DRAWER: &str = "examples/tools/drawer.csv";
const PAPER_TASK: &str = "examples/tasks/paper_position.toml";
const REACH_TASK: &str = "examples/tasks/reach_45.toml";
/// The arm of the command line's examples: m1, m2, l1, l2.
const ARM: &str = "0.3,0.4,0.5,0.2";

fn run(args: &[&str], threads: Option<&str>) -> Output {
    let mut cmd = common::toolconf_command();
    cmd.args(args);
    if let Some(t) = threads {
        cmd.env("RAYON_NUM_THREADS", t);
    }
    cmd.output().expect("run toolconf")
}

fn toolconf(args: &[&str]) -> Output {
    run(args, None)
}

/// A fresh folder for one test's files.
fn scratch(test: &str) -> PathBuf {
    common::fresh_dir(&format!("rank/{test}"))
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    common::write_file(dir, name, text).display().to_string()
}

/// `toolconf rank --tools TOOLS --task TASK --json ARGS…`'s JSON, the run having succeeded.
fn rank_json(tools: &str, task: &str, args: &[&str]) -> Value {
    let mut all = vec!["rank", "--tools", tools, "--task", task, "--json"];
    all.extend(args);
    common::json_ok(&toolconf(&all))
}

/// `toolconf COMMAND --arm ARM --json ARGS…`'s JSON (`simulate`, `confidence`), the run having
/// succeeded.
fn arm_json(command: &str, arm: &str, args: &[&str]) -> Value {
    let mut all = vec![command, "--arm", arm, "--json"];
    all.extend(args);
    common::json_ok(&toolconf(&all))
}

/// `toolconf select --json ARGS…`'s JSON, the run having succeeded.
fn select_json(args: &[&str]) -> Value {
    let mut all = vec!["select", "--json"];
    all.extend(args);
    common::json_ok(&toolconf(&all))
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

#[test]
fn the_readme_example_ranks_every_tool_by_free_energy() {
    let v = rank_json(DRAWER, REACH_TASK, &[]);
    let tools = v["tools"].as_array().unwrap();
    assert_eq!(tools.len(), 12);
    assert_eq!(v["tools_read"], 12);
    assert_eq!(v["objective"], "free_energy");
    let mut models: Vec<&str> = tools.iter().map(|t| t["model"].as_str().unwrap()).collect();
    models.sort_unstable();
    models.dedup();
    assert_eq!(models, ["arm2", "arm2_exact"]);
    for (k, t) in tools.iter().enumerate() {
        assert_eq!(t["rank"], k + 1);
        assert!(
            t["name"].is_string() && t["parameters"]["l2"].is_f64(),
            "{t}"
        );
        for key in ["logdet", "task_error", "free_energy", "cost_j"] {
            assert!(f(t, key).is_finite());
        }
    }
    let free_energy: Vec<f64> = tools.iter().map(|t| f(t, "free_energy")).collect();
    assert!(
        free_energy.windows(2).all(|w| w[0] <= w[1]),
        "{free_energy:?}"
    );

    // The text table lists the same tools in the same order.
    let out = toolconf(&["rank", "--tools", DRAWER, "--task", REACH_TASK]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let first = tools[0]["name"].as_str().unwrap();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("1 "))
        .unwrap();
    assert!(line.contains(first), "{line} vs {first}");
}

/// The paper's task 1 written as a task file gives, tool by tool, exactly what `simulate
/// --task position --json` gives for the same arm (and what the built-in `--task position`
/// gives for every tool, arm2_exact ones included).
#[test]
fn the_paper_task_as_a_file_equals_simulate_for_every_tool() {
    let from_file = rank_json(DRAWER, PAPER_TASK, &[]);
    let builtin = rank_json(DRAWER, "position", &[]);
    assert_eq!(from_file["tools"], builtin["tools"]);
    let mut compared = 0;
    for t in from_file["tools"].as_array().unwrap() {
        if t["model"] != "arm2" {
            continue;
        }
        let p = &t["parameters"];
        let arm = format!("{},{},{},{}", p["m1"], p["m2"], p["l1"], p["l2"]);
        let s = arm_json("simulate", &arm, &["--task", "position"]);
        for key in ["task_error", "free_energy", "cost_j", "logdet"] {
            assert_eq!(f(t, key), f(&s, key), "{key} of {arm}");
        }
        compared += 1;
    }
    assert_eq!(compared, 8);
}

const CUSTOM_TASK: &str = r#"
kind = "position"
[goal]
theta = [0.9, -0.3]
[precision]
theta = [[90.0, 15.0], [15.0, 40.0]]
theta_dot = 30.0
theta_ddot = 0.5
u = 2.0
[episode]
t_end = 3.0
dt = 0.05
perturbation = [0.2, -0.1]
initial_theta = [-1.4, -1.6]
initial_torque = [0.05, 0.15]
learning_rate = 1.5
"#;

/// The custom task's task error by classical RK4 with a fixed step of 1e-4 s on the closed
/// loop's right-hand side, the task written out by hand: Σ over the grid of
/// (θ − θ^g)ᵀ P^θ (θ − θ^g).
fn fine_step_task_error(arm: [f64; 4]) -> f64 {
    let p = |s: f64| nalgebra::Matrix2::identity() * s;
    let task = TaskN::<2> {
        kind: TaskKind::Position,
        // θ's goal and the four joint terms' precisions; the tip's terms, which a joint task
        // does not use, zero.
        goal: std::array::from_fn(|i| match i {
            i if i == Term::Theta.index() => nalgebra::Vector2::new(0.9, -0.3),
            _ => nalgebra::Vector2::zeros(),
        }),
        precision: std::array::from_fn(|i| match i {
            i if i == Term::Theta.index() => nalgebra::Matrix2::new(90.0, 15.0, 15.0, 40.0),
            i if i == Term::ThetaDot.index() => p(30.0),
            i if i == Term::ThetaDdot.index() => p(0.5),
            i if i == Term::CONTROL.index() => p(2.0),
            _ => p(0.0),
        }),
    };
    let tool = Arm2Tool::new(arm).unwrap();
    let system = ClosedLoopN::<Arm2, 2, 4, 4, 6>::with_perturbation(
        &tool,
        &task,
        1.5,
        &nalgebra::Vector2::new(0.2, -0.1),
    )
    .unwrap();
    let mut z = nalgebra::SVector::<f64, 6>::from([-1.4, -1.6, 0.0, 0.0, 0.05, 0.15]);
    let error = |z: &nalgebra::SVector<f64, 6>| {
        let e = nalgebra::Vector2::new(z[0] - 0.9, z[1] + 0.3);
        e.dot(&(task.precision[Term::Theta.index()] * e))
    };
    let (steps_per_output, outputs, h) = (500, 60, 1e-4);
    let mut sum = error(&z);
    for _ in 0..outputs {
        for _ in 0..steps_per_output {
            let k1 = system.rhs(&z);
            let k2 = system.rhs(&(z + k1 * (h / 2.0)));
            let k3 = system.rhs(&(z + k2 * (h / 2.0)));
            let k4 = system.rhs(&(z + k3 * h));
            z += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
        sum += error(&z);
    }
    sum
}

#[test]
fn a_custom_goal_and_precision_agree_with_a_fine_step_integration() {
    let dir = scratch("custom");
    let tools = write(
        &dir,
        "tools.csv",
        "name,m1,m2,l1,l2\na,0.3,0.4,0.5,0.2\nb,0.2,0.5,0.3,0.35\n",
    );
    let tight = CUSTOM_TASK.replace(
        "learning_rate = 1.5",
        "learning_rate = 1.5\nrtol = 1e-10\natol = 1e-12",
    );
    for (file, text, tolerance) in [
        // The requested relative tolerance bounds the difference (measured: ~4e-14; RK4 at
        // 1e-4 s is accurate far below it).
        ("tight.toml", tight.as_str(), 1e-10),
        // ode45's tolerances, what `rank` runs by default: within its rtol of 1e-3 (measured:
        // ~6e-7).
        ("default.toml", CUSTOM_TASK, 1e-3),
    ] {
        let task = write(&dir, file, text);
        let v = rank_json(&tools, &task, &[]);
        for t in v["tools"].as_array().unwrap() {
            let p = &t["parameters"];
            let arm = ["m1", "m2", "l1", "l2"].map(|k| p[k].as_f64().unwrap());
            let reference = fine_step_task_error(arm);
            let got = f(t, "task_error");
            let relative = (got - reference).abs() / reference;
            eprintln!(
                "{file} {arm:?}: task error {got}, fine-step {reference}, relative {relative:e}"
            );
            assert!(
                relative < tolerance,
                "{file} {arm:?}: task error {got} vs fine-step {reference} (relative {relative:e})"
            );
        }
    }
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let dir = scratch("threads");
    // 90 tools: more than one parallel chunk, in a fixed pseudo-random pattern.
    let mut text = String::from("name,model,m1,m2,m3,l1,l2,l3\n");
    for i in 0..90u32 {
        let u = |k: u32| 0.1 + 0.5 * (((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0);
        if i % 5 == 4 {
            text += &format!(
                "t{i},arm3,{},{},{},{},{},{}\n",
                u(1),
                u(2),
                u(3),
                u(4),
                u(5),
                u(6)
            );
        } else {
            text += &format!("t{i},arm2,{},{},,{},{},\n", u(1), u(2), u(4), u(5));
        }
    }
    let tools = write(&dir, "many.csv", &text);
    let outputs: Vec<(Vec<u8>, Vec<u8>)> = ["1", "2"]
        .iter()
        .map(|threads| {
            let csv = dir.join(format!("out{threads}.csv"));
            let out = run(
                &[
                    "rank",
                    "--tools",
                    &tools,
                    "--task",
                    "velocity",
                    "--screen",
                    "70",
                    "--json",
                    "--csv",
                    csv.to_str().unwrap(),
                ],
                Some(threads),
            );
            common::assert_ok(&out);
            (out.stdout, std::fs::read(&csv).unwrap())
        })
        .collect();
    // Everything but the stages' wall times (`timing`), which vary from run to run.
    let without_timing = |stdout: &[u8]| -> Value {
        let mut v: Value = serde_json::from_slice(stdout).unwrap();
        assert!(v.as_object_mut().unwrap().remove("timing").is_some());
        v
    };
    assert_eq!(
        without_timing(&outputs[0].0),
        without_timing(&outputs[1].0),
        "JSON differs between 1 and 2 threads"
    );
    assert_eq!(
        outputs[0].1, outputs[1].1,
        "CSV differs between 1 and 2 threads"
    );
    let v: Value = serde_json::from_slice(&outputs[0].0).unwrap();
    assert_eq!(v["tools"].as_array().unwrap().len(), 70);
    let csv = String::from_utf8(outputs[0].1.clone()).unwrap();
    assert_eq!(csv.lines().count(), 71);
    assert!(
        csv.starts_with("row,name,model,m1,m2,l1,l2,m3,l3,logdet,"),
        "{csv}"
    );
}

/// `--screen K` simulates the K tools with the largest ln|Π^U|, which `confidence` computes.
#[test]
fn the_screen_keeps_the_most_confident_tools() {
    let all = rank_json(DRAWER, "velocity", &["--objective", "confidence"]);
    let screened = rank_json(
        DRAWER,
        "velocity",
        &["--screen", "4", "--objective", "confidence"],
    );
    let names = |v: &Value, n: usize| -> Vec<Value> {
        v["tools"].as_array().unwrap()[..n]
            .iter()
            .map(|t| t["name"].clone())
            .collect()
    };
    assert_eq!(names(&screened, 4), names(&all, 4));
    let logdets: Vec<f64> = common::each_tool(&all, |t| f(t, "logdet"));
    assert!(logdets.windows(2).all(|w| w[0] >= w[1]));
    let top = &all["tools"][0];
    let p = &top["parameters"];
    if top["model"] == "arm2" {
        let arm = format!("{},{},{},{}", p["m1"], p["m2"], p["l1"], p["l2"]);
        let c = arm_json("confidence", &arm, &["--task", "velocity"]);
        assert_eq!(f(&c, "logdet"), f(top, "logdet"));
    }
}

/// Both stages are timed: the confidence stage over every tool read, the simulation stage over
/// the K episodes kept, in the JSON, the text and the report.
#[test]
fn both_stages_report_their_wall_time_and_throughput() {
    let dir = scratch("timing");
    let report = dir.join("report");
    let args = [
        "rank",
        "--tools",
        DRAWER,
        "--task",
        "position",
        "--screen",
        "3",
        "--report",
        report.to_str().unwrap(),
    ];
    let v = common::json_ok(&run(&[&args[..], &["--json"]].concat(), Some("1")));
    let (c, s) = (
        &v["timing"]["confidence_stage"],
        &v["timing"]["simulation_stage"],
    );
    assert_eq!(c["tools"], v["tools_read"]);
    assert!(f(&v, "tools_read") > 3.0, "the screen drops tools");
    assert_eq!(s["episodes"], 3);
    assert_eq!(s["episodes"], v["simulated"]);
    assert_eq!(s["threads"], 1);
    for (stage, items, rate) in [
        (c, "tools", "tools_per_second"),
        (s, "episodes", "episodes_per_second"),
    ] {
        let (secs, n, per_s) = (f(stage, "seconds"), f(stage, items), f(stage, rate));
        assert!(secs > 0.0 && per_s > 0.0, "{stage}");
        assert!((per_s * secs / n - 1.0).abs() < 1e-9, "{stage}");
    }
    assert!((f(c, "ns_per_tool") * 1e-9 * f(c, "tools") / f(c, "seconds") - 1.0).abs() < 1e-9);
    // On one thread the episodes' own times add up to at most the stage's wall time.
    let episodes_s = f(s, "us_per_episode") * 1e-6 * f(s, "episodes");
    assert!(
        episodes_s > 0.0 && episodes_s <= f(s, "seconds") * (1.0 + 1e-9),
        "{s}"
    );
    let text = toolconf(&args);
    assert!(text.status.success());
    let text = String::from_utf8(text.stdout).unwrap();
    for part in [
        "confidence stage: ",
        " tools/s, ",
        "simulation stage: 3 episodes in ",
        " episodes/s, ",
    ] {
        assert!(text.contains(part), "text lacks {part}: {text}");
    }
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    for part in ["## Run time", "tools/s", "3 episodes", "episodes/s"] {
        assert!(md.contains(part), "report.md lacks {part}");
    }
}

#[test]
fn a_json_tools_file_gives_what_the_same_csv_gives() {
    let dir = scratch("json");
    let csv = write(
        &dir,
        "t.csv",
        "name,model,m1,m2,m3,l1,l2,l3\nx,arm2,0.3,0.4,,0.5,0.2,\ny,arm3,0.3,0.25,0.2,0.4,0.35,0.3\n",
    );
    let json = write(
        &dir,
        "t.json",
        r#"[{"name": "x", "m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2},
            {"name": "y", "model": "arm3", "m1": 0.3, "m2": 0.25, "m3": 0.2, "l1": 0.4, "l2": 0.35, "l3": 0.3}]"#,
    );
    let a = rank_json(&csv, "acceleration", &[]);
    let b = rank_json(&json, "acceleration", &[]);
    assert_eq!(a["tools"], b["tools"]);
    assert_eq!(a["tools"].as_array().unwrap().len(), 2);
}

#[test]
fn the_report_has_markdown_html_and_inline_figures() {
    let dir = scratch("report");
    let report = dir.join("report");
    let out = toolconf(&[
        "rank",
        "--tools",
        DRAWER,
        "--task",
        REACH_TASK,
        "--report",
        report.to_str().unwrap(),
    ]);
    common::assert_ok(&out);
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    for part in [
        "Control confidence",
        "Task error",
        "## Ranking",
        "| predicted task error | task error |",
        "best_and_worst.svg",
    ] {
        assert!(md.contains(part), "report.md lacks {part}");
    }
    assert_eq!(html.matches("<svg").count(), 2, "both figures inline");
    assert!(html.contains("short hammer"));
    assert!(!md.contains("NaN") && !html.contains("NaN"));
}

#[test]
fn a_failed_tool_keeps_its_error_and_goes_last() {
    let dir = scratch("failed");
    // With P^θ = e₁e₁ᵀ and P^U = e₂e₂ᵀ, Π^U = r rᵀ + e₂e₂ᵀ for r the first row of ∂θ/∂U, whose
    // first entry vanishes at l1 = 1, m1 + 3 m2 = 3 (tests/identities.rs): that tool fails, the
    // batch goes on.
    let tools = write(
        &dir,
        "t.csv",
        "name,m1,m2,l1,l2\nok,0.3,0.3,0.3,0.3\nsingular,1.5,0.5,1.0,0.3\nok2,0.2,0.4,0.3,0.3\n",
    );
    let singular = write(
        &dir,
        "singular.toml",
        "kind = \"position\"\n[precision]\ntheta = [[1.0, 0.0], [0.0, 0.0]]\ntheta_dot = 0.0\n\
         theta_ddot = 0.0\nu = [[0.0, 0.0], [0.0, 1.0]]\n[episode]\nt_end = 0.5\n",
    );
    let v = rank_json(&tools, &singular, &[]);
    let tools_json = v["tools"].as_array().unwrap();
    assert_eq!(tools_json.len(), 3);
    assert_eq!(tools_json[2]["name"], "singular");
    assert_eq!(tools_json[2]["rank"], 3);
    assert!(tools_json[2]["error"]
        .as_str()
        .unwrap()
        .contains("not positive definite"));
    assert!(tools_json[..2].iter().all(|t| t.get("error").is_none()));

    // When every episode fails (here a torque of 2·10⁶ N m, at the edge of the valid range,
    // throws each arm past the divergence bound within 0.01 s), each row still gets its error,
    // and the run as a whole exits with 1.
    let task = write(
        &dir,
        "wild.toml",
        "kind = \"position\"\n[episode]\nperturbation = 1e6\ninitial_torque = 1e6\n\
         t_end = 0.01\ndt = 0.01\n",
    );
    let three = write(
        &dir,
        "three.csv",
        "name,m1,m2,l1,l2\nshort hammer,0.30,0.40,0.25,0.20\nlong hammer,0.30,0.40,0.55,0.45\n\
         mallet,0.25,0.60,0.40,0.15\n",
    );
    let csv = dir.join("out.csv");
    let out = toolconf(&[
        "rank",
        "--tools",
        &three,
        "--task",
        &task,
        "--json",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let all = v["tools"].as_array().unwrap();
    assert_eq!(all.len(), 3);
    assert!(all.iter().all(|t| t["error"]
        .as_str()
        .unwrap()
        .contains("diverged at t = 0.01 s")));
    let rows: Vec<u64> = all.iter().map(|t| t["row"].as_u64().unwrap()).collect();
    assert_eq!(rows, [1, 2, 3], "failed tools keep file order");
    let text = std::fs::read_to_string(csv).unwrap();
    assert_eq!(text.lines().count(), 4);
    assert!(text.lines().skip(1).all(|l| l.contains("diverged")));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        stderr.trim_end(),
        "toolconf: error: every one of the 3 simulated tools failed"
    );
}

#[test]
fn skip_bad_rows_reports_each_and_ranks_the_rest() {
    let dir = scratch("skip");
    let tools = write(
        &dir,
        "t.csv",
        "name,m1,m2,l1,l2\ngood,0.3,0.4,0.5,0.2\nbad,0.3,x,0.5,0.2\nalso good,0.2,0.2,0.3,0.3\nneg,0.3,0.4,-1,0.2\n",
    );
    let out = toolconf(&[
        "rank",
        "--tools",
        &tools,
        "--task",
        "position",
        "--json",
        "--skip-bad-rows",
    ]);
    let v = common::json_ok(&out);
    assert_eq!(v["tools"].as_array().unwrap().len(), 2);
    assert_eq!(v["skipped_rows"], 2);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 2, "{stderr}");
    assert!(
        stderr.contains("line 3") && stderr.contains("m2 = 'x'"),
        "{stderr}"
    );
    assert!(
        stderr.contains("line 5") && stderr.contains("l1 = -1"),
        "{stderr}"
    );
}

/// Runs `args` (with `--csv` and `--report` into `dir`) and checks: exit status 2, one line on
/// stderr holding every `expected` fragment, no panic, and no output file created.
fn assert_refused(dir: &Path, args: &[&str], expected: &[&str]) {
    let csv = dir.join("out.csv");
    let report = dir.join("report");
    let mut all: Vec<&str> = args.to_vec();
    all.extend([
        "--csv",
        csv.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    let out = toolconf(&all);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{args:?}: {stderr:?} lacks {e:?}");
    }
    assert!(!stderr.contains("panicked"));
    assert!(
        out.stdout.is_empty(),
        "{args:?} printed {}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(
        !csv.exists() && !report.exists(),
        "{args:?} left output behind"
    );
}

/// Tools files `rank` refuses, and what its message names: (file, text, fragments).
#[rustfmt::skip]
const BAD_TOOLS_FILES: &[(&str, &str, &[&str])] = &[
    ("missing.csv", "name,model,m1,m2,l1,l2\nok,arm2,0.3,0.4,0.5,0.2\nhole,arm2,0.3,,0.5,0.2\n", &["missing.csv", "line 3", "m2 is missing", "hole"]),
    ("text.csv", "name,model,m1,m2,l1,l2\nw,arm2,0.3,heavy,0.5,0.2\n", &["text.csv", "line 2", "m2 = 'heavy' is not a number"]),
    ("nan.csv", "name,model,m1,m2,l1,l2\nw,arm2,NaN,0.4,0.5,0.2\n", &["nan.csv", "line 2", "m1 = NaN must be a number in [1e-6, 1e6]"]),
    ("zero.csv", "name,model,m1,m2,l1,l2\nw,arm2,0.3,0.4,0,0.2\n", &["zero.csv", "line 2", "l1 = 0 must be"]),
    ("negative.csv", "name,model,m1,m2,l1,l2\nw,arm2,0.3,0.4,0.5,-0.2\n", &["negative.csv", "line 2", "l2 = -0.2"]),
    ("model.csv", "name,model,m1,m2,l1,l2\nw,arm7,0.3,0.4,0.5,0.2\n", &["model.csv", "line 2", "unknown model 'arm7'"]),
    ("no_m3.csv", "name,model,m1,m2,l1,l2\nw,arm3,0.3,0.4,0.5,0.2\n", &["no_m3.csv", "line 2", "m3 is missing", "arm3"]),
    ("extra.csv", "name,model,m1,m2,m3,l1,l2\nw,arm2,0.3,0.4,0.1,0.5,0.2\n", &["extra.csv", "line 2", "m3 is given", "arm2"]),
    ("column.csv", "name,mass1,m2,l1,l2\nw,0.3,0.4,0.5,0.2\n", &["column.csv", "line 1", "unknown column 'mass1'"]),
    ("short.csv", "name,model,m1,m2,l1,l2\nw,arm2,0.3,0.4\n", &["short.csv", "line 2", "4 cells", "header 6"]),
    ("empty.csv", "", &["empty.csv", "no tools"]),
    ("header.csv", "name,model,m1,m2,l1,l2\n", &["header.csv", "no tools"]),
    ("empty.json", "[]", &["empty.json", "no tools"]),
    ("row.json", r#"[{"m1": 0.3, "m2": "a", "l1": 0.5, "l2": 0.2}]"#, &["row.json", "tool 1", "m2 = 'a' is not a number"]),
    ("extra.json", r#"[{"name": "w", "model": "arm2", "m1": 0.3, "m2": 0.4, "m3": 0.1, "l1": 0.5, "l2": 0.2}]"#, &["extra.json", "tool 1", "m3 is given", "model arm2", "(tool 'w')"]),
    ("key.json", r#"[{"m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2, "colour": 1}]"#, &["key.json", "tool 1", "unknown key 'colour'"]),
    ("object.json", r#"{"m1": 0.3}"#, &["object.json", "line 1", "not a JSON array"]),
];

#[test]
fn every_bad_tools_file_is_refused_naming_file_line_and_value() {
    let dir = scratch("bad_tools");
    for (file, text, expected) in BAD_TOOLS_FILES {
        let tools = write(&dir, file, text);
        assert_refused(
            &dir,
            &["rank", "--tools", &tools, "--task", "position"],
            expected,
        );
    }
    // Skipping does not rescue a file with no valid row, nor one that cannot be parsed.
    let tools = write(&dir, "all_bad.csv", "m1,m2,l1,l2\n0.3,0.4,0.5,-1\n");
    let out = toolconf(&[
        "rank",
        "--tools",
        &tools,
        "--task",
        "position",
        "--skip-bad-rows",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no valid tools"));
    assert_refused(
        &dir,
        &["rank", "--tools", "no/such.csv", "--task", "position"],
        &["no/such.csv", "cannot open"],
    );
}

/// Task files `rank` refuses, and what its message names: (file, text, fragments).
#[rustfmt::skip]
const BAD_TASK_FILES: &[(&str, &str, &[&str])] = &[
    ("unknown.toml", "kind = \"position\"\ncolour = 3\n", &["unknown.toml", "line 2", "unknown field `colour`"]),
    ("unknown_episode.toml", "kind = \"position\"\n[episode]\nt_stop = 3.0\n", &["unknown_episode.toml", "line 3", "t_stop"]),
    ("kind.toml", "kind = \"grasp\"\n", &["kind.toml", "key kind", "'grasp'"]),
    ("no_kind.toml", "[goal]\ntheta = [0.1, 0.2]\n", &["no_kind.toml", "kind"]),
    ("shape.toml", "kind = \"position\"\n[precision]\ntheta = \"high\"\n", &["shape.toml", "key precision.theta", "\"high\""]),
    ("goal_shape.toml", "kind = \"position\"\n[goal]\ntheta = 0.5\n", &["goal_shape.toml", "line 3"]),
    ("ragged.toml", "kind = \"position\"\n[precision]\ntheta = [[1.0, 0.0], [0.0]]\n", &["ragged.toml", "key precision.theta", "square"]),
    ("asym.toml", "kind = \"position\"\n[precision]\ntheta = [[80.0, 5.0], [1.0, 80.0]]\n", &["asym.toml", "key precision.theta", "not symmetric", "5"]),
    ("indefinite.toml", "kind = \"position\"\n[precision]\ntheta = [[1.0, 3.0], [3.0, 1.0]]\n", &["indefinite.toml", "key precision.theta", "not positive semi-definite"]),
    ("negative.toml", "kind = \"velocity\"\n[precision]\nu = -1.0\n", &["negative.toml", "key precision.u", "-1"]),
    ("nan.toml", "kind = \"position\"\n[goal]\ntheta = [nan, 0.0]\n", &["nan.toml", "key goal.theta", "NaN"]),
    ("unused.toml", "kind = \"velocity\"\n[goal]\ntheta = [0.1, 0.2]\n", &["unused.toml", "key goal.theta", "velocity task does not use it"]),
    ("dt.toml", "kind = \"position\"\n[episode]\ndt = 0.0\n", &["dt.toml", "key episode.dt", "0 must be"]),
    ("long.toml", "kind = \"position\"\n[episode]\nt_end = 1e5\n", &["long.toml", "key episode.t_end", "episode too long", "t_end = 100000 s"]),
    ("far.toml", "kind = \"position\"\n[episode]\nt_end = 1e9\n", &["far.toml", "key episode.t_end", "1e9 must be a number in (0, 1e6] s"]),
    ("joints.toml", "kind = \"position\"\n[episode]\nperturbation = [0.1, 0.2, 0.3]\n", &["joints.toml", "key episode.perturbation", "3 values", "2 joints"]),
];

#[test]
fn every_bad_task_file_is_refused_naming_file_key_and_value() {
    let dir = scratch("bad_tasks");
    let arm3 = write(
        &dir,
        "arm3.csv",
        "model,m1,m2,m3,l1,l2,l3\narm3,0.3,0.25,0.2,0.4,0.35,0.3\n",
    );
    for (file, text, expected) in BAD_TASK_FILES {
        let task = write(&dir, file, text);
        assert_refused(
            &dir,
            &["rank", "--tools", DRAWER, "--task", &task],
            expected,
        );
    }
    // Precisions that leave Π^U singular for every tool.
    let task = write(
        &dir,
        "singular.toml",
        "kind = \"acceleration\"\n[precision]\ntheta_ddot = 0.0\nu = 0.0\n",
    );
    assert_refused(
        &dir,
        &["rank", "--tools", DRAWER, "--task", &task],
        &[
            "singular.toml",
            "key precision",
            "cannot be positive definite for any tool",
            "(precision.theta_ddot, precision.u) have ranks adding up to 0",
        ],
    );
    // A two-joint goal for a three-joint tool.
    let task = write(
        &dir,
        "two.toml",
        "kind = \"position\"\n[goal]\ntheta = [0.1, 0.2]\n",
    );
    assert_refused(
        &dir,
        &["rank", "--tools", &arm3, "--task", &task],
        &[
            "two.toml",
            "key goal.theta",
            "model arm3 has 3 joints",
            "[0.1, 0.2]",
        ],
    );
    // Neither a task name nor a file.
    assert_refused(
        &dir,
        &["rank", "--tools", DRAWER, "--task", "grasping"],
        &["grasping", "neither a built-in task"],
    );
}

#[test]
fn simulate_and_confidence_take_a_task_file() {
    let p = arm_json("simulate", ARM, &["--task-file", PAPER_TASK]);
    let q = arm_json("simulate", ARM, &["--task", "position"]);
    for key in ["task_error", "free_energy", "cost_j", "logdet"] {
        assert_eq!(f(&p, key), f(&q, key), "{key}");
    }
    let c = arm_json("confidence", ARM, &["--task-file", REACH_TASK]);
    // Π^U of the file's precisions differs from the paper's task 1 (P^θ is not 100·I).
    let paper = arm_json("confidence", ARM, &["--task", "position"]);
    assert_ne!(c["logdet"], paper["logdet"]);
    // A command-line flag overrides the file's [episode].
    let shorter = arm_json(
        "simulate",
        ARM,
        &["--task-file", REACH_TASK, "--t-end", "1"],
    );
    let full = arm_json("simulate", ARM, &["--task-file", REACH_TASK]);
    assert!(f(&shorter, "rhs_evals") < f(&full, "rhs_evals"));
    assert_eq!(full["perturb"], serde_json::json!([0.3, -0.2]));
}

#[test]
fn select_takes_a_task_file_for_each_drawn_model() {
    let s = select_json(&["--task-file", PAPER_TASK, "--tools", "3"]);
    let t = select_json(&["--task", "position", "--tools", "3"]);
    // The same episodes; the task file adds each tool's prediction.
    let mut from_file = s["tools"].clone();
    for tool in from_file.as_array_mut().unwrap() {
        let fields = tool.as_object_mut().unwrap();
        assert!(fields["predicted_task_error"].as_f64().unwrap() > 0.0);
        fields.retain(|k, _| !k.starts_with("predict"));
    }
    assert_eq!(from_file, t["tools"]);
    // Drawn tools of several models each run the file's task bound to their model...
    let mixed = select_json(&[
        "--task-file",
        REACH_TASK,
        "--models",
        "arm2,arm2_exact",
        "--tools",
        "4",
    ]);
    assert_eq!(mixed["tools"].as_array().unwrap().len(), 4);
    assert!(mixed["tools"]
        .as_array()
        .unwrap()
        .iter()
        .all(|t| t["task_error"].is_f64()));
    // ...and a goal that does not fit one of them is refused.
    let out = toolconf(&[
        "select",
        "--task-file",
        REACH_TASK,
        "--models",
        "arm2,arm3",
        "--tools",
        "4",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("key goal.theta"));
}

#[test]
fn a_task_file_that_does_not_fit_the_arm_is_refused() {
    // simulate's 2-link arm with a three-joint goal.
    let dir = scratch("simulate_file");
    let task = write(
        &dir,
        "three.toml",
        "kind = \"position\"\n[goal]\ntheta = [0.1, 0.2, 0.3]\n",
    );
    let out = toolconf(&["simulate", "--arm", ARM, "--task-file", &task]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("three.toml, key goal.theta: 3 values"),
        "{stderr}"
    );
    // select's 2-link tools carry one ΔT for both joints: a per-joint one is refused, with status 2.
    let out = toolconf(&["select", "--task-file", REACH_TASK, "--tools", "3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("differs between the joints"));
}

#[test]
fn an_episode_too_long_to_hold_is_refused_up_front() {
    for extra in [
        &[][..],
        &["--controller", "mpc"][..],
        &["--csv", "/dev/null"][..],
    ] {
        let mut args = vec![
            "simulate", "--arm", ARM, "--task", "position", "--t-end", "1e5",
        ];
        args.extend(extra);
        let out = toolconf(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("episode too long") && stderr.contains("t_end = 100000 s"),
            "{stderr}"
        );
        assert_eq!(stderr.trim_end().lines().count(), 1);
    }
}

/// The K rows with the smallest `key` (ties: the earlier row), from an unscreened ranking.
fn best_rows(all: &Value, key: &str, k: usize, larger_first: bool) -> Vec<u64> {
    let mut tools: Vec<(f64, u64)> =
        common::each_tool(all, |t| (f(t, key), t["row"].as_u64().unwrap()));
    tools.sort_by(|a, b| {
        let by_key = if larger_first {
            b.0.total_cmp(&a.0)
        } else {
            a.0.total_cmp(&b.0)
        };
        by_key.then(a.1.cmp(&b.1))
    });
    let mut rows: Vec<u64> = tools[..k].iter().map(|t| t.1).collect();
    rows.sort();
    rows
}

fn rows_of(v: &Value) -> Vec<u64> {
    let mut rows: Vec<u64> = common::each_tool(v, |t| t["row"].as_u64().unwrap());
    rows.sort();
    rows
}

/// By default `--screen K` keeps the K tools with the lowest predicted ∫F dt (∫J dt when ranking
/// by ∫J dt), the values `rank` without a screen reports for every tool; `--screen-by
/// confidence` keeps the K most confident; either is the same on 1 and 2 threads.
#[test]
fn the_screen_by_prediction_keeps_the_tools_predicted_cheapest() {
    let base = ["rank", "--tools", DRAWER, "--task", REACH_TASK, "--json"];
    let all = common::json_ok(&toolconf(&base));
    for (objective, key) in [
        ("free-energy", "predicted_free_energy"),
        ("cost-j", "predicted_cost_j"),
    ] {
        let args = [&base[..], &["--screen", "4", "--objective", objective]].concat();
        let screened = common::json_ok(&toolconf(&args));
        assert_eq!(screened["screen_by"], "predicted");
        assert_eq!(
            rows_of(&screened),
            best_rows(&all, key, 4, false),
            "{objective}"
        );
        let one = run(&args, Some("1"));
        let two = run(&args, Some("2"));
        assert_eq!(
            common::json_ok(&one)["tools"],
            common::json_ok(&two)["tools"],
            "the screen depends on the thread count"
        );
    }
    let args = [&base[..], &["--screen", "4", "--screen-by", "confidence"]].concat();
    let screened = common::json_ok(&toolconf(&args));
    assert_eq!(screened["screen_by"], "confidence");
    assert_eq!(rows_of(&screened), best_rows(&all, "logdet", 4, true));
    assert!(screened.get("prediction_check").is_none());
    assert!(all.get("screen_by").is_none(), "no screen, no criterion");
}

/// `--screen-by` means nothing without `--screen`: a usage error, status 2.
#[test]
fn screen_by_without_a_screen_is_a_usage_error() {
    let out = toolconf(&[
        "rank",
        "--tools",
        DRAWER,
        "--task",
        "position",
        "--screen-by",
        "predicted",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--screen <SCREEN>"), "{err}");
}
