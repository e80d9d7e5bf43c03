//! # toolconf-model
//!
//! The model layer of toolconf (Anil Meera & Lanillos, "Confidence-Aware Decision-Making and
//! Control for Tool Selection"): every model, built in ([`toolconf_generated`]) or loaded at run
//! time from a model library ([`loaded`]), behind one [`registry`]; a tool of the paper's arm
//! ([`Arm`]) and a task ([`Task`]); a closed-loop episode ([`closed_loop`]); the closed-form
//! control confidence Π^U = ∂²F/∂U² ([`control_confidence`]) and the linearised loop's predicted
//! cost ([`prediction`]); and the files a user brings, read under one bound ([`inputs`]: task
//! files, tools files).
//!
//! The algorithms over it (MPC, selection, ranking, design, the evaluation) are the crate
//! `toolconf`, above this one.

pub mod arm;
pub mod closed_loop;
pub mod confidence;
pub mod error;
pub mod inputs;
pub mod loaded;
pub mod model;
pub mod prediction;
pub mod registry;
pub mod robot_scales;
pub mod task;
pub mod validate;

pub use arm::Arm;
pub use confidence::{control_confidence, ControlConfidence, Sensitivities};
pub use error::Error;
pub use task::{Task, TaskKind, Term};

/// 2-vector of joint quantities (θ, θ̇, θ̈, U) of the paper's 2-DOF arm.
pub type Vector2 = nalgebra::SVector<f64, 2>;
/// 2×2 matrix (precisions, sensitivities, Π^U).
pub type Matrix2 = nalgebra::SMatrix<f64, 2, 2>;
/// State X = [θ1 θ2 θ̇1 θ̇2].
pub type State = nalgebra::SVector<f64, 4>;
/// State matrix A (4×4).
pub type StateMatrix = nalgebra::SMatrix<f64, 4, 4>;
/// Input matrix B (4×2).
pub type InputMatrix = nalgebra::SMatrix<f64, 4, 2>;
