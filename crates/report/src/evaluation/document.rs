//! The report of an evaluation: the rules, then the verdicts, then one section per figure with
//! its data, statistics and figure.

use toolconf::evaluation::trials::{MEASURES, RULES};
use toolconf::evaluation::{Claim, ClaimVerdict, Evaluation, Finding, HighlightRun};
use toolconf_stats::summary;

use super::figures::Figure;
use super::RunInfo;
use crate::experiments::report::{Block, Outcome, Verdict};
use crate::experiments::verdict::num;
use crate::view3d;

fn outcome(f: Finding) -> Outcome {
    match f {
        Finding::Holds => Outcome::Holds,
        Finding::Reversed => Outcome::Reversed,
        Finding::NoRelation => Outcome::NoRelation,
        Finding::NotJudged => Outcome::NotJudged,
    }
}

fn verdict_block(v: &ClaimVerdict) -> Block {
    Block::Verdict(Verdict {
        claim: v.claim.label().trim_matches(['(', ')']).to_string(),
        statement: v.claim.statement().to_string(),
        outcome: outcome(v.finding),
        evidence: format!("{}.", v.evidence),
        rule: format!("{}.", v.rule),
    })
}

fn verdict_of(e: &Evaluation, claim: Claim) -> &ClaimVerdict {
    e.verdicts
        .iter()
        .find(|v| v.claim == claim)
        .expect("every claim is judged")
}

/// The figure drawn for `file`, or a paragraph saying why there is none.
fn figure_block(figures: &[Option<Figure>], file: &str, caption: String) -> Block {
    match figures.iter().flatten().find(|f| f.file == file) {
        Some(f) => Block::Figure {
            file: f.file.into(),
            caption,
            svg: f.svg.clone(),
        },
        None => Block::p(format!(
            "No figure `{file}`: no tool has the numbers it draws (see the CSV's error column)."
        )),
    }
}

/// The whole report.
pub fn document(e: &Evaluation, info: &RunInfo, figures: &[Option<Figure>]) -> Vec<Block> {
    let mut doc = header(e, info);
    doc.push(Block::Heading(
        2,
        "The rules, fixed before the numbers".into(),
    ));
    doc.push(Block::Bullets(
        Claim::ALL
            .iter()
            .map(|c| {
                format!(
                    "{} {}: {}.",
                    c.label(),
                    c.statement(),
                    c.rule(e.plan.level, e.plan.alpha)
                )
            })
            .collect(),
    ));
    doc.push(Block::Heading(2, "Verdicts".into()));
    doc.push(Block::table(
        &["claim", "verdict", "statistic"],
        e.verdicts
            .iter()
            .map(|v| {
                vec![
                    format!("{} {}", v.claim.label(), v.claim.statement()),
                    format!("**{}**", v.finding.words()),
                    v.evidence.clone(),
                ]
            })
            .collect(),
    ));
    if let Some(note) = &e.barely_moved {
        doc.push(Block::p(format!("**Note: {note}.**")));
    }
    doc.extend(run_time(e, info));
    doc.extend(fig2_section(e, figures));
    doc.extend(fig3_section(e, figures));
    doc.extend(fig4_section(e, figures));
    doc.extend(fig5_section(e, figures));
    doc.extend(fig6_section(e, figures));
    doc.extend(fig7_section(e, figures));
    doc
}

fn header(e: &Evaluation, info: &RunInfo) -> Vec<Block> {
    let s = &e.setup;
    let dt: Vec<String> = s.perturbation.values.iter().map(|v| num(*v)).collect();
    let scales: Vec<String> = s.scales.iter().map(|v| scale(*v)).collect();
    vec![
        Block::Heading(1, format!("Is confidence a good guide here? The paper's evaluation on {}", e.task_title())),
        Block::p(format!(
            "Command: `{}`. Seed {}; {} counts. toolconf {}.",
            info.command,
            e.seed,
            if e.plan.quick { "quick (reduced: for testing the pipeline, not for judging)" } else { "the paper's" },
            env!("CARGO_PKG_VERSION")
        )),
        Block::Bullets(vec![
            format!("**Model**: {} ({}), {} joints.", s.model, s.model.title(), s.model.dof()),
            format!(
                "**Task**: {}{}; the task error is the paper's weighted sum over the output grid of \
                 the squared error of {} (eq. task_error).",
                s.spec.label(),
                s.spec.description.as_ref().map(|d| format!(", \"{d}\"")).unwrap_or_default(),
                s.spec.kind.error_term().doc()
            ),
            format!("**Goal**: {}.", s.spec.tip_goal.describe()),
            format!("**Tools**: {} ({} tools).", e.population.source, e.population.len()),
            format!("**ΔT** per joint [N m]: [{}], {}.", dt.join(", "), s.perturbation.source),
            format!("**Sweep** (Fig. 5): ΔT scaled by {{{}}}, the paper's −1.0 … 1.0 N m around its −0.8 N m.", scales.join(", ")),
            format!("**Integration**: {}.", info.method),
        ]),
        Block::p(
            "Control confidence is ln|Π^U|, the log-determinant of the control precision \
             Π^U = ∂²F/∂U² (computed in closed form, no simulation). Every tool is simulated without \
             and with ΔT; the selection experiments (Figs. 6, 7) choose among tools of the same \
             population, so they need no episodes of their own. A failed episode is a CSV row \
             with its error and is left out of the statistics.",
        ),
    ]
}

/// A sweep scale: "+1.25", "0", "−0.5".
fn scale(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:+}").replace('-', "−")
    }
}

fn run_time(e: &Evaluation, info: &RunInfo) -> Vec<Block> {
    let (episodes, rhs) = e.work();
    let secs = info.wall.as_secs_f64();
    vec![
        Block::Heading(2, "Run time".into()),
        Block::p(format!(
            "Wall time {secs:.2} s on {} rayon thread{}; {episodes} episodes ({rhs} right-hand-side \
             evaluations), {:.0} episodes/s.",
            info.threads,
            if info.threads == 1 { "" } else { "s" },
            if secs > 0.0 { episodes as f64 / secs } else { 0.0 }
        )),
    ]
}

fn range(v: &[f64]) -> String {
    match summary(v) {
        Ok(s) => format!("{} [{}, {}]", num(s.median), num(s.min), num(s.max)),
        Err(_) => "-".into(),
    }
}

fn fig2_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let ok: Vec<_> = e
        .records
        .iter()
        .filter(|r| r.logdet().is_some() && r.task_error().is_some())
        .collect();
    let logdet: Vec<f64> = ok.iter().filter_map(|r| r.logdet()).collect();
    let error: Vec<f64> = ok.iter().filter_map(|r| r.task_error()).collect();
    let progress: Vec<f64> = ok
        .iter()
        .filter_map(|r| r.base.as_ref().ok()?.progress)
        .collect();
    let mut head = vec![
        "n",
        "failed",
        "ln|Π^U|: median [min, max]",
        "task error: median [min, max]",
    ];
    let mut row = vec![
        ok.len().to_string(),
        (e.records.len() - ok.len()).to_string(),
        range(&logdet),
        range(&error),
    ];
    if !progress.is_empty() {
        head.push("progress: median [min, max]");
        row.push(range(&progress));
    }
    head.extend(["Spearman ρ [95 %]"]);
    row.push(e.statistics.task_error.describe_short());
    vec![
        Block::Heading(2, "Fig. 2: control confidence and task error (claim a)".into()),
        Block::p(format!(
            "Every tool of the population without ΔT. Data: `fig2_confidence_vs_error.csv` (one row per tool{}).",
            if progress.is_empty() { "" } else { "; progress is 1 − e(T)/e(0), e the distance to the goal" }
        )),
        Block::table(&head, vec![row]),
        figure_block(figures, "fig2_confidence_vs_error.svg", "Task error against control confidence, one dot per tool. Compare with the paper's Fig. 2.".into()),
        verdict_block(verdict_of(e, Claim::TaskError)),
    ]
}

/// Fig. 3's table row of one run: which, its confidence, ΔT, its distance to the goal at the
/// start and at the end (or why it has none).
fn highlight_row(r: &HighlightRun) -> Vec<String> {
    let d = r.distance();
    let first = d.as_ref().and_then(|d| d.first().map(|p| num(p.1)));
    let last = d.as_ref().and_then(|d| d.last().map(|p| num(p.1)));
    vec![
        format!("{} (tool {})", r.role, r.tool),
        num(r.logdet),
        if r.perturbed {
            "ΔT".into()
        } else {
            "0".into()
        },
        first.unwrap_or_else(|| "-".into()),
        last.unwrap_or_else(|| r.trace.as_ref().err().cloned().unwrap_or_default()),
    ]
}

fn fig3_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let rows: Vec<Vec<String>> = e.highlight.runs.iter().map(highlight_row).collect();
    vec![
        Block::Heading(2, "Fig. 3: the most and least confident tool under ΔT".into()),
        Block::p(format!(
            "The highest- and lowest-confidence tools of the first {} of the population, each \
             without and with ΔT, their trajectories recorded. Data: `fig3_tools.csv`, \
             `fig3_trajectories.csv` (the task variable, its distance to the goal{}).",
            e.highlight.sample,
            if e.reads_tip() { " and the tip's position" } else { "" }
        )),
        Block::table(&["run", "ln|Π^U|", "ΔT", "distance to goal at t = 0", "at the end"], rows),
        figure_block(
            figures,
            "fig3_trajectories.svg",
            format!(
                "Distance of the task variable to its goal over time (solid: ΔT = 0, dashed: with ΔT){}. Compare with the paper's Fig. 3.",
                if e.reads_tip() { "; the tip's path seen from above and from the side" } else { "" }
            ),
        ),
    ]
    .into_iter()
    .chain(fig3_view(e))
    .collect()
}

/// The 3-D view of Fig. 3's most and least confident tools without ΔT (on a model without a URDF
/// flange, the line saying why there is none).
fn fig3_view(e: &Evaluation) -> Vec<Block> {
    let shown: Vec<view3d::Shown> = ["high", "low"]
        .into_iter()
        .filter_map(|role| {
            let run = e
                .highlight
                .runs
                .iter()
                .find(|r| r.role == role && !r.perturbed)?;
            Some(view3d::Shown {
                label: match e.population.names.get(run.tool) {
                    Some(Some(name)) => format!("{role} confidence: tool {} ({name})", run.tool),
                    _ => format!("{role} confidence: tool {}", run.tool),
                },
                tool: e.population.tools.get(run.tool)?,
                trace: run.trace.as_ref().ok()?,
            })
        })
        .collect();
    view3d::section(view3d::tip_goal(e.setup.spec.kind, &shown), &shown)
}

fn fig4_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let changes: Vec<f64> = e.records.iter().filter_map(|r| r.abs_change()).collect();
    vec![
        Block::Heading(2, "Fig. 4: confidence and reliability under ΔT (claim b)".into()),
        Block::p("Every tool with and without ΔT; the measure is |task error(ΔT) − task error(0)|. Data: `fig4_perturbation_change.csv`."),
        Block::table(
            &["n", "|Δ task error|: median [min, max]", "Spearman ρ [95 %]"],
            vec![vec![changes.len().to_string(), range(&changes), e.statistics.reliability.describe_short()]],
        ),
        figure_block(figures, "fig4_perturbation_change.svg", "|Change of task error| under ΔT against control confidence. Compare with the paper's Fig. 4.".into()),
        verdict_block(verdict_of(e, Claim::Reliability)),
    ]
}

fn fig5_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let rows: Vec<Vec<String>> = e
        .statistics
        .sweep
        .iter()
        .map(|l| {
            vec![
                scale(l.scale),
                l.correlation.n.to_string(),
                l.correlation.describe_short(),
                l.correlation.finding().words().into(),
            ]
        })
        .collect();
    let signs: Vec<Vec<String>> = e
        .statistics
        .signs
        .iter()
        .map(|s| vec![format!("{}", s.magnitude), s.paired.describe()])
        .collect();
    vec![
        Block::Heading(2, "Fig. 5: reliability over a sweep of ΔT".into()),
        Block::p(format!(
            "The first {} tools at every level s·ΔT of the sweep. Data: `fig5_perturbation_sweep.csv` (one row per tool and level; s = 0 is the reference).",
            e.plan.sweep_tools.min(e.records.len())
        )),
        Block::table(&["scale s", "n", "ρ(ln|Π^U|, |Δ task error|) [95 %]", "by claim (b)'s rule"], rows),
        Block::p("ΔT's own sign against the opposite, per tool (|Δ| at +s − at −s):"),
        Block::table(&["|s|", "paired comparison"], signs),
        figure_block(figures, "fig5_perturbation_sweep.svg", "Left: |Δ task error| against confidence per level (blue: ΔT's sign, red: the opposite). Right: its mean per level. Compare with the paper's Fig. 5.".into()),
    ]
}

fn fig6_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let (differ, judged) = e.statistics.grid_disagreements;
    vec![
        Block::Heading(2, "Fig. 6: which tool ∫F and ∫J choose".into()),
        Block::p(format!(
            "{} trials, each of {} tools of the population drawn at random; F = argmin ∫F dt, J = \
             argmin ∫J dt (ties to the earlier tool). They chose differently in {differ} of {judged} \
             trials. Data: `fig6_selection_grid.csv`.",
            e.grid.len(),
            e.plan.grid_tools.min(e.records.len())
        )),
        figure_block(figures, "fig6_selection_grid.svg", "Chosen tool per trial: light grey F, dark grey J, black both. Compare with the paper's Fig. 6.".into()),
    ]
}

fn fig7_section(e: &Evaluation, figures: &[Option<Figure>]) -> Vec<Block> {
    let mut summary_rows = Vec::new();
    for (m, name) in MEASURES.iter().enumerate() {
        for (r, rule) in RULES.iter().enumerate() {
            let v: Vec<f64> = e.statistics.chosen[m][r]
                .iter()
                .flatten()
                .copied()
                .collect();
            summary_rows.push(vec![
                name.to_string(),
                rule.name().into(),
                v.len().to_string(),
                range(&v),
            ]);
        }
    }
    let tests: Vec<Vec<String>> = e
        .statistics
        .comparisons
        .iter()
        .map(|c| {
            vec![
                MEASURES[c.measure].into(),
                format!("{} − {}", RULES[c.a].name(), RULES[c.b].name()),
                c.paired.describe(),
            ]
        })
        .collect();
    let overlap = e.plan.trial_tools * e.trials.len() > e.records.len();
    vec![
        Block::Heading(
            2,
            "Fig. 7: benchmarking the choice by ∫F, ∫J and confidence (claim c)".into(),
        ),
        Block::p(format!(
            "{} trials, each of {} tools of the population drawn at random; each rule's tool is \
             compared on its confidence, task error and sensitivity |Δ task error| under ΔT, trial \
             by trial.{} Data: `fig7_benchmark.csv`, `fig7_choices.csv`.",
            e.trials.len(),
            e.plan.trial_tools.min(e.records.len()),
            if overlap {
                " The trials share tools (the population is smaller than trials × tools), so they are not independent."
            } else {
                ""
            }
        )),
        Block::table(&["measure", "rule", "n", "median [min, max]"], summary_rows),
        Block::table(&["measure", "difference", "paired test"], tests),
        figure_block(
            figures,
            "fig7_benchmark.svg",
            "The chosen tools per rule: box plots with mean ± sd. Compare with the paper's Fig. 7."
                .into(),
        ),
        verdict_block(verdict_of(e, Claim::Selection)),
    ]
}
