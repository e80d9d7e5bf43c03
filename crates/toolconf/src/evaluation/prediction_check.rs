//! Whether the prediction ([`toolconf_model::prediction`]) predicts the task error where `rank --screen
//! --screen-by predicted` follows it: Spearman's ρ(predicted task error, simulated task error)
//! on the same seeded sample the confidence check simulates ([`super::check`]).
//!
//! The rule mirrors claim (a)'s with the prediction's sign: **holds** where the 95 % bootstrap
//! interval lies above 0 (tools predicted worse do worse), **reversed** below 0, **no
//! relation** where it contains 0.

use serde_json::Value;

use super::check::Sample;
use super::verdict::Finding;

/// ρ(predicted, simulated task error) on the sample, and the verdict by the rule above.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionCheck {
    pub sample: Sample,
    pub finding: Finding,
    /// Sampled tools without a prediction (an unstable linearised loop).
    pub without_prediction: usize,
}

impl PredictionCheck {
    /// The check on (predicted, simulated task error) of the sampled tools that have both.
    pub fn compute(
        points: &[(f64, f64)],
        sampled: usize,
        without_prediction: usize,
        population: &str,
    ) -> Self {
        let sample = Sample::new(points, sampled, population, "validation/prediction");
        let finding = match &sample.correlation.ci {
            Ok(ci) if ci.low > 0.0 => Finding::Holds,
            Ok(ci) if ci.high < 0.0 => Finding::Reversed,
            Ok(_) => Finding::NoRelation,
            Err(_) => Finding::NotJudged,
        };
        Self {
            sample,
            finding,
            without_prediction,
        }
    }

    /// The one line `rank` prints when the prediction does not predict the task error here
    /// (`None` when it does); `consequence` says what that means for the command.
    pub fn note(&self, consequence: &str) -> Option<String> {
        let what = match self.finding {
            Finding::Holds => return None,
            Finding::Reversed => "tools predicted cheaper do the task worse here",
            Finding::NoRelation => "the prediction says nothing about the task error here",
            Finding::NotJudged => {
                "whether the prediction predicts the task error here cannot be judged"
            }
        };
        let extra = format!("{} without a prediction", self.without_prediction);
        Some(self.sample.note(what, &extra, consequence))
    }

    pub fn json(&self) -> Value {
        let extra = ("without_prediction", self.without_prediction);
        self.sample.json(self.finding, extra)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prediction_that_orders_the_tools_holds_and_one_that_reverses_them_is_said() {
        let up: Vec<(f64, f64)> = (0..40).map(|i| (i as f64, (i * i) as f64)).collect();
        let check = PredictionCheck::compute(&up, 40, 0, "of x");
        assert_eq!(check.finding, Finding::Holds);
        assert_eq!(check.sample.correlation.rho, Ok(1.0));
        assert_eq!(check.note("c"), None);
        let down: Vec<(f64, f64)> = up.iter().map(|&(x, y)| (-x, y)).collect();
        let check = PredictionCheck::compute(&down, 41, 1, "of x");
        assert_eq!(check.finding, Finding::Reversed);
        let note = check.note("so what").unwrap();
        assert!(
            note.starts_with("tools predicted cheaper do the task worse here (ρ = −1.00"),
            "{note}"
        );
        assert!(
            note.ends_with(
                "41 tools sampled of x and simulated alongside; 1 without a prediction): so what"
            ),
            "{note}"
        );
    }
}
