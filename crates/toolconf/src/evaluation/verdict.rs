//! The paper's two claims and its benchmark's, each judged by a rule stated before the numbers:
//! "holds" (the paper's direction, significantly), "reversed" (the other direction,
//! significantly) or "no relation".
//!
//! - (a) confidence predicts the task error, and (b) confidence predicts the reliability under
//!   ΔT (|Δ task error|): Spearman's ρ between ln|Π^U| and the measure over the population, with
//!   its 95 % percentile-bootstrap interval; **holds** where the interval lies below 0 (more
//!   confident tools have the lower measure, the paper's sign), **reversed** where it lies above
//!   0, **no relation** where it contains 0.
//! - (c) tools chosen by ∫F are less sensitive to ΔT than tools chosen by ∫J: over the trials,
//!   the paired difference |Δ task error| of J's tool − F's tool (two-sided Wilcoxon
//!   signed-rank); **holds** where p < 0.05 and the mean difference is positive, **reversed**
//!   where p < 0.05 and it is negative, **no relation** otherwise (F and J choosing the same
//!   tool in every trial included).

use serde_json::{json, Value};

use toolconf_stats::{
    bootstrap_spearman_ci, complete_pairs, paired_test, spearman, Interval, PairedTest,
};

/// A claim's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finding {
    Holds,
    Reversed,
    NoRelation,
    /// The statistic cannot be computed (too few tools, a constant confidence): said why.
    NotJudged,
}

impl Finding {
    pub fn words(self) -> &'static str {
        match self {
            Finding::Holds => "holds",
            Finding::Reversed => "reversed",
            Finding::NoRelation => "no relation",
            Finding::NotJudged => "cannot be judged",
        }
    }
}

/// Spearman's ρ with its bootstrap interval, or why either is undefined.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlation {
    pub n: usize,
    pub rho: Result<f64, String>,
    pub ci: Result<Interval, String>,
    pub level: f64,
}

impl Correlation {
    /// ρ(x, y) and its `level` interval from `resamples` resamples seeded by `seed`.
    pub fn compute(x: &[f64], y: &[f64], resamples: usize, level: f64, seed: u64) -> Self {
        let rho = spearman(x, y).map_err(|e| e.to_string());
        let ci = match &rho {
            Ok(_) => bootstrap_spearman_ci(x, y, resamples, level, seed).map_err(|e| e.to_string()),
            Err(e) => Err(e.clone()),
        };
        Self {
            n: x.len(),
            rho,
            ci,
            level,
        }
    }

    /// The rule: the interval below 0 holds, above 0 reversed, containing 0 no relation.
    pub fn finding(&self) -> Finding {
        match &self.ci {
            Ok(ci) if ci.high < 0.0 => Finding::Holds,
            Ok(ci) if ci.low > 0.0 => Finding::Reversed,
            Ok(_) => Finding::NoRelation,
            Err(_) => Finding::NotJudged,
        }
    }

    /// "ρ = −0.41 [−0.49, −0.32], n = 300", or why it is undefined.
    pub fn describe(&self) -> String {
        match (&self.rho, &self.ci) {
            (Ok(r), Ok(ci)) => format!(
                "{} ({:.0} % bootstrap interval), n = {}",
                rho_with_interval(*r, ci),
                self.level * 100.0,
                self.n
            ),
            (Ok(r), Err(e)) => format!("ρ = {} (n = {}), no interval: {e}", signed(*r), self.n),
            (Err(e), _) => format!("ρ is undefined (n = {}): {e}", self.n),
        }
    }

    /// "ρ = −0.41 [−0.49, −0.32]" (a figure's title), or "ρ undefined".
    pub fn describe_short(&self) -> String {
        match (&self.rho, &self.ci) {
            (Ok(r), Ok(ci)) => rho_with_interval(*r, ci),
            (Ok(r), Err(_)) => format!("ρ = {}", signed(*r)),
            (Err(_), _) => "ρ undefined".into(),
        }
    }

    /// `rho`, `ci` ([low, high]), `n`, `level`; `why_undefined` instead of what is undefined
    /// (no key is ever null).
    pub fn json(&self) -> Value {
        let mut v = json!({ "n": self.n, "level": self.level });
        match &self.rho {
            Ok(r) => v["rho"] = json!(r),
            Err(e) => v["why_undefined"] = json!(e),
        }
        match &self.ci {
            Ok(c) => v["ci"] = json!([c.low, c.high]),
            Err(e) => v["why_undefined"] = json!(e),
        }
        v
    }
}

/// "+0.41" / "−0.41": two decimals with the sign, as the claims table prints ρ.
pub fn signed(x: f64) -> String {
    format!("{x:+.2}").replace('-', "−")
}

/// "ρ = −0.41 [−0.49, −0.32]": ρ and its interval, [`signed`].
fn rho_with_interval(rho: f64, ci: &Interval) -> String {
    format!(
        "ρ = {} [{}, {}]",
        signed(rho),
        signed(ci.low),
        signed(ci.high)
    )
}

/// Two paired samples compared (the tools two rules chose, trial by trial): a − b.
#[derive(Debug, Clone, PartialEq)]
pub struct Paired {
    /// Pairs with both values.
    pub n: usize,
    /// Pairs without one (a failed episode).
    pub dropped: usize,
    /// Pairs with a = b (both rules chose the same tool).
    pub ties: usize,
    pub mean_difference: Option<f64>,
    pub test: Result<PairedTest, String>,
}

impl Paired {
    pub fn compute(a: &[Option<f64>], b: &[Option<f64>]) -> Self {
        let (x, y) = complete_pairs(a, b);
        let n = x.len();
        let mean_difference =
            (n > 0).then(|| x.iter().zip(&y).map(|(a, b)| a - b).sum::<f64>() / n as f64);
        Self {
            n,
            dropped: a.len().max(b.len()) - n,
            ties: x.iter().zip(&y).filter(|(a, b)| a == b).count(),
            mean_difference,
            test: paired_test(&x, &y).map_err(|e| e.to_string()),
        }
    }

    /// Every pair equal: the rules chose the same tool in every trial.
    pub fn identical(&self) -> bool {
        self.n > 0 && self.ties == self.n
    }

    /// The rule: p < alpha with a positive mean difference holds, negative reversed, else no
    /// relation (identical samples too).
    pub fn finding(&self, alpha: f64) -> Finding {
        if self.identical() {
            return Finding::NoRelation;
        }
        match &self.test {
            Ok(t) if t.wilcoxon_p_value < alpha && t.mean_difference > 0.0 => Finding::Holds,
            Ok(t) if t.wilcoxon_p_value < alpha && t.mean_difference < 0.0 => Finding::Reversed,
            Ok(_) => Finding::NoRelation,
            Err(_) => Finding::NotJudged,
        }
    }

    /// "mean difference +1.2e-3 (Wilcoxon p = 0.003, n = 50, 12 ties)".
    pub fn describe(&self) -> String {
        self.describe_with("the same tool every time", |t| {
            format!(
                "mean difference {:+.3e} (Wilcoxon signed-rank p = {}, paired t p = {}; n = {}, \
                 {} tie(s))",
                t.mean_difference,
                p_value(t.wilcoxon_p_value),
                p_value(t.t_p_value),
                t.n,
                self.ties
            )
        })
    }

    /// The frame of every paired comparison's description, here and in the report's: identical
    /// samples ("identical in all n pairs (`same`)"), an undefined test, or the test's `numbers`;
    /// then the [`dropped_clause`].
    pub fn describe_with(&self, same: &str, numbers: impl FnOnce(&PairedTest) -> String) -> String {
        let dropped = dropped_clause(self.dropped);
        if self.identical() {
            return format!("identical in all {} pairs ({same}){dropped}", self.n);
        }
        match &self.test {
            Ok(t) => format!("{}{dropped}", numbers(t)),
            Err(e) => format!("no paired test (n = {}): {e}{dropped}", self.n),
        }
    }

    /// `mean_difference`, `wilcoxon_p`, `t_p`, `n`, `ties`, `dropped`; `why_undefined` instead
    /// of a test that is undefined (no key is ever null).
    pub fn json(&self) -> Value {
        let mut v = json!({ "n": self.n, "ties": self.ties, "dropped": self.dropped });
        if let Some(d) = self.mean_difference {
            v["mean_difference"] = json!(d);
        }
        match &self.test {
            Ok(t) => {
                v["wilcoxon_p"] = json!(t.wilcoxon_p_value);
                v["t_p"] = json!(t.t_p_value);
            }
            Err(_) if self.identical() => v["identical"] = json!(true),
            Err(e) => v["why_undefined"] = json!(e),
        }
        v
    }
}

/// A p-value for text.
pub fn p_value(p: f64) -> String {
    if p < 1e-3 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// The three claims.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Claim {
    /// (a) Fig. 2.
    TaskError,
    /// (b) Figs. 4–5.
    Reliability,
    /// (c) Fig. 7.
    Selection,
}

impl Claim {
    pub const ALL: [Claim; 3] = [Claim::TaskError, Claim::Reliability, Claim::Selection];

    /// The key in JSON and Python.
    pub fn key(self) -> &'static str {
        match self {
            Claim::TaskError => "confidence_predicts_task_error",
            Claim::Reliability => "confidence_predicts_reliability",
            Claim::Selection => "free_energy_choices_less_sensitive",
        }
    }

    /// "(a)", "(b)", "(c)".
    pub fn label(self) -> &'static str {
        match self {
            Claim::TaskError => "(a)",
            Claim::Reliability => "(b)",
            Claim::Selection => "(c)",
        }
    }

    pub fn statement(self) -> &'static str {
        match self {
            Claim::TaskError => {
                "confidence predicts the task error: more confident tools do the task better \
                 (the paper's Fig. 2)"
            }
            Claim::Reliability => {
                "confidence predicts reliability: more confident tools change their task error \
                 less under a constant torque perturbation ΔT (Figs. 3–5)"
            }
            Claim::Selection => {
                "tools chosen by ∫F dt are less sensitive to ΔT than tools chosen by ∫J dt \
                 (Fig. 7)"
            }
        }
    }

    /// The rule, stated before the numbers.
    pub fn rule(self, level: f64, alpha: f64) -> String {
        let pct = format!("{:.0} %", level * 100.0);
        match self {
            Claim::TaskError | Claim::Reliability => format!(
                "Spearman's ρ between ln|Π^U| and {} over the tools, with its {pct} \
                 percentile-bootstrap interval: holds if the interval lies below 0, reversed if \
                 it lies above 0, no relation if it contains 0",
                if self == Claim::TaskError {
                    "the task error"
                } else {
                    "|task error(ΔT) − task error(0)|"
                }
            ),
            Claim::Selection => format!(
                "over the trials of Fig. 7, |task error(ΔT) − task error(0)| of the tool ∫J dt \
                 chose minus that of the tool ∫F dt chose, paired by trial (two-sided Wilcoxon \
                 signed-rank): holds if p < {alpha} and the mean difference is positive, \
                 reversed if p < {alpha} and it is negative, no relation otherwise (the same \
                 tool in every trial included)"
            ),
        }
    }
}

/// A claim's verdict with the statistic it rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimVerdict {
    pub claim: Claim,
    pub finding: Finding,
    pub evidence: String,
    pub statistic: Value,
    pub rule: String,
}

impl ClaimVerdict {
    pub fn json(&self) -> Value {
        json!({
            "claim": self.claim.statement(),
            "verdict": self.finding.words(),
            "evidence": self.evidence,
            "rule": self.rule,
            "statistic": self.statistic,
        })
    }
}

/// ", 3 pair(s) dropped for a failed episode", or nothing when no pair was dropped: the clause
/// a paired comparison's description ends with (here and in the report's).
pub fn dropped_clause(dropped: usize) -> String {
    match dropped {
        0 => String::new(),
        d => format!(", {d} pair(s) dropped for a failed episode"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_way_rule() {
        let x: Vec<f64> = (0..60).map(f64::from).collect();
        let down: Vec<f64> = x.iter().map(|v| -v + (v * 7.0).sin()).collect();
        let up: Vec<f64> = down.iter().map(|v| -v).collect();
        let noise: Vec<f64> = x.iter().map(|v| (v * 12.9898).sin()).collect();
        let f = |y: &[f64]| Correlation::compute(&x, y, 500, 0.95, 1).finding();
        assert_eq!(f(&down), Finding::Holds);
        assert_eq!(f(&up), Finding::Reversed);
        assert_eq!(f(&noise), Finding::NoRelation);
        assert_eq!(
            Correlation::compute(&[1.0; 5], &x[..5], 100, 0.95, 1).finding(),
            Finding::NotJudged
        );
        let a: Vec<Option<f64>> = (0..30).map(|i| Some(1.0 + f64::from(i) * 0.1)).collect();
        let b: Vec<Option<f64>> = (0..30)
            .map(|i| Some(f64::from(i) * 0.1 + (f64::from(i)).sin() * 0.01))
            .collect();
        assert_eq!(Paired::compute(&a, &b).finding(0.05), Finding::Holds);
        assert_eq!(Paired::compute(&b, &a).finding(0.05), Finding::Reversed);
        assert_eq!(Paired::compute(&a, &a).finding(0.05), Finding::NoRelation);
        assert_eq!(signed(-0.414), "−0.41");
    }
}
