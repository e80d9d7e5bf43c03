//! Fig. 5 (claim C2 over a range of perturbations): velocity task, constant perturbations
//! ΔT = −1.0 … 1.0 N m; variability of task performance |task error(ΔT) − task error(0)| against
//! control confidence, per ΔT, and negative against positive ΔT.
//!
//! Seeds: tools from `"fig5/tools"`, bootstrap from `"fig5/bootstrap/<ΔT>"`.

use toolconf::select::draw_tools;
use toolconf_model::{Task, TaskKind};

use super::batch::{map_ordered, run_tool, ToolRuns};
use super::figure_parts::{arm_cells, columns, dt_label, files_block, mean_lines, TOOL_COLUMNS};
use super::plot::{self, diverging, Colour, Series};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::{
    mean_sd, negative_correlation_rule, num, p_value, Comparison, Correlation, CorrelationReport,
};
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::Cell;

pub struct Fig5;

const CSV: &str = "fig5_perturbation_sweep.csv";
const SVG: &str = "fig5_perturbation_sweep.svg";
pub const HEADER: [&str; 11] = columns(&[
    &TOOL_COLUMNS,
    &[
        "perturbation",
        "task_error",
        "task_error_unperturbed",
        "abs_change",
        "error",
    ],
]);

/// The non-zero perturbations of the sweep; episode 0 of every tool is the unperturbed one and
/// episode k + 1 is `sweep[k]`.
fn sweep(plan: &Plan) -> Vec<f64> {
    plan.fig5_perturbations
        .iter()
        .copied()
        .filter(|&d| d != 0.0)
        .collect()
}

/// The episode index of perturbation `dt` (0 for ΔT = 0).
fn episode_of(sweep: &[f64], dt: f64) -> usize {
    sweep.iter().position(|&d| d == dt).map_or(0, |k| k + 1)
}

impl Experiment for Fig5 {
    described!(
        "fig5",
        "Fig. 5: variability over a range of perturbations, velocity task (C2)",
        [CSV, SVG]
    );

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        (plan.fig5_tools * (1 + sweep(plan).len())) as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let sweep = sweep(plan);
        let tools = draw_tools(plan.fig5_tools, ctx.seed_for(self, "tools"));
        let (results, rows_per_tool) = simulate_sweep(ctx, &tools, &sweep)?;
        let jobs: Vec<(Vec<f64>, Vec<f64>, u64)> = sweep
            .iter()
            .enumerate()
            .map(|(k, dt)| {
                let (x, y) = variability_points(&results, k + 1).into_iter().unzip();
                (x, y, ctx.seed_for(self, &format!("bootstrap/{dt:+.1}")))
            })
            .collect();
        let corrs = Correlation::compute_all(&jobs, plan.bootstrap_resamples, plan.level);
        let by_dt = ByPerturbation::new(&results, &sweep, &corrs, tools.len());
        let signs = SignComparison::new(&results, &sweep);
        let svg = figure(ctx, &results, &sweep, by_dt.dots.clone())?;
        let failed = results.iter().filter(|r| !r.error().is_empty()).count();
        let blocks =
            vec![
                Block::p(format!(
                "{} random tools on task 2 (velocity), each simulated without perturbation and \
                 with every constant ΔT of {{{}}} N m on both joints (the paper does not say how \
                 many tools it used). Variability = |task error(ΔT) − task error(0)|.",
                tools.len(),
                sweep.iter().map(|d| dt_label(*d)).collect::<Vec<_>>().join(", ")
            )),
                files_block(
                    &[CSV.into(), SVG.into()],
                    results.len() * rows_per_tool,
                    failed,
                    "rows, one per tool and ΔT (ΔT = 0 is the reference)",
                ),
                Block::table(&BY_DT_HEADER, by_dt.rows.clone()),
                Block::p(
                    "Negative against positive perturbations of the same size (per tool; Wilcoxon \
                 signed-rank p, two-sided):",
                ),
                Block::table(&SIGN_HEADER, signs.rows.clone()),
                Block::Figure {
                    file: SVG.into(),
                    caption:
                        "Left: variability of task performance against control confidence, one \
                          colour per ΔT (blue negative, red positive). Right: mean variability per \
                          ΔT for the least and the most confident third of the tools. Compare \
                          with the paper's Fig. 5."
                            .into(),
                    svg,
                },
                Block::Verdict(by_dt.verdict(plan.level)),
                Block::Verdict(signs.verdict(plan.alpha)),
            ];
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: (results.len() * (1 + sweep.len())) as u64,
            rhs_evals: results.iter().map(ToolRuns::rhs_evals).sum(),
        })
    }
}

const BY_DT_HEADER: [&str; 7] = [
    "ΔT [N m]",
    "n",
    "failed",
    "variability mean ± sd",
    "Spearman ρ",
    "bootstrap CI",
    "verdict for this ΔT",
];

const SIGN_HEADER: [&str; 5] = [
    "|ΔT| [N m]",
    "mean variability, ΔT < 0",
    "mean variability, ΔT > 0",
    "tools with more variability at ΔT < 0",
    "p",
];

/// Every tool without and with each ΔT of the sweep; CSV rows (one per tool and listed ΔT, the
/// reference ΔT = 0 included) as each tool finishes. Returns the runs and the rows per tool.
fn simulate_sweep(
    ctx: &Context,
    tools: &[toolconf_model::Arm],
    sweep: &[f64],
) -> Result<(Vec<ToolRuns>, usize), ReproduceError> {
    let task = Task::paper(TaskKind::Velocity);
    let mut listed: Vec<f64> = ctx.plan.fig5_perturbations.clone();
    if !listed.contains(&0.0) {
        listed.insert(0, 0.0);
    }
    let options: Vec<_> = std::iter::once(0.0)
        .chain(sweep.iter().copied())
        .map(|d| ctx.perturbed(d))
        .collect();
    let indices: Vec<usize> = (0..tools.len()).collect();
    let mut csv = ctx.csv(CSV, &HEADER)?;
    let results = map_ordered(
        &indices,
        ctx.progress,
        options.len() as u64,
        |&i| run_tool(&tools[i], &task, &options, ctx.plant),
        |i, r| {
            for &dt in &listed {
                let k = episode_of(sweep, dt);
                let mut row = vec![Cell::from(i)];
                row.extend(arm_cells(&r.arm));
                row.extend([
                    Cell::from(r.logdet()),
                    Cell::from(dt),
                    Cell::from(r.task_error(k)),
                    Cell::from(r.task_error(0)),
                    Cell::from(r.abs_change(k)),
                    Cell::from(r.error_of(&[0, k])),
                ]);
                csv.row(row)?;
            }
            Ok::<(), ReproduceError>(())
        },
    )?;
    csv.finish()?;
    Ok((results, listed.len()))
}

/// (ln|Π^U|, variability) of every tool with both, for episode `k`.
fn variability_points(results: &[ToolRuns], k: usize) -> Vec<(f64, f64)> {
    results
        .iter()
        .filter_map(|r| Some((r.logdet()?, r.abs_change(k)?)))
        .collect()
}

/// Confidence against variability for each ΔT: the table rows, the verdicts, the dots.
struct ByPerturbation {
    rows: Vec<Vec<String>>,
    outcomes: Vec<(f64, Outcome)>,
    dots: Vec<Series>,
}

impl ByPerturbation {
    fn new(results: &[ToolRuns], sweep: &[f64], corrs: &[Correlation], tools: usize) -> Self {
        let mut out = ByPerturbation {
            rows: Vec::new(),
            outcomes: Vec::new(),
            dots: Vec::new(),
        };
        let largest = sweep.iter().fold(0.0, |m: f64, d| m.max(d.abs()));
        for (k, &dt) in sweep.iter().enumerate() {
            let ok = variability_points(results, k + 1);
            let y: Vec<f64> = ok.iter().map(|p| p.1).collect();
            let corr = &corrs[k];
            let outcome = corr.negative_outcome();
            out.outcomes.push((dt, outcome));
            out.rows.push(vec![
                dt_label(dt),
                ok.len().to_string(),
                (tools - ok.len()).to_string(),
                mean_sd(&y),
                corr.rho_cell(),
                corr.ci_cell(),
                outcome.words().into(),
            ]);
            out.dots.push(Series::new(
                format!("ΔT = {}", dt_label(dt)),
                diverging(dt / largest),
                ok,
            ));
        }
        out
    }

    fn count(&self, o: Outcome) -> usize {
        self.outcomes.iter().filter(|x| x.1 == o).count()
    }

    fn verdict(&self, level: f64) -> Verdict {
        let judged: Vec<Outcome> = self
            .outcomes
            .iter()
            .map(|o| o.1)
            .filter(|o| *o != Outcome::NotJudged)
            .collect();
        let outcome = if judged.is_empty() {
            Outcome::NotJudged
        } else if judged.len() == self.outcomes.len() && judged.iter().all(|o| *o == Outcome::Holds)
        {
            Outcome::Holds
        } else if judged.iter().any(|o| *o != Outcome::DoesNotHold) {
            Outcome::Partly
        } else {
            Outcome::DoesNotHold
        };
        Verdict {
            claim: "C2 (Fig. 5), range of ΔT".into(),
            statement: "\"The trend remains the same for a range of perturbations\": tools \
                        with low control confidence show high variability, tools with high \
                        confidence low variability, for every ΔT."
                .into(),
            outcome,
            evidence: format!(
                "of {} perturbations, the negative correlation holds for {}, partly holds \
                 for {}, does not hold for {}, cannot be judged for {} (table above).",
                self.outcomes.len(),
                self.count(Outcome::Holds),
                self.count(Outcome::Partly),
                self.count(Outcome::DoesNotHold),
                self.count(Outcome::NotJudged)
            ),
            rule: format!(
                "per ΔT the correlation rule: {} Overall: holds if it holds for every ΔT, \
                 partly holds if it holds or partly holds for at least one, does not hold \
                 otherwise.",
                negative_correlation_rule(level)
            ),
        }
    }
}

/// A tool's variability at perturbation `dt` of the sweep.
fn change(r: &ToolRuns, sweep: &[f64], dt: f64) -> Option<f64> {
    r.abs_change(episode_of(sweep, dt))
}

/// Negative against positive ΔT of the same magnitude: per magnitude and pooled per tool.
struct SignComparison {
    magnitudes: Vec<f64>,
    rows: Vec<Vec<String>>,
    /// Whether the mean variability is larger for ΔT < 0 at every magnitude.
    every_magnitude: bool,
    pooled: Comparison,
}

impl SignComparison {
    fn new(results: &[ToolRuns], sweep: &[f64]) -> Self {
        let magnitudes: Vec<f64> = sweep
            .iter()
            .copied()
            .filter(|&d| d > 0.0 && sweep.contains(&-d))
            .collect();
        let mut rows = Vec::new();
        let mut every_magnitude = !magnitudes.is_empty();
        for &m in &magnitudes {
            let neg: Vec<Option<f64>> = results.iter().map(|r| change(r, sweep, -m)).collect();
            let pos: Vec<Option<f64>> = results.iter().map(|r| change(r, sweep, m)).collect();
            let c = Comparison::compute(&neg, &pos);
            let more = neg
                .iter()
                .zip(&pos)
                .filter_map(|(a, b)| Some((*a)? > (*b)?))
                .collect::<Vec<_>>();
            every_magnitude &= c.mean_difference().is_some_and(|d| d > 0.0);
            rows.push(vec![
                format!("{m:.1}"),
                c.mean_a.map_or("-".into(), num),
                c.mean_b.map_or("-".into(), num),
                format!("{} of {}", more.iter().filter(|&&b| b).count(), more.len()),
                c.p().map_or("-".into(), p_value),
            ]);
        }
        let per_tool = |sign: f64| -> Vec<Option<f64>> {
            results
                .iter()
                .map(|r| {
                    let v: Option<Vec<f64>> = magnitudes
                        .iter()
                        .map(|&m| change(r, sweep, sign * m))
                        .collect();
                    let v = v?;
                    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
                })
                .collect()
        };
        let pooled = Comparison::compute(&per_tool(-1.0), &per_tool(1.0));
        SignComparison {
            magnitudes,
            rows,
            every_magnitude,
            pooled,
        }
    }

    fn verdict(&self, alpha: f64) -> Verdict {
        let outcome = match (self.pooled.a_greater(alpha), self.every_magnitude) {
            (None, _) => Outcome::NotJudged,
            (Some(true), true) => Outcome::Holds,
            (Some(true), false) | (Some(false), true) => Outcome::Partly,
            (Some(false), false) => Outcome::DoesNotHold,
        };
        let magnitudes: Vec<String> = self.magnitudes.iter().map(|m| format!("{m:.1}")).collect();
        Verdict {
            claim: "C2 (Fig. 5), sign of ΔT".into(),
            statement: "\"Higher variability when the perturbation resists the controller \
                        (perturbing torque is negative and opposes the controller torque).\""
                .into(),
            outcome,
            evidence: format!(
                "per-tool mean variability over |ΔT| ∈ {{{}}}: ΔT < 0 {} against ΔT > 0 {}; \
                 {}. Mean variability larger for ΔT < 0 at every |ΔT|: {}.",
                magnitudes.join(", "),
                self.pooled.mean_a.map_or("-".into(), num),
                self.pooled.mean_b.map_or("-".into(), num),
                self.pooled.describe(),
                if self.every_magnitude { "yes" } else { "no" }
            ),
            rule: format!(
                "holds if the per-tool variability is significantly larger for negative ΔT \
                 (Wilcoxon p < {alpha} with a positive mean difference) and the mean is larger \
                 for the negative ΔT at every |ΔT|; partly holds if only one of the two; \
                 does not hold if neither."
            ),
        }
    }
}

/// Left: variability against confidence per ΔT (`dots`); right: mean variability per ΔT for
/// the least and most confident third of the tools and for all.
fn figure(
    ctx: &Context,
    results: &[ToolRuns],
    sweep: &[f64],
    dots: Vec<Series>,
) -> Result<String, ReproduceError> {
    let ranked: Vec<&ToolRuns> = results.iter().filter(|r| r.logdet().is_some()).collect();
    let m = mean_lines(
        ranked,
        |r| r.logdet(),
        sweep,
        |r, k| change(r, sweep, sweep[k]),
    );
    let mut lines = Vec::new();
    if let Some((third, least, most)) = m.thirds {
        let label = |which: &str| format!("{which}-confidence third ({third} tools)");
        lines.push(Series::new(label("lowest"), Colour(200, 30, 30), least));
        lines.push(Series::new(label("highest"), Colour(30, 80, 200), most));
    }
    lines.push(Series::new("all tools", Colour(60, 60, 60), m.all));
    plot::save(
        &ctx.path(SVG),
        &[
            plot::scatter_panel(
                "Velocity task: variability against confidence, by ΔT",
                "control confidence ln|Π^U|",
                "|task error(ΔT) − task error(0)|",
                dots,
            ),
            plot::means_panel(
                "Mean variability per ΔT (negative ΔT opposes the controller)",
                "perturbation ΔT [N m]",
                "mean |change of task error|",
                lines,
            ),
        ],
        (640, 480),
    )
}
