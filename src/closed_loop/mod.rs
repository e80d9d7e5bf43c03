//! The paper's closed loop: the active-inference controller on the nonlinear arm, one episode
//! at a time, with the metrics tools are ranked by.

mod controller;
mod episode;
mod system;

pub use controller::ActiveInference;
pub use episode::{simulate, Episode, EpisodeOptions, Metrics, SimulationError, Trajectory};
pub use system::{ClosedLoop, JointJacobian, JointState, Plant};
