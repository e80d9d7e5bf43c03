//! The paper's evaluation (its Results section, Figs. 2–7) on any model, task and tool
//! population: does control confidence predict the task error, and the reliability under a
//! perturbation, on *this* robot and task? `toolconf reproduce --model`, `toolconf.reproduce`
//! and `toolconf.dask.reproduce` run it; the report crate draws it.
//!
//! # One population, shared episodes
//!
//! The population is N tools: a tools file's, or drawn from the model's sampling box exactly as
//! `select --models M --tools N --seed S` draws them ([`Population`]). Every tool runs twice on
//! the task: without ΔT (its ln|Π^U|, task error, ∫F dt and ∫J dt: Fig. 2, and what the
//! selection rules choose by) and with the task's ΔT (|Δ task error|: Fig. 4). The first
//! `sweep_tools` also run at every level of the sweep (Fig. 5), whose levels 0 and 1 are those
//! two runs. The trials of Figs. 6 and 7 choose among a few tools of the population drawn per
//! trial ([`trials`]), so they need no episodes of their own; Fig. 3's two tools are rerun with
//! their trajectories recorded. In all, 2N + sweep_tools·(levels − 2) + 4 episodes (the paper's
//! counts: 2N + 904).
//!
//! # ΔT
//!
//! The task file's `[episode] perturbation`, one value for every joint or one per joint; else
//! −10 % of each joint's rated torque on a URDF arm, the paper's −0.8 N m otherwise
//! ([`toolconf_model::robot_scales::default_perturbation`]). The unperturbed runs use ΔT = 0 whatever the
//! file says.
//!
//! # Seeds
//!
//! One master seed: the sample is drawn from it (as `select --seed`), and every other stream
//! from [`derive_seed`]`(seed, label)`: `fig6/trial/<k>`, `fig7/trial/<k>`, `fig2/bootstrap`,
//! `fig4/bootstrap`, `fig5/bootstrap/<scale>`. Results are the same whatever the thread count.
//!
//! # Verdicts
//!
//! The three claims' rules are stated in [`verdict`], before any number is computed.

pub mod analysis;
pub mod check;
pub mod highlight;
mod plan;
mod population;
pub mod prediction_check;
pub mod records;
mod seeds;
mod setup;
pub mod tables;
pub mod trials;
pub mod verdict;

pub use analysis::{barely_moved, Statistics};
pub use check::{ConfidenceCheck, VALIDATION_TOOLS};
pub use highlight::{Highlight, HighlightRun};
pub use plan::{check_population, Plan, MAX_COUNT, MAX_TOOLS};
pub use population::{parse_box, sample_box, Population};
pub use prediction_check::PredictionCheck;
pub use records::{run_tools, Numbers, ToolRecord};
pub use seeds::derive_seed;
pub use setup::Setup;
pub use trials::Trial;
pub use verdict::{Claim, ClaimVerdict, Finding};

use serde_json::{json, Value};

use toolconf_generated::Read;

/// Why an evaluation gave no result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvaluationError {
    /// Bad input, found before any episode: one line naming the flag, file or key.
    #[error("{0}")]
    Input(String),
    /// Every tool's unperturbed episode failed.
    #[error("{0}")]
    Failed(String),
}

/// An evaluation's result.
#[derive(Debug, Clone)]
pub struct Evaluation {
    pub setup: Setup,
    pub population: Population,
    pub plan: Plan,
    pub seed: u64,
    pub records: Vec<ToolRecord>,
    pub highlight: Highlight,
    /// Fig. 6's trials and Fig. 7's.
    pub grid: Vec<Trial>,
    pub trials: Vec<Trial>,
    pub statistics: Statistics,
    pub verdicts: Vec<ClaimVerdict>,
    /// On a position task, when no tool moved: [`barely_moved`]'s sentence.
    pub barely_moved: Option<String>,
}

/// Episodes an evaluation of `n` tools runs.
pub fn planned_episodes(setup: &Setup, n: usize, plan: &Plan) -> u64 {
    (2 * n + plan.sweep_tools.min(n) * setup.own_levels() + 4) as u64
}

/// The whole evaluation of `population` on `setup`'s task: every tool's episodes on rayon's
/// threads, then [`finish`]. `done` hears of each tool's episodes as they finish.
pub fn evaluate(
    setup: Setup,
    population: Population,
    plan: &Plan,
    seed: u64,
    done: &(dyn Fn(u64) + Sync),
) -> Result<Evaluation, EvaluationError> {
    let records = run_tools(&setup, &population.tools, 0, plan.sweep_tools, done);
    finish(setup, population, records, plan, seed, done)
}

/// The evaluation from every tool's record (computed here, or in blocks elsewhere and put back
/// in order): Fig. 3's four traced runs, the trials, the statistics and the verdicts.
pub fn finish(
    setup: Setup,
    population: Population,
    records: Vec<ToolRecord>,
    plan: &Plan,
    seed: u64,
    done: &(dyn Fn(u64) + Sync),
) -> Result<Evaluation, EvaluationError> {
    if records.len() != population.len() || records.iter().enumerate().any(|(i, r)| r.index != i) {
        return Err(EvaluationError::Input(format!(
            "{} records for a population of {} tools, or out of order",
            records.len(),
            population.len()
        )));
    }
    if records.iter().all(|r| r.base.is_err()) {
        return Err(EvaluationError::Failed(format!(
            "every one of the {} tools' episodes failed; the first: {}",
            records.len(),
            records[0].error()
        )));
    }
    let highlight = highlight::highlight(&setup, &population, &records, plan.highlight_sample);
    done(4);
    let grid = trials::run(&records, plan.grid_trials, plan.grid_tools, seed, "fig6");
    let trials = trials::run(&records, plan.trials, plan.trial_tools, seed, "fig7");
    let statistics = Statistics::compute(&records, &setup.scales, &grid, &trials, plan, seed);
    let verdicts = statistics.verdicts(plan);
    let progress: Vec<f64> = records
        .iter()
        .filter_map(|r| r.base.as_ref().ok()?.progress)
        .collect();
    Ok(Evaluation {
        barely_moved: barely_moved(setup.spec.kind, &progress),
        setup,
        population,
        plan: plan.clone(),
        seed,
        records,
        highlight,
        grid,
        trials,
        statistics,
        verdicts,
    })
}

impl Evaluation {
    /// "panda, tip_position (panda_touch_point.toml)": the figures' titles.
    pub fn task_title(&self) -> String {
        let s = &self.setup.spec;
        let file = std::path::Path::new(&s.file)
            .file_name()
            .map(|f| format!(" ({})", f.to_string_lossy()))
            .unwrap_or_default();
        format!("{}, {}{file}", self.setup.model, s.kind)
    }

    /// Whether the task reads the tool's tip.
    pub fn reads_tip(&self) -> bool {
        toolconf_core::reads_tip(self.setup.spec.kind)
    }

    /// The names of the task variable's components: `tip_x` … on a tip task, else the model's
    /// joints (`theta1` …).
    pub fn task_components(&self) -> Vec<String> {
        let term = self.setup.spec.kind.error_term();
        match term.read() {
            Read::Tip { .. } => {
                let d = self.setup.model.info().tip_dim;
                toolconf_model::registry::AXES[..d.min(3)]
                    .iter()
                    .map(|a| format!("{}_{a}", term.name()))
                    .collect()
            }
            _ => (1..=self.setup.model.dof())
                .map(|j| format!("{}{j}", term.name()))
                .collect(),
        }
    }

    /// Episodes simulated and their right-hand-side evaluations.
    pub fn work(&self) -> (u64, u64) {
        let (e, r) = self
            .records
            .iter()
            .map(|r| r.work(&self.setup))
            .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        (e + self.highlight.runs.len() as u64, r)
    }

    /// What the command line's `--json` prints and Python's `verdicts` holds.
    pub fn summary_json(&self) -> Value {
        let verdicts: serde_json::Map<String, Value> = self
            .verdicts
            .iter()
            .map(|v| (v.claim.key().to_string(), v.json()))
            .collect();
        let s = &self.setup;
        let (episodes, rhs_evals) = self.work();
        let mut v = json!({
            "model": s.model.name(),
            "task": s.spec.kind,
            "goal": s.spec.tip_goal.kind_name(),
            "goal_description": s.spec.tip_goal.describe(),
            "perturbation": s.perturbation.values,
            "perturbation_source": s.perturbation.source,
            "sweep_scales": s.scales,
            "population": self.population.source,
            "tools": self.population.len(),
            "seed": self.seed,
            "plan": self.plan,
            "verdicts": verdicts,
            "notes": self.barely_moved.iter().collect::<Vec<_>>(),
            "episodes": episodes,
            "rhs_evals": rhs_evals,
        });
        if !s.spec.file.is_empty() {
            v["task_file"] = json!(s.spec.file);
        }
        if let Some(d) = &s.spec.description {
            v["description"] = json!(d);
        }
        v
    }
}
