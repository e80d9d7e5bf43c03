//! Fig. 2 (claim C1): task error against control confidence for random tools on all three tasks,
//! with an exponential trend y = a·exp(b·x) per task and Spearman's ρ with a bootstrap CI.
//!
//! Seeds: tools from `"fig2/tools"` (the same tools for every task, as in the paper), bootstrap
//! from `"fig2/bootstrap/<task>"`.

use toolconf::select::draw_tools;
use toolconf_model::TaskKind;
use toolconf_stats::{fit_exponential, summary};

use super::batch::{run_every_task, ToolRuns};
use super::figure_parts::{columns, files_block, task_label, wants_log, PAPER_TASKS, TOOL_COLUMNS};
use super::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::{negative_correlation_rule, num, Correlation, CorrelationReport};
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::Cell;

pub struct Fig2;

const CSV: &str = "fig2_confidence_vs_error.csv";
const SVG: &str = "fig2_confidence_vs_error.svg";
pub const HEADER: [&str; 12] = columns(&[
    &["task"],
    &TOOL_COLUMNS,
    &["task_error", "free_energy", "cost_j", "rhs_evals", "error"],
]);
/// Task errors whose coefficient of variation (sd/mean) is at most this count as "similar".
const SIMILAR_CV: f64 = 0.25;

const COLOURS: [Colour; 3] = [Colour(0, 114, 178), Colour(213, 94, 0), Colour(0, 158, 115)];

impl Experiment for Fig2 {
    described!(
        "fig2",
        "Fig. 2: control confidence and task error (C1)",
        [CSV, SVG]
    );

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        3 * plan.fig2_tools as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let tools = draw_tools(plan.fig2_tools, ctx.seed_for(self, "tools"));
        let results = simulate_every_task(ctx, &tools)?;
        let runs_of = |kind: TaskKind| -> Vec<&ToolRuns> {
            results
                .iter()
                .filter(|r| r.0 == kind)
                .map(|r| &r.2)
                .collect()
        };
        let stats: Vec<TaskStats> = PAPER_TASKS
            .iter()
            .map(|&k| TaskStats::new(&runs_of(k)))
            .collect();
        let jobs: Vec<(Vec<f64>, Vec<f64>, u64)> = PAPER_TASKS
            .iter()
            .zip(&stats)
            .map(|(kind, st)| {
                let seed = ctx.seed_for(self, &format!("bootstrap/{}", kind.name()));
                (st.x.clone(), st.y.clone(), seed)
            })
            .collect();
        let corrs = Correlation::compute_all(&jobs, plan.bootstrap_resamples, plan.level);

        let mut rows = Vec::new();
        let mut panels = Vec::new();
        let mut verdicts = Vec::new();
        for (t, kind) in PAPER_TASKS.into_iter().enumerate() {
            let (st, corr) = (&stats[t], &corrs[t]);
            rows.push(st.table_row(kind, corr));
            panels.push(st.panel(kind, corr, COLOURS[t]));
            verdicts.push(match kind {
                TaskKind::Acceleration => st.equal_confidence_verdict(kind, corr),
                _ => st.correlation_verdict(kind, corr, plan.level),
            });
        }
        let failed_total = stats.iter().map(|st| st.failed).sum();
        let svg = plot::save(&ctx.path(SVG), &panels, (500, 420))?;
        let mut blocks = vec![introduction(tools.len(), plan)];
        blocks.push(files_block(
            &[CSV.into(), SVG.into()],
            results.len(),
            failed_total,
            "rows, one per task and tool",
        ));
        blocks.push(Block::table(&TABLE_HEADER, rows));
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

const TABLE_HEADER: [&str; 9] = [
    "task",
    "n",
    "failed",
    "ln|Π^U| range",
    "task error median [min, max]",
    "CV",
    "Spearman ρ",
    "bootstrap CI",
    "exponential fit (task error = a·exp(b·ln|Π^U|))",
];

/// Every tool on every paper task, without perturbation; one CSV row per (task, tool) as the
/// episodes finish, results in (task, tool) order.
fn simulate_every_task(
    ctx: &Context,
    tools: &[toolconf_model::Arm],
) -> Result<Vec<(TaskKind, usize, ToolRuns)>, ReproduceError> {
    let options = [ctx.options];
    run_every_task(
        ctx,
        tools,
        &PAPER_TASKS,
        (&options, &ctx.path(CSV), &HEADER),
        |r| {
            let m = r.metrics(0);
            vec![
                Cell::from(r.logdet()),
                Cell::from(m.map(|m| m.task_error)),
                Cell::from(m.map(|m| m.free_energy)),
                Cell::from(m.map(|m| m.cost_j)),
                m.map_or(Cell::Empty, |m| Cell::from(m.rhs_evals)),
                Cell::from(r.error()),
            ]
        },
    )
}

fn introduction(tools: usize, plan: &Plan) -> Block {
    Block::p(format!(
        "{} random tools (m1, m2, l1, l2 uniform on [0.1, 0.6)), each simulated on the three \
         tasks without perturbation. For each task: Spearman's ρ between ln|Π^U| and the task \
         error with a {}% percentile-bootstrap interval ({} resamples), and the least-squares \
         fit task error = a·exp(b·ln|Π^U|) that the paper draws.",
        tools,
        (plan.level * 100.0).round(),
        plan.bootstrap_resamples
    ))
}

/// One task's tools that finished: (ln|Π^U|, task error) points and their summaries.
struct TaskStats {
    ok: Vec<(f64, f64)>,
    failed: usize,
    x: Vec<f64>,
    y: Vec<f64>,
    /// (min, max) of ln|Π^U|.
    x_range: (f64, f64),
    spread: f64,
    error_summary: Result<toolconf_stats::Summary, toolconf_stats::StatsError>,
    /// Coefficient of variation sd/mean of the task errors.
    cv: Option<f64>,
    fit: Result<toolconf_stats::ExpFit, toolconf_stats::StatsError>,
}

impl TaskStats {
    fn new(runs: &[&ToolRuns]) -> Self {
        let ok: Vec<(f64, f64)> = runs
            .iter()
            .filter_map(|r| Some((r.logdet()?, r.task_error(0)?)))
            .collect();
        let (x, y): (Vec<f64>, Vec<f64>) = ok.iter().copied().unzip();
        let x_range = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let error_summary = summary(&y);
        let cv = error_summary
            .as_ref()
            .ok()
            .filter(|s| s.mean > 0.0)
            .map(|s| s.sd / s.mean);
        TaskStats {
            failed: runs.len() - ok.len(),
            fit: fit_exponential(&x, &y),
            spread: x_range.1 - x_range.0,
            ok,
            x,
            y,
            x_range,
            error_summary,
            cv,
        }
    }

    fn table_row(&self, kind: TaskKind, corr: &Correlation) -> Vec<String> {
        vec![
            task_label(kind),
            self.ok.len().to_string(),
            self.failed.to_string(),
            if self.x.is_empty() {
                "-".into()
            } else {
                format!("[{}, {}]", num(self.x_range.0), num(self.x_range.1))
            },
            self.error_summary.as_ref().map_or("-".into(), |s| {
                format!("{} [{}, {}]", num(s.median), num(s.min), num(s.max))
            }),
            self.cv.map_or("-".into(), num),
            corr.rho_cell(),
            corr.ci_cell(),
            match &self.fit {
                Ok(f) => format!(
                    "a = {}, b = {}, R² = {}, RMSE = {}",
                    num(f.a),
                    num(f.b),
                    num(f.r_squared),
                    num(f.rmse)
                ),
                Err(e) => format!("no fit: {e}"),
            },
        ]
    }

    /// The task's scatter with the fitted exponential.
    fn panel(&self, kind: TaskKind, corr: &Correlation, colour: Colour) -> Panel {
        let mut lines = Vec::new();
        if let Ok(f) = &self.fit {
            let curve = (0..=100)
                .map(|k| {
                    let v = self.x_range.0 + self.spread * f64::from(k) / 100.0;
                    (v, f.a * (f.b * v).exp())
                })
                .collect();
            lines.push(Series::new(
                format!("{}·exp({}·x)", num(f.a), num(f.b)),
                Colour(0, 0, 0),
                curve,
            ));
        }
        let (i, name) = (kind.paper_index(), kind.name());
        let title = match &corr.rho {
            Ok(r) => format!("Task {i} ({name}): ρ = {}", num(*r)),
            Err(_) if !self.x.is_empty() && self.spread == 0.0 => format!(
                "Task {i} ({name}): ln|Π^U| = {} for every tool",
                num(self.x[0])
            ),
            Err(_) => format!("Task {i} ({name}): ρ undefined"),
        };
        Panel::Xy(XyPanel {
            title,
            x_label: "control confidence ln|Π^U|".into(),
            y_label: "task error".into(),
            dots: vec![Series::new("tools", colour, self.ok.clone())],
            lines,
            log_y: wants_log(&self.y),
            legend: Legend::UpperRight,
            headroom: 0.15,
        })
    }

    fn failed_note(&self) -> String {
        if self.failed > 0 {
            format!(" ({} failed episode(s) left out)", self.failed)
        } else {
            String::new()
        }
    }

    /// C1 on tasks 1–2: higher confidence, lower task error.
    fn correlation_verdict(&self, kind: TaskKind, corr: &Correlation, level: f64) -> Verdict {
        Verdict {
            claim: format!("C1, {}", task_label(kind)),
            statement: format!(
                "\"On average, the tools with higher control confidence performs better \
                 at the task than the tools with lower control confidence\" ({}): a clear \
                 negative correlation between ln|Π^U| and task error.",
                task_label(kind)
            ),
            outcome: corr.negative_outcome(),
            evidence: format!("{}{}.", corr.sentence(), self.failed_note()),
            rule: negative_correlation_rule(level),
        }
    }

    /// C1 on task 3: the same confidence for every tool, and similar task errors.
    fn equal_confidence_verdict(&self, kind: TaskKind, corr: &Correlation) -> Verdict {
        let (x_range, cv) = (self.x_range, self.cv);
        let constant = !self.x.is_empty() && self.spread <= 1e-9 * x_range.0.abs().max(1.0);
        let similar = cv.map(|c| c <= SIMILAR_CV);
        let outcome = match (constant, similar) {
            (_, None) if self.x.is_empty() => Outcome::NotJudged,
            (true, Some(true)) => Outcome::Holds,
            (true, _) | (false, Some(true)) => Outcome::Partly,
            (false, _) => Outcome::DoesNotHold,
        };
        let errors = self.error_summary.as_ref();
        Verdict {
            claim: format!("C1, {}", task_label(kind)),
            statement: "\"For task 3, the controller has the same confidence on all \
                        tools, which is in line with similar task errors for all \
                        tools.\""
                .into(),
            outcome,
            evidence: format!(
                "ln|Π^U| ranges over [{}, {}] ({}); task error median {}, range \
                 [{}, {}], coefficient of variation {} ({}){}. {}.",
                num(x_range.0),
                num(x_range.1),
                if constant {
                    "identical for every tool"
                } else {
                    "not constant"
                },
                errors.map_or("-".into(), |s| num(s.median)),
                errors.map_or("-".into(), |s| num(s.min)),
                errors.map_or("-".into(), |s| num(s.max)),
                cv.map_or("undefined".into(), num),
                match similar {
                    Some(true) => "similar",
                    Some(false) => "not similar",
                    None => "undefined",
                },
                self.failed_note(),
                corr.sentence()
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
}
