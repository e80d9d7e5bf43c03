//! The paper's active-inference controller (AIC) against the MPC baseline (default
//! options: re-linearised, offset-free, 1 s horizon, ±5 N m) on the same random tools, per task:
//! task error, ∫J, control effort, sensitivity to ΔT, compute time, and whether the two rank the
//! tools alike (Spearman's ρ between AIC's ∫F and MPC's J*). Runs with `reproduce --mpc`.
//!
//! Seeds: tools from `"mpc/tools"`, bootstrap from `"mpc/bootstrap/<task>"`. Compute times are
//! wall-clock and so appear in the report only, never in the CSV.

use std::time::{Duration, Instant};

use toolconf::mpc::{MpcOptions, SimulateMpc};
use toolconf::select::draw_tools;
use toolconf_model::{Arm, Task, TaskKind};
use toolconf_stats::summary;

use super::batch::map_ordered;
use super::figure_parts::{arm_cells, columns, files_block, task_label, PAPER_TASKS, TOOL_COLUMNS};
use super::report::{Block, Section};
use super::verdict::{num, Correlation, CorrelationReport};
use super::{described, Context, Experiment, Plan, ReproduceError};
use toolconf_files::csv::{Cell, CsvWriter};

pub struct MpcComparison;

const CSV: &str = "mpc_comparison.csv";
pub const HEADER: [&str; 13] = columns(&[
    &["task"],
    &TOOL_COLUMNS,
    &[
        "perturbation",
        "controller",
        "task_error",
        "cost_j",
        "control_effort",
        "error",
    ],
]);

/// One controller's episode: metrics (task error, ∫J or J*, effort, ∫F) or the error, and its time.
struct Run {
    values: Result<[f64; 4], String>,
    time: Duration,
}

struct Item {
    kind: TaskKind,
    tool: usize,
    arm: Arm,
    logdet: Option<f64>,
    /// [AIC, MPC] × [ΔT = 0, ΔT = perturbation].
    runs: [[Run; 2]; 2],
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let t0 = Instant::now();
    let out = f();
    (out, t0.elapsed())
}

impl Experiment for MpcComparison {
    described!("mpc", "Active inference against the MPC baseline", [CSV]);

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        if plan.mpc {
            3 * 4 * plan.mpc_tools as u64
        } else {
            0
        }
    }

    fn needs_mpc(&self) -> bool {
        true
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let plan = ctx.plan;
        let tools = draw_tools(plan.mpc_tools, ctx.seed_for(self, "tools"));
        let results = run_both_controllers(ctx, &tools)?;
        let mut rows = Vec::new();
        let mut ranking = Vec::new();
        let mut episodes = 0u64;
        for kind in PAPER_TASKS {
            let of: Vec<&Item> = results.iter().filter(|r| r.kind == kind).collect();
            for (c, name) in ["active inference", "MPC (J*)"].iter().enumerate() {
                episodes += 2 * of.len() as u64;
                rows.push(controller_row(kind, name, c, &of));
            }
            let seed = ctx.seed_for(self, &format!("bootstrap/{}", kind.name()));
            ranking.push(format!(
                "{}: ∫F (AIC) against J* (MPC): {}",
                task_label(kind),
                rank_agreement(&of, plan, seed).sentence()
            ));
        }
        let failed = results
            .iter()
            .flat_map(|r| r.runs.iter().flatten())
            .filter(|r| r.values.is_err())
            .count();
        let blocks = vec![
            Block::p(format!(
                "The same {} random tools run each task under the paper's controller and under the MPC \
                 baseline (re-linearised at every step, offset-free disturbance observer, 1 s horizon, \
                 ±5 N m, control period 0.05 s), both on the paper's nonlinear plant, without and with a \
                 constant perturbation ΔT = {} N m. J* is the ∫J dt the MPC achieves; |Δ task error| is \
                 the change of task error under ΔT. Compute time is the wall time of one episode on one \
                 core (medians).",
                tools.len(),
                plan.perturbation
            )),
            Block::table(&TABLE_HEADER, rows),
            Block::p(
                "Do the confidence-aware objective and the optimal-control baseline rank tools alike? \
                 Spearman's ρ between each tool's ∫F dt under active inference and its J* under MPC:",
            ),
            Block::Bullets(ranking),
            files_block(
                &[CSV.into()],
                4 * results.len(),
                failed,
                "rows, one per task, tool, controller and ΔT",
            ),
        ];
        Ok(Section {
            id: self.id(),
            title: self.title().into(),
            blocks,
            episodes,
            rhs_evals: 0,
        })
    }
}

const TABLE_HEADER: [&str; 8] = [
    "task",
    "controller",
    "succeeded",
    "median task error",
    "median ∫J dt",
    "median ∫|U|² dt",
    "median |Δ task error|",
    "median time per episode [ms]",
];

/// Every tool on every paper task under both controllers, without and with ΔT; four CSV rows
/// per (task, tool) as each finishes.
fn run_both_controllers(ctx: &Context, tools: &[Arm]) -> Result<Vec<Item>, ReproduceError> {
    let dts = [0.0, ctx.plan.perturbation];
    let items: Vec<(TaskKind, usize)> = PAPER_TASKS
        .iter()
        .flat_map(|&k| (0..tools.len()).map(move |i| (k, i)))
        .collect();
    let mut csv = ctx.csv(CSV, &HEADER)?;
    let done = map_ordered(
        &items,
        ctx.progress,
        4,
        |&(kind, i)| {
            let task = Task::paper(kind);
            let arm = tools[i];
            let run = |controller: usize, dt: f64| run_one(ctx, &arm, &task, controller, dt);
            Item {
                kind,
                tool: i,
                arm,
                logdet: toolconf_model::confidence::control_confidence(&arm, &task)
                    .ok()
                    .map(|c| c.logdet),
                runs: [
                    [run(0, dts[0]), run(0, dts[1])],
                    [run(1, dts[0]), run(1, dts[1])],
                ],
            }
        },
        |_, item| write_item(&mut csv, item, &dts),
    )?;
    csv.finish()?;
    Ok(done)
}

/// One timed episode: controller 0 is active inference, 1 the MPC baseline.
fn run_one(ctx: &Context, arm: &Arm, task: &Task, controller: usize, dt: f64) -> Run {
    let options = ctx.perturbed(dt);
    let (values, time) = if controller == 0 {
        timed(|| {
            ctx.plant
                .simulate(arm, task, &options)
                .map(|e| {
                    let m = e.metrics;
                    [m.task_error, m.cost_j, m.control_effort, m.free_energy]
                })
                .map_err(|e| e.to_string())
        })
    } else {
        timed(|| {
            ctx.plant
                .simulate_mpc(arm, task, &options, &MpcOptions::default())
                .map(|e| {
                    let m = e.metrics;
                    [m.task_error, m.cost_j, m.control_effort, m.free_energy]
                })
                .map_err(|e| e.to_string())
        })
    };
    Run { values, time }
}

fn write_item(csv: &mut CsvWriter, item: &Item, dts: &[f64; 2]) -> Result<(), ReproduceError> {
    for (c, name) in ["aic", "mpc"].iter().enumerate() {
        for (d, dt) in dts.iter().enumerate() {
            let r = &item.runs[c][d];
            let mut row = vec![Cell::from(item.kind.name()), Cell::from(item.tool)];
            row.extend(arm_cells(&item.arm));
            row.extend([Cell::from(item.logdet), Cell::from(*dt), Cell::from(*name)]);
            match &r.values {
                Ok(v) => row.extend([
                    Cell::from(v[0]),
                    Cell::from(v[1]),
                    Cell::from(v[2]),
                    Cell::from(""),
                ]),
                Err(e) => row.extend([
                    Cell::Empty,
                    Cell::Empty,
                    Cell::Empty,
                    Cell::from(e.as_str()),
                ]),
            }
            csv.row(row)?;
        }
    }
    Ok(())
}

/// One task's row for controller `c`: successes and medians.
fn controller_row(kind: TaskKind, name: &str, c: usize, of: &[&Item]) -> Vec<String> {
    let ok = of.iter().filter(|r| r.runs[c][0].values.is_ok()).count();
    let pick = |d: usize, k: usize| -> Vec<f64> {
        of.iter()
            .filter_map(|r| r.runs[c][d].values.as_ref().ok().map(|v| v[k]))
            .collect()
    };
    let change: Vec<f64> = of
        .iter()
        .filter_map(|r| match (&r.runs[c][0].values, &r.runs[c][1].values) {
            (Ok(a), Ok(b)) => Some((b[0] - a[0]).abs()),
            _ => None,
        })
        .collect();
    let times: Vec<f64> = of
        .iter()
        .map(|r| r.runs[c][0].time.as_secs_f64() * 1e3)
        .collect();
    let median = |v: &[f64]| {
        summary(v)
            .map(|s| num(s.median))
            .unwrap_or_else(|_| "n/a".into())
    };
    vec![
        task_label(kind),
        name.to_string(),
        format!("{ok}/{}", of.len()),
        median(&pick(0, 0)),
        median(&pick(0, 1)),
        median(&pick(0, 2)),
        median(&change),
        median(&times),
    ]
}

/// Do ∫F (active inference, with confidence) and J* (MPC) rank the tools alike?
fn rank_agreement(of: &[&Item], plan: &Plan, seed: u64) -> Correlation {
    let (x, y): (Vec<f64>, Vec<f64>) = of
        .iter()
        .filter_map(|r| match (&r.runs[0][0].values, &r.runs[1][0].values) {
            (Ok(a), Ok(m)) => Some((a[3], m[1])),
            _ => None,
        })
        .unzip();
    Correlation::compute(&x, &y, plan.bootstrap_resamples, plan.level, seed)
}
