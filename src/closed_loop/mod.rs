//! The paper's closed loop: the active-inference controller on the nonlinear arm, one episode
//! at a time, with the metrics tools are ranked by.

mod controller;
mod episode;

pub use controller::ActiveInference;
pub use episode::{
    simulate, Episode, EpisodeOptions, JointState, Metrics, SimulationError, Trajectory,
};
