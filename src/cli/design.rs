//! `toolconf design --model M --task NAME|FILE --design FILE [--json] [--report DIR]
//! [--sweep 'LEFT <= A..B:K']`: which tool to build (src/design).

use std::path::PathBuf;
use std::time::Instant;

use serde_json::{json, Map, Value};
use toolconf::design::file::DesignSpec;
use toolconf::design::sweep::{parse_sweep, run_sweep};
use toolconf::design::{design, DesignError, DesignResult, Setting};
use toolconf::model::mixed::ModelKind;
use toolconf::rank::ModelTasks;
use toolconf_report::design::{parameters_text, write_report, ReportInput};

use super::output::CliError;
use super::rank::task_spec;

#[derive(clap::Args)]
pub struct Args {
    /// The model of the tool to design (arm2, the paper's arm; arm2_exact, arm2_payload, arm3, msd).
    #[arg(long, default_value = "arm2")]
    model: String,
    /// The task: a built-in name (position, velocity, acceleration or 1, 2, 3) or a task file.
    #[arg(long)]
    task: String,
    /// The design file (TOML): bounds, constraints, fixed parameters, objective (see the README).
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
    let tasks = ModelTasks::new(&task);
    tasks.check(model)?;
    let names: Vec<&'static str> = model.parameter_names().to_vec();
    let spec = DesignSpec::from_file(&args.design, model)?;
    let sweep = args
        .sweep
        .as_deref()
        .map(|s| parse_sweep(s, &names))
        .transpose()
        .map_err(CliError::Usage)?;
    let setting = Setting {
        model,
        task: &task,
        tasks: &tasks,
    };
    let started = Instant::now();
    let result = design(&spec, &setting)?;
    let elapsed = started.elapsed();
    let front = match &sweep {
        Some(s) => Some(run_sweep(&spec, &setting, s)?),
        None => None,
    };
    if let Some(dir) = &args.report {
        let command = format!(
            "toolconf design --model {} --task {} --design {}{}",
            model,
            args.task,
            args.design.display(),
            args.sweep
                .as_ref()
                .map(|s| format!(" --sweep '{s}'"))
                .unwrap_or_default()
        );
        let input = ReportInput {
            command: &command,
            model: model.name(),
            task: &args.task,
            spec: &spec,
            result: &result,
            sweep: sweep.as_ref().zip(front.as_deref()),
        };
        write_report(dir, &input)?;
    }
    if args.json {
        let mut v = to_json(&spec, &result);
        v["model"] = Value::from(model.name());
        v["task"] = Value::from(args.task.as_str());
        if let Some(points) = &front {
            v["sweep"] = points
                .iter()
                .map(|p| match &p.outcome {
                    Ok((params, logdet, _)) => json!({"budget": p.value, "logdet": logdet, "params": named(&names, params)}),
                    Err(e) => json!({"budget": p.value, "error": e}),
                })
                .collect();
        }
        println!("{}", serde_json::to_string_pretty(&v).expect("JSON"));
    } else {
        print_text(&spec, &result, elapsed.as_secs_f64());
        if let (Some(s), Some(points)) = (&sweep, &front) {
            println!("\ntrade-off, {} b:", s.label);
            for p in points {
                match &p.outcome {
                    Ok((params, logdet, _)) => println!(
                        "  b = {:<8} ln|Pi^U| = {logdet:.6}  {}",
                        p.value,
                        parameters_text(&names, params)
                    ),
                    Err(e) => println!("  b = {:<8} {e}", p.value),
                }
            }
        }
    }
    Ok(())
}

fn named(names: &[&str], values: &[f64]) -> Value {
    Value::Object(
        names
            .iter()
            .zip(values)
            .map(|(n, v)| (n.to_string(), Value::from(*v)))
            .collect::<Map<_, _>>(),
    )
}

fn to_json(spec: &DesignSpec, r: &DesignResult) -> Value {
    let free: Vec<&str> = spec
        .names
        .iter()
        .zip(&spec.fixed)
        .filter(|(_, f)| f.is_none())
        .map(|(n, _)| *n)
        .collect();
    let o = &r.confidence_optimum;
    let verification: Vec<Value> = r
        .checks
        .iter()
        .map(|c| {
            let mut v = json!({"tool": c.label, "params": named(&spec.names, &c.params), "logdet": c.logdet});
            match &c.simulated {
                Ok(m) => {
                    v["task_error"] = Value::from(m.task_error);
                    v["free_energy"] = Value::from(m.free_energy);
                    v["task_error_perturbed"] = Value::from(m.task_error_perturbed);
                    v["sensitivity"] = Value::from(m.sensitivity);
                }
                Err(e) => v["error"] = Value::from(e.as_str()),
            }
            v
        })
        .collect();
    let best = r.random.top.first();
    json!({
        "objective": r.objective.name(),
        "params": named(&spec.names, &r.params),
        "logdet": r.logdet,
        "confidence_optimum": {"params": named(&spec.names, &spec_params(spec, o)), "logdet": o.value},
        "gradient": named(&free, &o.gradient),
        "gradient_check": r.gradient_check,
        "kkt_residual": o.kkt_residual,
        "iterations": o.iterations,
        "start": o.start,
        "free_energy_simulations": r.free_energy_evaluations,
        "perturbation": spec.search.perturbation,
        "random": {
            "requested": r.random.requested,
            "feasible": r.random.feasible,
            "drawn": r.random.drawn,
            "best_logdet": best.map(|b| b.1),
        },
        "verification": verification,
    })
}

/// The confidence optimum's full parameters (fixed ones in place).
fn spec_params(spec: &DesignSpec, o: &toolconf::design::solver::Optimum) -> Vec<f64> {
    toolconf::design::polytope::Polytope::new(spec).full(&o.x)
}

fn print_text(spec: &DesignSpec, r: &DesignResult, seconds: f64) {
    let o = &r.confidence_optimum;
    println!(
        "design ({}): {}",
        r.objective.name(),
        parameters_text(&spec.names, &r.params)
    );
    println!("  ln|Pi^U| = {:.6}", r.logdet);
    if r.free_energy_evaluations > 0 {
        println!(
            "  free-energy search: {} episodes from the confidence optimum, {} (ln|Pi^U| = {:.6})",
            r.free_energy_evaluations,
            parameters_text(&spec.names, &spec_params(spec, o)),
            o.value
        );
    }
    println!("  confidence optimum: KKT residual {:.2e}, {} SQP iterations from start {}, gradient vs central differences {:.1e}", o.kkt_residual, o.iterations, o.start, r.gradient_check);
    println!("  time (design, random comparison and episodes): {seconds:.3} s");
    println!(
        "best of {} random feasible tools ({} draws): ln|Pi^U| = {}",
        r.random.feasible,
        r.random.drawn,
        r.random
            .top
            .first()
            .map_or("-".into(), |b| format!("{:.6}", b.1))
    );
    println!(
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
        println!(
            "{:<10} {:>11.6} {cells}  {}",
            c.label,
            c.logdet,
            parameters_text(&spec.names, &c.params)
        );
    }
}
