//! How well, and how cheaply, the linearised closed loop predicts the episode
//! (`toolconf_model::prediction`), beside ln|Π^U|: for one model and task, on random tools.
//!
//! Prints one JSON object: Spearman's ρ of the predicted and the simulated task error and ∫F dt,
//! ρ of ln|Π^U| and the same, the median |predicted/simulated − 1|, the recall of the best 1 %
//! by simulated ∫F when only the top 10 % by each criterion (lowest predicted ∫F, highest
//! ln|Π^U|) is simulated, the tools without a prediction and why, and the cost per tool of a
//! prediction, of ln|Π^U| and of an episode, each timed on the calling thread. With `--points
//! FILE`, writes each tool's initial distance to the goal and its predicted and simulated task
//! error as CSV (the figure of docs/prediction.md).
//!
//! ```sh
//! cargo run --release --example prediction -- --model panda --task examples/tasks/panda_touch_point.toml [--tools 1000] [--seed 7] [--timed 50] [--points FILE]
//! ```

use std::collections::BTreeMap;
use std::process::ExitCode;
use std::time::Instant;

use rayon::prelude::*;
use serde_json::json;
use toolconf::evaluation::Population;
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::{lookup, AnyTool};
use toolconf_stats::spearman;

struct Args {
    model: String,
    task: String,
    tools: usize,
    seed: u64,
    timed: usize,
    points: Option<String>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        model: String::new(),
        task: String::new(),
        tools: 1000,
        seed: 7,
        timed: 50,
        points: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let number = |v: &str| v.parse::<u64>().map_err(|e| format!("{flag} {v}: {e}"));
        match flag.as_str() {
            "--model" => a.model = value,
            "--task" => a.task = value,
            "--tools" => a.tools = number(&value)?.max(1) as usize,
            "--seed" => a.seed = number(&value)?,
            "--timed" => a.timed = number(&value)? as usize,
            "--points" => a.points = Some(value),
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    if a.model.is_empty() || a.task.is_empty() {
        return Err("give --model and --task".into());
    }
    Ok(a)
}

fn spec(task: &str) -> Result<TaskSpec, String> {
    match toolconf_model::task::parse_task(task) {
        Ok(kind) => Ok(TaskSpec::builtin(kind)),
        Err(_) => TaskSpec::from_file(std::path::Path::new(task)).map_err(|e| e.to_string()),
    }
}

/// Mean seconds per call of `f` over `tools`, on this thread.
fn time_per_tool<T>(tools: &[AnyTool], f: impl Fn(&AnyTool) -> T) -> f64 {
    let start = Instant::now();
    for t in tools {
        std::hint::black_box(f(t));
    }
    start.elapsed().as_secs_f64() / tools.len().max(1) as f64
}

/// The share of the best 1 % by `truth` (lowest) among the top 10 % by `score` (lowest).
fn recall(truth: &[f64], score: &[f64]) -> f64 {
    let order = |v: &[f64]| {
        let mut i: Vec<usize> = (0..v.len()).collect();
        i.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
        i
    };
    let best = ((truth.len() as f64) * 0.01).ceil() as usize;
    let kept = ((score.len() as f64) * 0.10).ceil() as usize;
    let kept: Vec<usize> = order(score).into_iter().take(kept).collect();
    let hits = order(truth)
        .into_iter()
        .take(best)
        .filter(|i| kept.contains(i))
        .count();
    hits as f64 / best as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// One tool's numbers: (ln|Π^U|, predicted TE, ∫F, simulated TE, ∫F, initial distance).
type Row = (f64, f64, f64, f64, f64, f64);

fn evaluate(tasks: &ModelTasks, tool: &AnyTool) -> Result<Row, String> {
    let logdet = tasks.logdet(tool).map_err(|e| e.to_string())?;
    let p = tasks.predict(tool).map_err(|e| e.reason())?;
    let s = tasks.simulate(tool).map_err(|e| format!("episode: {e}"))?;
    let system = tasks.linear_system(tool).map_err(|e| e.reason())?;
    let e = system
        .terms
        .iter()
        .find(|t| t.name == system.error_term)
        .expect("the error term is among the terms");
    let distance =
        e.c.iter()
            .zip(&e.offset)
            .zip(&e.goal)
            .map(|((row, o), g)| {
                let v: f64 = row.iter().zip(&system.z0).map(|(c, z)| c * z).sum::<f64>() + o - g;
                v * v
            })
            .sum::<f64>()
            .sqrt();
    Ok((
        logdet,
        p.task_error,
        p.free_energy,
        s.task_error,
        s.free_energy,
        distance,
    ))
}

fn run(a: &Args) -> Result<serde_json::Value, String> {
    // A model loaded at run time (TOOLCONF_MODEL_PATH, as the command line's), e.g. the xArm7.
    toolconf_model::loaded::load_environment()
        .map_err(|e| format!("{}: {e}", toolconf_model::loaded::ENVIRONMENT))?;
    let model = lookup(&a.model)?;
    let spec = spec(&a.task)?;
    let tasks = ModelTasks::new(&spec);
    tasks.check(model).map_err(|e| e.to_string())?;
    let population = Population::sample(model, a.tools, a.seed, &[])?;
    let tools = &population.tools;
    let results: Vec<Result<Row, String>> = tools.par_iter().map(|t| evaluate(&tasks, t)).collect();
    let mut failures = BTreeMap::<String, usize>::new();
    let rows: Vec<Row> = results
        .into_iter()
        .filter_map(|r| r.map_err(|e| *failures.entry(e).or_default() += 1).ok())
        .collect();
    let col = |f: fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<_>>();
    let (logdet, p_te, p_f) = (col(|r| r.0), col(|r| r.1), col(|r| r.2));
    let (s_te, s_f) = (col(|r| r.3), col(|r| r.4));
    // ρ is undefined (null) where a criterion is the same for every tool (ln|Π^U| on a task
    // whose Π^U does not depend on the tool).
    let rho = |x: &[f64], y: &[f64]| -> Result<Option<f64>, String> { Ok(spearman(x, y).ok()) };
    let neg_logdet: Vec<f64> = logdet.iter().map(|v| -v).collect();
    if let Some(path) = &a.points {
        let mut csv = String::from("distance,predicted_task_error,simulated_task_error\n");
        for r in &rows {
            csv += &format!("{},{},{}\n", r.5, r.1, r.3);
        }
        std::fs::write(path, csv).map_err(|e| format!("{path}: {e}"))?;
    }
    let timed = &tools[..a.timed.min(tools.len())];
    let ratio =
        |p: &[f64], s: &[f64]| median(p.iter().zip(s).map(|(p, s)| (p / s - 1.0).abs()).collect());
    Ok(json!({
        "model": model.name(), "task": a.task, "tools": tools.len(), "seed": a.seed,
        "predicted": rows.len(), "failures": failures,
        "rho_predicted_task_error": rho(&p_te, &s_te)?,
        "rho_predicted_free_energy": rho(&p_f, &s_f)?,
        "rho_logdet_task_error": rho(&logdet, &s_te)?,
        "rho_logdet_free_energy": rho(&logdet, &s_f)?,
        "median_relative_error_task_error": ratio(&p_te, &s_te),
        "median_relative_error_free_energy": ratio(&p_f, &s_f),
        "recall_predicted": recall(&s_f, &p_f),
        "recall_confidence": recall(&s_f, &neg_logdet),
        "us_per_prediction": 1e6 * time_per_tool(tools, |t| tasks.predict(t).ok()),
        "us_per_logdet": 1e6 * time_per_tool(tools, |t| tasks.logdet(t).ok()),
        "us_per_episode": 1e6 * time_per_tool(timed, |t| tasks.simulate(t).ok()),
    }))
}

fn main() -> ExitCode {
    match parse_args().and_then(|a| run(&a)) {
        Ok(v) => {
            println!("{v}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("prediction: {e}");
            ExitCode::from(2)
        }
    }
}
