//! # toolconf-stats
//!
//! Statistics for the paper's Results section.
//!
//! - Confidence vs task error over random tools ("Control confidence and tool performance"):
//!   [`spearman`] / [`pearson`] with a [`bootstrap_spearman_ci`] interval, and the figure's
//!   exponential trend line [`fit_exponential`].
//! - Benchmarking F against J over paired trials ("Benchmarking tool selection"): box-plot
//!   [`summary`] per objective and [`paired_test`] (paired t and Wilcoxon signed-rank).
//!
//! Every routine validates its input (lengths, sample size, finiteness) and returns a
//! [`StatsError`] instead of panicking or producing NaN. Conventions follow scipy/numpy
//! (average ranks for ties, type-7 quantiles, n − 1 standard deviation) so results can be
//! cross-checked there.

mod bootstrap;
mod correlation;
mod error;
mod fit;
mod paired;
mod rank;
mod special;
mod summary;
#[cfg(test)]
mod test_support;

pub use bootstrap::{bootstrap_spearman_ci, Interval};
pub use correlation::{pearson, spearman};
pub use error::StatsError;
pub use fit::{fit_exponential, ExpFit};
pub use paired::{complete_pairs, paired_test, PairedTest};
pub use rank::ranks;
pub use summary::{summary, Summary};
