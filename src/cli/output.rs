//! Printing matrices as text and as JSON lists of rows.

use nalgebra::SMatrix;
use serde_json::Value;
pub use toolconf_files::run_files::RunFiles;

/// A matrix as a JSON list of rows.
pub fn matrix_rows<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> Value {
    Value::from(
        (0..R)
            .map(|i| (0..C).map(|j| m[(i, j)]).collect::<Vec<f64>>())
            .collect::<Vec<_>>(),
    )
}

/// A titled matrix, one row a line, in a width that keeps columns aligned.
pub fn print_matrix<const R: usize, const C: usize>(title: &str, m: &SMatrix<f64, R, C>) {
    outln!("{title}:");
    for i in 0..R {
        let row: Vec<String> = (0..C).map(|j| format!("{:>16.9e}", m[(i, j)])).collect();
        outln!("  [{}]", row.join(" "));
    }
}

/// Adds a tool's confidence and episode outcome to its JSON object: `logdet` (or
/// `logdet_error`), then `task_error`, `free_energy`, `cost_j`, `rhs_evals` and on a position task
/// `progress` (or `error`), the keys `select` and `rank` share.
pub fn add_outcome<E: std::fmt::Display, F: std::fmt::Display>(
    v: &mut Value,
    logdet: &Result<f64, E>,
    episode: &Result<toolconf_model::closed_loop::Metrics, F>,
) {
    match logdet {
        Ok(l) => v["logdet"] = Value::from(*l),
        Err(e) => v["logdet_error"] = Value::from(e.to_string()),
    }
    match episode {
        Ok(m) => {
            v["task_error"] = Value::from(m.task_error);
            v["free_energy"] = Value::from(m.free_energy);
            v["cost_j"] = Value::from(m.cost_j);
            v["rhs_evals"] = Value::from(m.rhs_evals);
            if let Some(p) = m.progress {
                v["progress"] = Value::from(p);
            }
        }
        Err(e) => v["error"] = Value::from(e.to_string()),
    }
}

/// What a command can fail with; `exit_code` maps bad input to 2 and failed work to 1.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    #[error(transparent)]
    Input(#[from] toolconf_model::Error),
    #[error(transparent)]
    Mpc(#[from] toolconf::mpc::MpcEpisodeError),
    #[error("cannot write {path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    TaskFile(#[from] toolconf_model::inputs::task_file::TaskFileError),
    #[error(transparent)]
    ToolsFile(#[from] toolconf_model::inputs::tools_file::ToolFileError),
    #[error(transparent)]
    Model(#[from] toolconf_model::model::ModelSimulationError),
    #[error(transparent)]
    Output(#[from] toolconf_report::experiments::ReproduceError),
    #[error(transparent)]
    Write(#[from] toolconf_files::WriteError),
    /// Bad input that is none of the above, in words.
    #[error("{0}")]
    Usage(String),
    /// A run that failed as a whole, in words.
    #[error("{0}")]
    Failed(String),
    /// Standard output could not be written (other than a closed pipe, which ends the process).
    #[error("cannot write to standard output: {0}")]
    Stdout(std::io::Error),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            // Valid input the arithmetic cannot answer: a failed run, not bad input.
            CliError::Input(e)
            | CliError::Mpc(toolconf::mpc::MpcEpisodeError::Input(e))
            | CliError::Model(toolconf_model::model::ModelSimulationError::Input(e))
                if e.is_failed_run() =>
            {
                1
            }
            CliError::Input(_)
            | CliError::Mpc(toolconf::mpc::MpcEpisodeError::Input(_))
            | CliError::Model(toolconf_model::model::ModelSimulationError::Input(_))
            | CliError::TaskFile(_)
            | CliError::ToolsFile(_)
            | CliError::Usage(_) => 2,
            CliError::Mpc(_)
            | CliError::Model(_)
            | CliError::Io { .. }
            | CliError::Output(_)
            | CliError::Write(_)
            | CliError::Failed(_)
            | CliError::Stdout(_) => 1,
        }
    }
}

/// Writes a whole file or nothing: a temporary file beside the target, renamed into place, so an
/// interrupted run never leaves a half-written file; a device or other non-regular file is
/// written in place, never replaced ([`toolconf_files::file`]).
pub fn write_atomically(path: &std::path::Path, contents: &str) -> Result<(), CliError> {
    toolconf_files::file::write_whole(path, contents.as_bytes()).map_err(|source| CliError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// A run's input and output files checked before any work ([`RunFiles::check`]): an output
/// that is a folder, a link to nothing or in a missing folder, that is an input, or that is
/// another output of the run, is bad input (status 2), not a failed run.
pub fn check_files(files: &RunFiles) -> Result<(), CliError> {
    files.check().map_err(CliError::Usage)
}
