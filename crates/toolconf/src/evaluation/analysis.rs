//! The statistics of an evaluation, from its records and trials: the correlations of Figs. 2, 4
//! and 5, the sweep's sign comparison, the selection experiments' paired comparisons, and the
//! three verdicts.

use rayon::prelude::*;

use super::records::ToolRecord;
use super::seeds::derive_seed;
use super::trials::{chosen_values, Trial, MEASURES, RULES};
use super::verdict::{Claim, ClaimVerdict, Correlation, Paired};
use super::Plan;

/// One level of the sweep: its scale of ΔT and ρ(ln|Π^U|, |Δ task error|) over the sweep's tools.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepLevel {
    pub scale: f64,
    pub correlation: Correlation,
}

/// |Δ task error| at +s against −s ΔT, per tool (Fig. 5's sign of ΔT).
#[derive(Debug, Clone, PartialEq)]
pub struct SignComparison {
    pub magnitude: f64,
    /// With ΔT's own sign (scale +s) − the opposite (scale −s).
    pub paired: Paired,
}

/// Measure m ([`MEASURES`]) of the tools rules a and b chose, compared trial by trial (a − b).
#[derive(Debug, Clone, PartialEq)]
pub struct RuleComparison {
    pub measure: usize,
    pub a: usize,
    pub b: usize,
    pub paired: Paired,
}

/// Everything the report's tables and the verdicts rest on.
#[derive(Debug, Clone, PartialEq)]
pub struct Statistics {
    /// Fig. 2: ρ(ln|Π^U|, task error).
    pub task_error: Correlation,
    /// Fig. 4: ρ(ln|Π^U|, |Δ task error| under ΔT).
    pub reliability: Correlation,
    /// Fig. 5: every non-zero level.
    pub sweep: Vec<SweepLevel>,
    pub signs: Vec<SignComparison>,
    /// Fig. 6: trials where F and J chose differently, of the trials both chose in.
    pub grid_disagreements: (usize, usize),
    /// Fig. 7: `values[m][r][k]`, measure m of rule r's tool in trial k.
    pub chosen: Vec<Vec<Vec<Option<f64>>>>,
    pub comparisons: Vec<RuleComparison>,
}

/// (ln|Π^U|, y) of every tool with both.
fn points(records: &[ToolRecord], y: impl Fn(&ToolRecord) -> Option<f64>) -> (Vec<f64>, Vec<f64>) {
    records
        .iter()
        .filter_map(|r| Some((r.logdet()?, y(r)?)))
        .unzip()
}

impl Statistics {
    pub fn compute(
        records: &[ToolRecord],
        scales: &[f64],
        grid: &[Trial],
        trials: &[Trial],
        plan: &Plan,
        seed: u64,
    ) -> Self {
        let sweep_records = &records[..plan.sweep_tools.min(records.len())];
        let levels: Vec<usize> = (0..scales.len()).filter(|&k| scales[k] != 0.0).collect();
        let mut jobs: Vec<(Vec<f64>, Vec<f64>, u64)> = vec![
            with_seed(
                points(records, ToolRecord::task_error),
                seed,
                "fig2/bootstrap",
            ),
            with_seed(
                points(records, ToolRecord::abs_change),
                seed,
                "fig4/bootstrap",
            ),
        ];
        for &k in &levels {
            let label = format!("fig5/bootstrap/{:+}", scales[k]);
            jobs.push(with_seed(
                points(sweep_records, |r| r.sweep_change(k)),
                seed,
                &label,
            ));
        }
        let mut corrs: Vec<Correlation> = jobs
            .par_iter()
            .map(|(x, y, s)| Correlation::compute(x, y, plan.resamples, plan.level, *s))
            .collect();
        let sweep = levels
            .iter()
            .zip(corrs.drain(2..))
            .map(|(&k, correlation)| SweepLevel {
                scale: scales[k],
                correlation,
            })
            .collect();
        let reliability = corrs.pop().expect("two correlations");
        let task_error = corrs.pop().expect("two correlations");
        let chosen = chosen_values(records, trials);
        Self {
            task_error,
            reliability,
            sweep,
            signs: signs(sweep_records, scales),
            grid_disagreements: disagreements(grid),
            comparisons: comparisons(&chosen),
            chosen,
        }
    }

    /// The three verdicts, by the rules of [`super::verdict`].
    pub fn verdicts(&self, plan: &Plan) -> Vec<ClaimVerdict> {
        let rule = |c: Claim| c.rule(plan.level, plan.alpha);
        let correlation = |claim: Claim, c: &Correlation| ClaimVerdict {
            claim,
            finding: c.finding(),
            evidence: c.describe(),
            statistic: c.json(),
            rule: rule(claim),
        };
        let selection = self.selection();
        vec![
            correlation(Claim::TaskError, &self.task_error),
            correlation(Claim::Reliability, &self.reliability),
            ClaimVerdict {
                claim: Claim::Selection,
                finding: selection.finding(plan.alpha),
                evidence: format!(
                    "|Δ task error| of J's tool − F's tool: {}",
                    selection.describe()
                ),
                statistic: selection.json(),
                rule: rule(Claim::Selection),
            },
        ]
    }

    /// Claim (c)'s comparison: sensitivity of J's tool − F's tool.
    pub fn selection(&self) -> Paired {
        let (f, j) = (
            rule_index(crate::select::Objective::FreeEnergy),
            rule_index(crate::select::Objective::CostJ),
        );
        Paired::compute(&self.chosen[2][j], &self.chosen[2][f])
    }
}

fn rule_index(o: crate::select::Objective) -> usize {
    RULES
        .iter()
        .position(|r| *r == o)
        .expect("a rule of the experiments")
}

fn with_seed(xy: (Vec<f64>, Vec<f64>), seed: u64, label: &str) -> (Vec<f64>, Vec<f64>, u64) {
    (xy.0, xy.1, derive_seed(seed, label))
}

/// Per magnitude s of the sweep with both ±s: |Δ| at +s − at −s, per tool.
fn signs(records: &[ToolRecord], scales: &[f64]) -> Vec<SignComparison> {
    scales
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > 0.0)
        .filter_map(|(k, &s)| {
            let minus = scales.iter().position(|&t| t == -s)?;
            let a: Vec<Option<f64>> = records.iter().map(|r| r.sweep_change(k)).collect();
            let b: Vec<Option<f64>> = records.iter().map(|r| r.sweep_change(minus)).collect();
            Some(SignComparison {
                magnitude: s,
                paired: Paired::compute(&a, &b),
            })
        })
        .collect()
}

/// Trials where F and J chose different tools, of those both chose in.
fn disagreements(grid: &[Trial]) -> (usize, usize) {
    let (f, j) = (
        rule_index(crate::select::Objective::FreeEnergy),
        rule_index(crate::select::Objective::CostJ),
    );
    let both: Vec<bool> = grid
        .iter()
        .filter_map(|t| Some(t.chosen[f]? != t.chosen[j]?))
        .collect();
    (both.iter().filter(|d| **d).count(), both.len())
}

/// Every measure, every pair of rules.
fn comparisons(chosen: &[Vec<Vec<Option<f64>>>]) -> Vec<RuleComparison> {
    let mut out = Vec::new();
    for (m, by_rule) in chosen.iter().enumerate().take(MEASURES.len()) {
        for a in 0..RULES.len() {
            for b in a + 1..RULES.len() {
                out.push(RuleComparison {
                    measure: m,
                    a,
                    b,
                    paired: Paired::compute(&by_rule[a], &by_rule[b]),
                });
            }
        }
    }
    out
}

/// The most progress any tool may make for the task to count as having barely moved them.
pub const BARELY_MOVED: f64 = 0.1;

/// On a position task (joint or tip), when every tool's progress 1 − e(T)/e(0) is below
/// [`BARELY_MOVED`]: the sentence saying so and which precision to raise.
pub fn barely_moved(kind: toolconf_model::TaskKind, progress: &[f64]) -> Option<String> {
    let largest = progress.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if progress.is_empty() || largest >= BARELY_MOVED {
        return None;
    }
    let term = kind.error_term();
    Some(format!(
        "the task barely moved the tools: every one of the {} tools' progress 1 − e(T)/e(0) is \
         below {BARELY_MOVED} (the largest {largest:.3}), so the controller's prior on U \
         outweighs the goal: raise precision.{term} (1/σ² of the tolerance on {}) or lower \
         precision.u",
        progress.len(),
        term.name(),
    ))
}
