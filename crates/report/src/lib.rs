//! # toolconf-report
//!
//! What toolconf writes for a reader: the paper's experiments ([`experiments`], `toolconf
//! reproduce`: CSVs, SVG figures, the Markdown/HTML report with claims and verdicts), the reports
//! and figures of `toolconf rank` ([`rank`]) and `toolconf design` ([`design`]), and the progress
//! bars. It sits on the std runtime (`toolconf`) and adds plotters and indicatif, which neither
//! the runtime nor the Python package needs.
//!
//! ```text
//! generated/ → crates/core/ → crates/runtime/ (toolconf) → crates/report/ (this crate) → the CLI
//! ```

// The runtime's modules and 2-link names at this crate's root: the experiments were written
// inside the runtime crate, and they keep their paths (`crate::closed_loop`, `crate::Arm`, ...).
use toolconf::{
    closed_loop, confidence, integrate, mpc, select, stats, task_file, Arm, Task, TaskKind, Term,
};

pub mod design;
pub mod evaluation;
pub mod experiments;
pub mod progress;
pub mod rank;
