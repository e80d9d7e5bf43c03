//! `toolconf select --task T --tools N --seed S [--json]`.

use serde_json::{json, Value};
use toolconf::select::{draw_tools, evaluate, Objective, ToolResult};
use toolconf::{Task, TaskKind};

use super::episode_args::EpisodeArgs;
use super::output::CliError;
use super::parse_task;

#[derive(clap::Args)]
pub struct Args {
    /// The task: position, velocity or acceleration (or 1, 2, 3).
    #[arg(long, value_parser = parse_task)]
    task: TaskKind,
    /// How many random tools to draw (parameters uniform on [0.1, 0.6]).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    tools: u64,
    /// Seed of the tool stream: the same seed draws the same tools.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    episode: EpisodeArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

fn tool_json(r: &ToolResult) -> Value {
    let mut v = json!({ "index": r.index, "arm": r.arm });
    match &r.logdet {
        Ok(l) => v["logdet"] = json!(l),
        Err(e) => v["logdet_error"] = json!(e.to_string()),
    }
    match &r.episode {
        Ok(m) => {
            v["task_error"] = json!(m.task_error);
            v["free_energy"] = json!(m.free_energy);
            v["cost_j"] = json!(m.cost_j);
            v["rhs_evals"] = json!(m.rhs_evals);
        }
        Err(e) => v["error"] = json!(e.to_string()),
    }
    v
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let task = Task::paper(args.task);
    let options = args.episode.options(false)?;
    let tools = draw_tools(args.tools as usize, args.seed);
    let results = evaluate(&tools, &task, &options);
    let choices: Vec<(Objective, Option<usize>)> = Objective::ALL
        .iter()
        .map(|o| (*o, o.choose(&results)))
        .collect();
    if args.json {
        let mut choice = serde_json::Map::new();
        for (o, c) in &choices {
            choice.insert(o.name().into(), json!(c));
        }
        let out = json!({
            "task": args.task,
            "seed": args.seed,
            "perturb": args.episode.perturbation,
            "tools": results.iter().map(tool_json).collect::<Vec<_>>(),
            "choice": choice,
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
        return Ok(());
    }
    println!(
        "task: {} (task {})    tools: {}    seed: {}",
        args.task,
        args.task.paper_index(),
        args.tools,
        args.seed
    );
    println!(
        "{:>5}  {:>7} {:>7} {:>7} {:>7}  {:>12} {:>14} {:>14} {:>14}",
        "tool", "m1", "m2", "l1", "l2", "ln|Pi^U|", "task error", "int F dt", "int J dt"
    );
    for r in &results {
        let logdet = r
            .logdet
            .as_ref()
            .map_or("error".to_string(), |l| format!("{l:.6}"));
        let metrics = match &r.episode {
            Ok(m) => format!(
                "{:>14.6e} {:>14.6e} {:>14.6e}",
                m.task_error, m.free_energy, m.cost_j
            ),
            Err(e) => format!("failed: {e}"),
        };
        println!(
            "{:>5}  {:>7.4} {:>7.4} {:>7.4} {:>7.4}  {:>12} {}",
            r.index,
            r.arm.m1(),
            r.arm.m2(),
            r.arm.l1(),
            r.arm.l2(),
            logdet,
            metrics
        );
    }
    for (o, c) in &choices {
        match c {
            Some(i) => println!("chosen by {:<12} tool {i}", o.name()),
            None => println!("chosen by {:<12} none (every tool failed)", o.name()),
        }
    }
    Ok(())
}
