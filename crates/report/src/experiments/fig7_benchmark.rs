//! Fig. 7 (claim C4): trials of random tools on the velocity task; the tools chosen by every
//! decision rule (∫F, ∫J, confidence alone, and any added rule) compared on control confidence,
//! task error and sensitivity to ΔT = −0.8 N m (|change of task error|), with box plots,
//! mean ± sd and paired tests between every two rules.
//!
//! Seeds: trial k draws its tools from `"fig7/trial/<k>"`.

use toolconf::select::{evaluate, ToolResult};
use toolconf_model::{Arm, TaskKind};
use toolconf_stats::summary;

use super::figure_parts::{arm_cells, dt_label, files_block, rhs_evals, ARM_COLUMNS};
use super::objectives::{decision_rules, run_trials, DecisionRule, MpcCost, TrialPlan};
use super::plot::{self, BoxPanel, Panel};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::{num, Comparison};
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf::mpc::MpcOptions;
use toolconf_files::csv::{Cell, CsvWriter};

/// Fig. 7; `with_mpc` adds the MPC baseline's J* ranking to the paper's three rules when the run
/// has the MPC switched on ([`Plan::mpc`]).
pub struct Fig7 {
    pub with_mpc: bool,
}

impl Fig7 {
    fn rules(&self, plan: &Plan) -> Vec<Box<dyn DecisionRule>> {
        let mut rules = decision_rules();
        if self.with_mpc && plan.mpc {
            rules.push(Box::new(MpcCost(MpcOptions::default())));
        }
        rules
    }
}

const CSV: &str = "fig7_benchmark.csv";
const CHOICES_CSV: &str = "fig7_choices.csv";
const SVG: &str = "fig7_benchmark.svg";
pub const TASK: TaskKind = TaskKind::Velocity;
/// The choices' columns, those of the evaluation's fig7_choices.csv.
pub use toolconf::evaluation::tables::CHOICES_HEADER;

/// The per-tool header: parameters, metrics, perturbed task error, one `chosen_by_<rule>` per
/// rule, error.
pub fn header(rules: &[Box<dyn DecisionRule>]) -> Vec<String> {
    let mut h: Vec<String> = ["trial", "tool"]
        .into_iter()
        .chain(ARM_COLUMNS)
        .chain([
            "logdet",
            "task_error",
            "free_energy",
            "cost_j",
            "task_error_perturbed",
            "abs_change",
        ])
        .map(String::from)
        .collect();
    h.extend(rules.iter().map(|r| format!("chosen_by_{}", r.id())));
    h.push("error".into());
    h
}

struct TrialResult {
    tools: Vec<Arm>,
    results: Vec<ToolResult>,
    perturbed: Vec<ToolResult>,
    chosen: Vec<Option<usize>>,
}

impl TrialResult {
    fn logdet(&self, i: usize) -> Option<f64> {
        self.results[i].logdet.as_ref().ok().copied()
    }

    fn task_error(&self, i: usize) -> Option<f64> {
        self.results[i].episode.as_ref().ok().map(|m| m.task_error)
    }

    fn perturbed_error(&self, i: usize) -> Option<f64> {
        self.perturbed[i]
            .episode
            .as_ref()
            .ok()
            .map(|m| m.task_error)
    }

    fn abs_change(&self, i: usize) -> Option<f64> {
        Some((self.perturbed_error(i)? - self.task_error(i)?).abs()).filter(|v| v.is_finite())
    }

    fn error(&self, i: usize) -> String {
        let (r, p) = (&self.results[i], &self.perturbed[i]);
        match (&r.logdet, &r.episode, &p.episode) {
            (Err(e), _, _) => e.to_string(),
            (_, Err(e), _) => e.to_string(),
            (_, _, Err(e)) => format!("perturbed episode: {e}"),
            _ => String::new(),
        }
    }
}

/// The three measures of the figure, each a function of (trial, chosen tool).
const METRICS: [(&str, &str); 3] = [
    ("confidence", "control confidence ln|Π^U|"),
    ("task error", "task error"),
    ("sensitivity", "|change of task error| under ΔT"),
];

fn metric(t: &TrialResult, m: usize, tool: usize) -> Option<f64> {
    match m {
        0 => t.logdet(tool),
        1 => t.task_error(tool),
        _ => t.abs_change(tool),
    }
}

impl Experiment for Fig7 {
    described!(
        "fig7",
        "Fig. 7: benchmarking tool selection by F, J and confidence (C4)",
        [CSV, CHOICES_CSV, SVG]
    );

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        (if self.with_mpc && plan.mpc { 3 } else { 2 })
            * (plan.fig7_trials * plan.fig7_tools) as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let rules = self.rules(plan);
        let done = self.run_trials(ctx, &rules)?;
        let values = ChosenValues::new(&done, &rules);
        let svg = values.figure(ctx, &rules)?;
        let failed = done
            .iter()
            .map(|t| {
                (0..t.tools.len())
                    .filter(|&i| !t.error(i).is_empty())
                    .count()
            })
            .sum();
        let labels: Vec<&str> = rules.iter().map(|r| r.label()).collect();
        let mut blocks = vec![
            Block::p(format!(
                "{} trials, each of {} random tools on task 2 (velocity). Every tool is simulated \
                 without and with ΔT = {} N m; each rule picks a tool from the unperturbed \
                 episodes ({}), and the chosen tools are compared on control confidence, task \
                 error and sensitivity |task error(ΔT) − task error(0)|. Paired tests pair the \
                 rules' tools trial by trial (a trial where both rules chose the same tool is a \
                 zero difference).",
                done.len(),
                plan.fig7_tools,
                dt_label(plan.perturbation),
                labels.join(", ")
            )),
            files_block(
                &[CSV.into(), CHOICES_CSV.into(), SVG.into()],
                done.len() * plan.fig7_tools,
                failed,
                "tool rows, two episodes each, and one choice row per trial and rule",
            ),
            Block::table(
                &["measure", "rule", "n", "mean ± sd", "median [q1, q3]"],
                values.summary_rows(&rules),
            ),
            Block::table(
                &["measure", "difference", "paired tests"],
                values.test_rows(&rules),
            ),
            Block::Figure {
                file: SVG.into(),
                caption: "The tools chosen by each rule: box plots (median, quartiles, whiskers \
                          at 1.5 IQR, outliers as rings) with mean ± sd (triangle and bar) beside \
                          each box. Compare with the paper's Fig. 7."
                    .into(),
                svg,
            },
        ];
        let compare = |m: usize, a: usize, b: usize| values.compare(m, a, b);
        blocks.extend(
            verdicts(&rules, &compare, plan.alpha)
                .into_iter()
                .map(Block::Verdict),
        );
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: 2 * (done.len() * plan.fig7_tools) as u64,
            rhs_evals: rhs_evals(
                done.iter()
                    .flat_map(|t| t.results.iter().chain(&t.perturbed)),
            ),
        })
    }
}

impl Fig7 {
    /// Every trial: draw the tools, simulate each without and with ΔT, let every rule choose;
    /// the tool rows and the choices are written as each trial finishes.
    fn run_trials(
        &self,
        ctx: &Context,
        rules: &[Box<dyn DecisionRule>],
    ) -> Result<Vec<TrialResult>, ReproduceError> {
        let perturbed = ctx.perturbed(ctx.plan.perturbation);
        let header = header(rules);
        let mut csv = ctx.csv(CSV, &header)?;
        let mut choices_csv = ctx.csv(CHOICES_CSV, &CHOICES_HEADER)?;
        let plan = TrialPlan {
            kind: TASK,
            trials: ctx.plan.fig7_trials,
            tools: ctx.plan.fig7_tools,
            episodes_per_tool: 2,
        };
        let done = run_trials(
            ctx,
            self,
            plan,
            rules,
            |task, (tools, results, chosen)| {
                let perturbed = evaluate(&tools, task, &perturbed, ctx.plant);
                TrialResult {
                    tools,
                    results,
                    perturbed,
                    chosen,
                }
            },
            |k, t| write_trial(&mut csv, &mut choices_csv, rules, k, t),
        )?;
        csv.finish()?;
        choices_csv.finish()?;
        Ok(done)
    }
}

/// Trial `k`'s tool rows (with which rules chose each) and one choice row per rule.
fn write_trial(
    csv: &mut CsvWriter,
    choices_csv: &mut CsvWriter,
    rules: &[Box<dyn DecisionRule>],
    k: usize,
    t: &TrialResult,
) -> Result<(), ReproduceError> {
    for (i, r) in t.results.iter().enumerate() {
        let m = r.episode.as_ref().ok();
        let mut row = vec![Cell::from(k), Cell::from(i)];
        row.extend(arm_cells(&t.tools[i]));
        row.extend([
            Cell::from(t.logdet(i)),
            Cell::from(t.task_error(i)),
            Cell::from(m.map(|m| m.free_energy)),
            Cell::from(m.map(|m| m.cost_j)),
            Cell::from(t.perturbed_error(i)),
            Cell::from(t.abs_change(i)),
        ]);
        row.extend(t.chosen.iter().map(|c| Cell::from(*c == Some(i))));
        row.push(Cell::from(t.error(i)));
        csv.row(row)?;
    }
    for (rule, c) in rules.iter().zip(&t.chosen) {
        // The trial, the rule, its tool and the tool's METRICS: CHOICES_HEADER's columns.
        let mut row = vec![
            Cell::from(k),
            Cell::from(rule.id()),
            c.map_or(Cell::Empty, Cell::from),
        ];
        row.extend((0..METRICS.len()).map(|m| Cell::from(c.and_then(|i| metric(t, m, i)))));
        choices_csv.row(row)?;
    }
    Ok(())
}

/// `values[m][r][k]`: measure m ([`METRICS`]) of the tool rule r chose in trial k.
struct ChosenValues {
    values: Vec<Vec<Vec<Option<f64>>>>,
}

impl ChosenValues {
    fn new(done: &[TrialResult], rules: &[Box<dyn DecisionRule>]) -> Self {
        let values = (0..METRICS.len())
            .map(|m| {
                (0..rules.len())
                    .map(|r| {
                        done.iter()
                            .map(|t| t.chosen[r].and_then(|i| metric(t, m, i)))
                            .collect()
                    })
                    .collect()
            })
            .collect();
        ChosenValues { values }
    }

    fn present(&self, m: usize, r: usize) -> Vec<f64> {
        self.values[m][r].iter().flatten().copied().collect()
    }

    fn compare(&self, m: usize, a: usize, b: usize) -> Comparison {
        Comparison::compute(&self.values[m][a], &self.values[m][b])
    }

    fn summary_rows(&self, rules: &[Box<dyn DecisionRule>]) -> Vec<Vec<String>> {
        let mut rows = Vec::new();
        for (m, (name, _)) in METRICS.iter().enumerate() {
            for (r, rule) in rules.iter().enumerate() {
                let v = self.present(m, r);
                rows.push(match summary(&v) {
                    Ok(s) => vec![
                        name.to_string(),
                        rule.label().into(),
                        s.n.to_string(),
                        format!("{} ± {}", num(s.mean), num(s.sd)),
                        format!("{} [{}, {}]", num(s.median), num(s.q1), num(s.q3)),
                    ],
                    Err(e) => vec![
                        name.to_string(),
                        rule.label().into(),
                        v.len().to_string(),
                        format!("undefined: {e}"),
                        "-".into(),
                    ],
                });
            }
        }
        rows
    }

    /// Paired tests of every pair of rules on every measure.
    fn test_rows(&self, rules: &[Box<dyn DecisionRule>]) -> Vec<Vec<String>> {
        let mut rows = Vec::new();
        for (m, (name, _)) in METRICS.iter().enumerate() {
            for a in 0..rules.len() {
                for b in a + 1..rules.len() {
                    rows.push(vec![
                        name.to_string(),
                        format!("{} − {}", rules[a].label(), rules[b].label()),
                        self.compare(m, a, b).describe(),
                    ]);
                }
            }
        }
        rows
    }

    /// One box panel per measure, one box per rule.
    fn figure(
        &self,
        ctx: &Context,
        rules: &[Box<dyn DecisionRule>],
    ) -> Result<String, ReproduceError> {
        let panels: Vec<Panel> = METRICS
            .iter()
            .enumerate()
            .map(|(m, (name, axis))| {
                Panel::Boxes(BoxPanel {
                    title: format!("{name} of the chosen tool"),
                    y_label: if m == 2 {
                        format!("{axis} = {} N m", dt_label(ctx.plan.perturbation))
                    } else {
                        axis.to_string()
                    },
                    groups: rules
                        .iter()
                        .enumerate()
                        .map(|(r, rule)| (short(rule.as_ref()), rule.colour(), self.present(m, r)))
                        .collect(),
                })
            })
            .collect();
        plot::save(&ctx.path(SVG), &panels, (440, 440))
    }
}

/// The label up to its first space ("F", "J", "confidence").
fn short(rule: &dyn DecisionRule) -> String {
    rule.label().split(' ').next().unwrap_or("").to_string()
}

/// The four verdicts of claim C4, when the rules F, J and confidence are all benchmarked.
fn verdicts(
    rules: &[Box<dyn DecisionRule>],
    compare: &dyn Fn(usize, usize, usize) -> Comparison,
    alpha: f64,
) -> Vec<Verdict> {
    let find = |id: &str| rules.iter().position(|r| r.id() == id);
    let (Some(f), Some(j), Some(c)) = (find("free_energy"), find("cost_j"), find("confidence"))
    else {
        return vec![];
    };
    let significant = format!("Wilcoxon signed-rank p < {alpha} (two-sided)");
    vec![
        confidence_verdict(&compare(0, f, j), alpha, &significant),
        sensitivity_verdict(&compare(2, j, f), alpha, &significant),
        task_error_verdict(rules, f, compare, alpha, &significant),
        similarity_verdict(c, f, compare, alpha),
    ]
}

/// Holds for a significantly greater a, does not for a significantly smaller one.
fn directional(better: Option<bool>) -> Outcome {
    match better {
        None => Outcome::NotJudged,
        Some(true) => Outcome::Holds,
        Some(false) => Outcome::DoesNotHold,
    }
}

/// Not judged, or else holds, partly holds or does not hold, the first that applies.
fn graded(judged: bool, holds: bool, partly: bool) -> Outcome {
    if !judged {
        Outcome::NotJudged
    } else if holds {
        Outcome::Holds
    } else if partly {
        Outcome::Partly
    } else {
        Outcome::DoesNotHold
    }
}

/// C4: J's tools have the lower confidence (`conf`: F's − J's).
fn confidence_verdict(conf: &Comparison, alpha: f64, significant: &str) -> Verdict {
    greater_verdict(
        "C4, confidence",
        "\"The tools selected by J showed lower control confidence\" than those selected by F.",
        (conf, alpha, "ln|Π^U| of F's tool − J's tool"),
        &format!("F's tools have the higher confidence with {significant}"),
    )
}

/// C4: F's tools are the less sensitive to a perturbation (`sens`: J's − F's).
fn sensitivity_verdict(sens: &Comparison, alpha: f64, significant: &str) -> Verdict {
    greater_verdict(
        "C4, sensitivity",
        "\"The tool selected using F has a superior tolerance to control perturbations than the \
         tool selected using J\": J's tools have the higher sensitivity to a constant \
         perturbation.",
        (sens, alpha, "|change of task error| of J's tool − F's tool"),
        &format!("J's tools are the more sensitive with {significant}"),
    )
}

/// The verdict on `claim` (`statement`) that the first sample of `comparison` (a − b, at level
/// alpha, in words `of`) exceeds the second: it holds `holds_if` so, and does not otherwise.
fn greater_verdict(
    claim: &str,
    statement: &str,
    (comparison, alpha, of): (&Comparison, f64, &str),
    holds_if: &str,
) -> Verdict {
    Verdict {
        claim: claim.into(),
        statement: statement.into(),
        outcome: directional(comparison.a_greater(alpha)),
        evidence: format!("{of}: {}.", comparison.describe()),
        rule: format!("holds if {holds_if}; does not hold otherwise."),
    }
}

/// C4: F (rule `f`) has the lowest mean task error of the rules.
fn task_error_verdict(
    rules: &[Box<dyn DecisionRule>],
    f: usize,
    compare: &dyn Fn(usize, usize, usize) -> Comparison,
    alpha: f64,
    significant: &str,
) -> Verdict {
    let others: Vec<usize> = (0..rules.len()).filter(|&r| r != f).collect();
    let error_cmp: Vec<(usize, Comparison)> =
        others.iter().map(|&r| (r, compare(1, r, f))).collect();
    let lowest = error_cmp
        .iter()
        .all(|(_, c)| c.mean_difference().is_some_and(|d| d > 0.0) || c.paired.identical());
    let all_significant = error_cmp
        .iter()
        .all(|(_, c)| c.a_greater(alpha) == Some(true));
    let judged = error_cmp.iter().all(|(_, c)| c.mean_difference().is_some());
    Verdict {
        claim: "C4, task error".into(),
        statement: "\"F has the lowest average task error\" of the rules.".into(),
        outcome: graded(judged, lowest && all_significant, lowest),
        evidence: error_cmp
            .iter()
            .map(|(r, c)| {
                format!(
                    "task error of {}'s tool − F's tool: {}",
                    short(rules[*r].as_ref()),
                    c.describe()
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
            + ".",
        rule: format!(
            "holds if F's mean task error is the lowest and lower than each other rule's with \
             {significant}; partly holds if it is the lowest mean but not significantly lower \
             than every other; does not hold if another rule has a lower mean."
        ),
    }
}

/// C4: the confidence-only rule (`c`) is similar to F (`f`) on every measure.
fn similarity_verdict(
    c: usize,
    f: usize,
    compare: &dyn Fn(usize, usize, usize) -> Comparison,
    alpha: f64,
) -> Verdict {
    let similar: Vec<(usize, Comparison)> =
        (0..METRICS.len()).map(|m| (m, compare(m, c, f))).collect();
    let verdicts: Vec<Option<bool>> = similar.iter().map(|(_, s)| s.similar(alpha)).collect();
    let yes = verdicts.iter().filter(|v| **v == Some(true)).count();
    Verdict {
        claim: "C4, confidence-only selection".into(),
        statement: "\"The confidence-based tool selection showed similar confidence, task error \
                    and sensitivity to that of F.\""
            .into(),
        outcome: graded(
            verdicts.iter().all(Option::is_some),
            yes == METRICS.len(),
            yes > 0,
        ),
        evidence: similar
            .iter()
            .map(|(m, s)| {
                format!(
                    "{} (confidence's tool − F's): {}",
                    METRICS[*m].0,
                    s.describe()
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
            + ".",
        rule: format!(
            "a measure counts as similar when the paired difference is not significant \
             (Wilcoxon p ≥ {alpha}) or the two rules chose the same tool in every trial (no \
             significant difference is weaker evidence than a proof of equality); holds if all \
             three measures are similar, partly holds if one or two are, does not hold if none."
        ),
    }
}
