//! Result files, one rule for the command line, the experiments, the reports and `make crate`:
//! whole files written atomically ([`write_atomically`]) and CSV rows appended as they are
//! computed ([`csv::CsvWriter`]), both through a temporary file renamed over the target only when
//! whole, and only over a new path or a regular file ([`file`]); no output that is an input or
//! another output of the same run ([`run_files`]); an interrupted run keeps the old files
//! ([`partial`]); a generated folder replaced only while it holds only what was written into it
//! ([`folder`]). A file a user names is read whole and bounded, never blocking on a FIFO
//! ([`input`]).
//!
//! The lowest layer for file output, on no other toolconf crate: the runtime, the reports, the
//! command line and the Python package use it, and the renderer (`derive/render`, which
//! `make crate` runs) too.

pub mod csv;
pub mod file;
pub mod folder;
pub mod input;
pub mod partial;
pub mod run_files;
#[cfg(test)]
mod test_support;

use std::path::{Path, PathBuf};

/// A file that could not be written, with the reason.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct WriteError {
    pub path: PathBuf,
    pub source: std::io::Error,
}

impl WriteError {
    /// The error of an I/O failure on `path`, for `map_err`.
    pub fn at(path: &Path) -> impl FnOnce(std::io::Error) -> WriteError + '_ {
        move |source| WriteError {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Writes a whole file or nothing, without replacing what is not a regular file
/// ([`file::write_whole`]).
pub fn write_atomically(path: &Path, contents: &str) -> Result<(), WriteError> {
    file::write_whole(path, contents.as_bytes()).map_err(WriteError::at(path))
}
