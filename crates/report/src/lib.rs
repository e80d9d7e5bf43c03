//! # toolconf-report
//!
//! What toolconf writes for a reader: the paper's experiments ([`experiments`], `toolconf
//! reproduce`: CSVs, SVG figures, the Markdown/HTML report with claims and verdicts), the reports
//! and figures of `toolconf rank` ([`rank`]) and `toolconf design` ([`design`]), and the progress
//! bars. It sits on the std runtime (`toolconf`) and adds plotters and indicatif, which neither
//! the runtime nor the Python package needs.
//!
//! ```text
//! generated/ → crates/core/ → crates/toolconf/ (toolconf) → crates/report/ (this crate) → the CLI
//! ```

pub mod design;
pub mod evaluation;
pub mod experiments;
pub mod progress;
pub mod rank;
pub mod view3d;
