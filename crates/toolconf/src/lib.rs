//! # toolconf
//!
//! Confidence-aware decision-making and control for tool selection, after Anil Meera & Lanillos,
//! "Confidence-Aware Decision-Making and Control for Tool Selection": the std runtime.
//!
//! A tool is a robot arm ([`Arm`], the paper's; any generated model's in [`model`]); a task
//! ([`Task`]) is position, velocity or acceleration control with the paper's goals and
//! precisions. The closed-form control confidence Π^U = ∂²F/∂U² ([`control_confidence`]) and
//! the controller come from the no_std core (`toolconf_core`, under [`model`]), built on the code
//! `make derive` generates ([`generated`]); this crate adds closed-loop episodes (integrated by
//! `toolconf_integrators`), the MPC baseline, selection, ranking, design, the evaluation (with
//! the statistics of `toolconf_stats`), task and tool files, and the models loaded at run time.
//!
//! ```text
//! generated/       toolconf-generated  no_std   the derived code: models, tasks, registry
//! crates/core/     toolconf-core       no_std   models, tools, tasks, Π^U, the controller's tick
//! crates/files/    toolconf-files      std      the one rule for output files (below it, beside core)
//! crates/stats/, crates/messages/, crates/integrators/  std  statistics, messages, integrators
//! crates/toolconf/  toolconf            std      this crate
//! crates/tool-urdf/ toolconf-tool-urdf std      a tool's row from its URDF (beside this crate)
//! crates/report/   toolconf-report     std      the paper's experiments, figures, reports
//! toolconf-cli (the `toolconf` command), toolconf-python (`import toolconf`)
//! ```
//!
//! Each crate depends only on those above it in this list (the layers below it).
//! Flow: model description → derivation → JSON IR → templates → generated code → core → this
//! runtime → report → command line and Python package.

pub mod arm;
pub mod bounded_read;
pub mod closed_loop;
pub mod confidence;
pub mod design;
pub mod error;
pub mod evaluation;
/// The code `make derive` writes into `generated/` (the crate toolconf-generated): one module
/// per model (see `generated/<model>.md` for each derivation report), the tasks and the
/// registry [`for_each_model!`]. Nobody edits these files: change a model description or the
/// templates and run `make derive`.
pub use toolconf_generated as generated;
pub use toolconf_generated::for_each_model;
pub mod loaded;
pub mod model;
pub mod mpc;
pub mod prediction;
pub mod rank;
pub mod registry;
pub mod robot_scales;
pub mod select;
pub mod task;
pub mod task_file;
pub mod threads;
pub mod tools_file;
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
