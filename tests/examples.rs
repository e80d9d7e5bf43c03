//! The Rust examples (examples/README.md) run as a user runs them, `cargo run --example NAME`
//! (built, then run), and print the command line's numbers for the same inputs, to every digit they print: the
//! drawer's ranking is `toolconf rank --json`'s, the episode's metrics `toolconf simulate
//! --json`'s, the generated functions' A, B and Π^U `toolconf confidence --json`'s, and a loaded
//! library's results the built-in model's.
//!
//! The example that loads a model library needs one: its test is ignored by plain `cargo test`,
//! and `make loaded-models-test` (part of `make test`) runs it with `TOOLCONF_TEST_LIBRARIES`
//! naming the folder of libraries it built. Without it the test fails, never passes.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_toolconf");
const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// `cargo run --example NAME -- ARGS` from the repository root: its standard output. Built with
/// `--workspace` and the profile this test was built with (`test`, or `release` under
/// `cargo test --release`): the features and profile `cargo test --workspace` (make test) built
/// the examples with, so that nothing is compiled twice there (under `dev`, cargo builds every
/// crate of the workspace again); run alone, `cargo test --workspace --test examples`.
fn example(name: &str, args: &[&str]) -> String {
    // This test is target/<profile dir>/deps/examples-<hash>; the examples are beside deps/.
    let exe = std::env::current_exe().expect("the test's path");
    let examples = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile dir>");
    let profile = match examples.file_name().and_then(|n| n.to_str()) {
        Some("release") => "release",
        _ => "test",
    };
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let build = Command::new(cargo)
        .current_dir(ROOT)
        .args(["build", "--quiet", "--profile", profile, "--workspace"])
        .args(["--example", name])
        .output()
        .expect("run cargo");
    let stderr = String::from_utf8_lossy(&build.stderr);
    assert!(
        build.status.success(),
        "cargo build --example {name}: {stderr}"
    );
    let out = Command::new(examples.join("examples").join(name))
        .current_dir(ROOT)
        .args(args)
        .output()
        .expect("run the example");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "example {name}: {stderr}");
    String::from_utf8(out.stdout).expect("UTF-8 output")
}

/// `toolconf ARGS --json` from the repository root, parsed.
fn toolconf(args: &[&str]) -> Value {
    let out = Command::new(BIN)
        .current_dir(ROOT)
        .args(args)
        .arg("--json")
        .output()
        .expect("run toolconf");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "toolconf {args:?}: {stderr}");
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// Whether `value`, printed in `text`'s notation with as many decimals, is `text`.
fn printed(text: &str, value: &Value) -> bool {
    let value = value.as_f64().expect("a number");
    let (mantissa, exponent) = match text.split_once('e') {
        Some((m, _)) => (m, true),
        None => (text, false),
    };
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len());
    let again = if exponent {
        format!("{value:.decimals$e}")
    } else {
        format!("{value:.decimals$}")
    };
    again == text
}

/// The values of a `name=value name=value ...` list, comma-separated, as the command line's
/// `--arm` and `--params` take them.
fn parameters(list: &str) -> String {
    let values: Vec<&str> = list
        .split_whitespace()
        .map(|p| p.split_once('=').expect("name=value").1)
        .collect();
    values.join(",")
}

#[test]
fn rank_drawer_prints_the_ranking_of_toolconf_rank() {
    let out = example("rank_drawer", &[]);
    let drawer = ["--tools", "examples/tools/drawer.csv"];
    let task = ["--task", "examples/tasks/reach_45.toml"];
    let cli = toolconf(&[&["rank"][..], &drawer, &task].concat());
    let tools = cli["tools"].as_array().expect("tools");
    let rows: Vec<&str> = out.lines().skip(1).collect();
    assert_eq!(rows.len(), tools.len(), "{out}");
    for (row, tool) in rows.iter().zip(tools) {
        // rank, name (may hold spaces), ln|Π^U|, task error, ∫F dt
        let words: Vec<&str> = row.split_whitespace().collect();
        let [rank, name @ .., logdet, task_error, free_energy] = &words[..] else {
            panic!("row {row:?}");
        };
        assert_eq!(rank.parse::<u64>().ok(), tool["rank"].as_u64(), "{row}");
        assert_eq!(
            Some(name.join(" ").as_str()),
            tool["name"].as_str(),
            "{row}"
        );
        assert!(printed(logdet, &tool["logdet"]), "{row}: {tool}");
        assert!(printed(task_error, &tool["task_error"]), "{row}: {tool}");
        assert!(printed(free_energy, &tool["free_energy"]), "{row}: {tool}");
    }
}

#[test]
fn the_episode_prints_the_metrics_of_toolconf_simulate() {
    let out = example("episode", &[]);
    let first = out.lines().next().expect("a first line");
    let (tool, method) = first
        .strip_prefix("tool: ")
        .and_then(|l| l.split_once("    method: "))
        .expect("tool: ...    method: ...");
    let arm = parameters(tool);
    let cli = toolconf(&[
        "simulate", "--arm", &arm, "--task", "position", "--method", method,
    ]);
    let labels = [
        ("task error", "task_error"),
        ("∫F dt", "free_energy"),
        ("∫J dt", "cost_j"),
        ("ln|Π^U|", "logdet"),
    ];
    for (label, key) in labels {
        let line = out.lines().find(|l| l.starts_with(label)).expect(label);
        let value = line[label.len()..].trim();
        assert!(printed(value, &cli[key]), "{line}: {key} {}", cli[key]);
    }
    // The trajectory every second, 0 to 5 s, ends near the goal θ = (π/3, π/6).
    let samples: Vec<&str> = out.lines().filter(|l| l.starts_with("t = ")).collect();
    assert_eq!(samples.len(), 6, "{out}");
}

/// The rows of the matrix printed under `title` (`A (14 x 14):`).
fn matrix<'a>(out: &'a str, title: &str) -> Vec<Vec<&'a str>> {
    let mut lines = out.lines().skip_while(|l| !l.starts_with(title));
    let heading = lines
        .next()
        .unwrap_or_else(|| panic!("no {title} in {out}"));
    let rows: usize = heading[title.len()..]
        .trim_start_matches(" (")
        .split(" x ")
        .next()
        .and_then(|r| r.parse().ok())
        .expect("(R x C)");
    lines
        .take(rows)
        .map(|l| l.split_whitespace().collect())
        .collect()
}

#[test]
fn the_generated_functions_give_the_a_b_and_pi_u_of_toolconf_confidence() {
    let out = example("generated_functions", &[]);
    let tool = out.lines().next().and_then(|l| l.strip_prefix("tool: "));
    let params = parameters(tool.expect("tool: ..."));
    let cli = toolconf(&[
        "confidence",
        "--model",
        "panda",
        "--params",
        &params,
        "--task",
        "position",
    ]);
    for (title, key, shape) in [
        ("A", "a", (14, 14)),
        ("B", "b", (14, 7)),
        ("Pi^U", "pi_u", (7, 7)),
    ] {
        let m = matrix(&out, title);
        assert_eq!((m.len(), m[0].len()), shape, "{title}");
        for (i, row) in m.iter().enumerate() {
            for (j, text) in row.iter().enumerate() {
                let want = &cli[key][i][j];
                assert!(
                    printed(text, want),
                    "{title}[{i}][{j}] = {text}, not {want}"
                );
            }
        }
    }
    let logdet = out.lines().find_map(|l| l.strip_prefix("ln|Pi^U| = "));
    assert!(printed(logdet.expect("ln|Pi^U|"), &cli["logdet"]));
}

/// A hammer on the Panda's flange (the example's docstring gives the same).
const HAMMER: &str =
    "1.384,-0.0037,0.0037,0.1675,0.0357,0.0361,0.0022,7.7e-4,-7.1e-4,7.1e-4,0.055,0,0.3684";

#[test]
#[ignore = "needs the model libraries of `make loaded-models-test`"]
fn a_loaded_library_gives_the_numbers_of_its_built_in_model() {
    let folder = std::env::var_os("TOOLCONF_TEST_LIBRARIES")
        .expect("TOOLCONF_TEST_LIBRARIES is not set: run `make loaded-models-test`");
    let library = Path::new(&folder).join("panda");
    let entry = format!("panda_example={}", library.display());
    let out = example("load_model", &[&entry, HAMMER]);
    let mut lines = out.lines();
    let heading = lines.next().expect("a heading");
    assert!(heading.starts_with("panda_example: 7 joints;"), "{heading}");
    let mut tasks = 0;
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        let [task, "ln|Π^U|", logdet, "task", "error", task_error, "∫F", "dt", free_energy] =
            words[..]
        else {
            panic!("line {line:?}");
        };
        let cli = toolconf(&[
            "simulate", "--model", "panda", "--params", HAMMER, "--task", task,
        ]);
        for (text, key) in [
            (logdet, "logdet"),
            (task_error, "task_error"),
            (free_energy, "free_energy"),
        ] {
            assert!(
                printed(text, &cli[key]),
                "{task}: {key} {text}, not {}",
                cli[key]
            );
        }
        tasks += 1;
    }
    assert_eq!(tasks, 6, "the Panda's joint and tip tasks: {out}");
}
