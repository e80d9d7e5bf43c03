//! The core's error type: every bad input names the value that is wrong, without allocating
//! (names are `&'static str`, values `f64`, numbers shown by [`Short`]). The runtime's
//! `toolconf_model::Error` wraps it transparently, so the command line and the Python package print
//! these messages as they are.

use core::fmt;

use crate::display::Short;
use crate::validate::{Range, PRECISION_ENTRY, TOOL_PARAMETER};
use crate::TaskKind;

/// What can go wrong building a tool, a task or a controller, or computing ln|Π^U|.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum Error {
    /// A tool parameter of a "> 0" domain (a mass, a length, a principal moment) outside
    /// [`TOOL_PARAMETER`], where the generated arithmetic is known to stay finite.
    #[error("invalid arm parameter {name} = {}: must be a number in {}", Short(*value), TOOL_PARAMETER)]
    InvalidParameter { name: &'static str, value: f64 },
    /// A tool parameter outside its model's domain (a URDF tool's centre of mass beyond the
    /// stated bound; `generated::validity`), the domain in words. A parameter whose domain is
    /// "> 0" is an [`Error::InvalidParameter`].
    #[error("invalid tool parameter {name} = {}: must be {domain}", Short(*value))]
    ParameterOutOfDomain {
        name: &'static str,
        value: f64,
        domain: &'static str,
    },
    /// A tool whose parameters break a constraint across them (c · p ≤ 0, e.g. the triangle
    /// inequality of a rigid body's principal moments), by `excess` = c · p > 0.
    #[error("invalid tool: {rule} does not hold (off by {excess:.2e})")]
    ToolConstraint { rule: &'static str, excess: f64 },
    /// A goal of `term` outside its range ([`crate::validate::goal_range`]).
    #[error("invalid goal {term}_g = {}: must be a number in {range}", Short(*value))]
    InvalidGoal {
        term: crate::generated::Term,
        value: f64,
        range: Range,
    },
    /// A precision matrix of `term` that is not in range, symmetric and positive semi-definite.
    #[error("invalid precision P_{term}: {problem}")]
    InvalidPrecision {
        term: crate::generated::Term,
        problem: PrecisionProblem,
    },
    /// A numeric option outside its domain (the learning rate γ, the control period).
    #[error("invalid {name} = {}", Short(*value))]
    InvalidOption { name: &'static str, value: f64 },
    /// A numeric option of the on-robot controller outside its documented range
    /// ([`crate::validate`]: the learning rate, the control rate, the initial torque).
    #[error("invalid {name} = {}: must be a number in {range}", Short(*value))]
    OptionOutOfRange {
        name: &'static str,
        value: f64,
        range: Range,
    },
    /// Π^U that is not positive definite for one tool, so it is no precision and ln|Π^U| is
    /// undefined. (A task whose precisions leave Π^U singular for every tool is refused up
    /// front: [`Error::ConfidenceRank`].)
    #[error("control confidence Π^U is not positive definite for this tool on this task (determinant {}): through this tool's sensitivities the task's precisions leave a direction of U without precision", Short(*determinant))]
    NotPositiveDefinite { determinant: f64 },
    /// Π^U so ill-conditioned for one tool that its determinant has no correct digit in double
    /// precision ([`crate::logdet_of`]).
    #[error("control confidence Π^U of this tool is too ill-conditioned for ln|Π^U| to be computed (its determinant is {} of the product of its diagonal, below 1e-10): the tool's parameters span too many decades", Short(*ratio))]
    IllConditioned { ratio: f64 },
    /// A task whose precisions cannot make Π^U = Σ SᵀPS + P^U positive definite for any tool:
    /// rank(SᵀPS) ≤ rank(P), so the ranks of the precisions it uses must add up to the joints.
    #[error("control confidence Π^U = Σ SᵀPS + P^U cannot be positive definite for any tool: the precisions the {kind} task uses ({}) have ranks adding up to {rank}, fewer than the {joints} joints; give them more weight (e.g. precision.u = 1.0)", PrecisionKeys(*kind))]
    ConfidenceRank {
        kind: TaskKind,
        rank: usize,
        joints: usize,
    },
    /// A task on the tool's tip for a model whose description gives no tip.
    #[error("the {kind} task reads the tool's tip, and model {model} has none (its description gives no [tip])")]
    NoTip { kind: TaskKind, model: &'static str },
}

/// Why a precision matrix is refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PrecisionProblem {
    /// An entry outside [`PRECISION_ENTRY`] (so also NaN or infinite).
    #[error("entry {} must be a number in {}", Short(*value), PRECISION_ENTRY)]
    OutOfRange { value: f64 },
    /// Two mirrored entries that differ by more than 1e-12 relative.
    #[error("is not symmetric ({} vs {})", Short(*upper), Short(*lower))]
    NotSymmetric { upper: f64, lower: f64 },
    /// A negative eigenvalue beyond rounding.
    #[error("is not positive semi-definite")]
    NotPositiveSemiDefinite,
}

/// `precision.theta_ddot, precision.u`: the task-file keys of the precisions `kind` uses.
pub struct PrecisionKeys(pub TaskKind);

impl fmt::Display for PrecisionKeys {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, term) in self.0.terms().iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "precision.{}", term.name())?;
        }
        Ok(())
    }
}
