//! Episode options shared by the commands that simulate (defaults: the paper's), and the task
//! choice: a built-in task name or a task file.

use std::path::PathBuf;

use toolconf_integrators::Method;
use toolconf_model::closed_loop::{EpisodeOptions, Plant};
use toolconf_model::inputs::task_file::{PerJoint, TaskSpec};
use toolconf_model::{Error, TaskKind};

use super::output::CliError;
use super::parse_task;

/// The task: `--task NAME` or `--task-file FILE` (exactly one).
#[derive(clap::Args, Debug, Clone)]
pub struct TaskArgs {
    /// The task (from derive/tasks.toml).
    #[arg(long, help = format!("The task: {}", toolconf_model::task::task_choices()), value_parser = parse_task, required_unless_present = "task_file", conflicts_with = "task_file")]
    pub task: Option<TaskKind>,
    /// A task file (TOML: kind, [goal], [precision], [episode]; see docs/reference/file-formats.md) instead of a
    /// built-in task. Episode flags given on the command line override its [episode].
    #[arg(long)]
    pub task_file: Option<PathBuf>,
}

impl TaskArgs {
    /// The task as a spec (a built-in task is a spec with nothing overridden).
    pub fn spec(&self) -> Result<TaskSpec, CliError> {
        match (&self.task_file, self.task) {
            (Some(path), _) => Ok(TaskSpec::from_file(path)?),
            (None, Some(kind)) => Ok(TaskSpec::builtin(kind)),
            (None, None) => Err(CliError::Usage("give --task or --task-file".into())),
        }
    }
}

/// Episode flags; a flag left out is the task file's value, else the paper's default.
#[derive(clap::Args, Debug, Clone)]
pub struct EpisodeArgs {
    /// Constant torque perturbation ΔT on every joint [N m] (default 0).
    #[arg(long = "perturb", allow_hyphen_values = true)]
    pub perturbation: Option<f64>,
    /// End time of the episode [s] (default 5).
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Output grid spacing [s] (default 0.05).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Learning rate γ of the controller (default 1).
    #[arg(long = "gamma", allow_hyphen_values = true)]
    pub learning_rate: Option<f64>,
    /// Integrator relative tolerance (default 1e-3, ode45's).
    #[arg(long, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Integrator absolute tolerance (default 1e-6, ode45's).
    #[arg(long, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// Plant: the paper's generative process, or the exact Lagrangian 2-link dynamics.
    #[arg(long, value_enum, default_value_t = PlantArg::Paper)]
    pub plant: PlantArg,
}

/// `--method` (select, rank, reproduce, simulate).
#[derive(clap::Args, Debug, Clone)]
pub struct MethodArgs {
    /// Integration method. fast (the default): DP5 (ode45's steps) until a quick stiffness test
    /// fires, then Rodas5P, for throughput on many tools; explicit: exactly MATLAB ode45, the
    /// paper's numerics; auto: ode45 on tasks 1-2 and the ode45-to-Rodas5P switch on task 3;
    /// stiff: Rodas5P throughout.
    #[arg(long, value_enum, default_value_t = MethodArg::Fast)]
    pub method: MethodArg,
}

/// The integration methods by name (see [`Method`]).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MethodArg {
    #[default]
    Fast,
    Explicit,
    Auto,
    Stiff,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Fast => Method::Fast,
            MethodArg::Explicit => Method::Explicit,
            MethodArg::Auto => Method::Auto,
            MethodArg::Stiff => Method::Stiff,
        }
    }
}

/// The simulated arm's equations of motion (the agent always uses the paper's model).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PlantArg {
    /// The paper's generative process (appendix "Tool Dynamics").
    #[default]
    Paper,
    /// The exact 2-link Lagrangian dynamics of the same arm.
    Exact,
}

impl From<PlantArg> for Plant {
    fn from(p: PlantArg) -> Self {
        match p {
            PlantArg::Paper => Plant::Paper,
            PlantArg::Exact => Plant::Exact,
        }
    }
}

/// The episode flags by the task-file key they override, to name a refused value by its flag.
const FLAGS: [(&str, &str); 6] = [
    ("episode.t_end", "--t-end"),
    ("episode.dt", "--dt"),
    ("episode.perturbation", "--perturb"),
    ("episode.learning_rate", "--gamma"),
    ("episode.rtol", "--rtol"),
    ("episode.atol", "--atol"),
];

impl EpisodeArgs {
    /// The 2-link options of a built-in task: the flags over the paper's defaults, checked as a
    /// task file's `[episode]` is.
    pub fn options(&self, record_trajectory: bool) -> Result<EpisodeOptions, CliError> {
        self.apply(&mut TaskSpec::builtin(TaskKind::Position))?;
        let d = EpisodeOptions::default();
        let mut o = EpisodeOptions {
            t_end: self.t_end.unwrap_or(d.t_end),
            dt: self.dt.unwrap_or(d.dt),
            perturbation: self.perturbation.unwrap_or(d.perturbation),
            learning_rate: self.learning_rate.unwrap_or(d.learning_rate),
            record_trajectory,
            ..d
        };
        o.integrator.rtol = self.rtol.unwrap_or(d.integrator.rtol);
        o.integrator.atol = self.atol.unwrap_or(d.integrator.atol);
        Ok(o)
    }

    /// Puts the flags that were given over the task's `[episode]`, then checks every option
    /// against its range ([`toolconf_model::inputs::task_file::EpisodeSpec::check`]): a refused value is named
    /// by the flag that gave it (`--dt: 0 must be a number in [1e-6, 1e6] s`), else by the task
    /// file and key.
    pub fn apply(&self, spec: &mut TaskSpec) -> Result<(), CliError> {
        let set = |slot: &mut Option<f64>, v: Option<f64>| {
            if v.is_some() {
                *slot = v;
            }
        };
        let e = &mut spec.episode;
        set(&mut e.t_end, self.t_end);
        set(&mut e.dt, self.dt);
        set(&mut e.learning_rate, self.learning_rate);
        set(&mut e.rtol, self.rtol);
        set(&mut e.atol, self.atol);
        if let Some(p) = self.perturbation {
            e.perturbation = Some(PerJoint::All(p));
        }
        let Err((key, message)) = spec.episode.check() else {
            return Ok(());
        };
        match self.flag_for(key) {
            Some(flag) => Err(CliError::Usage(format!("{flag}: {message}"))),
            None => Err(spec.error(key, message).into()),
        }
    }

    /// The flag that gave the value of `key`, if one did; for dt and t_end, which are checked
    /// against each other, the other one's flag if only it was given.
    fn flag_for(&self, key: &str) -> Option<&'static str> {
        let given = |k: &str| match k {
            "episode.t_end" => self.t_end.is_some(),
            "episode.dt" => self.dt.is_some(),
            "episode.perturbation" => self.perturbation.is_some(),
            "episode.learning_rate" => self.learning_rate.is_some(),
            "episode.rtol" => self.rtol.is_some(),
            "episode.atol" => self.atol.is_some(),
            _ => false,
        };
        let flag = |k: &str| FLAGS.iter().find(|(key, _)| *key == k).map(|(_, f)| *f);
        if given(key) {
            return flag(key);
        }
        let other = match key {
            "episode.dt" => "episode.t_end",
            "episode.t_end" => "episode.dt",
            _ => return None,
        };
        if given(other) {
            flag(other)
        } else {
            None
        }
    }
}

/// A task file's options for the paper's arm with one ΔT for both joints, as the 2-link
/// commands take them: a perturbation that differs between the joints is refused with `why`.
pub fn two_link_options(o: &EpisodeOptions, why: &str) -> Result<EpisodeOptions, Error> {
    let dt = o.total_perturbation();
    if dt[0] != dt[1] {
        return Err(Error::Unsupported(format!(
            "a perturbation that differs between the joints ({} and {} N m) {why}",
            dt[0], dt[1]
        )));
    }
    Ok(EpisodeOptions {
        perturbation: dt[0],
        joint_perturbation: nalgebra::SVector::zeros(),
        ..*o
    })
}
