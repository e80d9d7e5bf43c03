//! Fig. 6 (claim C3): trials of a few random tools on the velocity task; which tool ∫F and ∫J
//! select, drawn as the paper's grid (white none, light grey F, dark grey J, black both).
//!
//! Seeds: trial k draws its tools from `"fig6/trial/<k>"`, so a trial does not depend on how many
//! trials run. Every rule of [`decision_rules`] gets a `chosen_by_<id>` column; the grid and the
//! verdict contrast the first two (F and J), as the paper does.

use toolconf::select::ToolResult;
use toolconf_model::{Arm, TaskKind};

use super::figure_parts::{arm_cells, files_block, rhs_evals, ARM_COLUMNS};
use super::objectives::{decision_rules, run_trials, DecisionRule, TrialPlan};
use super::plot::{self, Colour, GridPanel, Panel};
use super::report::{Block, Outcome, Section, Verdict};
use super::verdict::num;
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::{Cell, CsvWriter};

pub struct Fig6;

const CSV: &str = "fig6_selection_grid.csv";
const SVG: &str = "fig6_selection_grid.svg";
pub const TASK: TaskKind = TaskKind::Velocity;

/// The header: trial, tool, parameters, metrics, one `chosen_by_<rule>` per rule, error.
pub fn header() -> Vec<String> {
    let mut h: Vec<String> = ["trial", "tool"]
        .into_iter()
        .chain(ARM_COLUMNS)
        .chain(["logdet", "task_error", "free_energy", "cost_j"])
        .map(String::from)
        .collect();
    h.extend(
        decision_rules()
            .iter()
            .map(|r| format!("chosen_by_{}", r.id())),
    );
    h.push("error".into());
    h
}

struct TrialResult {
    tools: Vec<Arm>,
    results: Vec<ToolResult>,
    chosen: Vec<Option<usize>>,
}

impl Experiment for Fig6 {
    described!("fig6", "Fig. 6: which tool F and J select (C3)", [CSV, SVG]);

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        (plan.fig6_trials * plan.fig6_tools) as u64
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let rules = decision_rules();
        let done = self.run_trials(ctx, &rules)?;
        let svg = grid_figure(ctx, &done, &rules)?;
        let (pair_rows, (differ, judged)) = disagreements(&done, &rules);
        // ∫F − ∫J = −(t_end/2)·ln|Π^U| for every tool: F is J plus a confidence bonus.
        let half = 0.5 * ctx.options.t_end;
        let identity = done
            .iter()
            .flat_map(|t| &t.results)
            .filter_map(|r| {
                let m = r.episode.as_ref().ok()?;
                Some(((m.free_energy - m.cost_j) + half * m.logdet).abs())
            })
            .fold(0.0, f64::max);
        let failed = done
            .iter()
            .flat_map(|t| &t.results)
            .filter(|r| r.episode.is_err() || r.logdet.is_err())
            .count();
        let blocks = vec![
            Block::p(format!(
                "{} trials, each of {} random tools on task 2 (velocity; the paper's Fig. 6 does \
                 not name the task, task 2 is the one of its benchmark). In each trial every rule \
                 picks one tool: F = argmin ∫F dt, J = argmin ∫J dt, confidence = argmax \
                 ln|Π^U| (ties to the lower tool number).",
                done.len(),
                plan.fig6_tools
            )),
            files_block(
                &[CSV.into(), SVG.into()],
                done.len() * plan.fig6_tools,
                failed,
                "rows, one per trial and tool, with a 0/1 column per rule",
            ),
            Block::table(
                &["rules", "trials where they choose differently"],
                pair_rows,
            ),
            Block::p(format!(
                "For every tool ∫F dt − ∫J dt = −(t_end/2)·ln|Π^U| = −{}·ln|Π^U| (largest \
                 deviation here {}): the free energy is J plus a bonus for confidence, so F and J \
                 disagree exactly when a more confident tool's bonus outweighs its higher ∫J.",
                num(half),
                num(identity)
            )),
            Block::Figure {
                file: SVG.into(),
                caption: "Selected tool per trial: white not selected, light grey F, dark grey J, \
                          black both. Compare with the paper's Fig. 6."
                    .into(),
                svg,
            },
            Block::Verdict(verdict(differ, judged)),
        ];
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes: (done.len() * plan.fig6_tools) as u64,
            rhs_evals: rhs_evals(done.iter().flat_map(|t| &t.results)),
        })
    }
}

impl Fig6 {
    /// Every trial: draw the tools, simulate them, let every rule choose; one CSV row per trial
    /// and tool as each trial finishes.
    fn run_trials(
        &self,
        ctx: &Context,
        rules: &[Box<dyn DecisionRule>],
    ) -> Result<Vec<TrialResult>, ReproduceError> {
        let header = header();
        let mut csv = ctx.csv(CSV, &header)?;
        let plan = TrialPlan {
            kind: TASK,
            trials: ctx.plan.fig6_trials,
            tools: ctx.plan.fig6_tools,
            episodes_per_tool: 1,
        };
        let done = run_trials(
            ctx,
            self,
            plan,
            rules,
            |_, (tools, results, chosen)| TrialResult {
                tools,
                results,
                chosen,
            },
            |k, t| write_trial(&mut csv, k, t),
        )?;
        csv.finish()?;
        Ok(done)
    }
}

/// Trial `k`'s rows: each tool's numbers and which rules chose it.
fn write_trial(csv: &mut CsvWriter, k: usize, t: &TrialResult) -> Result<(), ReproduceError> {
    for r in &t.results {
        let m = r.episode.as_ref().ok();
        let mut row = vec![Cell::from(k), Cell::from(r.index)];
        row.extend(arm_cells(&t.tools[r.index]));
        row.extend([
            Cell::from(r.logdet.as_ref().ok().copied()),
            Cell::from(m.map(|m| m.task_error)),
            Cell::from(m.map(|m| m.free_energy)),
            Cell::from(m.map(|m| m.cost_j)),
        ]);
        row.extend(t.chosen.iter().map(|c| Cell::from(*c == Some(r.index))));
        let error = match (&r.logdet, &r.episode) {
            (Err(e), _) => e.to_string(),
            (_, Err(e)) => e.to_string(),
            _ => String::new(),
        };
        row.push(Cell::from(error));
        csv.row(row)?;
    }
    Ok(())
}

/// The grid: rows are tools, columns trials; F is rule 0, J rule 1.
fn grid_figure(
    ctx: &Context,
    done: &[TrialResult],
    rules: &[Box<dyn DecisionRule>],
) -> Result<String, ReproduceError> {
    let tools = ctx.plan.fig6_tools;
    let cells: Vec<Vec<usize>> = (0..tools)
        .map(|i| {
            done.iter()
                .map(|t| {
                    usize::from(t.chosen[0] == Some(i)) + 2 * usize::from(t.chosen[1] == Some(i))
                })
                .collect()
        })
        .collect();
    let (f, j) = (&rules[0], &rules[1]);
    plot::save(
        &ctx.path(SVG),
        &[Panel::Grid(GridPanel {
            title: format!(
                "Tool selected by {} and {} in {} trials of {} random tools (task 2, velocity)",
                f.label(),
                j.label(),
                done.len(),
                tools
            ),
            x_label: "trial".into(),
            y_label: "tool".into(),
            cells,
            categories: vec![
                ("not selected".into(), Colour(255, 255, 255)),
                (format!("selected by {}", f.label()), Colour(205, 205, 205)),
                (format!("selected by {}", j.label()), Colour(105, 105, 105)),
                ("selected by both".into(), Colour(0, 0, 0)),
            ],
        })],
        (1000, 380),
    )
}

/// For every pair of rules, in how many trials they chose differently (table rows), and that
/// count with the number of trials both chose in for F and J (rules 0 and 1).
fn disagreements(
    done: &[TrialResult],
    rules: &[Box<dyn DecisionRule>],
) -> (Vec<Vec<String>>, (usize, usize)) {
    let mut pair_rows = Vec::new();
    let mut fj = (0, 0);
    for a in 0..rules.len() {
        for b in a + 1..rules.len() {
            let both: Vec<bool> = done
                .iter()
                .filter_map(|t| Some(t.chosen[a]? != t.chosen[b]?))
                .collect();
            let differ = both.iter().filter(|&&d| d).count();
            if (a, b) == (0, 1) {
                fj = (differ, both.len());
            }
            pair_rows.push(vec![
                format!("{} vs {}", rules[a].label(), rules[b].label()),
                format!("{differ} of {}", both.len()),
            ]);
        }
    }
    (pair_rows, fj)
}

/// C3: F and J do not always choose the same tool.
fn verdict(differ: usize, judged: usize) -> Verdict {
    let outcome = if judged == 0 {
        Outcome::NotJudged
    } else if differ > 0 {
        Outcome::Holds
    } else {
        Outcome::DoesNotHold
    };
    Verdict {
        claim: "C3".into(),
        statement: "\"Both objectives can produce different decision outcomes, i.e., \
                    different tool selections\": F and J do not always select the same \
                    tool."
            .into(),
        outcome,
        evidence: format!(
            "F and J chose different tools in {differ} of {judged} trials ({}%).",
            if judged > 0 {
                num(100.0 * differ as f64 / judged as f64)
            } else {
                "-".into()
            }
        ),
        rule: "holds if F and J choose different tools in at least one trial (the \
               paper's claim is existential: grey blocks exist), does not hold if they \
               always agree."
            .into(),
    }
}
