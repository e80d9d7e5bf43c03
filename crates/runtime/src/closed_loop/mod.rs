//! The paper's closed loop for its 2-DOF arm: the active-inference controller on the nonlinear
//! arm, one episode at a time, with the metrics tools are ranked by.
//!
//! A façade over the model-generic runtime ([`crate::model`], with [`crate::model::Arm2`] as the
//! agent's model): the controller, closed loop, episode, metrics and trajectory are the generic
//! ones; this module keeps the paper's `Arm`/`Task` API, the run-time [`Plant`] choice and the
//! errors that name the arm (`arm m1=…`), which the command line and the experiments rely on.

mod controller;
mod episode;
mod system;

pub use controller::ActiveInference;
pub use episode::{simulate, Episode, EpisodeOptions, Metrics, SimulationError, Trajectory};
pub use system::{ClosedLoop, JointJacobian, JointState, Plant};
