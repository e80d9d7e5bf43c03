//! The crate's error type: every bad input names the value that is wrong.

use crate::display::Short;

/// Everything that can go wrong in toolconf, each naming the offending value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A tool parameter outside [`crate::validate::TOOL_PARAMETER`].
    #[error("invalid arm parameter {name} = {}: must be a number in {}", Short(*value), crate::validate::TOOL_PARAMETER)]
    InvalidParameter { name: &'static str, value: f64 },
    /// An arm given in text that is not four comma-separated numbers.
    #[error("invalid arm '{text}': expected M1,M2,L1,L2 (four comma-separated numbers), {reason}")]
    ArmSyntax { text: String, reason: String },
    /// A task name that is not one of `derive/tasks.toml`'s.
    #[error("unknown task '{0}': expected {names}", names = crate::task::task_choices())]
    UnknownTask(String),
    /// A goal outside [`crate::validate::JOINT_VALUE`].
    #[error("invalid goal {name} = {}: must be a number in {}", Short(*value), crate::validate::JOINT_VALUE)]
    InvalidGoal { name: String, value: f64 },
    /// A precision matrix that is not finite, symmetric and positive semi-definite.
    #[error("invalid precision {name}: {reason}")]
    InvalidPrecision { name: String, reason: String },
    /// A numeric option outside its domain.
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
    /// Π^U that is not positive definite for one tool, so it is no precision and ln|Π^U| is
    /// undefined. (A task whose precisions leave Π^U singular for every tool is refused up
    /// front: [`Error::ConfidenceRank`].)
    #[error("control confidence Π^U is not positive definite for this tool on this task (determinant {}): through this tool's sensitivities the task's precisions leave a direction of U without precision", Short(*determinant))]
    NotPositiveDefinite { determinant: f64 },
    /// A result that is not a finite number: the last line of defence at the output
    /// ([`crate::validate::finite_output`]), so that no NaN, inf or null is ever printed. The
    /// input ranges ([`crate::validate`]) are chosen so that it does not happen.
    #[error("{quantity} of {tool} is {}, not a finite number: the run cannot report it", Short(*value))]
    NonFiniteResult {
        quantity: &'static str,
        tool: String,
        value: f64,
    },
    /// Π^U so ill-conditioned for one tool that its determinant has no correct digit in double
    /// precision ([`crate::model::logdet_of`]).
    #[error("control confidence Π^U of this tool is too ill-conditioned for ln|Π^U| to be computed (its determinant is {} of the product of its diagonal, below 1e-10): the tool's parameters span too many decades", Short(*ratio))]
    IllConditioned { ratio: f64 },
    /// A task whose precisions cannot make Π^U = Σ SᵀPS + P^U positive definite for any tool:
    /// rank(SᵀPS) ≤ rank(P), so the ranks of the precisions it uses must add up to the joints.
    #[error("control confidence Π^U = Σ SᵀPS + P^U cannot be positive definite for any tool: the precisions the {kind} task uses ({}) have ranks adding up to {rank}, fewer than the {joints} joints; give them more weight (e.g. precision.u = 1.0)", precision_keys(*kind))]
    ConfidenceRank {
        kind: crate::TaskKind,
        rank: usize,
        joints: usize,
    },
}

/// `precision.theta_ddot, precision.u`: the task-file keys of the precisions `kind` uses.
fn precision_keys(kind: crate::TaskKind) -> String {
    let keys: Vec<String> = kind
        .terms()
        .iter()
        .map(|t| format!("precision.{}", t.name()))
        .collect();
    keys.join(", ")
}
