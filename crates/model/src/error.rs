//! The crate's error type: every bad input names the value that is wrong.

use toolconf_messages::Short;

/// Everything that can go wrong in toolconf, each naming the offending value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A tool, task or controller the no_std core refuses (a parameter, goal, precision or
    /// learning rate out of its domain, Π^U not positive definite), with the core's message.
    #[error(transparent)]
    Core(#[from] toolconf_core::Error),
    /// An arm given in text that is not four comma-separated numbers.
    #[error("invalid arm '{text}': expected M1,M2,L1,L2 (four comma-separated numbers), {reason}")]
    ArmSyntax { text: String, reason: String },
    /// A task name that is not one of `derive/tasks.toml`'s.
    #[error("unknown task '{0}': expected {names}", names = crate::task::task_choices())]
    UnknownTask(String),
    /// A numeric option of the runtime outside its domain (episode, integrator, MPC).
    #[error("invalid {name} = {}", Short(*value))]
    InvalidOption { name: &'static str, value: f64 },
    /// A numeric option outside its documented range ([`crate::validate`]).
    #[error("invalid {name} = {}: must be a number in {range}", Short(*value))]
    OutOfRange {
        name: &'static str,
        value: f64,
        range: crate::validate::Range,
    },
    /// An episode whose output grid would have more points than can be kept in memory.
    #[error("episode too long: t_end = {} s at dt = {} s is {} output points, more than the {max} an episode may have; shorten t_end or enlarge dt", Short(*t_end), Short(*dt), Short(*points))]
    GridTooLarge {
        t_end: f64,
        dt: f64,
        points: f64,
        max: usize,
    },
    /// A tool given with the wrong number of parameters for its model.
    #[error("model {model} takes {expected} parameters ({names}), got {found}")]
    ParameterCount {
        model: &'static str,
        expected: usize,
        names: String,
        found: usize,
    },
    /// A combination of options that is not supported, with the reason.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A tool of a tools file that leaves its tip out, on a task that reads the tip: the file,
    /// the row and the missing columns.
    #[error("{file}, tool {row}: the {kind} task reads the tool's tip, and the row leaves out {columns} (the tip's offset in the flange frame, m)")]
    ToolWithoutTip {
        file: String,
        row: usize,
        kind: crate::TaskKind,
        columns: String,
    },
    /// A result that is not a finite number: the last line of defence at the output
    /// ([`crate::validate::finite_output`]), so that no NaN, inf or null is ever printed. The
    /// input ranges ([`crate::validate`]) are chosen so that it does not happen.
    #[error("{quantity} of {tool} is {}, not a finite number: the run cannot report it", Short(*value))]
    NonFiniteResult {
        quantity: &'static str,
        tool: String,
        value: f64,
    },
}

impl Error {
    /// Valid input the arithmetic cannot answer (a result that is not finite, Π^U too
    /// ill-conditioned): a failed run (status 1), not bad input.
    pub fn is_failed_run(&self) -> bool {
        matches!(
            self,
            Error::NonFiniteResult { .. }
                | Error::Core(toolconf_core::Error::IllConditioned { .. })
        )
    }
}
