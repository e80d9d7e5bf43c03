//! `toolconf rank --tools FILE --task NAME|FILE [--screen K [--screen-by predicted|confidence]]
//! [--objective O] [--json] [--csv OUT] [--report DIR] [--skip-bad-rows]`: the user's tools on the user's task.
//!
//! The whole tools file is read and checked (and every tool's confidence computed) before any
//! output is created, so bad input leaves nothing half-written.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::{json, Map, Value};
use toolconf::evaluation::{barely_moved, ConfidenceCheck, PredictionCheck};
use toolconf::rank::{
    ranking, screen_file_with_validation, simulate_all, simulate_all_timed, unpredicted_note,
    Candidate, ConfidenceTiming, ModelTasks, RankedTool, Screen, ScreenBy, ScreenError,
    SimulationTiming, StageTimings,
};
use toolconf::select::Objective;
use toolconf_files::csv::{Cell, CsvWriter};
use toolconf_messages::Clip;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::registry::ModelKind;
use toolconf_model::TaskKind;
use toolconf_report::progress::{self, ProgressBar};
use toolconf_report::rank::{write_report, ReportInput};

use super::output::{add_outcome, check_files, CliError, RunFiles};

#[derive(clap::Args)]
pub struct Args {
    /// The tools: a CSV or JSON file, one tool per row (columns name, model, and the model's
    /// parameters, e.g. m1,m2,l1,l2; see docs/reference/file-formats.md).
    #[arg(long)]
    tools: PathBuf,
    /// The task: a built-in name or a task file.
    #[arg(long, help = format!("The task: a built-in name ({}) or a task file", toolconf_model::task::task_choices()))]
    task: String,
    /// Simulate only K tools, chosen without simulating (see --screen-by).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    screen: Option<u64>,
    /// With --screen: keep the K tools with the lowest predicted cost (predicted: ∫F dt, or ∫J dt
    /// with --objective cost-j, of the closed loop linearised at the equilibrium; a tool without
    /// a prediction comes last) or the K most confident (confidence: largest ln|Pi^U|). Default:
    /// predicted, or confidence with --objective confidence.
    #[arg(long, value_enum, requires = "screen")]
    screen_by: Option<ScreenByArg>,
    /// What to rank by: free-energy (the paper's ∫F dt), cost-j (∫J dt) or confidence (ln|Pi^U|).
    #[arg(long, value_enum, default_value_t = ObjectiveArg::FreeEnergy)]
    objective: ObjectiveArg,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Write one row per simulated tool to this CSV, in file order, as episodes finish.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write a report (report.md, report.html with the figures inline, SVGs) into this folder.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Report a bad row on stderr and go on without it, instead of stopping.
    #[arg(long)]
    skip_bad_rows: bool,
    /// With --screen: also simulate a uniform sample of N tools of the file, to check that
    /// confidence predicts the task error among them (the output says so when it does not);
    /// 0 for no check.
    #[arg(long, default_value_t = toolconf::evaluation::VALIDATION_TOOLS as u64,
          value_parser = clap::value_parser!(u64).range(0..=100_000))]
    validation: u64,
    #[command(flatten)]
    method: super::episode_args::MethodArgs,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum ObjectiveArg {
    FreeEnergy,
    CostJ,
    Confidence,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum ScreenByArg {
    Predicted,
    Confidence,
}

/// The screen's criterion: the one asked for, else the prediction of what the ranking minimises
/// (measured to keep the best tools where confidence does not: docs/explanation/prediction.md),
/// except when the ranking is by confidence, which the confidence screen keeps exactly.
fn screen_by(args: &Args) -> ScreenBy {
    let objective = Objective::from(args.objective);
    match (args.screen_by, objective) {
        (Some(ScreenByArg::Confidence), _) | (None, Objective::Confidence) => ScreenBy::Confidence,
        (Some(ScreenByArg::Predicted), _) | (None, _) => ScreenBy::Predicted(objective),
    }
}

impl From<ObjectiveArg> for Objective {
    fn from(o: ObjectiveArg) -> Self {
        match o {
            ObjectiveArg::FreeEnergy => Objective::FreeEnergy,
            ObjectiveArg::CostJ => Objective::CostJ,
            ObjectiveArg::Confidence => Objective::Confidence,
        }
    }
}

/// A built-in task name, else a task file (one that exists but cannot be read says why).
pub(crate) fn task_spec(task: &str) -> Result<TaskSpec, CliError> {
    if let Ok(kind) = task.parse::<TaskKind>() {
        return Ok(TaskSpec::builtin(kind));
    }
    if std::fs::metadata(task).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound) {
        return Err(CliError::Usage(format!(
            "--task {}: neither a built-in task ({}) nor an existing task file",
            Clip(task),
            toolconf_model::task::task_choices()
        )));
    }
    Ok(TaskSpec::from_file(Path::new(task))?)
}

/// The cheap stage ([`screen_file`]), skipped rows reported on stderr. Returns the screen and
/// the number of rows skipped.
fn screen_tools(args: &Args, tasks: &ModelTasks) -> Result<(Screen, usize), CliError> {
    let limit = args.screen.map(|k| k as usize);
    let validation = match limit {
        Some(_) => args.validation as usize,
        None => 0,
    };
    screen_file_with_validation(
        &args.tools,
        tasks,
        &args.task,
        (limit, validation, screen_by(args)),
        args.skip_bad_rows,
        |bad| errln!("toolconf: skipping {bad}"),
    )
    .map_err(|e| match e {
        ScreenError::File(e) => e.into(),
        ScreenError::Input(message) => CliError::Usage(message),
    })
}

fn progress(total: usize) -> ProgressBar {
    progress::episodes(std::io::stderr().is_terminal(), total as u64)
}

/// The parameter columns of the models present, in the models' order.
fn parameter_columns(candidates: &[Candidate]) -> Vec<&'static str> {
    let mut columns = Vec::new();
    for model in ModelKind::all() {
        if candidates.iter().any(|c| c.row.tool.model() == model) {
            for p in model.parameter_names() {
                if !columns.contains(p) {
                    columns.push(*p);
                }
            }
        }
    }
    columns
}

fn csv_cells(r: &RankedTool, columns: &[&str]) -> Vec<Cell> {
    let params = r.row.tool.named_parameters();
    let mut cells = vec![
        Cell::from(r.row.row),
        r.row.name.clone().map_or(Cell::Empty, Cell::from),
        Cell::from(r.row.tool.model().name()),
    ];
    for c in columns {
        cells.push(Cell::from(
            params.iter().find(|(n, _)| n == c).map(|(_, v)| *v),
        ));
    }
    cells.push(Cell::from(r.logdet.as_ref().ok().copied()));
    match &r.episode {
        Ok(m) => {
            for v in [m.task_error, m.free_energy, m.cost_j] {
                cells.push(Cell::from(v));
            }
            cells.push(Cell::from(m.rhs_evals));
            cells.push(Cell::from(m.progress));
            cells.push(Cell::Empty);
        }
        Err(e) => {
            cells.extend([
                Cell::Empty,
                Cell::Empty,
                Cell::Empty,
                Cell::Empty,
                Cell::Empty,
            ]);
            cells.push(Cell::from(e.to_string()));
        }
    }
    cells.extend(super::prediction::csv_cells(&r.prediction));
    cells
}

fn tool_json(rank: usize, r: &RankedTool) -> Value {
    let params: Map<String, Value> = r
        .row
        .tool
        .named_parameters()
        .into_iter()
        .map(|(n, v)| (n.to_string(), json!(v)))
        .collect();
    let mut v = json!({
        "rank": rank,
        "row": r.row.row,
        "name": r.row.name,
        "model": r.row.tool.model().name(),
        "parameters": params,
    });
    add_outcome(&mut v, &r.logdet, &r.episode);
    super::prediction::add_prediction(&mut v, &r.prediction);
    v
}

/// The widest the name column grows; a longer name runs past it.
const NAME_COLUMN: usize = 40;

fn print_table(results: &[RankedTool], order: &[usize]) {
    let name = |r: &RankedTool| r.row.name.clone().unwrap_or_else(|| "-".into());
    let w = results
        .iter()
        .map(|r| name(r).chars().count())
        .max()
        .unwrap_or(4)
        .clamp(4, NAME_COLUMN);
    // A position task (joint or tip) also shows how far each tool got towards its goal.
    let with_progress = results
        .iter()
        .any(|r| r.episode.as_ref().is_ok_and(|m| m.progress.is_some()));
    outln!(
        "{:>5} {:>6}  {:<w$} {:<10} {:>12} {:>14}  {:>14} {:>14} {:>14}{}  parameters",
        "rank",
        "row",
        "name",
        "model",
        "ln|Pi^U|",
        "predicted err",
        "task error",
        "int F dt",
        "int J dt",
        if with_progress {
            format!(" {:>9}", "progress")
        } else {
            String::new()
        }
    );
    for (k, &i) in order.iter().enumerate() {
        let r = &results[i];
        let logdet = r
            .logdet
            .as_ref()
            .map_or("error".into(), |l| format!("{l:.6}"));
        let metrics = match &r.episode {
            Ok(m) => format!(
                "{:>14.6e} {:>14.6e} {:>14.6e}{}",
                m.task_error,
                m.free_energy,
                m.cost_j,
                match (with_progress, m.progress) {
                    (true, Some(p)) => format!(" {p:>9.4}"),
                    (true, None) => format!(" {:>9}", "-"),
                    (false, _) => String::new(),
                }
            ),
            Err(e) => format!("failed: {e}"),
        };
        outln!(
            "{:>5} {:>6}  {:<w$} {:<10} {:>12} {}  {metrics}  {}",
            k + 1,
            r.row.row,
            name(r),
            r.row.tool.model().name(),
            logdet,
            super::prediction::table_cell(&r.prediction),
            r.parameters_text()
        );
    }
}

/// What the cheap stage counted, for the output.
struct Counts {
    read: usize,
    skipped: usize,
    without_confidence: usize,
    without_prediction: usize,
    first_prediction_error: Option<String>,
}

impl Counts {
    /// The screen's counts, with the bad rows skipped before it.
    fn of(screen: &Screen, skipped: usize) -> Self {
        Counts {
            read: screen.read,
            skipped,
            without_confidence: screen.without_confidence,
            without_prediction: screen.without_prediction,
            first_prediction_error: screen.first_prediction_error.clone(),
        }
    }
}

/// The files the run reads and writes, checked before anything is read or written.
fn check_run_files(args: &Args, spec: &TaskSpec) -> Result<(), CliError> {
    let mut files = RunFiles::new();
    files.input("--tools", &args.tools);
    if !spec.file.is_empty() {
        files.input("--task", Path::new(&args.task));
    }
    if let Some(path) = &args.csv {
        files.output_file("--csv", path);
    }
    if let Some(dir) = &args.report {
        files.output_folder("--report", dir, &toolconf_report::rank::REPORT_FILES);
    }
    check_files(&files)
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let mut spec = task_spec(&args.task)?;
    check_run_files(args, &spec)?;
    spec.episode.method = Some(args.method.method.into());
    let tasks = ModelTasks::new(&spec);
    let objective = Objective::from(args.objective);
    let started = Instant::now();
    let (screen, skipped) = screen_tools(args, &tasks)?;
    let counts = Counts::of(&screen, skipped);
    let sample = screen.validation_sample();
    let candidates = screen.finish();
    let confidence = ConfidenceTiming {
        tools: counts.read,
        wall: started.elapsed(),
    };
    if let Some(dir) = &args.report {
        toolconf_files::file::create_folder(dir).map_err(|source| CliError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let (results, simulation) = simulate_streaming(args, candidates, &tasks)?;
    let timing = StageTimings {
        confidence,
        simulation,
    };
    let order = ranking(&results, objective);
    let by = screen_by(args);
    let checks = (!sample.is_empty()).then(|| validation_checks(sample, &results, &tasks, by));
    let notes = notes(&spec, checks.as_ref(), by, &counts, &results);
    let ranked = Ranked {
        args,
        spec: &spec,
        objective,
        counts: &counts,
        results: &results,
        order: &order,
        timing: &timing,
    };
    print_ranking(ranked, checks.as_ref(), &notes);
    if let Some(dir) = &args.report {
        let command: Vec<String> = std::env::args().collect();
        let input = ReportInput {
            command: &command.join(" "),
            tools_file: &args.tools.display().to_string(),
            spec: &spec,
            tasks: &tasks,
            objective,
            read: counts.read,
            skipped: counts.skipped,
            screen: args.screen.map(|k| (k as usize, by)),
            results: &results,
            order: &order,
            timing: Some(timing),
            notes,
        };
        let files = write_report(dir, &input)?;
        if !args.json {
            outln!("report: {}", files[1].display());
        }
    }
    some_succeeded(&results)
}

/// A run whose every simulated tool failed is a failed run (status 1).
fn some_succeeded(results: &[RankedTool]) -> Result<(), CliError> {
    match results.iter().all(|r| r.episode.is_err()) {
        true => Err(CliError::Failed(format!(
            "every one of the {} simulated tools failed",
            results.len()
        ))),
        false => Ok(()),
    }
}

/// The expensive stage, each result written to `--csv` (file order) as its chunk finishes.
fn simulate_streaming(
    args: &Args,
    candidates: Vec<Candidate>,
    tasks: &ModelTasks,
) -> Result<(Vec<RankedTool>, SimulationTiming), CliError> {
    let columns = parameter_columns(&candidates);
    let mut csv = match &args.csv {
        Some(path) => {
            let mut header = vec!["row", "name", "model"];
            header.extend(&columns);
            header.extend([
                "logdet",
                "task_error",
                "free_energy",
                "cost_j",
                "rhs_evals",
                "progress",
                "error",
            ]);
            header.extend(super::prediction::CSV_COLUMNS);
            Some(CsvWriter::create(path, &header)?)
        }
        None => None,
    };
    let bar = progress(candidates.len());
    let (results, timing) = simulate_all_timed(candidates, tasks, |r| {
        bar.inc(1);
        match csv.as_mut() {
            Some(w) => w.row(csv_cells(r, &columns)),
            None => Ok(()),
        }
    })?;
    bar.finish_and_clear();
    if let Some(w) = csv {
        w.finish()?;
    }
    Ok((results, timing))
}

/// Both stages' wall times and throughput, as JSON (they vary from run to run).
fn timing_json(t: &StageTimings) -> Value {
    let (c, s) = (&t.confidence, &t.simulation);
    json!({
        "confidence_stage": {
            "tools": c.tools,
            "seconds": c.wall.as_secs_f64(),
            "tools_per_second": c.tools_per_second(),
            "ns_per_tool": c.ns_per_tool(),
        },
        "simulation_stage": {
            "episodes": s.episodes,
            "seconds": s.wall.as_secs_f64(),
            "threads": s.threads,
            "episodes_per_second": s.episodes_per_second(),
            "us_per_episode": s.us_per_episode(),
        },
    })
}

/// Both stages' wall times and throughput, one line each.
fn timing_text(t: &StageTimings) -> String {
    let (c, s) = (&t.confidence, &t.simulation);
    format!(
        "confidence stage: {} tools in {:.3} s ({:.0} tools/s, {:.0} ns per tool, reading the file included)\n\
         simulation stage: {} episodes in {:.3} s on {} thread{} ({:.0} episodes/s, {:.1} µs per episode)",
        c.tools,
        c.wall.as_secs_f64(),
        c.tools_per_second(),
        c.ns_per_tool(),
        s.episodes,
        s.wall.as_secs_f64(),
        s.threads,
        if s.threads == 1 { "" } else { "s" },
        s.episodes_per_second(),
        s.us_per_episode()
    )
}

/// Claim (a) on the validation sample, and with a screen by prediction the prediction's check
/// on the same tools: their task errors from the ranking's episodes where the screen kept them,
/// else simulated here.
fn validation_checks(
    sample: Vec<Candidate>,
    results: &[RankedTool],
    tasks: &ModelTasks,
    by: ScreenBy,
) -> (ConfidenceCheck, Option<PredictionCheck>) {
    let sampled = sample.len();
    let (known, extra): (Vec<Candidate>, Vec<Candidate>) = sample
        .into_iter()
        .partition(|c| results.iter().any(|r| r.row.row == c.row.row));
    let episodes = extra.len();
    let simulated = simulate_all(extra, tasks, |_| Ok::<(), ()>(())).unwrap_or_default();
    let tools: Vec<&RankedTool> = known
        .iter()
        .filter_map(|c| results.iter().find(|r| r.row.row == c.row.row))
        .chain(&simulated)
        .collect();
    let points = |x: &dyn Fn(&RankedTool) -> Option<f64>| -> Vec<(f64, f64)> {
        tools
            .iter()
            .filter_map(|r| Some((x(r)?, r.episode.as_ref().ok()?.task_error)))
            .collect()
    };
    let population = "from the tools file";
    let confidence = ConfidenceCheck::compute(
        &points(&|r| r.logdet.as_ref().ok().copied()),
        sampled,
        episodes,
        population,
    );
    let prediction = by.needs_prediction().then(|| {
        let without = tools.iter().filter(|r| r.prediction.is_err()).count();
        PredictionCheck::compute(
            &points(&|r| r.prediction.as_ref().ok().map(|p| p.task_error)),
            sampled,
            without,
            population,
        )
    });
    (confidence, prediction)
}

/// What the output and the report add in words: the screen's criterion does not predict the
/// task error (with a screen), some tools have no prediction (with a screen by prediction), or
/// the task barely moved the tools.
fn notes(
    spec: &TaskSpec,
    checks: Option<&(ConfidenceCheck, Option<PredictionCheck>)>,
    by: ScreenBy,
    counts: &Counts,
    results: &[RankedTool],
) -> Vec<String> {
    let progress: Vec<f64> = results
        .iter()
        .filter_map(|r| r.episode.as_ref().ok()?.progress)
        .collect();
    let check = checks.and_then(|(confidence, prediction)| match (by, prediction) {
        (ScreenBy::Predicted(_), Some(p)) => p.note(
            "the screen keeps the tools predicted cheapest, which need not be the best here; \
             screen by confidence, less, or not at all",
        ),
        _ => confidence.note(
            "the screen keeps the most confident tools, which need not be the best here; \
             screen less, or not at all",
        ),
    });
    let unpredicted = unpredicted_note(
        by,
        counts.without_prediction,
        counts.first_prediction_error.as_deref(),
    );
    check
        .into_iter()
        .chain(unpredicted)
        .chain(barely_moved(spec.kind, &progress))
        .collect()
}

/// What a ranking run's output (its JSON or its text) is written from.
#[derive(Clone, Copy)]
struct Ranked<'a> {
    args: &'a Args,
    spec: &'a TaskSpec,
    objective: Objective,
    counts: &'a Counts,
    results: &'a [RankedTool],
    order: &'a [usize],
    timing: &'a StageTimings,
}

/// The ranking on stdout: its JSON (with the validation checks and the notes) or its text
/// (with the notes).
fn print_ranking(
    ranked: Ranked,
    checks: Option<&(ConfidenceCheck, Option<PredictionCheck>)>,
    notes: &[String],
) {
    if ranked.args.json {
        let mut out = rank_json(ranked);
        if let Some((check, prediction)) = checks {
            out["confidence_check"] = check.json();
            if let Some(p) = prediction {
                out["prediction_check"] = p.json();
            }
        }
        out["notes"] = json!(notes);
        outln!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
    } else {
        print_text(ranked);
        for note in notes {
            outln!("note: {note}");
        }
    }
}

fn rank_json(r: Ranked) -> Value {
    let mut v = json!({
        "task": r.spec.kind,
        "task_file": (!r.spec.file.is_empty()).then_some(&r.spec.file),
        "tools_file": r.args.tools,
        "objective": r.objective.name(),
        "method": r.spec.episode.method.unwrap_or_default().describe(),
        "tools_read": r.counts.read,
        "skipped_rows": r.counts.skipped,
        "screen": r.args.screen,
        "without_confidence": r.counts.without_confidence,
        "simulated": r.results.len(),
        "timing": timing_json(r.timing),
        "tools": r.order
            .iter()
            .enumerate()
            .map(|(k, &i)| tool_json(k + 1, &r.results[i]))
            .collect::<Vec<_>>(),
        "goal": r.spec.tip_goal.kind_name(),
    });
    // Only with a screen, so that the output without one is unchanged.
    if r.args.screen.is_some() {
        v["screen_by"] = json!(screen_by(r.args).name());
        v["without_prediction"] = json!(r.counts.without_prediction);
    }
    v
}

/// What a screen by prediction minimises, in the table's words.
fn predicted_name(objective: Objective) -> &'static str {
    match objective {
        Objective::CostJ => "int J dt",
        Objective::FreeEnergy | Objective::Confidence => "int F dt",
    }
}

fn print_text(r: Ranked) {
    outln!(
        "tools: {}    task: {}    ranked by: {}",
        r.args.tools.display(),
        r.spec.label(),
        r.objective.name()
    );
    outln!(
        "integration method: {}",
        r.spec.episode.method.unwrap_or_default().describe()
    );
    let screened = r
        .args
        .screen
        .map_or(String::new(), |k| match screen_by(r.args) {
            ScreenBy::Confidence => format!(
                "    screened to the {k} most confident ({} without a confidence)",
                r.counts.without_confidence
            ),
            ScreenBy::Predicted(o) => format!(
            "    screened to the {k} with the lowest predicted {} ({} without a confidence, {} \
             without a prediction)",
            predicted_name(o),
            r.counts.without_confidence,
            r.counts.without_prediction
        ),
        });
    outln!(
        "read {} tools    skipped {} bad rows    simulated {}{screened}",
        r.counts.read,
        r.counts.skipped,
        r.results.len()
    );
    print_table(r.results, r.order);
    outln!("{}", timing_text(r.timing));
}
