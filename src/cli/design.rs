//! `toolconf design --model M --task NAME|FILE --design FILE [--json] [--report DIR]
//! [--sweep 'LEFT <= A..B:K']`: which tool to build (src/design).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use toolconf::design::json::design_json;
use toolconf::design::solver::KKT_TOLERANCE;
use toolconf::design::sweep::{parse_sweep, run_sweep, Sweep, SweepPoint};
use toolconf::design::{design_with_progress, DesignError, DesignResult, Setting};
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::DesignSpec;
use toolconf_model::registry::ModelKind;
use toolconf_report::design::{parameters_text, write_report, ReportInput};

use super::output::{check_files, CliError, RunFiles};
use super::rank::task_spec;

#[derive(clap::Args)]
pub struct Args {
    /// The model of the tool to design (arm2, the paper's arm; arm2_exact, arm2_payload, arm3, msd).
    #[arg(long, default_value = "arm2")]
    model: String,
    /// The task: a built-in name (position, velocity, acceleration or 1, 2, 3) or a task file.
    #[arg(long)]
    task: String,
    /// The design file (TOML): bounds, constraints, fixed parameters, objective (see docs/reference/file-formats.md).
    #[arg(long)]
    design: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Write report.md and report.html (and the sweep's CSV and SVG) into this folder.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Trace best confidence against a budget: 'LEFT <= A..B:K' re-solves with K right sides.
    #[arg(long, allow_hyphen_values = true)]
    sweep: Option<String>,
}

impl From<DesignError> for CliError {
    fn from(e: DesignError) -> Self {
        match e {
            DesignError::Input(m) | DesignError::Infeasible(m) => CliError::Usage(m),
            DesignError::Failed(m) => CliError::Failed(m),
        }
    }
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let model: ModelKind = args
        .model
        .parse()
        .map_err(|e| CliError::Usage(format!("--model: {e}")))?;
    let task = task_spec(&args.task)?;
    let mut files = RunFiles::new();
    files.input("--design", &args.design);
    if !task.file.is_empty() {
        files.input("--task", std::path::Path::new(&args.task));
    }
    if let Some(dir) = &args.report {
        let report = toolconf_report::design::report_files(args.sweep.is_some());
        files.output_folder("--report", dir, report);
    }
    check_files(&files)?;
    let tasks = ModelTasks::new(&task);
    tasks.check(model)?;
    let names: Vec<&'static str> = model.parameter_names().to_vec();
    let spec = DesignSpec::from_file(&args.design, model).map_err(DesignError::from)?;
    let sweep = args
        .sweep
        .as_deref()
        .map(|s| parse_sweep(s, &names))
        .transpose()
        .map_err(CliError::Usage)?;
    let setting = Setting::new(model, &task, &tasks);
    let started = Instant::now();
    let counts = "draws of random tools, {msg} (eta {eta})";
    let bar = toolconf_report::progress::counting(
        std::io::stderr().is_terminal(),
        spec.search.samples as u64,
        counts,
    );
    let result = design_with_progress(&spec, &setting, &mut |s| {
        bar.set_length(s.max_draws);
        bar.set_position(s.drawn);
        bar.set_message(format!("{} of {} feasible", s.feasible, s.requested));
    })?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    result.check_finite(&names)?;
    warn_about(&result);
    let front = match &sweep {
        Some(s) => Some(run_sweep(&spec, &setting, s)?),
        None => None,
    };
    if let Some(dir) = &args.report {
        let input = ReportInput {
            command: &command_line(args, model),
            model: model.name(),
            task: &args.task,
            spec: &spec,
            result: &result,
            sweep: sweep.as_ref().zip(front.as_deref()),
            tasks: &tasks,
            model_kind: model,
        };
        write_report(dir, &input)?;
    }
    if args.json {
        let v = design_json(&spec, &result, model, &args.task, front.as_deref());
        outln!("{}", serde_json::to_string_pretty(&v).expect("JSON"));
    } else {
        print_text(&spec, &result, elapsed.as_secs_f64());
        if let (Some(s), Some(points)) = (&sweep, &front) {
            print_front(s, points, &names);
        }
    }
    Ok(())
}

/// The command that made a report, as its page shows it.
fn command_line(args: &Args, model: ModelKind) -> String {
    format!(
        "toolconf design --model {} --task {} --design {}{}",
        model,
        args.task,
        args.design.display(),
        args.sweep
            .as_ref()
            .map(|s| format!(" --sweep '{s}'"))
            .unwrap_or_default()
    )
}

/// The trade-off front of `--sweep`, a line per value of b.
fn print_front(sweep: &Sweep, points: &[SweepPoint], names: &[&str]) {
    outln!("\ntrade-off, {} b:", sweep.label);
    for p in points {
        match &p.outcome {
            Ok((params, logdet, _)) => outln!(
                "  b = {:<8} ln|Pi^U| = {logdet:.6}  {}",
                p.value,
                parameters_text(names, params)
            ),
            Err(e) => outln!("  b = {:<8} {e}", p.value),
        }
    }
}

/// What the result itself cannot say loudly enough, on stderr: an optimum that did not converge,
/// a random comparison that stopped short.
fn warn_about(r: &DesignResult) {
    let o = &r.confidence_optimum;
    if !o.converged() {
        errln!(
            "toolconf: warning: the confidence optimum did not converge (KKT residual {:.2e} > {:.0e} \
             after {} SQP iterations): the design is the best point found, not a proven maximum",
            o.kkt_residual,
            KKT_TOLERANCE,
            o.iterations
        );
    }
    let random = &r.random;
    if random.feasible < random.requested {
        errln!(
            "toolconf: warning: only {} of the {} random feasible tools asked for ([search] samples) \
             were found in {} draws from the box: the feasible set is a small part of it, and the \
             comparison uses those found",
            random.feasible,
            random.requested,
            random.drawn
        );
    }
}

/// The confidence optimum's full parameters (fixed ones in place).
fn spec_params(spec: &DesignSpec, o: &toolconf::design::solver::Optimum) -> Vec<f64> {
    toolconf::design::polytope::Polytope::new(spec).full(&o.x)
}

/// The predicted cost from the SQP's value: it maximised −ln(task error) or −∫F dt.
fn predicted_value(
    objective: toolconf_model::inputs::design_file::DesignObjective,
    value: f64,
) -> f64 {
    match objective {
        toolconf_model::inputs::design_file::DesignObjective::PredictedTaskError => (-value).exp(),
        _ => -value,
    }
}

fn print_text(spec: &DesignSpec, r: &DesignResult, seconds: f64) {
    let o = &r.confidence_optimum;
    outln!(
        "design ({}): {}",
        r.objective.name(),
        parameters_text(&spec.names, &r.params)
    );
    outln!("  ln|Pi^U| = {:.6}", r.logdet);
    if r.free_energy_evaluations > 0 {
        outln!(
            "  free-energy search: {} episodes from the confidence optimum, {} (ln|Pi^U| = {:.6})",
            r.free_energy_evaluations,
            parameters_text(&spec.names, &spec_params(spec, o)),
            o.value
        );
    }
    if let Some(p) = &r.predicted_optimum {
        outln!(
            "  predicted {}: {:.6e} (KKT residual {:.2e}, {} SQP iterations from start {})",
            match r.objective {
                toolconf_model::inputs::design_file::DesignObjective::PredictedTaskError =>
                    "task error",
                _ => "int F dt",
            },
            predicted_value(r.objective, p.value),
            p.kkt_residual,
            p.iterations,
            p.start
        );
    }
    outln!("  confidence optimum: KKT residual {:.2e}, {} SQP iterations from start {}, gradient vs central differences {:.1e}", o.kkt_residual, o.iterations, o.start, r.gradient_check);
    outln!("  time (design, random comparison and episodes): {seconds:.3} s");
    outln!(
        "best of {} random feasible tools ({} draws): ln|Pi^U| = {}",
        r.random.feasible,
        r.random.drawn,
        r.random
            .top
            .first()
            .map_or("-".into(), |b| format!("{:.6}", b.1))
    );
    outln!(
        "\n{:<10} {:>11} {:>14} {:>14} {:>14}  parameters",
        "tool",
        "ln|Pi^U|",
        "task error",
        "int F dt",
        format!("sens. dT={}", spec.search.perturbation)
    );
    for c in &r.checks {
        let cells = match &c.simulated {
            Ok(m) => format!(
                "{:>14.6e} {:>14.6e} {:>14.6e}",
                m.task_error, m.free_energy, m.sensitivity
            ),
            Err(e) => format!("episode failed: {e}"),
        };
        outln!(
            "{:<10} {:>11.6} {cells}  {}",
            c.label,
            c.logdet,
            parameters_text(&spec.names, &c.params)
        );
    }
    if let Some(note) = r.confidence_note() {
        outln!("note: {note}");
    }
}
