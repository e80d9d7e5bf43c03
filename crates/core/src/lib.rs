//! # toolconf-core
//!
//! The part of toolconf a robot's controller needs, without std, an allocator, integrators or
//! threads: for any model `make derive` generated ([`toolconf_generated`]), a validated tool
//! ([`ToolN`]) and task ([`TaskN`]), the closed-form control confidence Π^U = ∂²F/∂U² with
//! ln|Π^U| ([`control_confidence`], eq. control_conf), and the active-inference controller
//! ([`ActiveInferenceN`]: U̇ = −γ ∂F/∂U, eq. U_dot_deriv, the free energy F, the cost J and the
//! task error) with [`ActiveInferenceN::tick`], one control period on a robot: measured state →
//! U̇ → the next torque, and [`ArmController`], the on-robot controller ticking at a fixed rate
//! (`examples/on_robot`; the C ABI of a model library, crates/cabi, ticks through it).
//!
//! ```text
//! generated/       toolconf-generated  no_std   the derived code: models, tasks, registry
//!     ▲
//! crates/core/     toolconf-core       no_std   this crate
//!     ▲
//! crates/toolconf/  toolconf            std      integrators, episodes, MPC, ranking, design, files
//!     ▲
//! crates/report/   toolconf-report     std      the paper's experiments, figures, reports
//!     ▲
//! toolconf-cli (the `toolconf` command), toolconf-python (`import toolconf`)
//! ```
//!
//! Each crate depends only on those below it; a robot links this crate and the generated one
//! (`examples/on_robot/` is such a controller).
//!
//! Features: `std` takes `ln` from the platform's libm instead of the `libm` crate (the runtime
//! turns it on, so that ln|Π^U| has the bits the paper's snapshots pin; the two differ in the last
//! bit for about one argument in a hundred); `serde` adds `Serialize` for [`ToolN`] and
//! [`TaskKind`].

#![no_std]

#[cfg(feature = "std")]
extern crate std;

mod arm_controller;
mod arm_model;
mod confidence;
mod controller;
pub mod display;
mod error;
pub mod linalg;
mod task;
mod tool;
pub mod validate;

/// The generated crate this one is built on (`generated/`).
pub use toolconf_generated as generated;

pub use arm_controller::{ArmController, Command, RATE_HZ};
pub use arm_model::*;
pub use confidence::{control_confidence, logdet_of, ControlConfidenceN, ValidatedTaskN};
pub use controller::{
    control_of, observe, observe_tool, observe_with_tip, tip_kinematics, tip_parameters,
    ActiveInferenceN, ObservationN, TipKinematics, TipObserver,
};
pub use error::{Error, PrecisionKeys, PrecisionProblem};
pub use generated::{Read, TaskKind, Term, TERMS};
pub use task::{reads_tip, reads_tip_acceleration, term_components, term_identity, TaskN};
pub use tool::{SensitivitiesN, ToolN};

/// ln x: the platform's with the `std` feature (glibc's on Linux), else the `libm` crate's.
#[inline]
pub(crate) fn ln(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.ln()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::log(x)
    }
}
