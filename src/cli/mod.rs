//! Command-line front end: parses arguments, runs one subcommand, prints text or JSON.
//!
//! The exit-code rule, the same for every subcommand: bad input (an argument, a file, an option
//! out of its range, a task whose Π^U cannot be positive definite) is refused before any work
//! starts, with one line on stderr and status 2; a run that fails (a simulation, every tool of a
//! batch, a write) ends with one line and status 1; a batch in which only some tools failed
//! succeeds (0) and reports them with the results.

/// `println!` that never panics: standard output through [`stdout::write`].
macro_rules! outln {
    () => {
        $crate::toolconf_cli::stdout::write(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::toolconf_cli::stdout::write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprintln!` that never panics: standard error through [`stdout::write_error`].
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::toolconf_cli::stdout::write_error(format_args!("{}\n", format_args!($($arg)*)))
    };
}

mod confidence;
mod design;
mod episode_args;
mod evaluate;
mod output;
mod prediction;
mod rank;
mod reproduce;
mod select;
mod simulate;
mod stdout;
mod tool;
mod tool_args;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use toolconf_messages::Clip;
use toolconf_model::{Arm, TaskKind};

/// Confidence-aware decision-making and control for tool selection.
#[derive(Parser)]
#[command(name = "toolconf", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Load a model library (the OUT folder of `make model`, or its .so) next to the built-in
    /// models, NAME=PATH to load it under another name; repeatable. TOOLCONF_MODEL_PATH
    /// (':'-separated) loads more. The library is native code run with your privileges: load
    /// only libraries you built (docs/reference/c-abi.md).
    #[arg(long = "model-path", global = true, value_name = "PATH")]
    model_path: Vec<String>,
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
    /// Run every experiment of the paper's Results section (CSVs, SVG figures, report); with
    /// --model, on any model, task and tools, with a verdict for each claim.
    Reproduce(reproduce::Args),
    /// A tool's row of a tools file from its own URDF: mass, centre of mass, inertia and tip
    /// in the flange frame.
    Tool(tool::Args),
}

pub(crate) fn parse_arm(s: &str) -> Result<Arm, String> {
    toolconf_model::arm::parse(s).map_err(|e| e.to_string())
}

pub(crate) fn parse_model(s: &str) -> Result<toolconf_model::registry::ModelKind, String> {
    s.parse()
}

/// A tool of `model` from `--params P1,P2,…` in the model's parameter order.
pub(crate) fn tool_from_params(
    model: toolconf_model::registry::ModelKind,
    text: &str,
) -> Result<toolconf_model::registry::AnyTool, output::CliError> {
    let params = text
        .split(',')
        .map(|v| {
            v.trim().parse::<f64>().map_err(|_| {
                let (text, v) = (Clip(text), Clip(v.trim()));
                output::CliError::Usage(format!("--params {text}: '{v}' is not a number"))
            })
        })
        .collect::<Result<Vec<f64>, _>>()?;
    let params = model.with_defaults(&params).unwrap_or(params);
    Ok(toolconf_model::registry::AnyTool::new(model, &params)?)
}

pub(crate) fn parse_task(s: &str) -> Result<TaskKind, String> {
    toolconf_model::task::parse_task(s).map_err(|e| e.to_string())
}

pub fn run() -> ExitCode {
    // Before the arguments are parsed: their model names may be a loaded library's.
    if let Err(e) = load_model_libraries() {
        errln!("toolconf: error: {e}");
        return ExitCode::from(2);
    }
    let cli = match parse() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    // Ctrl-C, SIGTERM or SIGHUP then keep the old output files and remove the temporaries; the
    // signals' default (the process ends, the temporaries stay) is all a failure here costs.
    let _ = toolconf_files::partial::remove_on_interrupt();
    if let Some(note) = toolconf::threads::cap_pool() {
        errln!("toolconf: note: {note}");
    }
    let result = match cli.command {
        Command::Confidence(args) => confidence::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Select(args) => select::run(&args),
        Command::Rank(args) => rank::run(&args),
        Command::Reproduce(args) => reproduce::run(&args),
        Command::Design(args) => design::run(&args),
        Command::Tool(args) => tool::run(&args),
    };
    let flushed = stdout::finish().map_err(output::CliError::Stdout);
    match result.and(flushed) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            errln!("toolconf: error: {err}");
            ExitCode::from(err.exit_code())
        }
    }
}

/// The arguments, or the exit code of a run that ends here: `--help` and `--version` (0, or 1
/// when they cannot be printed), a bad argument (2, one line on stderr). A negative number is
/// a value, not a flag (`--tools -1` is the value -1 of `--tools`, refused by its own check).
fn parse() -> Result<Cli, ExitCode> {
    let command = Cli::command().mut_subcommands(|sub| {
        sub.mut_args(|arg| {
            if arg.get_action().takes_values() {
                arg.allow_negative_numbers(true)
            } else {
                arg
            }
        })
    });
    let error = match command
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m))
    {
        Ok(cli) => return Ok(cli),
        Err(e) => e,
    };
    use clap::error::ErrorKind;
    match error.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            outln!("{}", error.to_string().trim_end());
            match stdout::finish() {
                Ok(()) => Err(ExitCode::SUCCESS),
                Err(e) => {
                    errln!("toolconf: error: {}", output::CliError::Stdout(e));
                    Err(ExitCode::from(1))
                }
            }
        }
        // `toolconf` alone: the list of subcommands is the answer.
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            errln!("{}", error.to_string().trim_end());
            Err(ExitCode::from(2))
        }
        _ => {
            errln!("toolconf: error: {}", one_line(&error.to_string()));
            Err(ExitCode::from(2))
        }
    }
}

/// Loads the model libraries `TOOLCONF_MODEL_PATH` names, then those of every `--model-path`
/// (found by a scan of the arguments ahead of clap, which parses model names with the models
/// there are), in order.
fn load_model_libraries() -> Result<(), String> {
    toolconf_model::loaded::load_environment()
        .map_err(|e| format!("{}: {e}", toolconf_model::loaded::ENVIRONMENT))?;
    let mut args = std::env::args_os().skip(1);
    while let Some(arg) = args.next() {
        if arg == "--" {
            break;
        }
        let value = if arg == "--model-path" {
            match args.next() {
                Some(v) => v,
                // clap names the missing value.
                None => break,
            }
        } else {
            match arg.to_str().and_then(|a| a.strip_prefix("--model-path=")) {
                Some(v) => v.into(),
                None => continue,
            }
        };
        let value = value.to_str().ok_or_else(|| {
            format!(
                "--model-path {}: is not valid UTF-8",
                Clip(&value.to_string_lossy())
            )
        })?;
        toolconf_model::loaded::load_entry(value).map_err(|e| format!("--model-path: {e}"))?;
    }
    Ok(())
}

/// The most characters of clap's message the one line keeps (it may repeat a long value).
const MAX_MESSAGE_CHARS: usize = 400;

/// clap's message as one line: its first paragraph and tips, without the usage and the pointer
/// to `--help`, at most [`MAX_MESSAGE_CHARS`] characters.
fn one_line(rendered: &str) -> String {
    let parts: Vec<&str> = rendered
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let line = parts.join("; ");
    let line = line.strip_prefix("error: ").unwrap_or(&line);
    let mut out: String = line.chars().take(MAX_MESSAGE_CHARS).collect();
    if line.chars().count() > MAX_MESSAGE_CHARS {
        out.push('…');
    }
    out.replace(['\n', '\r'], " ")
}
