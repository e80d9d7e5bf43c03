//! Result files: whole files written atomically ([`write_atomically`]) and CSV rows appended as
//! they are computed ([`csv::CsvWriter`]), for the command line, the experiments and the reports.

pub mod csv;

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

/// Writes a whole file or nothing: `X.partial` beside it, renamed into place.
pub fn write_atomically(path: &Path, contents: &str) -> Result<(), WriteError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".partial");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, contents).map_err(WriteError::at(&tmp))?;
    std::fs::rename(&tmp, path).map_err(WriteError::at(path))
}
