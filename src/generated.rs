//! The code `make derive` writes into `generated/`, included here unchanged.
//!
//! Each model is a module of plain functions (see `generated/<model>.md` for the derivation
//! report). Nobody edits these files: change the model description or the templates and run
//! `make derive`.

/// The paper's 2-DOF arm (`derive/models/arm2.toml`).
#[path = "../generated/arm2.rs"]
pub mod arm2;

/// The exact 2-link arm by Lagrangian mechanics (`derive/models/arm2_exact.toml`): the same
/// tool as `arm2`, used as the exact plant against the paper's model.
#[path = "../generated/arm2_exact.rs"]
pub mod arm2_exact;

/// A 3-link arm by Lagrangian mechanics (`derive/models/arm3.toml`).
#[path = "../generated/arm3.rs"]
pub mod arm3;
