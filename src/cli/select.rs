//! `toolconf select --task T --tools N --seed S [--models arm2,arm3] [--json]`.
//!
//! With the default `--models arm2` this is the 2-link selection of `toolconf::select`, output
//! unchanged; with other models the set is drawn and ranked by `toolconf::select::mixed`.

use rayon::prelude::*;
use serde_json::{json, Value};
use toolconf::mpc::{MpcEpisodeError, MpcMetrics};
use toolconf::rank::ModelTasks;
use toolconf::select::mixed::{draw_mixed_tools, evaluate_mixed, MixedObjective, MixedResult};
use toolconf::select::{
    choose_by_mpc_cost, draw_tools, evaluate, evaluate_mpc, Objective, ToolResult,
};
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{EpisodeOptions, Metrics, Plant};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::model::Arm2;
use toolconf_model::registry::ModelKind;
use toolconf_model::{Arm, Task, TaskKind};

use super::episode_args::{two_link_options, EpisodeArgs, MethodArgs, PlantArg, TaskArgs};
use super::output::{add_outcome, CliError};
use super::parse_model;
use super::simulate::MpcArgs;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    task: TaskArgs,
    /// How many random tools to draw (parameters uniform on [0.1, 0.6]).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    tools: u64,
    /// Seed of the tool stream: the same seed draws the same tools.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Models the tools are drawn from, comma-separated (any generated model; the list is in
    /// `--help`). Per tool a model is drawn, then its parameters; each tool runs its own model's
    /// version of the task.
    #[arg(long, value_delimiter = ',', default_value = "arm2", value_parser = parse_model,
          long_help = format!("Models the tools are drawn from, comma-separated: any of {}. Per tool a \
              model is drawn, then its parameters; each tool runs its own model's version of the task.",
              toolconf_generated::MODEL_NAMES.join(", ")))]
    models: Vec<ModelKind>,
    #[command(flatten)]
    episode: EpisodeArgs,
    #[command(flatten)]
    method: MethodArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also rank by J*, the cost the MPC baseline achieves on each tool (2-link tools only).
    #[arg(long)]
    mpc: bool,
    #[command(flatten)]
    mpc_options: MpcArgs,
}

fn tool_json(r: &ToolResult) -> Value {
    let mut v = json!({ "index": r.index, "arm": r.arm });
    add_outcome(&mut v, &r.logdet, &r.episode);
    v
}

/// What the 2-link selection found: each tool's episode and the tool each objective chooses,
/// and, with `--mpc`, each tool's MPC episode.
struct Selection {
    kind: TaskKind,
    options: EpisodeOptions,
    results: Vec<ToolResult>,
    /// With a task file, each tool's predicted cost, in the order of `results`; else empty.
    predictions: Vec<Predicted>,
    choices: Vec<(Objective, Option<usize>)>,
    mpc: Option<Vec<Result<MpcMetrics, MpcEpisodeError>>>,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    if args.models != [ModelKind::PAPER_ARM] {
        if args.mpc {
            return Err(toolconf_model::Error::Unsupported(
                "--mpc ranks 2-link tools only (the MPC baseline is built on the 2-link model); drop --models or --mpc".into(),
            )
            .into());
        }
        return run_mixed(args);
    }
    let selection = select(args)?;
    emit(
        args,
        selection.results.iter().map(|r| r.episode.as_ref().err()),
        || selection_json(args, &selection),
        || print_selection(args, &selection),
    )
}

/// A selection's output: the `--json` object `json` builds, or the table `table` prints; then
/// the run's outcome, [`every_tool_failed`] of the tools' episodes (each one's error, if any).
fn emit<'a, E: std::fmt::Display + 'a>(
    args: &Args,
    episodes: impl ExactSizeIterator<Item = Option<&'a E>>,
    json: impl FnOnce() -> Value,
    table: impl FnOnce(),
) -> Result<(), CliError> {
    let outcome = every_tool_failed(episodes.len(), episodes.flatten());
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&json()).expect("finite numbers")
        );
    } else {
        table();
    }
    outcome
}

/// Draws the tools and runs each one's episode (and MPC episode, with `--mpc`).
fn select(args: &Args) -> Result<Selection, CliError> {
    let (task, options) = two_link_task(args)?;
    let mpc_options = match args.mpc {
        true => Some(args.mpc_options.options(options.t_end, options.dt)?),
        false => None,
    };
    let tools = draw_tools(args.tools as usize, args.seed);
    let plant = Plant::from(args.episode.plant);
    let results = evaluate(&tools, &task, &options, plant);
    let choices = Objective::ALL
        .iter()
        .map(|o| (*o, o.choose(&results)))
        .collect();
    let mpc = mpc_options.map(|o| evaluate_mpc(&tools, &task, &options, &o, plant));
    let predictions = match args.task.task_file {
        Some(_) => two_link_predictions(&tools, &task, &options, plant),
        None => Vec::new(),
    };
    Ok(Selection {
        kind: task.kind,
        options,
        results,
        predictions,
        choices,
        mpc,
    })
}

/// Each 2-link tool's predicted cost, in parallel, in the tools' order. The prediction
/// linearises the controller's own model, the paper's: with the exact plant it would predict
/// another loop than the one simulated, so there it is `null` with that reason.
fn two_link_predictions(
    tools: &[Arm],
    task: &Task,
    options: &EpisodeOptions,
    plant: Plant,
) -> Vec<Predicted> {
    tools
        .par_iter()
        .map(|arm| match plant {
            Plant::Paper => toolconf_model::prediction::predict(arm, task, options),
            Plant::Exact => Err(toolconf_model::Error::Unsupported(
                "--plant exact: the prediction linearises the paper's model, not the exact plant"
                    .into(),
            )
            .into()),
        })
        .collect()
}

/// The `--json` object of a 2-link selection.
fn selection_json(args: &Args, s: &Selection) -> Value {
    let mut choice = serde_json::Map::new();
    for (o, c) in &s.choices {
        choice.insert(o.name().into(), json!(c));
    }
    let mut tools_json: Vec<Value> = s.results.iter().map(tool_json).collect();
    for (t, p) in tools_json.iter_mut().zip(&s.predictions) {
        super::prediction::add_prediction(t, p);
    }
    if let Some(mpc) = &s.mpc {
        choice.insert("mpc_cost".into(), json!(choose_by_mpc_cost(mpc)));
        for (t, r) in tools_json.iter_mut().zip(mpc) {
            match r {
                Ok(m) => t["mpc_cost"] = json!(m.cost_j),
                Err(e) => t["mpc_error"] = json!(e.to_string()),
            }
        }
    }
    json!({
        "task": s.kind,
        "seed": args.seed,
        "method": Method::from(args.method.method).describe(),
        "perturb": s.options.perturbation,
        "tools": tools_json,
        "choice": choice,
    })
}

/// The text output of a 2-link selection: the header, a row per tool, the MPC costs, the
/// choices.
fn print_selection(args: &Args, s: &Selection) {
    outln!(
        "task: {} (task {})    tools: {}    seed: {}",
        s.kind,
        s.kind.paper_index(),
        args.tools,
        args.seed
    );
    outln!(
        "integration method: {}",
        Method::from(args.method.method).describe()
    );
    let predicted = predicted_heading(&s.predictions);
    outln!(
        "{:>5}  {:>7} {:>7} {:>7} {:>7}  {:>12}{predicted} {:>14} {:>14} {:>14}",
        "tool",
        "m1",
        "m2",
        "l1",
        "l2",
        "ln|Pi^U|",
        "task error",
        "int F dt",
        "int J dt"
    );
    for (i, r) in s.results.iter().enumerate() {
        print_tool_row(r, s.predictions.get(i));
    }
    if let Some(mpc) = &s.mpc {
        for (i, r) in mpc.iter().enumerate() {
            match r {
                Ok(m) => outln!("tool {i:>3}  J* (MPC int J dt) {:>14.6e}", m.cost_j),
                Err(e) => outln!("tool {i:>3}  MPC failed: {e}"),
            }
        }
    }
    for (o, c) in &s.choices {
        match c {
            Some(i) => outln!("chosen by {:<12} tool {i}", o.name()),
            None => outln!("chosen by {:<12} none (every tool failed)", o.name()),
        }
    }
    if let Some(mpc) = &s.mpc {
        match choose_by_mpc_cost(mpc) {
            Some(i) => outln!("chosen by {:<12} tool {i}", "mpc_cost"),
            None => outln!(
                "chosen by {:<12} none (every MPC episode failed)",
                "mpc_cost"
            ),
        }
    }
}

/// The table's `predicted err` heading where the tools were predicted; none on the built-in
/// tasks, which have no prediction, so that their table is unchanged.
fn predicted_heading(predictions: &[Predicted]) -> String {
    match predictions.is_empty() {
        true => String::new(),
        false => format!(" {:>14}", "predicted err"),
    }
}

/// A 2-link tool's row: its parameters, ln|Π^U|, its predicted task error if it was predicted,
/// and the episode's metrics (or why it failed).
fn print_tool_row(r: &ToolResult, prediction: Option<&Predicted>) {
    let logdet = r
        .logdet
        .as_ref()
        .map_or("error".to_string(), |l| format!("{l:.6}"));
    let p = r.arm.params();
    let predicted = prediction.map_or(String::new(), |p| {
        format!(" {}", super::prediction::table_cell(p))
    });
    outln!(
        "{:>5}  {:>7.4} {:>7.4} {:>7.4} {:>7.4}  {:>12}{predicted} {}",
        r.index,
        p[0],
        p[1],
        p[2],
        p[3],
        logdet,
        metrics_cells(&r.episode)
    );
}

/// An episode's three metric columns (task error, ∫F dt, ∫J dt), or `failed: <why>`.
fn metrics_cells<E: std::fmt::Display>(episode: &Result<Metrics, E>) -> String {
    match episode {
        Ok(m) => format!(
            "{:>14.6e} {:>14.6e} {:>14.6e}",
            m.task_error, m.free_energy, m.cost_j
        ),
        Err(e) => format!("failed: {e}"),
    }
}

/// A batch succeeds if one tool's episode did (the others' failures are in its output); if
/// every one failed, the run failed (status 1), as `rank` says too.
fn every_tool_failed<'a, E: std::fmt::Display + 'a>(
    tools: usize,
    mut errors: impl Iterator<Item = &'a E>,
) -> Result<(), CliError> {
    let first = errors.next();
    let failed = usize::from(first.is_some()) + errors.count();
    match first {
        Some(e) if failed == tools => Err(CliError::Failed(format!(
            "every one of the {tools} tools failed; the first: {e}"
        ))),
        _ => Ok(()),
    }
}

/// The 2-link task and options: the paper's task with the flags, or the task file's with the
/// flags over its [episode].
fn two_link_task(args: &Args) -> Result<(Task, EpisodeOptions), CliError> {
    let spec = args.task.spec()?;
    if args.task.task_file.is_none() {
        let mut options = args.episode.options(false)?;
        options.integrator.method = args.method.method.into();
        return Ok((Task::paper(spec.kind), options));
    }
    let spec = with_flags(args, spec)?;
    let task = spec.task::<Arm2, 2, 4, 4, 6>()?;
    let why = "is not supported by select's 2-link tools; use rank with a tools file";
    let options = two_link_options(&spec.episode::<Arm2, 2, 4, 4, 6>()?, why)?;
    Ok((task, options))
}

fn with_flags(args: &Args, mut spec: TaskSpec) -> Result<TaskSpec, CliError> {
    args.episode.apply(&mut spec)?;
    spec.episode.method = Some(args.method.method.into());
    Ok(spec)
}

/// Every tool on the task file's task bound to its own model (the file's goals and
/// precisions must fit each model drawn).
fn evaluate_on_file(
    args: &Args,
    spec: TaskSpec,
    tools: &[toolconf_model::registry::AnyTool],
) -> Result<(Vec<MixedResult>, Vec<Predicted>), CliError> {
    if args.episode.plant != PlantArg::Paper {
        return Err(CliError::Usage(
            "--plant exact with --task-file and --models: draw arm2_exact tools instead".into(),
        ));
    }
    let tasks = ModelTasks::new(&with_flags(args, spec)?);
    for model in &args.models {
        tasks.check(*model)?;
    }
    Ok(tools
        .par_iter()
        .enumerate()
        .map(|(index, tool)| {
            let result = MixedResult {
                index,
                tool: *tool,
                logdet: tasks.logdet(tool),
                episode: tasks.simulate(tool),
            };
            (result, tasks.predict(tool))
        })
        .unzip())
}

/// A tool's predicted cost on a task file's task (`toolconf_model::prediction`), or why there is none.
type Predicted =
    Result<toolconf_model::prediction::Prediction, toolconf_model::prediction::PredictionError>;

fn mixed_tool_json(r: &MixedResult) -> Value {
    let params: serde_json::Map<String, Value> = r
        .tool
        .named_parameters()
        .into_iter()
        .map(|(name, value)| (name.to_string(), json!(value)))
        .collect();
    let mut v = json!({ "index": r.index, "model": r.model().name(), "arm": params });
    add_outcome(&mut v, &r.logdet, &r.episode);
    if r.logdet.is_ok() {
        v["logdet_per_joint"] = json!(r.logdet_per_joint());
    }
    v
}

/// What a selection over several models found: each tool's episode on its own model's task and
/// the tool each objective chooses.
struct MixedSelection {
    kind: TaskKind,
    options: EpisodeOptions,
    results: Vec<MixedResult>,
    /// With a task file, each tool's predicted cost, in the order of `results`; else empty.
    predictions: Vec<Predicted>,
    choices: Vec<(MixedObjective, Option<usize>)>,
}

/// Selection over tools of several models (each on its own model's paper-style task).
fn run_mixed(args: &Args) -> Result<(), CliError> {
    let selection = select_mixed(args)?;
    emit(
        args,
        selection.results.iter().map(|r| r.episode.as_ref().err()),
        || mixed_selection_json(args, &selection),
        || print_mixed_selection(args, &selection),
    )
}

/// Draws the tools of the models and runs each one's episode.
fn select_mixed(args: &Args) -> Result<MixedSelection, CliError> {
    let spec = args.task.spec()?;
    let kind = spec.kind;
    let mut options = args.episode.options(false)?;
    options.integrator.method = args.method.method.into();
    let tools = draw_mixed_tools(&args.models, args.tools as usize, args.seed)?;
    // With a task file, each tool's prediction too (in the JSON: the built-in tasks' output is
    // unchanged).
    let (results, predictions) = match args.task.task_file {
        None => (
            evaluate_mixed(&tools, kind, &options, args.episode.plant.into()),
            Vec::new(),
        ),
        Some(_) => evaluate_on_file(args, spec, &tools)?,
    };
    let choices = MixedObjective::ALL
        .iter()
        .map(|o| (*o, o.choose(&results)))
        .collect();
    Ok(MixedSelection {
        kind,
        options,
        results,
        predictions,
        choices,
    })
}

/// The names of `--models`, in their order.
fn model_names(args: &Args) -> Vec<&'static str> {
    args.models.iter().map(|m| m.name()).collect()
}

/// The `--json` object of a selection over several models.
fn mixed_selection_json(args: &Args, s: &MixedSelection) -> Value {
    let mut choice = serde_json::Map::new();
    for (o, c) in &s.choices {
        choice.insert(o.name().into(), json!(c));
    }
    json!({
        "task": s.kind,
        "seed": args.seed,
        "method": Method::from(args.method.method).describe(),
        "perturb": s.options.perturbation,
        "models": model_names(args),
        "tools": s
            .results
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let mut v = mixed_tool_json(r);
                if let Some(p) = s.predictions.get(i) {
                    super::prediction::add_prediction(&mut v, p);
                }
                v
            })
            .collect::<Vec<_>>(),
        "choice": choice,
    })
}

/// The text output of a selection over several models: the header, a row per tool (with a task
/// file, its predicted task error beside its confidence, as `rank`'s table), the choices (each
/// naming the chosen tool's model).
fn print_mixed_selection(args: &Args, s: &MixedSelection) {
    let models = model_names(args);
    outln!(
        "task: {} (task {})    tools: {}    seed: {}    models: {}",
        s.kind,
        s.kind.paper_index(),
        args.tools,
        args.seed,
        models.join(",")
    );
    outln!(
        "integration method: {}",
        Method::from(args.method.method).describe()
    );
    // The model column fits the longest name in this set (at least 10 wide).
    let w = models.iter().map(|m| m.len()).max().unwrap_or(0).max(10);
    let predicted = predicted_heading(&s.predictions);
    outln!(
        "{:>5}  {:<w$} {:>12} {:>12}{predicted}  {:>14} {:>14} {:>14}  parameters",
        "tool",
        "model",
        "ln|Pi^U|",
        "ln|Pi^U|/n",
        "task error",
        "int F dt",
        "int J dt"
    );
    for (i, r) in s.results.iter().enumerate() {
        print_mixed_tool_row(r, s.predictions.get(i), w);
    }
    for (o, c) in &s.choices {
        match c {
            Some(i) => outln!(
                "chosen by {:<21} tool {i} ({})",
                o.name(),
                s.results[*i].model().name()
            ),
            None => outln!("chosen by {:<21} none (every tool failed)", o.name()),
        }
    }
}

/// A tool's row in a selection over several models, the model column `w` wide, with its
/// predicted task error if it was predicted.
fn print_mixed_tool_row(r: &MixedResult, prediction: Option<&Predicted>, w: usize) {
    let (logdet, per_joint) = match (&r.logdet, r.logdet_per_joint()) {
        (Ok(l), Some(n)) => (format!("{l:.6}"), format!("{n:.6}")),
        _ => ("error".to_string(), "error".to_string()),
    };
    let params: Vec<String> = r
        .tool
        .named_parameters()
        .into_iter()
        .map(|(name, value)| format!("{name}={value:.4}"))
        .collect();
    let predicted = prediction.map_or(String::new(), |p| {
        format!(" {}", super::prediction::table_cell(p))
    });
    outln!(
        "{:>5}  {:<w$} {:>12} {:>12}{predicted}  {}  {}",
        r.index,
        r.model().name(),
        logdet,
        per_joint,
        metrics_cells(&r.episode),
        params.join(" ")
    );
}
