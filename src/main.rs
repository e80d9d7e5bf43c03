//! The `toolconf` command line.

use std::process::ExitCode;

fn main() -> ExitCode {
    toolconf_cli::run()
}

#[path = "cli/mod.rs"]
mod toolconf_cli;
