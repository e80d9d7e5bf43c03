//! The code `make derive` writes into `generated/`, included here unchanged.
//!
//! Each model is a module of plain functions (see `generated/<model>.md` for the derivation
//! report). Nobody edits these files: change the model description or the templates and run
//! `make derive`.

/// The paper's 2-DOF arm (`derive/models/arm2.toml`).
#[path = "../generated/arm2.rs"]
pub mod arm2;
