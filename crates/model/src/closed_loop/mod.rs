//! The paper's closed loop for its 2-DOF arm: the active-inference controller on the nonlinear
//! arm, one episode at a time, with the metrics tools are ranked by.
//!
//! These are the generic runtime's types ([`crate::model`]) for the paper's model
//! [`crate::model::Arm2`], under the paper's names: one implementation. What is the 2-link arm's
//! own is the run-time [`Plant`] choice (the paper's generative process or the exact Lagrangian
//! dynamics, which the command line and the experiments switch between) and errors that name the
//! tool `arm m1=… m2=… l1=… l2=…`.

mod episode;
mod system;

pub use episode::{simulate, Episode, EpisodeOptions, Metrics, SimulationError, Trajectory};
pub use system::{ClosedLoop, JointJacobian, JointState, Plant};

/// The controller of one arm for one task: U̇ = −γ ∂F/∂U (eq. U_dot_deriv).
pub type ActiveInference = crate::model::ActiveInferenceN<2>;
