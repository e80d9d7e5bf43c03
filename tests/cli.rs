//! The command line as a user runs it: output shape, and bad input as exit status 2.

mod common;

use std::process::Command;

use common::toolconf;
use serde_json::Value;

/// The arm of the command line's examples: m1, m2, l1, l2.
const ARM: &str = "0.3,0.4,0.5,0.2";

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
    let v: Value = common::json_ok(&out);
    for key in ["a", "b", "pi_u", "logdet", "task", "arm"] {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    // Each matrix's row lengths: A is 4 × 4, B 4 × 2.
    let row_lengths = |key: &str| -> Vec<usize> {
        let rows = v[key].as_array().unwrap();
        rows.iter().map(|r| r.as_array().unwrap().len()).collect()
    };
    assert_eq!(row_lengths("a"), [4; 4]);
    assert_eq!(row_lengths("b"), [2; 4]);
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
    for (arm, task, needle) in [
        ("0.3,-0.4,0.5,0.2", "velocity", "m2 = -0.4"),
        ("0.3,nan,0.5,0.2", "velocity", "m2 = NaN"),
        ("0.3,0.4,0.5", "velocity", "got 3 values"),
        (ARM, "jump", "unknown task 'jump'"),
    ] {
        let out = assert_refused(&["confidence", "--arm", arm, "--task", task], needle);
        assert!(out.stdout.is_empty());
    }
    let out = assert_refused(&["confidence", "--arm", ARM], "--task");
    assert!(out.stdout.is_empty());
}

/// Runs `toolconf ARGS` and checks that it exits with status 2 and a message holding `needle`.
#[track_caller]
fn assert_refused(args: &[&str], needle: &str) -> std::process::Output {
    let out = toolconf(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(needle),
        "{args:?}: stderr lacks '{needle}':\n{err}"
    );
    out
}

/// Keys every episode's JSON has: its metrics and the integrator's work.
const EPISODE_KEYS: [&str; 5] = ["task_error", "free_energy", "cost_j", "logdet", "rhs_evals"];

/// `toolconf simulate TOOL --task position --json --csv CSV`'s JSON, the run having succeeded;
/// `tool` names the tool (`--arm …`, `--model … --params …`) and may add options.
fn simulate_position(tool: &[&str], csv: &std::path::Path) -> Value {
    let mut args = vec!["simulate"];
    args.extend(tool);
    args.extend([
        "--task",
        "position",
        "--json",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    common::json_ok(&toolconf(&args))
}

#[test]
fn simulate_json_and_csv() {
    // A folder of the test's own, removed when it ends, whatever the outcome.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let csv = dir.join("trajectory.csv");
    let v = simulate_position(&["--arm", ARM, "--perturb", "-0.8"], &csv);
    for key in EPISODE_KEYS.iter().chain(&["arm", "task", "perturb"]) {
        assert!(v.get(key).is_some(), "missing key {key}");
    }
    assert_eq!(v["perturb"], -0.8);
    assert_eq!(v["task"], "position");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "t,theta1,theta2,theta1_dot,theta2_dot,theta1_ddot,theta2_ddot,u1,u2"
    );
    assert_eq!(lines.len(), 102);
    assert!(lines[1..]
        .iter()
        .all(|l| l.split(',').count() == 9 && !l.contains("NaN")));
    let left: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains(".partial"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    // The trajectory and the metrics agree: task error is the sum over the CSV's θ rows.
    let g = [std::f64::consts::FRAC_PI_3, std::f64::consts::FRAC_PI_6];
    let sum: f64 = lines[1..]
        .iter()
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            100.0 * ((c[1] - g[0]).powi(2) + (c[2] - g[1]).powi(2))
        })
        .sum();
    assert!((sum - v["task_error"].as_f64().unwrap()).abs() < 1e-9 * sum);
}

#[test]
fn select_chooses_by_each_objective() {
    let out = toolconf(&[
        "select", "--task", "velocity", "--tools", "6", "--seed", "3", "--json",
    ]);
    let v: Value = common::json_ok(&out);
    let tools = v["tools"].as_array().unwrap();
    assert_eq!(tools.len(), 6);
    let column = |key: &str| {
        tools
            .iter()
            .map(|t| t[key].as_f64().unwrap())
            .collect::<Vec<_>>()
    };
    let argmin = |x: Vec<f64>| (0..x.len()).min_by(|&a, &b| x[a].total_cmp(&x[b])).unwrap();
    assert_eq!(v["choice"]["free_energy"], argmin(column("free_energy")));
    assert_eq!(v["choice"]["cost_j"], argmin(column("cost_j")));
    assert_eq!(
        v["choice"]["confidence"],
        argmin(column("logdet").into_iter().map(|l| -l).collect())
    );
    // Same seed, same tools and numbers.
    let again = toolconf(&[
        "select", "--task", "velocity", "--tools", "6", "--seed", "3", "--json",
    ]);
    assert_eq!(out.stdout, again.stdout);
}

#[test]
fn simulate_and_select_reject_bad_input() {
    // `simulate --arm A --task position ARGS`.
    let simulate = |arm: &'static str, args: &[&'static str]| {
        [&["simulate", "--arm", arm, "--task", "position"][..], args].concat()
    };
    for (args, needle) in [
        (simulate("0.3,0.4,0.5,0", &[]), "l2 = 0"),
        (
            simulate(ARM, &["--perturb", "nan"]),
            "--perturb: NaN must be a number in [-1e6, 1e6] N m",
        ),
        (simulate(ARM, &["--dt", "0"]), "dt"),
        (simulate(ARM, &["--rtol", "-1"]), "rtol"),
        (
            vec!["select", "--task", "velocity", "--tools", "0"],
            "--tools",
        ),
        (
            vec!["select", "--task", "sideways", "--tools", "3"],
            "unknown task",
        ),
    ] {
        assert_refused(&args, needle);
    }
}

#[test]
fn select_ranks_by_the_mpc_cost_when_asked() {
    let out = toolconf(&[
        "select", "--task", "velocity", "--tools", "2", "--seed", "3", "--mpc", "--json",
    ]);
    let v: Value = common::json_ok(&out);
    let costs: Vec<f64> = common::each_tool(&v, |t| t["mpc_cost"].as_f64().unwrap());
    let best = if costs[1] < costs[0] { 1 } else { 0 };
    assert_eq!(v["choice"]["mpc_cost"], best);
    let mixed = toolconf(&[
        "select",
        "--task",
        "velocity",
        "--tools",
        "2",
        "--mpc",
        "--models",
        "arm2,arm3",
    ]);
    assert_eq!(mixed.status.code(), Some(2));
}

#[test]
fn a_reader_that_stops_early_ends_the_run_quietly() {
    // `toolconf select … | head`: the closed pipe ends the process (SIGPIPE), not a panic.
    use std::io::Read;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args([
            "select",
            "--task",
            "acceleration",
            "--tools",
            "1000",
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    // The read end is dropped here, with far more than a pipe buffer of JSON still to come.
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!out.status.success());
}

/// `simulate --model M --params …` runs any generated model. For arm2 it is the same episode as
/// `--arm` (the model-generic runtime reproduces the 2-link one bit for bit), on every task.
#[test]
fn simulate_model_arm2_equals_simulate_arm_on_every_task() {
    for task in ["position", "velocity", "acceleration"] {
        // `simulate TOOL --task TASK --perturb -0.4 --json`, the tool named by `tool`.
        let json = |tool: &[&str]| -> Value {
            let rest = ["--task", task, "--perturb", "-0.4", "--json"];
            common::json_ok(&toolconf(&[&["simulate"][..], tool, &rest].concat()))
        };
        let by_model = json(&["--model", "arm2", "--params", ARM]);
        let by_arm = json(&["--arm", ARM]);
        for key in EPISODE_KEYS.iter().chain(&["steps"]) {
            assert_eq!(by_model[key], by_arm[key], "{task}: {key}");
        }
        assert_eq!(by_model["params"]["l2"], 0.2);
        assert_eq!(by_model["perturb"], serde_json::json!([-0.4, -0.4]));
    }
}

/// The models nobody wrote runtime code for run end to end: the payload arm (5 parameters) and
/// the 1-DOF mass–spring–damper, with a trajectory CSV of their own width.
#[test]
fn simulate_model_runs_the_payload_arm_and_the_mass_spring_damper() {
    let dir = scratch("sim-model");
    for (model, params, columns) in [
        (
            "arm2_payload",
            "0.3,0.4,0.5,0.2,0.1",
            "t,theta1,theta2,theta1_dot,theta2_dot,theta1_ddot,theta2_ddot,u1,u2",
        ),
        ("msd", "1.0,2.0,0.5", "t,theta1,theta1_dot,theta1_ddot,u1"),
    ] {
        let csv = dir.join(format!("{model}.csv"));
        let v = simulate_position(&["--model", model, "--params", params], &csv);
        assert_eq!(v["model"], model);
        assert!(v["task_error"].as_f64().unwrap().is_finite());
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(columns));
        assert_eq!(lines.count(), 101, "{model}: one row per output time");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn simulate_model_rejects_bad_parameters_and_two_link_only_options() {
    let cases: [(&str, &str, &[&str], &str); 6] = [
        ("arm3", "1,2", &[], "arm3 takes 6 parameters"),
        ("msd", "1,x,2", &[], "'x' is not a number"),
        ("msd", "1,-2,2", &[], "-2"),
        ("msd", "1,2,2", &["--controller", "mpc"], "--arm"),
        ("msd", "1,2,2", &["--plant", "exact"], "--arm"),
        ("nope", "1", &[], "unknown model 'nope'"),
    ];
    for (model, params, extra, needle) in cases {
        let mut args = vec![
            "simulate", "--task", "position", "--model", model, "--params", params,
        ];
        args.extend(extra);
        let out = assert_refused(&args, needle);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A folder of the test's own, empty.
fn scratch(name: &str) -> std::path::PathBuf {
    common::fresh_dir(&format!("cli-{name}"))
}

/// The temporary files in `dir`.
fn partials(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.to_string_lossy().ends_with(".partial"))
        .collect()
}

/// Waits for `child` at most `limit`; one that runs longer is killed and fails the test.
fn wait_bounded(
    child: &mut std::process::Child,
    limit: std::time::Duration,
) -> std::process::ExitStatus {
    let deadline = std::time::Instant::now() + limit;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("still running after {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

#[cfg(unix)]
#[test]
fn sigterm_during_rank_csv_keeps_the_old_file_and_leaves_no_temporary() {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let dir = scratch("sigterm");
    // Enough tools that the simulation stage lasts well past the first rows.
    let mut tools = String::from("name,m1,m2,l1,l2\n");
    for i in 0..3000 {
        tools += &format!("t{i},0.3,0.4,{},0.2\n", 0.2 + f64::from(i % 60) * 0.005);
    }
    std::fs::write(dir.join("tools.csv"), tools).unwrap();
    let old = b"row,name\n1,my previous results\n";
    std::fs::write(dir.join("results.csv"), old).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(["rank", "--tools", "tools.csv", "--task", "position"])
        .args(["--csv", "results.csv"])
        .current_dir(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Signalled once rows are being written: the temporary holds the header and a row.
    let deadline = Instant::now() + Duration::from_secs(120);
    let rows = |p: &std::path::Path| {
        std::fs::read(p).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
    };
    while !partials(&dir).iter().any(|p| rows(p) >= 2) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was signalled"
        );
        assert!(Instant::now() < deadline, "no rows written after 120 s");
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(std::fs::read(dir.join("results.csv")).unwrap(), old);
    // SAFETY: kill(2) on the child's own pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let status = wait_bounded(&mut child, Duration::from_secs(30));
    assert_eq!(status.code(), Some(128 + libc::SIGTERM), "{status:?}");
    assert_eq!(std::fs::read(dir.join("results.csv")).unwrap(), old);
    assert_eq!(partials(&dir), Vec::<std::path::PathBuf>::new());
}

/// `args` run in `dir` with `fifo` made a FIFO there that no process reads: refused with
/// status 2 and one line (returned), not blocked.
#[cfg(unix)]
fn refused_at_fifo(dir: &std::path::Path, fifo: &str, args: &[&str]) -> String {
    use std::process::Stdio;
    let path = std::ffi::CString::new(dir.join(fifo).to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(path.as_ptr(), 0o644) }, 0);
    let mut child = Command::new(env!("CARGO_BIN_EXE_toolconf"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status = wait_bounded(&mut child, std::time::Duration::from_secs(60));
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(2), "{fifo}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    stderr
}

#[cfg(unix)]
#[test]
fn a_fifo_nothing_reads_is_refused_at_once_and_stays_a_fifo() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("fifo");
    std::fs::create_dir(dir.join("r")).unwrap();
    let drawer = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/tools/drawer.csv");
    for (fifo, args) in [
        (
            "r/report.md",
            vec![
                "rank", "--tools", drawer, "--task", "position", "--screen", "1", "--report", "r",
            ],
        ),
        (
            "out.csv",
            vec![
                "simulate",
                "--arm",
                "0.3,0.4,0.5,0.2",
                "--task",
                "position",
                "--csv",
                "out.csv",
            ],
        ),
    ] {
        let stderr = refused_at_fifo(&dir, fifo, &args);
        let name = fifo.rsplit('/').next().unwrap();
        assert!(
            stderr.contains(name) && stderr.contains("a FIFO that no process reads"),
            "{stderr}"
        );
        assert!(std::fs::symlink_metadata(dir.join(fifo))
            .unwrap()
            .file_type()
            .is_fifo());
    }
    assert!(!dir.join("r/report.html").exists());
}

/// An input that is a FIFO with no writer reads as empty at once (one line, status 2), never
/// waits for a writer; a pipe with one (`--task <(...)`) is read as a file.
#[cfg(unix)]
#[test]
fn an_input_fifo_with_no_writer_is_one_line_at_once() {
    let dir = scratch("input-fifo");
    let drawer = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/tools/drawer.csv");
    for (fifo, args) in [
        (
            "t.csv",
            vec!["rank", "--tools", "t.csv", "--task", "position"],
        ),
        (
            "t.json",
            vec!["rank", "--tools", "t.json", "--task", "position"],
        ),
        (
            "task.toml",
            vec!["rank", "--tools", drawer, "--task", "task.toml"],
        ),
        (
            "tf.toml",
            vec![
                "confidence",
                "--arm",
                "0.3,0.4,0.5,0.2",
                "--task-file",
                "tf.toml",
            ],
        ),
        (
            "d.toml",
            vec!["design", "--task", "velocity", "--design", "d.toml"],
        ),
    ] {
        let stderr = refused_at_fifo(&dir, fifo, &args);
        assert!(stderr.contains(fifo), "{stderr}");
    }
}
