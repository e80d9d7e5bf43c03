//! Fig. 2 (claim C1): task error against control confidence for random tools on all three tasks,
//! with an exponential trend y = a·exp(b·x) per task and Spearman's ρ with a bootstrap CI.
//!
//! Seeds: tools from `"fig2/tools"` (the same tools for every task, as in the paper), bootstrap
//! from `"fig2/bootstrap/<task>"`.

use crate::select::draw_tools;
use crate::stats::{fit_exponential, summary};
use crate::{Task, TaskKind};

use super::batch::{map_ordered, run_tool, ToolRuns};
use super::common::{arm_cells, files_block, task_label, wants_log};
use super::csv::{Cell, CsvWriter};
use super::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::{negative_correlation_rule, num, Correlation};
use super::{Context, Experiment, Plan, ReproduceError};

pub struct Fig2;

const CSV: &str = "fig2_confidence_vs_error.csv";
const SVG: &str = "fig2_confidence_vs_error.svg";
pub const HEADER: [&str; 12] = [
    "task",
    "tool",
    "m1",
    "m2",
    "l1",
    "l2",
    "logdet",
    "task_error",
    "free_energy",
    "cost_j",
    "rhs_evals",
    "error",
];
/// Task errors whose coefficient of variation (sd/mean) is at most this count as "similar".
const SIMILAR_CV: f64 = 0.25;

const COLOURS: [Colour; 3] = [Colour(0, 114, 178), Colour(213, 94, 0), Colour(0, 158, 115)];

impl Experiment for Fig2 {
    fn id(&self) -> &'static str {
        "fig2"
    }

    fn title(&self) -> &'static str {
        "Fig. 2: control confidence and task error (C1)"
    }

    fn outputs(&self) -> Vec<String> {
        vec![CSV.into(), SVG.into()]
    }

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        3 * plan.fig2_tools as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let tools = draw_tools(plan.fig2_tools, ctx.seed_for(self, "tools"));
        let items: Vec<(TaskKind, usize)> = TaskKind::ALL
            .iter()
            .flat_map(|&k| (0..tools.len()).map(move |i| (k, i)))
            .collect();
        let mut csv = CsvWriter::create(&ctx.path(CSV), &HEADER)?;
        let options = [ctx.options.clone()];
        let results = map_ordered(
            &items,
            ctx.progress,
            1,
            |&(kind, i)| (kind, i, run_tool(&tools[i], &Task::paper(kind), &options)),
            |(kind, i, r)| {
                let m = r.metrics(0);
                let mut row = vec![Cell::from(kind.name()), Cell::from(*i)];
                row.extend(arm_cells(&r.arm));
                row.extend([
                    Cell::from(r.logdet()),
                    Cell::from(m.map(|m| m.task_error)),
                    Cell::from(m.map(|m| m.free_energy)),
                    Cell::from(m.map(|m| m.cost_j)),
                    m.map_or(Cell::Empty, |m| Cell::from(m.rhs_evals)),
                    Cell::from(r.error()),
                ]);
                csv.row(row)
            },
        )?;

        let mut blocks = vec![Block::p(format!(
            "{} random tools (m1, m2, l1, l2 uniform on [0.1, 0.6)), each simulated on the three \
             tasks without perturbation. For each task: Spearman's ρ between ln|Π^U| and the task \
             error with a {}% percentile-bootstrap interval ({} resamples), and the least-squares \
             fit task error = a·exp(b·ln|Π^U|) that the paper draws.",
            tools.len(),
            (plan.level * 100.0).round(),
            plan.bootstrap_resamples
        ))];
        let mut panels = Vec::new();
        let mut rows = Vec::new();
        let mut verdicts = Vec::new();
        let mut failed_total = 0;
        let jobs: Vec<(Vec<f64>, Vec<f64>, u64)> = TaskKind::ALL
            .iter()
            .map(|&kind| {
                let (x, y) = results
                    .iter()
                    .filter(|r| r.0 == kind)
                    .filter_map(|r| Some((r.2.logdet()?, r.2.task_error(0)?)))
                    .unzip();
                (
                    x,
                    y,
                    ctx.seed_for(self, &format!("bootstrap/{}", kind.name())),
                )
            })
            .collect();
        let corrs = Correlation::compute_all(&jobs, plan.bootstrap_resamples, plan.level);
        for (t, kind) in TaskKind::ALL.into_iter().enumerate() {
            let runs: Vec<&ToolRuns> = results
                .iter()
                .filter(|r| r.0 == kind)
                .map(|r| &r.2)
                .collect();
            let ok: Vec<(f64, f64)> = runs
                .iter()
                .filter_map(|r| Some((r.logdet()?, r.task_error(0)?)))
                .collect();
            let failed = runs.len() - ok.len();
            failed_total += failed;
            let (x, y): (Vec<f64>, Vec<f64>) = ok.iter().copied().unzip();
            let corr = &corrs[t];
            let fit = fit_exponential(&x, &y);
            let x_range = x
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            let spread = x_range.1 - x_range.0;
            let error_summary = summary(&y);
            let cv = error_summary
                .as_ref()
                .ok()
                .filter(|s| s.mean > 0.0)
                .map(|s| s.sd / s.mean);
            rows.push(vec![
                task_label(kind),
                ok.len().to_string(),
                failed.to_string(),
                if x.is_empty() {
                    "-".into()
                } else {
                    format!("[{}, {}]", num(x_range.0), num(x_range.1))
                },
                error_summary.as_ref().map_or("-".into(), |s| {
                    format!("{} [{}, {}]", num(s.median), num(s.min), num(s.max))
                }),
                cv.map_or("-".into(), num),
                corr.rho_cell(),
                corr.ci_cell(),
                match &fit {
                    Ok(f) => format!(
                        "a = {}, b = {}, R² = {}, RMSE = {}",
                        num(f.a),
                        num(f.b),
                        num(f.r_squared),
                        num(f.rmse)
                    ),
                    Err(e) => format!("no fit: {e}"),
                },
            ]);

            let mut lines = Vec::new();
            if let Ok(f) = &fit {
                let curve = (0..=100)
                    .map(|k| {
                        let v = x_range.0 + spread * f64::from(k) / 100.0;
                        (v, f.a * (f.b * v).exp())
                    })
                    .collect();
                lines.push(Series::new(
                    format!("{}·exp({}·x)", num(f.a), num(f.b)),
                    Colour(0, 0, 0),
                    curve,
                ));
            }
            let title = match &corr.rho {
                Ok(r) => format!(
                    "Task {} ({}): ρ = {}",
                    kind.paper_index(),
                    kind.name(),
                    num(*r)
                ),
                Err(_) if !x.is_empty() && spread == 0.0 => format!(
                    "Task {} ({}): ln|Π^U| = {} for every tool",
                    kind.paper_index(),
                    kind.name(),
                    num(x[0])
                ),
                Err(_) => format!("Task {} ({}): ρ undefined", kind.paper_index(), kind.name()),
            };
            panels.push(Panel::Xy(XyPanel {
                title,
                x_label: "control confidence ln|Π^U|".into(),
                y_label: "task error".into(),
                dots: vec![Series::new("tools", COLOURS[t], ok.clone())],
                lines,
                log_y: wants_log(&y),
                legend: Legend::UpperRight,
                headroom: 0.15,
            }));

            let label = format!("C1, {}", task_label(kind));
            let extra = if failed > 0 {
                format!(" ({failed} failed episode(s) left out)")
            } else {
                String::new()
            };
            verdicts.push(match kind {
                TaskKind::Position | TaskKind::Velocity => Verdict {
                    claim: label,
                    statement: format!(
                        "\"On average, the tools with higher control confidence performs better \
                         at the task than the tools with lower control confidence\" ({}): a clear \
                         negative correlation between ln|Π^U| and task error.",
                        task_label(kind)
                    ),
                    outcome: corr.negative_outcome(),
                    evidence: format!("{}{extra}.", corr.describe()),
                    rule: negative_correlation_rule(plan.level),
                },
                TaskKind::Acceleration => {
                    let constant = !x.is_empty() && spread <= 1e-9 * x_range.0.abs().max(1.0);
                    let similar = cv.map(|c| c <= SIMILAR_CV);
                    let outcome = match (constant, similar) {
                        (_, None) if x.is_empty() => Outcome::NotJudged,
                        (true, Some(true)) => Outcome::Holds,
                        (true, _) | (false, Some(true)) => Outcome::Partly,
                        (false, _) => Outcome::DoesNotHold,
                    };
                    Verdict {
                        claim: label,
                        statement: "\"For task 3, the controller has the same confidence on all \
                                    tools, which is in line with similar task errors for all \
                                    tools.\""
                            .into(),
                        outcome,
                        evidence: format!(
                            "ln|Π^U| ranges over [{}, {}] ({}); task error median {}, range \
                             [{}, {}], coefficient of variation {} ({}){extra}. {}.",
                            num(x_range.0),
                            num(x_range.1),
                            if constant {
                                "identical for every tool"
                            } else {
                                "not constant"
                            },
                            error_summary.as_ref().map_or("-".into(), |s| num(s.median)),
                            error_summary.as_ref().map_or("-".into(), |s| num(s.min)),
                            error_summary.as_ref().map_or("-".into(), |s| num(s.max)),
                            cv.map_or("undefined".into(), num),
                            match similar {
                                Some(true) => "similar",
                                Some(false) => "not similar",
                                None => "undefined",
                            },
                            corr.describe()
                        ),
                        rule: format!(
                            "two parts: equal confidence (max − min of ln|Π^U| ≤ 1e-9 relative) \
                             and similar task errors (coefficient of variation sd/mean ≤ \
                             {SIMILAR_CV}); holds if both, partly holds if one, does not hold if \
                             neither. Spearman's ρ is undefined when the confidence is constant \
                             and is reported only for completeness."
                        ),
                    }
                }
            });
        }
        let svg = plot::save(&ctx.path(SVG), &panels, (500, 420))?;
        blocks.push(files_block(
            &[CSV.into(), SVG.into()],
            results.len(),
            failed_total,
            "rows, one per task and tool",
        ));
        blocks.push(Block::table(
            &[
                "task",
                "n",
                "failed",
                "ln|Π^U| range",
                "task error median [min, max]",
                "CV",
                "Spearman ρ",
                "bootstrap CI",
                "exponential fit (task error = a·exp(b·ln|Π^U|))",
            ],
            rows,
        ));
        blocks.push(Block::Figure {
            file: SVG.into(),
            caption: format!(
                "Task error against control confidence for {} random tools on the three tasks, \
                 with the least-squares exponential fit (black). Compare with the paper's Fig. 2.",
                tools.len()
            ),
            svg,
        });
        blocks.extend(verdicts.into_iter().map(Block::Verdict));
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: results.len() as u64,
            rhs_evals: results.iter().map(|r| r.2.rhs_evals()).sum(),
        })
    }
}
