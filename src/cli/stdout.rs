//! Standard output and standard error for every command, never a panic.
//!
//! `println!` panics when standard output cannot be written (`> /dev/full`: "failed printing to
//! stdout: No space left on device", status 101), and `eprintln!` when standard error cannot.
//! Here ([`outln!`](crate::outln)) the first write error on standard output is kept and the
//! rest of the output dropped; [`finish`], at the end of every command, turns it into the one
//! error line and status 1. A closed pipe (EPIPE) does not get here: SIGPIPE ends the process
//! first, as it does any Unix tool (src/main.rs). A line that cannot be written to standard
//! error ([`errln!`](crate::errln)) has nowhere else to go, and is dropped.

use std::fmt::Arguments;
use std::io::{self, Write};
use std::sync::Mutex;

/// The first error writing standard output, if any.
static FAILED: Mutex<Option<io::Error>> = Mutex::new(None);

/// Writes to standard output unless an earlier write failed.
pub fn write(args: Arguments) {
    let mut failed = FAILED
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if failed.is_none() {
        if let Err(e) = io::stdout().lock().write_fmt(args) {
            *failed = Some(e);
        }
    }
}

/// Flushes standard output; the first error writing it, if there was one.
pub fn finish() -> io::Result<()> {
    let mut failed = FAILED
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if failed.is_none() {
        if let Err(e) = io::stdout().lock().flush() {
            *failed = Some(e);
        }
    }
    failed.take().map_or(Ok(()), Err)
}

/// Writes to standard error, dropping what cannot be written.
pub fn write_error(args: Arguments) {
    let _ = io::stderr().lock().write_fmt(args);
}
