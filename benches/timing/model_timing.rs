//! Times toolconf's episodes of any model's tools on one thread, for benches/peers/urdf_peers.py.
//!
//! Reads a tools file (`toolconf rank`'s CSV or JSON: examples/tools/panda_tools.csv, or one the
//! peer script writes) and a task (a built-in name or a task file), and runs every tool's episode
//! through the model-generic runtime (`rank::ModelTasks`, what `toolconf rank` simulates) on the
//! calling thread: once to warm up, then `--repeat` times; the tool's time is the median of those
//! runs. Prints one JSON object with, per tool, its row, the time [µs], the right-hand-side and
//! Jacobian evaluations and the metrics.
//!
//! ```sh
//! cargo run --release --example model_timing -- --tools FILE --task NAME|FILE [--repeat 11] [--method fast]
//! ```

mod common;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use serde_json::{json, Value};
use toolconf::rank::ModelTasks;
use toolconf_integrators::Method;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::{read_tools, ToolRow};

struct Args {
    tools: PathBuf,
    task: String,
    repeat: usize,
    method: Option<Method>,
}

fn parse_args() -> Result<Args, String> {
    let (mut tools, mut task, mut repeat, mut method) = (None, None, 11, None);
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--tools" => tools = Some(PathBuf::from(value()?)),
            "--task" => task = Some(value()?),
            "--repeat" => repeat = common::repeat_count(&value()?)?,
            "--method" => method = Some(value()?.parse().map_err(|e| format!("--method {e}"))?),
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    Ok(Args {
        tools: tools.ok_or("give --tools FILE")?,
        task: task.ok_or("give --task NAME|FILE")?,
        repeat,
        method,
    })
}

fn run() -> Result<Value, String> {
    let args = parse_args()?;
    let mut spec = match args.task.parse() {
        Ok(kind) => TaskSpec::builtin(kind),
        Err(_) => {
            TaskSpec::from_file(std::path::Path::new(&args.task)).map_err(|e| e.to_string())?
        }
    };
    spec.episode.method = args.method.or(Some(Method::Fast));
    let tasks = ModelTasks::new(&spec);
    let mut rows: Vec<ToolRow> = Vec::new();
    read_tools(&args.tools, |row| {
        rows.push(row?);
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    let mut per_tool = Vec::with_capacity(rows.len());
    for row in &rows {
        tasks.check(row.tool.model()).map_err(|e| e.to_string())?;
        let first = tasks.simulate(&row.tool).map_err(|e| e.to_string())?;
        let mut runs: Vec<f64> = (0..args.repeat)
            .map(|_| {
                let start = Instant::now();
                let m = tasks.simulate(std::hint::black_box(&row.tool));
                let elapsed = start.elapsed().as_secs_f64();
                std::hint::black_box(m).ok();
                elapsed * 1e6
            })
            .collect();
        per_tool.push(json!({
            "row": row.row,
            "model": row.tool.model().name(),
            "us": common::median(&mut runs),
            "rhs_evals": first.rhs_evals,
            "jacobian_evals": first.jacobian_evals,
            "task_error": first.task_error,
            "free_energy": first.free_energy,
            "cost_j": first.cost_j,
            "logdet": first.logdet,
        }));
    }
    Ok(json!({
        "method": spec.episode.method.unwrap_or_default().name(),
        "repeat": args.repeat,
        "tools": per_tool,
    }))
}

fn main() -> ExitCode {
    common::exit_code("model_timing", run().map(|v| common::print_json(&v)))
}
