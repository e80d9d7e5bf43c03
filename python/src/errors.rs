//! Rust errors as Python exceptions: bad input is `ValueError` (`TypeError` for a Python value
//! of the wrong type) with the command line's message; an output that cannot be allocated is
//! `MemoryError`; a failed episode is `toolconf.SimulationError` with the tool, the time and the
//! reason.

use pyo3::create_exception;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use toolconf_model::model::ModelSimulationError;

create_exception!(
    toolconf,
    SimulationError,
    PyRuntimeError,
    "An episode that failed: the integrator gave up or the state diverged.\n\n\
     Attributes: tool (str, e.g. 'arm2(m1=0.3 m2=0.4 l1=0.5 l2=0.2)'), time (float, s, or None \
     when the failure has no time) and reason (str)."
);

/// What a call can fail with, built without the GIL (inside `Python::detach`) and raised after.
#[derive(Debug)]
pub enum Failure {
    /// Bad input: the message the command line prints (after `toolconf: error: `).
    Input(String),
    /// A Python value of the wrong type (a complex or boolean array where numbers are expected).
    Type(String),
    /// An allocation sized by the input that failed, raised as `MemoryError` (an abort would
    /// take the interpreter down).
    Memory(String),
    /// A run that failed other than by an episode (a result that is not finite: the command
    /// line's status 1), raised as `RuntimeError`.
    Run(String),
    /// A Python exception that is not a failure of the input (`KeyboardInterrupt`), as it is.
    Raised(PyErr),
    /// A failed episode.
    Simulation {
        message: String,
        tool: String,
        time: Option<f64>,
        reason: String,
    },
}

impl Failure {
    pub fn input(e: impl std::fmt::Display) -> Self {
        Failure::Input(e.to_string())
    }

    /// A Python exception raised while reading an argument, prefixed with `context` (the
    /// argument's name): `MemoryError` and `TypeError` stay themselves, any other `Exception`
    /// is bad input (`ValueError`), and what is not an `Exception` passes through.
    pub fn python(context: &str, e: PyErr) -> Self {
        Python::attach(|py| {
            if !e.is_instance_of::<pyo3::exceptions::PyException>(py) {
                return Failure::Raised(e);
            }
            // The exception's own words: its type is the one raised, or said by the message.
            let words = e
                .value(py)
                .str()
                .map(|s| s.to_string())
                .unwrap_or_else(|_| e.to_string());
            let message = format!("{context}: {}", toolconf_messages::ClipMessage(&words));
            if e.is_instance_of::<PyMemoryError>(py) {
                Failure::Memory(message)
            } else if e.is_instance_of::<PyTypeError>(py) {
                Failure::Type(message)
            } else {
                Failure::Input(message)
            }
        })
    }

    /// A crate error: bad input, or a result that is not finite (a failed run).
    pub fn from_error(e: toolconf_model::Error) -> Self {
        if e.is_failed_run() {
            Failure::Run(e.to_string())
        } else {
            Failure::input(e)
        }
    }

    /// An episode's error: bad input stays bad input; the rest names the tool and the time.
    pub fn episode(e: ModelSimulationError) -> Self {
        let message = e.to_string();
        let time = e.time();
        match e {
            ModelSimulationError::Input(e) => Failure::input(e),
            ModelSimulationError::Integration { tool, source } => Failure::Simulation {
                message,
                tool,
                time,
                reason: source.to_string(),
            },
            ModelSimulationError::Diverged {
                tool, magnitude, ..
            } => Failure::Simulation {
                message,
                tool,
                time,
                reason: format!("diverged: |state| = {magnitude:e}"),
            },
        }
    }

    /// The Python exception.
    pub fn into_pyerr(self, py: Python<'_>) -> PyErr {
        match self {
            Failure::Input(message) => PyValueError::new_err(message),
            Failure::Type(message) => PyTypeError::new_err(message),
            Failure::Memory(message) => PyMemoryError::new_err(message),
            Failure::Raised(e) => e,
            Failure::Run(message) => PyRuntimeError::new_err(message),
            Failure::Simulation {
                message,
                tool,
                time,
                reason,
            } => {
                let err = SimulationError::new_err(message);
                let value = err.value(py);
                let attributes = [
                    value.setattr("tool", tool),
                    value.setattr("time", time),
                    value.setattr("reason", reason),
                ];
                match attributes.into_iter().find_map(Result::err) {
                    Some(e) => e,
                    None => err,
                }
            }
        }
    }
}

/// Runs `work` without the GIL (so other Python threads go on while rayon's threads compute) and
/// raises its failure.
pub fn detached<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Failure> + Send,
) -> PyResult<T> {
    py.detach(work).map_err(|f| f.into_pyerr(py))
}
