//! `toolconf simulate --arm M1,M2,L1,L2 --task T [--perturb DT] [--json] [--csv FILE]`.

use std::path::PathBuf;

use serde_json::{json, Value};
use toolconf::mpc::{MpcMetrics, MpcModel, MpcOptions, SimulateMpc};
use toolconf::rank::{ModelTasks, TrajectoryTable};
use toolconf_integrators::Method;
use toolconf_model::closed_loop::{Episode, EpisodeOptions, Metrics, Plant};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::model::{episode_on, Arm2, Arm2Exact};
use toolconf_model::registry::ModelKind;
use toolconf_model::validate::finite_output;
use toolconf_model::{Arm, Task};

use super::episode_args::{two_link_options, EpisodeArgs, PlantArg, TaskArgs};
use super::output::{check_files, write_atomically, CliError, RunFiles};
use super::tool_args::ToolArgs;
use super::tool_from_params;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    tool: ToolArgs,
    #[command(flatten)]
    task: TaskArgs,
    #[command(flatten)]
    episode: EpisodeArgs,
    #[command(flatten)]
    method: super::episode_args::MethodArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Write the trajectory on the output grid to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// The controller: the paper's active inference (aic) or the linear MPC baseline (mpc).
    #[arg(long, value_enum, default_value_t = Controller::Aic)]
    controller: Controller,
    #[command(flatten)]
    mpc: MpcArgs,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Controller {
    Aic,
    Mpc,
}

/// Options of the MPC baseline (used with `--controller mpc`).
#[derive(clap::Args, Debug, Clone)]
pub struct MpcArgs {
    /// MPC control period [s] (zero-order hold); the output step must be a whole number of periods.
    #[arg(long, default_value_t = 0.05, allow_hyphen_values = true)]
    pub mpc_period: f64,
    /// MPC prediction horizon [s].
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub horizon: f64,
    /// Torque bound per joint [N m] for the MPC (inf for none).
    #[arg(long, default_value_t = 5.0, allow_hyphen_values = true)]
    pub torque_limit: f64,
    /// MPC prediction model: re-linearised at every step (local) or the paper's linearisation
    /// at the hanging equilibrium (equilibrium; with --disturbance-observer false, the
    /// original linear MPC).
    #[arg(long, value_enum, default_value_t = MpcModelArg::Local)]
    pub mpc_model: MpcModelArg,
    /// Estimate a constant input disturbance and plan with it (offset-free MPC): true or false.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub disturbance_observer: bool,
    /// Gain of the disturbance observer, in (0, 1] (1: the last step's estimate as is).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub observer_gain: f64,
}

/// `--mpc-model` values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MpcModelArg {
    Equilibrium,
    Local,
}

impl MpcArgs {
    /// The options, each flag against its range ([`toolconf_model::validate`]) and all of them
    /// against an episode of `t_end` s output every `dt` s ([`MpcOptions::check_grid`]), before
    /// any episode runs.
    pub fn options(&self, t_end: f64, dt: f64) -> Result<MpcOptions, CliError> {
        use toolconf_model::validate::{MPC_HORIZON, MPC_PERIOD, OBSERVER_GAIN, TORQUE_LIMIT};
        for (flag, value, range) in [
            ("--mpc-period", self.mpc_period, MPC_PERIOD),
            ("--horizon", self.horizon, MPC_HORIZON),
            ("--torque-limit", self.torque_limit, TORQUE_LIMIT),
            ("--observer-gain", self.observer_gain, OBSERVER_GAIN),
        ] {
            range
                .check(value)
                .map_err(|m| CliError::Usage(format!("{flag}: {m}")))?;
        }
        let options = MpcOptions {
            period: self.mpc_period,
            horizon: self.horizon,
            torque_limit: self.torque_limit,
            model: match self.mpc_model {
                MpcModelArg::Equilibrium => MpcModel::Equilibrium,
                MpcModelArg::Local => MpcModel::Local,
            },
            disturbance_observer: self.disturbance_observer,
            observer_gain: self.observer_gain,
        };
        options.check_grid(t_end, dt).map_err(|m| {
            CliError::Usage(format!(
                "--mpc-period, --horizon (and the episode's grid): {m}"
            ))
        })?;
        Ok(options)
    }
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let spec = args.task.spec()?;
    let mut files = RunFiles::new();
    if let Some(path) = &args.task.task_file {
        files.input("--task-file", path);
    }
    if let Some(path) = &args.csv {
        files.output_file("--csv", path);
    }
    check_files(&files)?;
    let arm = match (args.tool.arm, args.tool.model) {
        (Some(arm), _) => arm,
        (None, Some(model)) => return run_model(args, model, spec),
        (None, None) => return Err(CliError::Usage("give --arm or --model".into())),
    };
    if args.controller == Controller::Mpc {
        return run_mpc(args, &arm, spec);
    }
    let (episode, perturb) = match args.task.task_file {
        None => {
            let task = Task::paper(spec.kind);
            let mut options = args.episode.options(args.csv.is_some())?;
            options.integrator.method = args.method.method.into();
            let episode = Plant::from(args.episode.plant).simulate(&arm, &task, &options)?;
            (episode, json!(options.perturbation))
        }
        Some(_) => from_task_file(args, &arm, spec.clone())?,
    };
    if let (Some(path), Some(tr)) = (&args.csv, &episode.trajectory) {
        write_atomically(path, &TrajectoryTable::from_trajectory(tr).to_csv())?;
    }
    let identity = json!({ "arm": arm, "task": spec.kind, "perturb": perturb });
    let heading = format!(
        "arm: {arm}    task: {}    perturbation: {perturb} N m",
        spec.label()
    );
    print_episode(args, identity, &heading, &episode.metrics)
}

/// An active-inference episode's result: `identity` (the tool, task and perturbation) and the
/// metrics as one JSON object, or `heading` and the metrics as text; the same for `--arm` and
/// `--model`.
fn print_episode(args: &Args, mut out: Value, heading: &str, m: &Metrics) -> Result<(), CliError> {
    m.check_finite(&heading)?;
    let method = Method::from(args.method.method).describe();
    if args.json {
        for (key, value) in [
            ("task_error", json!(m.task_error)),
            ("free_energy", json!(m.free_energy)),
            ("cost_j", json!(m.cost_j)),
            ("logdet", json!(m.logdet)),
            ("rhs_evals", json!(m.rhs_evals)),
            ("steps", json!(m.steps)),
            ("rejected_steps", json!(m.rejected_steps)),
            ("method", json!(method)),
        ] {
            out[key] = value;
        }
        if let Some(p) = m.progress {
            out["progress"] = json!(p);
        }
        if let Some(path) = &args.task.task_file {
            out["task_file"] = json!(path);
        }
        outln!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
        return Ok(());
    }
    outln!("{heading}");
    outln!("integration method: {method}");
    outln!("task error     {:.9e}", m.task_error);
    outln!("integral F dt  {:.9e}", m.free_energy);
    outln!("integral J dt  {:.9e}", m.cost_j);
    outln!("ln|Pi^U|       {:.9e}", m.logdet);
    if let Some(p) = m.progress {
        outln!("progress       {p:.6}  (1 - e(T)/e(0), e the distance to the goal)");
    }
    outln!(
        "rhs evals      {} ({} steps, {} rejected)",
        m.rhs_evals,
        m.steps,
        m.rejected_steps
    );
    if let Some(path) = &args.csv {
        outln!("trajectory     {}", path.display());
    }
    Ok(())
}

/// The task file's task for `arm`: a tip goal relative to the tool's tip resolved at the arm's
/// own tip where the episode starts.
fn two_link_task(
    spec: &TaskSpec,
    arm: &Arm,
    options: &toolconf_model::model::EpisodeOptionsN<2, 4>,
) -> Result<Task, CliError> {
    let (task, offset) = spec.task_and_offset::<Arm2, 2, 4, 4, 6>()?;
    let Some(offset) = offset else {
        return Ok(task);
    };
    let q0 = options.x0.fixed_rows::<2>(0).into_owned();
    Ok(toolconf_model::inputs::task_file::at_initial_tip(
        &task, &offset, arm, &q0,
    )?)
}

/// One episode of the task file's task: the generic 2-link runtime, which takes the file's
/// initial state, initial torque and per-joint perturbation as they are.
fn from_task_file(
    args: &Args,
    arm: &Arm,
    mut spec: TaskSpec,
) -> Result<(Episode, Value), CliError> {
    args.episode.apply(&mut spec)?;
    spec.episode.method = Some(args.method.method.into());
    let mut options = spec.episode::<Arm2, 2, 4, 4, 6>()?;
    let task = two_link_task(&spec, arm, &options)?;
    options.record_trajectory = args.csv.is_some();
    let episode = match Plant::from(args.episode.plant) {
        Plant::Paper => episode_on::<Arm2, Arm2, 2, 4, 4, 6>(arm, &task, &options)?,
        Plant::Exact => episode_on::<Arm2, Arm2Exact, 2, 4, 4, 6>(arm, &task, &options)?,
    };
    let dt = options.total_perturbation();
    let perturb = if dt[0] == dt[1] {
        json!(dt[0])
    } else {
        json!([dt[0], dt[1]])
    };
    Ok((episode, perturb))
}

/// `--controller mpc`: one MPC episode of the paper's arm, its metrics checked finite before
/// anything is written.
fn run_mpc(args: &Args, arm: &Arm, mut spec: TaskSpec) -> Result<(), CliError> {
    let (task, options) = mpc_task(args, arm, &mut spec)?;
    let plant = Plant::from(args.episode.plant);
    let mpc = args.mpc.options(options.t_end, options.dt)?;
    let episode = plant.simulate_mpc(arm, &task, &options, &mpc)?;
    let m = &episode.metrics;
    let values = [
        m.task_error,
        m.free_energy,
        m.cost_j,
        m.control_effort,
        m.logdet,
    ];
    finite_output(&format!("arm {arm}"), "the MPC episode's metrics", values)?;
    if let (Some(path), Some(tr)) = (&args.csv, &episode.trajectory) {
        write_atomically(path, &TrajectoryTable::from_trajectory(tr).to_csv())?;
    }
    if args.json {
        let out = mpc_json(arm, &spec, &options, m);
        outln!(
            "{}",
            serde_json::to_string_pretty(&out).expect("finite numbers")
        );
    } else {
        print_mpc(args, arm, &spec, &options, m);
    }
    Ok(())
}

/// The MPC episode's task and options: the paper's task with the flags, or the task file's
/// (its tip goal resolved for `arm`) with the flags over its [episode].
fn mpc_task(
    args: &Args,
    arm: &Arm,
    spec: &mut TaskSpec,
) -> Result<(Task, EpisodeOptions), CliError> {
    Ok(match args.task.task_file {
        None => (
            Task::paper(spec.kind),
            args.episode.options(args.csv.is_some())?,
        ),
        Some(_) => {
            args.episode.apply(spec)?;
            let mut o = spec.episode::<Arm2, 2, 4, 4, 6>()?;
            let task = two_link_task(spec, arm, &o)?;
            o.record_trajectory = args.csv.is_some();
            let why = "is not supported by the MPC baseline";
            (task, two_link_options(&o, why)?)
        }
    })
}

/// The `--json` object of an MPC episode.
fn mpc_json(arm: &Arm, spec: &TaskSpec, options: &EpisodeOptions, m: &MpcMetrics) -> Value {
    json!({
        "arm": arm,
        "task": spec.kind,
        "controller": "mpc",
        "perturb": options.perturbation,
        "task_error": m.task_error,
        "free_energy": m.free_energy,
        "cost_j": m.cost_j,
        "control_effort": m.control_effort,
        "logdet": m.logdet,
        "rhs_evals": m.rhs_evals,
        "qp_solves": m.qp_solves,
        "qp_iterations": m.qp_iterations,
        "median_solve_time_us": m.median_solve_time.as_secs_f64() * 1e6,
        "max_solve_time_us": m.max_solve_time.as_secs_f64() * 1e6,
        "solver_status": m.worst_status,
    })
}

/// The text output of an MPC episode.
fn print_mpc(args: &Args, arm: &Arm, spec: &TaskSpec, options: &EpisodeOptions, m: &MpcMetrics) {
    outln!(
        "arm: {}    task: {}    controller: MPC    perturbation: {} N m",
        arm,
        spec.label(),
        options.perturbation
    );
    outln!("task error       {:.9e}", m.task_error);
    outln!(
        "integral J dt    {:.9e}  (J*: the cost the MPC achieves)",
        m.cost_j
    );
    outln!(
        "integral F dt    {:.9e}  (J* - T/2 ln|Pi^U|)",
        m.free_energy
    );
    outln!(
        "control effort   {:.9e}  (integral |U|^2 dt)",
        m.control_effort
    );
    outln!("ln|Pi^U|         {:.9e}", m.logdet);
    outln!("rhs evals        {}", m.rhs_evals);
    outln!(
        "QP solves        {} ({} iterations, median {:.1} us, max {:.1} us, status {})",
        m.qp_solves,
        m.qp_iterations,
        m.median_solve_time.as_secs_f64() * 1e6,
        m.max_solve_time.as_secs_f64() * 1e6,
        m.worst_status
    );
    if let Some(path) = &args.csv {
        outln!("trajectory       {}", path.display());
    }
}

/// One episode of a tool of any generated model (`--model M --params …`) on a built-in task or
/// a task file, through the model-generic runtime: the same numbers `toolconf rank` gives it.
fn run_model(args: &Args, model: ModelKind, mut spec: TaskSpec) -> Result<(), CliError> {
    if args.controller == Controller::Mpc {
        return Err(CliError::Usage(
            "--controller mpc runs the paper's arm only: give --arm".into(),
        ));
    }
    if args.episode.plant != PlantArg::Paper {
        return Err(CliError::Usage(
            "--plant exact is the paper's arm's exact dynamics: give --arm (or --model arm2_exact)"
                .into(),
        ));
    }
    let tool = tool_from_params(model, args.tool.params.as_deref().unwrap_or_default())?;
    args.episode.apply(&mut spec)?;
    spec.episode.method = Some(args.method.method.into());
    let tasks = ModelTasks::new(&spec);
    tasks.check(model)?;
    let episode = tasks.episode(&tool, args.csv.is_some())?;
    if let (Some(path), Some(tr)) = (&args.csv, &episode.trajectory) {
        write_atomically(path, &tr.to_csv())?;
    }
    let named: serde_json::Map<String, Value> = tool
        .named_parameters()
        .into_iter()
        .map(|(k, v)| (k.to_string(), json!(v)))
        .collect();
    let identity = json!({
        "model": model.name(),
        "params": named,
        "task": spec.kind,
        "perturb": episode.perturbation,
    });
    let heading = format!(
        "tool: {tool}    task: {}    perturbation: {:?} N m",
        spec.label(),
        episode.perturbation
    );
    print_episode(args, identity, &heading, &episode.metrics)
}
