//! # toolconf
//!
//! Confidence-aware decision-making and control for tool selection, after Anil Meera & Lanillos,
//! "Confidence-Aware Decision-Making and Control for Tool Selection": the algorithms over the
//! model layer (`toolconf_model`: models, episodes, Π^U, the prediction, input files).
//!
//! This crate adds the MPC baseline ([`mpc`]), selection of the best tool for a task
//! ([`select`]), ranking a population of tools over tasks ([`rank`]), designing a tool by
//! constrained optimisation ([`design`]) and the evaluation of the paper's claims on any robot
//! ([`evaluation`], with the statistics of `toolconf_stats`).
//!
//! ```text
//! generated/        toolconf-generated  no_std   the derived code: models, tasks, registry
//! crates/core/      toolconf-core       no_std   models, tools, tasks, Π^U, the controller's tick
//! crates/files/     toolconf-files      std      the one rule for output files (beside core)
//! crates/stats/, crates/messages/, crates/integrators/  std  statistics, messages, integrators
//! crates/cabi/      toolconf-cabi       std      the C ABI of a model library
//! crates/model/     toolconf-model      std      models behind one registry, episodes, input files
//! crates/toolconf/  toolconf            std      this crate
//! crates/tool-urdf/ toolconf-tool-urdf  std      a tool's row from its URDF (beside this crate)
//! crates/report/    toolconf-report     std      the paper's experiments, figures, reports
//! toolconf-cli (the `toolconf` command), toolconf-python (`import toolconf`)
//! ```
//!
//! Each crate depends only on those above it in this list (the layers below it).
//! Flow: model description → derivation → JSON IR → templates → generated code → core → model
//! layer → these algorithms → report → command line and Python package.

pub mod design;
pub mod evaluation;
pub mod mpc;
pub mod rank;
pub mod select;
pub mod threads;
