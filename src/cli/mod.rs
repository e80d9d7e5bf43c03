//! Command-line front end: parses arguments, runs one subcommand, prints text or JSON.
//! Bad input is a message on stderr and exit status 2.

mod confidence;
mod output;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
}

pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Confidence(args) => confidence::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("toolconf: error: {err}");
            ExitCode::from(2)
        }
    }
}
