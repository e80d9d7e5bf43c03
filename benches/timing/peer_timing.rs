//! Times toolconf's episodes on one thread for `benches/peers/compare.py`.
//!
//! Reads tools as JSON on stdin — the output of `toolconf select --json` (its `tools[].arm`), or a
//! list of `{"m1", "m2", "l1", "l2"}` objects, or a list of `[m1, m2, l1, l2]` — and runs every
//! tool's episode for each task at the paper's defaults (`EpisodeOptions::default()`), on the
//! calling thread only. Each tool's episode is run once to warm up, then `--repeat` times; the
//! tool's time is the median of those runs. Prints one JSON object: per task the median over
//! tools of the per-episode time [µs], and per tool the time, right-hand-side and Jacobian
//! evaluations and task error. `--method` picks the integration method (`explicit`, `auto`,
//! `stiff`, `fast`; default: the library's, `EpisodeOptions::default()`), which the output names.
//!
//! ```sh
//! cargo run --release --example peer_timing -- [--tasks position,velocity,acceleration]
//!     [--repeat 21] [--limit N] [--method NAME] < tools.json
//! ```
//!
//! With `--repeat 1` it is also the small driver for profiling N episodes under callgrind.

mod common;

use std::io::Read;
use std::process::ExitCode;
use std::time::Instant;

use serde_json::{json, Value};
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{simulate, EpisodeOptions};
use toolconf_model::{Arm, Task, TaskKind};

fn arm_from(v: &Value) -> Result<Arm, String> {
    let v = v.get("arm").unwrap_or(v);
    let numbers: Vec<f64> = match v {
        Value::Array(a) => a.iter().filter_map(Value::as_f64).collect(),
        Value::Object(o) => ["m1", "m2", "l1", "l2"]
            .iter()
            .filter_map(|k| o.get(*k).and_then(Value::as_f64))
            .collect(),
        _ => Vec::new(),
    };
    match numbers[..] {
        [m1, m2, l1, l2] => Arm::new([m1, m2, l1, l2]).map_err(|e| e.to_string()),
        _ => Err(format!("not a tool: {v}")),
    }
}

struct Args {
    tasks: Vec<TaskKind>,
    repeat: usize,
    limit: Option<usize>,
    method: Method,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        tasks: TaskKind::ALL.to_vec(),
        repeat: 21,
        limit: None,
        method: EpisodeOptions::default().integrator.method,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--tasks" => args.tasks = common::task_kinds(&value()?)?,
            "--repeat" => args.repeat = common::repeat_count(&value()?)?,
            "--method" => args.method = value()?.parse().map_err(|e| format!("--method {e}"))?,
            "--limit" => args.limit = Some(value()?.parse().map_err(|e| format!("--limit: {e}"))?),
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    Ok(args)
}

fn run() -> Result<Value, String> {
    let args = parse_args()?;
    let mut input = String::new();
    std::io::stdin()
        .read_to_string(&mut input)
        .map_err(|e| e.to_string())?;
    let input: Value = serde_json::from_str(&input).map_err(|e| format!("stdin: {e}"))?;
    let list = input.get("tools").unwrap_or(&input);
    let mut tools = list
        .as_array()
        .ok_or("stdin: expected a list of tools or an object with `tools`")?
        .iter()
        .map(arm_from)
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(n) = args.limit {
        tools.truncate(n);
    }
    let mut options = EpisodeOptions::default();
    options.integrator.method = args.method;
    let mut out = serde_json::Map::new();
    out.insert("method".into(), json!(args.method.name()));
    for kind in &args.tasks {
        let task = Task::paper(*kind);
        let mut times = Vec::with_capacity(tools.len());
        let mut per_tool = Vec::with_capacity(tools.len());
        for arm in &tools {
            let first = simulate(arm, &task, &options).map_err(|e| e.to_string())?;
            let mut runs: Vec<f64> = (0..args.repeat)
                .map(|_| {
                    let start = Instant::now();
                    let m = simulate(std::hint::black_box(arm), &task, &options);
                    let elapsed = start.elapsed().as_secs_f64();
                    std::hint::black_box(m).ok();
                    elapsed * 1e6
                })
                .collect();
            let us = common::median(&mut runs);
            times.push(us);
            let m = first.metrics;
            per_tool.push(json!({
                "arm": arm,
                "us": us,
                "rhs_evals": m.rhs_evals,
                "jacobian_evals": m.jacobian_evals,
                "task_error": m.task_error,
            }));
        }
        out.insert(
            kind.name().into(),
            json!({
                "median_us": common::median(&mut times),
                "repeat": args.repeat,
                "tools": per_tool,
            }),
        );
    }
    Ok(Value::Object(out))
}

fn main() -> ExitCode {
    common::exit_code("peer_timing", run().map(|v| common::print_json(&v)))
}
