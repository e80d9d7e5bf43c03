//! Fig. 4 (claim C2): |change of task error| under a constant perturbation ΔT = −0.8 N m against
//! control confidence, for random tools on tasks 1 and 2.
//!
//! Seeds: tools from `"fig4/tools"` (the same tools for both tasks), bootstrap from
//! `"fig4/bootstrap/<task>"`.

use toolconf::select::draw_tools;
use toolconf_model::{Arm, TaskKind};

use super::batch::{run_every_task, ToolRuns};
use super::figure_parts::{columns, dt_label, files_block, task_label, wants_log, TOOL_COLUMNS};
use super::plot::{self, Colour, Legend, Panel, Series, XyPanel};
use super::report::{Block, Section, Verdict};
use super::verdict::{mean_sd, negative_correlation_rule, Correlation, CorrelationReport};
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::Cell;

pub struct Fig4;

const CSV: &str = "fig4_perturbation_change.csv";
const SVG: &str = "fig4_perturbation_change.svg";
pub const HEADER: [&str; 11] = columns(&[
    &["task"],
    &TOOL_COLUMNS,
    &["task_error", "task_error_perturbed", "abs_change", "error"],
]);
const TASKS: [TaskKind; 2] = [TaskKind::Position, TaskKind::Velocity];

impl Experiment for Fig4 {
    described!(
        "fig4",
        "Fig. 4: confidence and sensitivity to a perturbation (C2)",
        [CSV, SVG]
    );

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        2 * 2 * plan.fig4_tools as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let tools = draw_tools(plan.fig4_tools, ctx.seed_for(self, "tools"));
        let results = simulate(ctx, &tools)?;
        let jobs: Vec<(Vec<f64>, Vec<f64>, u64)> = TASKS
            .iter()
            .map(|&kind| {
                let (x, y) = points(&results, kind).into_iter().unzip();
                let seed = ctx.seed_for(self, &format!("bootstrap/{}", kind.name()));
                (x, y, seed)
            })
            .collect();
        let corrs = Correlation::compute_all(&jobs, plan.bootstrap_resamples, plan.level);
        let (mut panels, mut rows, mut verdicts) = (Vec::new(), Vec::new(), Vec::new());
        let mut failed_total = 0;
        for (t, kind) in TASKS.into_iter().enumerate() {
            let ok = points(&results, kind);
            let failed = tools.len() - ok.len();
            failed_total += failed;
            let y: Vec<f64> = ok.iter().map(|p| p.1).collect();
            let corr = &corrs[t];
            rows.push(vec![
                task_label(kind),
                ok.len().to_string(),
                failed.to_string(),
                mean_sd(&y),
                corr.rho_cell(),
                corr.ci_cell(),
            ]);
            panels.push(panel(kind, t, corr, ok, wants_log(&y)));
            verdicts.push(verdict(kind, corr, failed, plan));
        }
        let svg = plot::save(&ctx.path(SVG), &panels, (540, 420))?;
        let mut blocks = blocks(&tools, &results, failed_total, rows, svg, plan);
        blocks.extend(verdicts.into_iter().map(Block::Verdict));
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: 2 * results.len() as u64,
            rhs_evals: results.iter().map(|r| r.2.rhs_evals()).sum(),
        })
    }
}

/// Each tool on each task without and with the perturbation, its row written to the CSV.
fn simulate(
    ctx: &Context,
    tools: &[Arm],
) -> Result<Vec<(TaskKind, usize, ToolRuns)>, ReproduceError> {
    let options = [ctx.options, ctx.perturbed(ctx.plan.perturbation)];
    run_every_task(
        ctx,
        tools,
        &TASKS,
        (&options, &ctx.path(CSV), &HEADER),
        |r| {
            vec![
                Cell::from(r.logdet()),
                Cell::from(r.task_error(0)),
                Cell::from(r.task_error(1)),
                Cell::from(r.abs_change(1)),
                Cell::from(r.error()),
            ]
        },
    )
}

/// (ln|Π^U|, |change of task error|) of the tools on task `kind` whose episodes both ran.
fn points(results: &[(TaskKind, usize, ToolRuns)], kind: TaskKind) -> Vec<(f64, f64)> {
    results
        .iter()
        .filter(|r| r.0 == kind)
        .filter_map(|r| Some((r.2.logdet()?, r.2.abs_change(1)?)))
        .collect()
}

/// Task `kind`'s panel: |change| against ln|Π^U|, one dot per tool.
fn panel(kind: TaskKind, t: usize, corr: &Correlation, ok: Vec<(f64, f64)>, log_y: bool) -> Panel {
    Panel::Xy(XyPanel {
        title: format!(
            "Task {} ({}): ρ = {}",
            kind.paper_index(),
            kind.name(),
            corr.rho_cell()
        ),
        x_label: "control confidence ln|Π^U|".into(),
        y_label: "|change of task error|".into(),
        dots: vec![Series::new(
            "",
            [Colour(0, 114, 178), Colour(213, 94, 0)][t],
            ok,
        )],
        lines: vec![],
        log_y,
        legend: Legend::UpperRight,
        headroom: 0.0,
    })
}

/// Claim C2 on task `kind`: a negative correlation.
fn verdict(kind: TaskKind, corr: &Correlation, failed: usize, plan: &Plan) -> Verdict {
    Verdict {
        claim: format!("C2, {}", task_label(kind)),
        statement: format!(
            "\"The tools with higher control confidence show less changes in task \
             performance under a control perturbation\" (ΔT = {} N m, {}).",
            dt_label(plan.perturbation),
            task_label(kind)
        ),
        outcome: corr.negative_outcome(),
        evidence: format!(
            "{} between ln|Π^U| and |task error(ΔT) − task error(0)|{}.",
            corr.sentence(),
            if failed > 0 {
                format!(" ({failed} tool(s) with a failed episode left out)")
            } else {
                String::new()
            }
        ),
        rule: negative_correlation_rule(plan.level),
    }
}

/// The section's text, files, table and figure (the verdicts follow them).
fn blocks(
    tools: &[Arm],
    results: &[(TaskKind, usize, ToolRuns)],
    failed_total: usize,
    rows: Vec<Vec<String>>,
    svg: String,
    plan: &Plan,
) -> Vec<Block> {
    vec![
        Block::p(format!(
            "{} random tools, each simulated on tasks 1 and 2 without perturbation and with a \
             constant torque ΔT = {} N m on both joints; the measure is |task error(ΔT) − task \
             error(0)|.",
            tools.len(),
            dt_label(plan.perturbation)
        )),
        files_block(
            &[CSV.into(), SVG.into()],
            results.len(),
            failed_total,
            "rows, one per task and tool, two episodes each",
        ),
        Block::table(
            &[
                "task",
                "n",
                "failed",
                "|change| mean ± sd",
                "Spearman ρ",
                "bootstrap CI",
            ],
            rows,
        ),
        Block::Figure {
            file: SVG.into(),
            caption: format!(
                "|Change of task error| under ΔT = {} N m against control confidence, tasks 1 \
                 and 2. Compare with the paper's Fig. 4.",
                dt_label(plan.perturbation)
            ),
            svg,
        },
    ]
}
