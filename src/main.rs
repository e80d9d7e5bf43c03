//! The `toolconf` command line.

use std::process::ExitCode;

fn main() -> ExitCode {
    default_sigpipe();
    toolconf_cli::run()
}

/// Output piped into a reader that stops early (`toolconf rank … | head`) ends the process as it
/// does any Unix tool, instead of a panic in `println!`: Rust ignores SIGPIPE by default.
fn default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; it only restores the
    // signal's default disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[path = "cli/mod.rs"]
mod toolconf_cli;
