//! The statistics the verdicts rest on, the rules that turn them into verdicts, and how numbers
//! are printed in the report (never as NaN: what cannot be computed is said in words).

use toolconf::evaluation::verdict::Paired;
use toolconf_stats::{complete_pairs, summary};

use super::report::Outcome;

/// |ρ| from which a correlation counts as "clear" (at least moderate).
pub const CLEAR_RHO: f64 = 0.3;

/// The rule for "higher confidence goes with lower Y".
pub fn negative_correlation_rule(level: f64) -> String {
    format!(
        "holds if the {}% bootstrap CI of Spearman's ρ between ln|Π^U| and the measure lies \
         entirely below 0 and ρ ≤ −{CLEAR_RHO} (a clear, at least moderate, negative \
         correlation); partly holds if the CI lies below 0 but ρ > −{CLEAR_RHO} (real but weak); \
         does not hold if the CI contains 0 or lies above it.",
        pct(level)
    )
}

fn pct(level: f64) -> String {
    format!("{}", (level * 100.0).round())
}

/// A number for the report: 3 significant digits, exponent form for very large or small values.
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return "not finite".into();
    }
    let a = x.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let digits = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}").replace('-', "−")
    } else {
        format!("{x:.2e}").replace('-', "−")
    }
}

/// A p-value for the report.
pub fn p_value(p: f64) -> String {
    if p < 1e-3 {
        format!("{p:.1e}").replace('-', "−")
    } else {
        format!("{p:.3}")
    }
}

/// Spearman's ρ with its bootstrap interval, the evaluation's own type; the report reads it
/// through [`CorrelationReport`].
pub use toolconf::evaluation::verdict::Correlation;

/// How the report computes, prints and judges a [`Correlation`].
pub trait CorrelationReport: Sized {
    /// Several correlations at once, in parallel (each with its own seed, so the result does not
    /// depend on the thread count): `jobs` are (x, y, seed).
    fn compute_all(jobs: &[(Vec<f64>, Vec<f64>, u64)], resamples: usize, level: f64) -> Vec<Self>;

    /// "Spearman's ρ = −0.83, 95% bootstrap CI [−0.87, −0.78], n = 300", or the reason it is
    /// undefined.
    fn sentence(&self) -> String;

    /// ρ for a table cell, or "undefined".
    fn rho_cell(&self) -> String;

    /// The interval for a table cell, or "undefined".
    fn ci_cell(&self) -> String;

    /// The verdict for "higher confidence, lower Y" (see [`negative_correlation_rule`]).
    fn negative_outcome(&self) -> Outcome;
}

impl CorrelationReport for Correlation {
    fn compute_all(jobs: &[(Vec<f64>, Vec<f64>, u64)], resamples: usize, level: f64) -> Vec<Self> {
        use rayon::prelude::*;
        jobs.par_iter()
            .map(|(x, y, seed)| Self::compute(x, y, resamples, level, *seed))
            .collect()
    }

    fn sentence(&self) -> String {
        match (&self.rho, &self.ci) {
            (Ok(r), Ok(ci)) => format!(
                "Spearman's ρ = {}, {}% bootstrap CI [{}, {}], n = {}",
                num(*r),
                pct(self.level),
                num(ci.low),
                num(ci.high),
                self.n
            ),
            (Ok(r), Err(e)) => format!(
                "Spearman's ρ = {} (n = {}), no bootstrap interval: {e}",
                num(*r),
                self.n
            ),
            (Err(e), _) => format!("Spearman's ρ is undefined (n = {}): {e}", self.n),
        }
    }

    fn rho_cell(&self) -> String {
        self.rho.as_ref().map_or("undefined".into(), |r| num(*r))
    }

    fn ci_cell(&self) -> String {
        self.ci.as_ref().map_or("undefined".into(), |ci| {
            format!("[{}, {}]", num(ci.low), num(ci.high))
        })
    }

    fn negative_outcome(&self) -> Outcome {
        match (&self.rho, &self.ci) {
            (Ok(r), Ok(ci)) if ci.high < 0.0 && *r <= -CLEAR_RHO => Outcome::Holds,
            (Ok(_), Ok(ci)) if ci.high < 0.0 => Outcome::Partly,
            (Ok(_), Ok(_)) => Outcome::DoesNotHold,
            _ => Outcome::NotJudged,
        }
    }
}

/// Two paired samples (e.g. the tools two objectives chose, trial by trial) compared: the
/// runtime's [`Paired`] (n, dropped pairs, ties, the tests) and each sample's mean.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub paired: Paired,
    pub mean_a: Option<f64>,
    pub mean_b: Option<f64>,
}

impl Comparison {
    pub fn compute(a: &[Option<f64>], b: &[Option<f64>]) -> Self {
        let (x, y) = complete_pairs(a, b);
        let mean = |v: &[f64]| summary(v).ok().map(|s| s.mean);
        Self {
            paired: Paired::compute(a, b),
            mean_a: mean(&x),
            mean_b: mean(&y),
        }
    }

    /// Mean of a − b over the pairs.
    pub fn mean_difference(&self) -> Option<f64> {
        match &self.paired.test {
            Ok(t) => Some(t.mean_difference),
            Err(_) => Some(self.mean_a? - self.mean_b?),
        }
    }

    /// Two-sided Wilcoxon signed-rank p-value, the one the verdicts use.
    pub fn p(&self) -> Option<f64> {
        self.paired.test.as_ref().ok().map(|t| t.wilcoxon_p_value)
    }

    /// Does a exceed b significantly (Wilcoxon p < alpha and mean(a − b) > 0)?
    pub fn a_greater(&self, alpha: f64) -> Option<bool> {
        if self.paired.identical() {
            return Some(false);
        }
        Some(self.p()? < alpha && self.mean_difference()? > 0.0)
    }

    /// Is there no significant difference (p ≥ alpha, or identical)?
    pub fn similar(&self, alpha: f64) -> Option<bool> {
        if self.paired.identical() {
            return Some(true);
        }
        Some(self.p()? >= alpha)
    }

    /// "mean difference +1.2 (t = 3.4, p = 0.002; Wilcoxon W = 120, p = 0.003; n = 50)".
    pub fn describe(&self) -> String {
        let ties = self.paired.ties;
        self.paired
            .describe_with("the same tool was chosen every time", |t| {
                format!(
                    "mean difference {} (paired t = {}, p = {}; Wilcoxon W = {}, p = {}; n = {}, \
                     {} tie(s))",
                    num(t.mean_difference),
                    num(t.t),
                    p_value(t.t_p_value),
                    num(t.wilcoxon_w),
                    p_value(t.wilcoxon_p_value),
                    t.n,
                    ties
                )
            })
    }
}

/// "mean ± sd (median, n)" of the present values, or why there is none.
pub fn mean_sd(values: &[f64]) -> String {
    match summary(values) {
        Ok(s) => format!("{} ± {}", num(s.mean), num(s.sd)),
        Err(e) => format!("undefined ({e})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_well() {
        assert_eq!(num(-0.834567), "−0.835");
        assert_eq!(num(1234.6), "1235");
        assert_eq!(num(12.345), "12.3");
        assert_eq!(num(2.5e-5), "2.50e−5");
        assert_eq!(num(f64::NAN), "not finite");
        assert_eq!(p_value(0.0123), "0.012");
        assert_eq!(p_value(2e-7), "2.0e−7");
    }

    #[test]
    fn constant_x_is_reported_in_words() {
        let c = Correlation::compute(&[1.0; 5], &[1.0, 2.0, 3.0, 4.0, 5.0], 100, 0.95, 1);
        assert_eq!(c.negative_outcome(), Outcome::NotJudged);
        assert!(c.sentence().contains("undefined"), "{}", c.sentence());
        assert!(!c.sentence().contains("NaN"));
    }

    #[test]
    fn comparison_handles_identical_and_missing_pairs() {
        let a = [Some(1.0), Some(2.0), None, Some(4.0)];
        let c = Comparison::compute(&a, &a);
        assert!(c.paired.identical());
        assert_eq!((c.paired.n, c.paired.dropped), (3, 1));
        assert_eq!(c.similar(0.05), Some(true));
        assert_eq!(c.a_greater(0.05), Some(false));
        assert!(c.describe().starts_with("identical in all 3 pairs"));
    }
}
