//! The runtime, generic over the arm model: control confidence, controller, closed loop and
//! episode for any model that `make derive` generates, with fixed sizes as const generics.
//!
//! The model trait, tools, tasks, Π^U and the controller are the no_std core's
//! (`toolconf_core`, re-exported here); this module adds what needs std: the closed loop the
//! integrators see, episodes and their metrics and trajectories. The paper's 2-link names
//! ([`crate::Arm`], [`crate::Task`], [`crate::closed_loop`]) are aliases of these types.
//!
//! * [`ArmModel`] is implemented for one marker type per generated model ([`Arm2`],
//!   [`Arm2Exact`], [`Arm3`], ...), forwarding to the generated module; the list comes from the
//!   generated registry ([`toolconf_generated::for_each_model!`]), so a new model description needs no edit here.
//! * [`ToolN`] (validated parameters), [`TaskN`] (goals and precisions), [`control_confidence`]
//!   (Π^U and ln|Π^U|), [`ActiveInferenceN`], [`ClosedLoopN`], [`simulate`]/[`simulate_on`]
//!   (metrics) and [`episode`]/[`episode_on`] (metrics and trajectory).
//! * [`crate::registry`] puts every model behind one object-safe trait, for code over all models.
//!
//! The sizes are N (joints = torques), NX = 2N (state X = [θ; θ̇]), NP (tool parameters) and
//! NZ = NX + N (closed-loop state Z = [X; U]). NZ is a parameter of its own because stable Rust
//! cannot write `NX + N` in a type; the core's `arm_model!` macro sets it and [`ClosedLoopN::new`]
//! checks `NX == 2N` and `NZ == NX + N` at compile time (a post-monomorphisation assertion).

pub mod budget;
pub(crate) mod closed_loop_n;

pub use toolconf_core::*;

pub(crate) use closed_loop_n::check_options as check_episode_options;
pub use closed_loop_n::{
    check_grid, episode, episode_on, simulate, simulate_on, ClosedLoopN, EpisodeN, EpisodeOptionsN,
    Metrics, ModelSimulationError, TrajectoryN, MAX_GRID_POINTS,
};
