//! `toolconf reproduce --model M --task T|--task-file F [--tools FILE | --sample N]`: the paper's
//! evaluation (Figs. 2–7) on any model, task and tool population, with the three verdicts
//! (`toolconf::evaluation`), written as the paper's reproduction is (`toolconf_report::evaluation`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::json;
use toolconf::evaluation::{
    check_population, evaluate, parse_box, planned_episodes, EvaluationError, Plan, Population,
    Setup, MAX_TOOLS,
};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::inputs::tools_file::read_tools;
use toolconf_model::registry::ModelKind;
use toolconf_report::evaluation::{write, RunInfo, FILES};

use super::output::{check_files, CliError, RunFiles};

/// The flags `reproduce` takes with `--model` only.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ModelArgs {
    /// Evaluate the paper's claims on this model (built in, or loaded with --model-path) instead
    /// of reproducing the paper: then give --task or --task-file, and --tools or --sample.
    #[arg(long, value_parser = super::parse_model)]
    pub model: Option<ModelKind>,
    /// With --model: a built-in task (position, velocity, acceleration, tip_position, …).
    #[arg(long, value_parser = super::parse_task, conflicts_with = "task_file")]
    pub task: Option<toolconf_model::TaskKind>,
    /// With --model: a task file; its [episode] perturbation is the experiments' ΔT.
    #[arg(long)]
    pub task_file: Option<PathBuf>,
    /// With --model: the population, a tools file of the model's tools.
    #[arg(long, conflicts_with = "sample")]
    pub tools: Option<PathBuf>,
    /// With --model: the population, N random tools from the model's sampling box (select
    /// --models M --tools N --seed S's tools). Default 300 (the paper's Fig. 2), 20 with --quick.
    #[arg(long)]
    pub sample: Option<u64>,
    /// With --sample: NAME=LO:HI replaces parameter NAME's interval of the sampling box
    /// (repeatable).
    #[arg(long = "box", value_name = "NAME=LO:HI")]
    pub sample_box: Vec<String>,
    /// Fig. 3: the most and least confident of the first N tools [default: 20].
    #[arg(long)]
    pub highlight_sample: Option<usize>,
    /// Fig. 5: the first N tools run at every sweep level [default: 100].
    #[arg(long)]
    pub sweep_tools: Option<usize>,
    /// Fig. 5: levels of the sweep, ΔT scaled from 1.25 to −1.25 [default: 11].
    #[arg(long)]
    pub sweep_levels: Option<usize>,
    /// Fig. 6: trials [default: 25].
    #[arg(long)]
    pub grid_trials: Option<usize>,
    /// Fig. 6: tools per trial [default: 5].
    #[arg(long)]
    pub grid_tools: Option<usize>,
    /// Fig. 7: trials [default: 50].
    #[arg(long)]
    pub trials: Option<usize>,
    /// Fig. 7: tools per trial [default: 10].
    #[arg(long)]
    pub trial_tools: Option<usize>,
    /// Bootstrap resamples per interval [default: 2000].
    #[arg(long)]
    pub resamples: Option<usize>,
    /// With --model: print the verdicts and the run's summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

impl ModelArgs {
    /// The first flag given that only `--model` takes.
    pub fn stray_flag(&self) -> Option<&'static str> {
        let given = [
            ("--task", self.task.is_some()),
            ("--task-file", self.task_file.is_some()),
            ("--tools", self.tools.is_some()),
            ("--sample", self.sample.is_some()),
            ("--box", !self.sample_box.is_empty()),
            ("--highlight-sample", self.highlight_sample.is_some()),
            ("--sweep-tools", self.sweep_tools.is_some()),
            ("--sweep-levels", self.sweep_levels.is_some()),
            ("--grid-trials", self.grid_trials.is_some()),
            ("--grid-tools", self.grid_tools.is_some()),
            ("--trials", self.trials.is_some()),
            ("--trial-tools", self.trial_tools.is_some()),
            ("--resamples", self.resamples.is_some()),
            ("--json", self.json),
        ];
        given.into_iter().find(|g| g.1).map(|g| g.0)
    }

    fn plan(&self, quick: bool) -> Result<Plan, CliError> {
        let base = if quick { Plan::quick() } else { Plan::paper() };
        let plan = Plan {
            highlight_sample: self.highlight_sample.unwrap_or(base.highlight_sample),
            sweep_tools: self.sweep_tools.unwrap_or(base.sweep_tools),
            sweep_levels: self.sweep_levels.unwrap_or(base.sweep_levels),
            grid_trials: self.grid_trials.unwrap_or(base.grid_trials),
            grid_tools: self.grid_tools.unwrap_or(base.grid_tools),
            trials: self.trials.unwrap_or(base.trials),
            trial_tools: self.trial_tools.unwrap_or(base.trial_tools),
            resamples: self.resamples.unwrap_or(base.resamples),
            ..base
        };
        plan.check()
            .map_err(|(flag, message)| CliError::Usage(format!("{flag}: {message}")))?;
        Ok(plan)
    }

    fn spec(&self, method: toolconf_integrators::Method) -> Result<TaskSpec, CliError> {
        let mut spec = match (&self.task_file, self.task) {
            (Some(path), _) => TaskSpec::from_file(path)?,
            (None, Some(kind)) => TaskSpec::builtin(kind),
            (None, None) => {
                return Err(CliError::Usage(
                    "--model: give the task, --task NAME or --task-file FILE".into(),
                ))
            }
        };
        spec.episode.method = Some(method);
        Ok(spec)
    }
}

/// The population: the tools file's rows, or `--sample N` (300 by default, 20 with `--quick`).
fn population(
    args: &ModelArgs,
    model: ModelKind,
    seed: u64,
    quick: bool,
) -> Result<Population, CliError> {
    if let Some(path) = &args.tools {
        if !args.sample_box.is_empty() {
            return Err(CliError::Usage(
                "--box: a sampling box is for --sample, not --tools".into(),
            ));
        }
        return tools_file(path, model);
    }
    let n = args.sample.unwrap_or(if quick { 20 } else { 300 });
    let n = usize::try_from(n).unwrap_or(usize::MAX);
    check_population(n, &format!("--sample {n}")).map_err(CliError::Usage)?;
    let boxes = args
        .sample_box
        .iter()
        .map(|b| parse_box(b))
        .collect::<Result<Vec<_>, _>>()
        .map_err(CliError::Usage)?;
    Population::sample(model, n, seed, &boxes).map_err(CliError::Usage)
}

/// A tools file's rows, at most [`MAX_TOOLS`], every one of `model`.
fn tools_file(path: &Path, model: ModelKind) -> Result<Population, CliError> {
    let source = toolconf_messages::ClipPath(&path.to_string_lossy()).to_string();
    let mut rows = Vec::new();
    read_tools(path, |row| {
        rows.push(row?);
        if rows.len() > MAX_TOOLS {
            return Err(toolconf_model::inputs::tools_file::ToolFileError {
                file: source.clone(),
                place: String::new(),
                message: format!("more than {MAX_TOOLS} tools, the most one evaluation takes"),
                row_level: false,
            });
        }
        Ok(())
    })?;
    check_population(rows.len(), &format!("--tools {source}")).map_err(CliError::Usage)?;
    Population::from_rows(rows, model, &source).map_err(CliError::Usage)
}

fn evaluation_error(e: EvaluationError) -> CliError {
    match e {
        EvaluationError::Input(m) => CliError::Usage(m),
        EvaluationError::Failed(m) => CliError::Failed(m),
    }
}

/// The evaluation, its files and its output.
pub fn run(
    args: &ModelArgs,
    model: ModelKind,
    common: &super::reproduce::Common,
) -> Result<(), CliError> {
    let plan = args.plan(common.quick)?;
    let spec = args.spec(common.method)?;
    let mut files = RunFiles::new();
    if let Some(path) = &args.tools {
        files.input("--tools", path);
    }
    if let Some(path) = &args.task_file {
        files.input("--task-file", path);
    }
    files.output_folder("--out", &common.out, &FILES);
    check_files(&files)?;
    let population = population(args, model, common.seed, common.quick)?;
    let setup = Setup::new(model, &spec, &plan).map_err(evaluation_error)?;
    let total = planned_episodes(&setup, population.len(), &plan);
    let bar = toolconf_report::progress::episodes(std::io::stderr().is_terminal(), total);
    let started = Instant::now();
    let evaluation = evaluate(setup, population, &plan, common.seed, &|n| bar.inc(n))
        .map_err(evaluation_error)?;
    bar.finish_and_clear();
    let info = RunInfo {
        command: &common.command,
        method: common.method.describe(),
        wall: started.elapsed(),
        threads: rayon::current_num_threads(),
    };
    let [md, html] = write(&common.out, &evaluation, &info)?;
    print(args, &evaluation, &info, [&md, &html]);
    Ok(())
}

fn print(
    args: &ModelArgs,
    e: &toolconf::evaluation::Evaluation,
    info: &RunInfo,
    report: [&Path; 2],
) {
    let secs = info.wall.as_secs_f64();
    if args.json {
        let mut out = e.summary_json();
        out["report"] = json!(report[0]);
        out["report_html"] = json!(report[1]);
        out["timing"] = json!({ "seconds": secs, "threads": info.threads });
        outln!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
        return;
    }
    outln!(
        "model: {}    task: {}    goal: {}",
        e.setup.model,
        e.setup.spec.label(),
        e.setup.spec.tip_goal.kind_name()
    );
    outln!("tools: {}", e.population.source);
    let dt: Vec<String> = e
        .setup
        .perturbation
        .values
        .iter()
        .map(|v| format!("{v}"))
        .collect();
    outln!(
        "ΔT per joint [N m]: [{}] ({})",
        dt.join(", "),
        e.setup.perturbation.source
    );
    for v in &e.verdicts {
        outln!(
            "{} {:<13} {}: {}",
            v.claim.label(),
            v.finding.words(),
            v.claim.key(),
            v.evidence
        );
    }
    if let Some(note) = &e.barely_moved {
        outln!("note: {note}");
    }
    let (episodes, _) = e.work();
    outln!(
        "{episodes} episodes in {secs:.2} s on {} thread(s) ({:.0} episodes/s)",
        info.threads,
        if secs > 0.0 {
            episodes as f64 / secs
        } else {
            0.0
        }
    );
    outln!("report: {}", report[0].display());
    outln!("report (HTML, figures inline): {}", report[1].display());
}
