//! The decision rules the selection experiments (Figs. 6 and 7) compare.
//!
//! A rule sees a whole trial (the task, the tools, and every tool's confidence and unperturbed
//! active-inference episode) and names the tool it picks. The paper's three are ∫F, ∫J and
//! confidence alone ([`toolconf::select::Objective`]). Another rule, for instance a ranking by an
//! MPC baseline's cost J*, implements [`DecisionRule`] (running whatever it needs inside
//! `choose`) and is added to [`decision_rules`]; the experiments then report its choices, its
//! tools' statistics and its paired tests against every other rule without further changes.

use plotters::style::RGBColor;

use toolconf::mpc::{MpcOptions, SimulateMpc};
use toolconf::select::{draw_tools, evaluate, Objective, ToolResult};
use toolconf_model::closed_loop::{EpisodeOptions, Plant};
use toolconf_model::{Arm, Task, TaskKind};

use super::batch::map_ordered;
use super::{Context, Experiment, ReproduceError};

/// One trial of a selection experiment, as the rules see it.
pub struct Trial<'a> {
    pub task: &'a Task,
    pub tools: &'a [Arm],
    /// Every tool's confidence and unperturbed episode, in tool order.
    pub results: &'a [ToolResult],
    /// The episode settings the results were computed with.
    pub options: &'a EpisodeOptions,
    /// The plant they were simulated on.
    pub plant: Plant,
}

/// A way of choosing one tool of a trial.
pub trait DecisionRule: Send + Sync {
    /// Identifier used in CSV columns (`chosen_by_<id>`) and file rows.
    fn id(&self) -> &'static str;
    /// Label in figures and the report.
    fn label(&self) -> &'static str;
    /// Fill colour in figures.
    fn colour(&self) -> RGBColor;
    /// The index of the chosen tool, `None` if it cannot choose (e.g. every tool failed).
    fn choose(&self, trial: &Trial) -> Option<usize>;
}

/// The paper's objectives through [`Objective::choose`] (ties go to the earlier tool).
pub struct Paper(pub Objective);

impl DecisionRule for Paper {
    fn id(&self) -> &'static str {
        self.0.name()
    }

    fn label(&self) -> &'static str {
        match self.0 {
            Objective::FreeEnergy => "F (∫F dt)",
            Objective::CostJ => "J (∫J dt)",
            Objective::Confidence => "confidence (ln|Π^U|)",
        }
    }

    fn colour(&self) -> RGBColor {
        match self.0 {
            Objective::FreeEnergy => RGBColor(0, 114, 178),
            Objective::CostJ => RGBColor(213, 94, 0),
            Objective::Confidence => RGBColor(0, 158, 115),
        }
    }

    fn choose(&self, trial: &Trial) -> Option<usize> {
        self.0.choose(trial.results)
    }
}

/// J*: the tool whose MPC baseline (default options: re-linearised, offset-free, 1 s horizon,
/// ±5 N m) achieves the lowest ∫J dt on the trial's task. The conventional optimal-control way of
/// ranking tools: simulate an optimal controller on each and keep the cheapest.
pub struct MpcCost(pub MpcOptions);

impl DecisionRule for MpcCost {
    fn id(&self) -> &'static str {
        "mpc_cost"
    }

    fn label(&self) -> &'static str {
        "J* (MPC ∫J dt)"
    }

    fn colour(&self) -> RGBColor {
        RGBColor(204, 121, 167)
    }

    fn choose(&self, trial: &Trial) -> Option<usize> {
        toolconf::select::first_argmin(trial.tools.iter().enumerate().filter_map(|(i, arm)| {
            (trial.plant)
                .simulate_mpc(arm, trial.task, trial.options, &self.0)
                .ok()
                .map(|e| (i, e.metrics.cost_j))
        }))
    }
}

/// Every rule the selection experiments compare, in report order. The first two are the pair
/// Fig. 6 contrasts (F and J).
pub fn decision_rules() -> Vec<Box<dyn DecisionRule>> {
    vec![
        Box::new(Paper(Objective::FreeEnergy)),
        Box::new(Paper(Objective::CostJ)),
        Box::new(Paper(Objective::Confidence)),
    ]
}

/// One trial's choices, one entry per rule of [`decision_rules`].
pub fn choices(rules: &[Box<dyn DecisionRule>], trial: &Trial) -> Vec<Option<usize>> {
    rules.iter().map(|r| r.choose(trial)).collect()
}

/// What a selection experiment runs: `trials` trials of `tools` tools on the paper task `kind`,
/// `episodes_per_tool` episodes a tool (for the progress bar).
pub struct TrialPlan {
    pub kind: TaskKind,
    pub trials: usize,
    pub tools: usize,
    pub episodes_per_tool: u64,
}

/// A trial's tools, their results and every rule's choice, as [`run_trial`] gives them.
pub type Drawn = (Vec<Arm>, Vec<ToolResult>, Vec<Option<usize>>);

/// Every trial of `plan`, in parallel ([`map_ordered`]): [`run_trial`], then `finish` with the
/// task (what else the experiment runs on the trial's tools, and its result); `sink` sees each
/// trial's index and result as it finishes, in order.
pub fn run_trials<E, R, F, S>(
    ctx: &Context,
    experiment: &E,
    plan: TrialPlan,
    rules: &[Box<dyn DecisionRule>],
    finish: F,
    sink: S,
) -> Result<Vec<R>, ReproduceError>
where
    E: Experiment + Sync,
    R: Send,
    F: Fn(&Task, Drawn) -> R + Sync + Send,
    S: FnMut(usize, &R) -> Result<(), ReproduceError>,
{
    let task = Task::paper(plan.kind);
    let trials: Vec<usize> = (0..plan.trials).collect();
    map_ordered(
        &trials,
        ctx.progress,
        plan.episodes_per_tool * plan.tools as u64,
        |&k| {
            finish(
                &task,
                run_trial(ctx, experiment, k, plan.tools, &task, rules),
            )
        },
        sink,
    )
}

/// Trial `k` of `experiment`: `count` tools drawn from its seed, simulated on `task` under the
/// context's options and plant, and every rule's choice among them.
pub fn run_trial(
    ctx: &Context,
    experiment: &dyn Experiment,
    k: usize,
    count: usize,
    task: &Task,
    rules: &[Box<dyn DecisionRule>],
) -> Drawn {
    let tools = draw_tools(count, ctx.seed_for(experiment, &format!("trial/{k}")));
    let results = evaluate(&tools, task, &ctx.options, ctx.plant);
    let trial = Trial {
        task,
        tools: &tools,
        results: &results,
        options: &ctx.options,
        plant: ctx.plant,
    };
    let chosen = choices(rules, &trial);
    (tools, results, chosen)
}
