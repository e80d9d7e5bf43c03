//! Command-line front end: parses arguments, runs one subcommand, prints text or JSON.
//! Bad input is a message on stderr and exit status 2; a failed simulation exits with 1.

mod confidence;
mod design;
mod episode_args;
mod output;
mod rank;
mod reproduce;
mod select;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use toolconf::{Arm, TaskKind};

/// Confidence-aware decision-making and control for tool selection.
#[derive(Parser)]
#[command(name = "toolconf", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The linearised model (A, B), the task's sensitivities and the control confidence Π^U.
    Confidence(confidence::Args),
    /// One closed-loop episode of the active-inference controller: task error, ∫F dt, ∫J dt.
    Simulate(simulate::Args),
    /// Draw random tools, simulate each, and choose by ∫F, ∫J and confidence.
    Select(select::Args),
    /// Rank your own tools (a CSV or JSON file) on a built-in task or a task file.
    Rank(rank::Args),
    /// Design a tool: maximise control confidence under bounds and linear constraints.
    Design(design::Args),
    /// Run every experiment of the paper's Results section: CSVs, SVG figures, report.
    Reproduce(reproduce::Args),
}

pub(crate) fn parse_arm(s: &str) -> Result<Arm, String> {
    toolconf::arm::parse(s).map_err(|e| e.to_string())
}

pub(crate) fn parse_model(s: &str) -> Result<toolconf::model::mixed::ModelKind, String> {
    s.parse()
}

/// A tool of `model` from `--params P1,P2,…` in the model's parameter order.
pub(crate) fn tool_from_params(
    model: toolconf::model::mixed::ModelKind,
    text: &str,
) -> Result<toolconf::model::mixed::AnyTool, output::CliError> {
    let params = text
        .split(',')
        .map(|v| {
            v.trim().parse::<f64>().map_err(|_| {
                output::CliError::Usage(format!("--params {text}: '{v}' is not a number"))
            })
        })
        .collect::<Result<Vec<f64>, _>>()?;
    Ok(toolconf::model::mixed::AnyTool::new(model, &params)?)
}

pub(crate) fn parse_task(s: &str) -> Result<TaskKind, String> {
    toolconf::task::parse_task(s).map_err(|e| e.to_string())
}

pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Confidence(args) => confidence::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Select(args) => select::run(&args),
        Command::Rank(args) => rank::run(&args),
        Command::Reproduce(args) => reproduce::run(&args),
        Command::Design(args) => design::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("toolconf: error: {err}");
            ExitCode::from(err.exit_code())
        }
    }
}
