//! The runtime, generic over the arm model: control confidence, controller, closed loop and
//! episode for any model that `make derive` generates, with fixed sizes as const generics.
//!
//! This is the implementation. The 2-link modules [`crate::confidence`] and
//! [`crate::closed_loop`] are a façade over it for the paper's arm (`Arm`, `Task`, `Matrix2`,
//! `Plant`, errors naming `arm m1=…`): they convert and delegate, so the math lives here once and
//! nothing outside the generated 2-link model assumes 2×2.
//!
//! * [`ArmModel`] is implemented for one marker type per generated model ([`Arm2`],
//!   [`Arm2Exact`], [`Arm3`], ...), forwarding to the generated module; the list comes from the
//!   generated registry ([`crate::for_each_model!`]), so a new model description needs no edit here.
//! * [`ToolN`] (validated parameters), [`TaskN`] (goals and precisions), [`control_confidence`]
//!   (Π^U and ln|Π^U|), [`ActiveInferenceN`], [`ClosedLoopN`], [`simulate`]/[`simulate_on`]
//!   (metrics) and [`episode`]/[`episode_on`] (metrics and trajectory). With [`Arm2`] they are
//!   the 2-link runtime; tests/generic_runtime.rs checks the façade and the generic entry points
//!   agree bit for bit.
//! * [`mixed`] draws and ranks tool sets that mix models.
//!
//! The sizes are N (joints = torques), NX = 2N (state X = [θ; θ̇]), NP (tool parameters) and
//! NZ = NX + N (closed-loop state Z = [X; U]). NZ is a parameter of its own because stable Rust
//! cannot write `NX + N` in a type; the `arm_model!` macro sets it and [`ClosedLoopN::new`]
//! checks `NX == 2N` and `NZ == NX + N` at compile time (a post-monomorphisation assertion).

mod arm_model;
mod confidence;
pub mod mixed;
pub(crate) mod runtime;
mod task;
mod tool;

pub use arm_model::*;
pub use confidence::{control_confidence, logdet_of, ControlConfidenceN, ValidatedTaskN};
pub use task::TaskN;
pub use tool::{SensitivitiesN, ToolN};

pub use runtime::{
    episode, episode_on, simulate, simulate_on, ActiveInferenceN, ClosedLoopN, EpisodeN,
    EpisodeOptionsN, Metrics, ModelSimulationError, TrajectoryN, MAX_GRID_POINTS,
};
