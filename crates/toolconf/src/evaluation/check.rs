//! Whether confidence predicts the task error where `rank --screen` and `design` follow it:
//! claim (a)'s rule ([`super::verdict`]) on a small seeded sample of the same tools, simulated
//! alongside.
//!
//! Why a sample simulated alongside, not a result cached from `reproduce`: the answer depends on
//! the robot, the task file and the tools (measured: it holds on two of six tip tasks and is
//! reversed on two), and a cached result would be silently stale after any of them changed. A
//! sample of [`VALIDATION_TOOLS`] tools costs that many episodes (about 40 ms on the Panda, 5 ms
//! on the paper's arm, on one core) and answers for the population at hand: `rank`'s tools file
//! (a uniform sample of its rows, drawn by a seeded hash of the row number, so that blocks
//! screened apart merge into the same sample) or `design`'s feasible set (its first random
//! feasible tools). With 100 tools the interval of ρ is about ±0.2 wide, enough to tell a clear
//! relation from none.

use serde_json::{json, Value};

use super::seeds::derive_seed;
use super::verdict::{Correlation, Finding};

pub use toolconf_model::inputs::design_file::VALIDATION_TOOLS;
/// Bootstrap resamples of the check's interval.
const RESAMPLES: usize = 2000;

/// The key that puts row `row` into the validation sample: the sample is the rows with the
/// smallest keys (a uniform sample without replacement, the same however the rows are split).
pub fn sample_key(row: usize) -> u64 {
    derive_seed(row as u64, "validation/row")
}

/// What a validation check knows of its sample: Spearman's ρ of its `points` with the 95 %
/// bootstrap interval (resamples from the seed of the check's stream), the tools sampled
/// (`correlation.n` counts those with both numbers) and the population they were drawn from
/// ("of the tools file", "of the design's feasible set").
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    pub correlation: Correlation,
    pub sampled: usize,
    pub population: String,
}

impl Sample {
    pub(super) fn new(
        points: &[(f64, f64)],
        sampled: usize,
        population: &str,
        stream: &str,
    ) -> Self {
        let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        let seed = derive_seed(0, stream);
        Self {
            correlation: Correlation::compute(&x, &y, RESAMPLES, 0.95, seed),
            sampled,
            population: population.into(),
        }
    }

    /// "`what` (ρ …, N tools sampled POPULATION and simulated alongside; `extra`): `consequence`",
    /// the one line a check's note is.
    pub(super) fn note(&self, what: &str, extra: &str, consequence: &str) -> String {
        format!(
            "{what} ({}, {} tools sampled {} and simulated alongside; {extra}): {consequence}",
            self.correlation.describe_short(),
            self.sampled,
            self.population,
        )
    }

    /// The check's JSON: its `finding`'s verdict, the correlation, the sample, and `extra`.
    pub(super) fn json(&self, finding: Finding, extra: (&str, usize)) -> Value {
        let mut v = json!({
            "verdict": finding.words(),
            "correlation": self.correlation.json(),
            "sampled": self.sampled,
            "population": self.population,
        });
        v[extra.0] = json!(extra.1);
        v
    }
}

/// Claim (a) on the sample: ρ(ln|Π^U|, task error) and the verdict by its rule.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfidenceCheck {
    pub sample: Sample,
    pub finding: Finding,
    /// Extra episodes it cost (the sampled tools not simulated anyway).
    pub episodes: usize,
}

impl ConfidenceCheck {
    /// The check on (ln|Π^U|, task error) of the sampled tools that have both.
    pub fn compute(
        points: &[(f64, f64)],
        sampled: usize,
        episodes: usize,
        population: &str,
    ) -> Self {
        let sample = Sample::new(points, sampled, population, "validation/bootstrap");
        Self {
            finding: sample.correlation.finding(),
            sample,
            episodes,
        }
    }

    /// The one line `rank` and `design` print when confidence does not predict the task error
    /// here (`None` when it does); `consequence` says what that means for the command.
    pub fn note(&self, consequence: &str) -> Option<String> {
        let what = match self.finding {
            Finding::Holds => return None,
            Finding::Reversed => "more confident tools do the task worse here",
            Finding::NoRelation => "confidence says nothing about the task error here",
            Finding::NotJudged => {
                "whether confidence predicts the task error here cannot be judged"
            }
        };
        let extra = format!("claim (a): {}", self.finding.words());
        Some(self.sample.note(what, &extra, consequence))
    }

    pub fn json(&self) -> Value {
        self.sample.json(self.finding, ("episodes", self.episodes))
    }
}
