//! The core's error type: every bad input names the value that is wrong, without allocating
//! (names are `&'static str`, values `f64`). The runtime's `toolconf::Error` wraps it
//! transparently, so the command line prints these messages as they are.

/// What can go wrong building a tool, a task or a controller, or computing ln|Π^U|.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum Error {
    /// A tool parameter that is not a finite number > 0.
    #[error("invalid arm parameter {name} = {value}: must be a finite number > 0")]
    InvalidParameter { name: &'static str, value: f64 },
    /// A tool parameter outside its model's domain (a URDF tool's centre of mass beyond the
    /// stated bound; `generated::validity`), the domain in words. A parameter whose domain is
    /// "> 0" is an [`Error::InvalidParameter`].
    #[error("invalid tool parameter {name} = {value}: must be {domain}")]
    ParameterOutOfDomain {
        name: &'static str,
        value: f64,
        domain: &'static str,
    },
    /// A tool whose parameters break a constraint across them (c · p ≤ 0, e.g. the triangle
    /// inequality of a rigid body's principal moments), by `excess` = c · p > 0.
    #[error("invalid tool: {rule} does not hold (off by {excess:e})")]
    ToolConstraint { rule: &'static str, excess: f64 },
    /// A goal that is not finite.
    #[error("invalid goal {name} = {value}: must be finite")]
    InvalidGoal { name: &'static str, value: f64 },
    /// A precision matrix that is not finite, symmetric and positive semi-definite.
    #[error("invalid precision {name}: {problem}")]
    InvalidPrecision {
        name: &'static str,
        problem: PrecisionProblem,
    },
    /// A numeric option outside its domain (the learning rate γ, the control period).
    #[error("invalid {name} = {value}")]
    InvalidOption { name: &'static str, value: f64 },
    /// Π^U that is not positive definite, so it is no precision and ln|Π^U| is undefined.
    #[error("control confidence Π^U is not positive definite for this arm and task (determinant {determinant:e}); check the task's precisions")]
    NotPositiveDefinite { determinant: f64 },
}

/// Why a precision matrix is refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PrecisionProblem {
    /// An entry that is NaN or infinite, with its (row, column), counted from 0.
    #[error("has a non-finite entry: {value} at ({row}, {col})")]
    NonFinite { row: usize, col: usize, value: f64 },
    /// Two mirrored entries that differ by more than 1e-12 relative.
    #[error("is not symmetric ({upper} vs {lower})")]
    NotSymmetric { upper: f64, lower: f64 },
    /// A negative eigenvalue beyond rounding.
    #[error("is not positive semi-definite")]
    NotPositiveSemiDefinite,
}
