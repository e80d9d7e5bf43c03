//! The task bound to every generated model ([`ModelTasks`]): what `rank`, `simulate --model`
//! and the confidence stage ask of a tool of any model, with the episode's results in
//! run-time-sized form ([`AnyEpisode`], [`TrajectoryTable`], [`TaskTrace`]).

use nalgebra::SVector;

use crate::generated;
use crate::model::mixed::{AnyTool, ModelKind};
use crate::model::{
    episode, ArmModel, EpisodeOptionsN, Metrics, ModelSimulationError, ToolN, TrajectoryN,
    ValidatedTaskN,
};
use crate::task_file::{TaskFileError, TaskSpec};
use crate::{Error, TaskKind, Term};

/// A task bound to one model: checked goals and precisions, and the episode options.
#[derive(Debug, Clone, Copy)]
pub struct Bound<const N: usize, const NX: usize> {
    pub task: ValidatedTaskN<N>,
    pub options: EpisodeOptionsN<N, NX>,
}

fn bind<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    spec: &TaskSpec,
) -> Result<Bound<N, NX>, TaskFileError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let task = spec.task::<M, N, NX, NP, NZ>()?;
    let options = spec.episode::<M, N, NX, NP, NZ>()?;
    let task = task.validated().map_err(|e| TaskFileError {
        file: spec.file.clone(),
        place: "key precision".into(),
        message: e.to_string(),
    })?;
    Ok(Bound { task, options })
}

/// [`ModelTasks`] with one binding per generated model ([`crate::for_each_model!`]).
macro_rules! model_tasks {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        /// The task bound to every model. A task that does not fit a model (a goal of the
        /// wrong length) is an error only once a tool of that model turns up
        /// ([`ModelTasks::check`]).
        #[derive(Debug, Clone)]
        pub struct ModelTasks {
            pub kind: TaskKind,
            $($module: Result<
                Bound<{ generated::$module::DOF }, { generated::$module::STATE_DIM }>,
                TaskFileError,
            >,)*
        }

        impl ModelTasks {
            pub fn new(spec: &TaskSpec) -> Self {
                Self {
                    kind: spec.kind,
                    $($module: bind::<
                        crate::model::$marker,
                        { generated::$module::DOF },
                        { generated::$module::STATE_DIM },
                        { generated::$module::PARAMETER_COUNT },
                        { generated::$module::STATE_DIM + generated::$module::DOF },
                    >(spec),)*
                }
            }

            /// Whether the task fits `model`.
            pub fn check(&self, model: ModelKind) -> Result<(), TaskFileError> {
                match model {
                    $(ModelKind::$marker => self.$module.as_ref().map(|_| ()).map_err(Clone::clone),)*
                }
            }

            /// ln|Π^U| of `tool` (eq. control_conf): the cheap stage.
            pub fn logdet(&self, tool: &AnyTool) -> Result<f64, Error> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => Ok(b.task.control_confidence(t)?.logdet),
                        Err(e) => Err(Error::Unsupported(e.to_string())),
                    },)*
                }
            }

            /// ln|Π^U| of `tool` and its gradient ∂ln|Π^U|/∂p (the generated closed form),
            /// in the model's parameter order: what `toolconf design` climbs.
            pub fn logdet_and_gradient(&self, tool: &AnyTool) -> Result<(f64, Vec<f64>), Error> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => {
                            let logdet = b.task.control_confidence(t)?.logdet;
                            Ok((logdet, b.task.logdet_gradient(t).as_slice().to_vec()))
                        }
                        Err(e) => Err(Error::Unsupported(e.to_string())),
                    },)*
                }
            }

            /// A, B, the task's sensitivities, Π^U and ln|Π^U| of `tool` (`confidence --model`).
            pub fn linearisation(&self, tool: &AnyTool) -> Result<Linearisation, Error> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => linearisation_of(t, b, self.kind),
                        Err(e) => Err(Error::Unsupported(e.to_string())),
                    },)*
                }
            }

            /// The episode's metrics.
            pub fn simulate(&self, tool: &AnyTool) -> Result<Metrics, ModelSimulationError> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => crate::model::simulate(t, b.task.task(), &b.options),
                        Err(e) => Err(unfit(e)),
                    },)*
                }
            }

            /// One episode of `tool` (`simulate --model`), with its trajectory if `record`.
            pub fn episode(&self, tool: &AnyTool, record: bool) -> Result<AnyEpisode, ModelSimulationError> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => episode_of(t, b, record),
                        Err(e) => Err(unfit(e)),
                    },)*
                }
            }

            /// The task variable (θ, θ̇ or θ̈ as the task kind says) over time, with its goal.
            pub fn trace(&self, tool: &AnyTool) -> Result<TaskTrace, ModelSimulationError> {
                match tool {
                    $(AnyTool::$marker(t) => match &self.$module {
                        Ok(b) => trace_of(t, b, self.kind),
                        Err(e) => Err(unfit(e)),
                    },)*
                }
            }
        }
    };
}

crate::for_each_model!(model_tasks);

/// A tool's linearisation and confidence with the sizes known only at run time (matrices as
/// rows): what `toolconf confidence --model` prints.
#[derive(Debug, Clone, PartialEq)]
pub struct Linearisation {
    /// A = ∂f/∂X at the equilibrium.
    pub a: Vec<Vec<f64>>,
    /// B = ∂f/∂U at the equilibrium.
    pub b: Vec<Vec<f64>>,
    /// The task's sensitivities by name (`d_theta_du`, `d_theta_dot_du`, `d_theta_ddot_du`), the
    /// terms it uses only.
    pub sensitivities: Vec<(&'static str, Vec<Vec<f64>>)>,
    /// Π^U (eq. control_conf).
    pub pi_u: Vec<Vec<f64>>,
    pub logdet: f64,
}

impl Linearisation {
    /// Every number finite ([`crate::validate::finite_output`]), naming `tool` and the quantity.
    pub fn check_finite(&self, tool: &dyn std::fmt::Display) -> Result<(), Error> {
        use crate::validate::finite_output;
        let flat = |m: &Vec<Vec<f64>>| m.iter().flatten().copied().collect::<Vec<f64>>();
        finite_output(tool, "A", flat(&self.a))?;
        finite_output(tool, "B", flat(&self.b))?;
        for (_, m) in &self.sensitivities {
            finite_output(tool, "a sensitivity", flat(m))?;
        }
        finite_output(tool, "Π^U", flat(&self.pi_u))?;
        finite_output(tool, "ln|Π^U|", [self.logdet])
    }
}

fn rows<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> Vec<Vec<f64>> {
    (0..R)
        .map(|i| (0..C).map(|j| m[(i, j)]).collect())
        .collect()
}

fn linearisation_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    bound: &Bound<N, NX>,
    kind: TaskKind,
) -> Result<Linearisation, Error>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let c = bound.task.control_confidence(tool)?;
    let s = tool.sensitivities(kind);
    let sensitivities = [
        ("d_theta_du", s.d_theta_du),
        ("d_theta_dot_du", s.d_theta_dot_du),
        ("d_theta_ddot_du", s.d_theta_ddot_du),
    ]
    .into_iter()
    .filter_map(|(name, m)| m.map(|m| (name, rows(&m))))
    .collect();
    Ok(Linearisation {
        a: rows(&tool.state_matrix()),
        b: rows(&tool.input_matrix()),
        sensitivities,
        pi_u: rows(&c.pi_u),
        logdet: c.logdet,
    })
}

fn unfit(e: &TaskFileError) -> ModelSimulationError {
    ModelSimulationError::Input(Error::Unsupported(e.to_string()))
}

/// One episode of a tool of any model: its metrics, the constant torque perturbation on each
/// joint, and the trajectory if it was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct AnyEpisode {
    pub metrics: Metrics,
    pub perturbation: Vec<f64>,
    pub trajectory: Option<TrajectoryTable>,
}

/// A trajectory on the output grid with the joint count known only at run time:
/// `theta[j][i]` is joint j at `t[i]`, and likewise θ̇, θ̈ (the plant's) and U.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryTable {
    pub t: Vec<f64>,
    pub theta: Vec<Vec<f64>>,
    pub theta_dot: Vec<Vec<f64>>,
    pub theta_ddot: Vec<Vec<f64>>,
    pub u: Vec<Vec<f64>>,
}

impl TrajectoryTable {
    /// The table of a trajectory with N joints known at compile time.
    pub fn from_trajectory<const N: usize>(tr: &TrajectoryN<N>) -> Self {
        TrajectoryTable {
            t: tr.t.clone(),
            theta: per_joint(&tr.theta),
            theta_dot: per_joint(&tr.theta_dot),
            theta_ddot: per_joint(&tr.theta_ddot),
            u: per_joint(&tr.u),
        }
    }

    /// As CSV: `t`, then θ, θ̇, θ̈ and U of each joint (`theta1, …, u<n>`), one row per time.
    pub fn to_csv(&self) -> String {
        // (prefix, suffix, values): the columns theta1, …, theta1_dot, …, u<n>.
        let blocks = [
            ("theta", "", &self.theta),
            ("theta", "_dot", &self.theta_dot),
            ("theta", "_ddot", &self.theta_ddot),
            ("u", "", &self.u),
        ];
        let mut header = vec!["t".to_string()];
        for (prefix, suffix, block) in blocks {
            header.extend((1..=block.len()).map(|j| format!("{prefix}{j}{suffix}")));
        }
        let mut out = header.join(",") + "\n";
        for i in 0..self.t.len() {
            let mut row = vec![self.t[i].to_string()];
            for (_, _, block) in blocks {
                row.extend(block.iter().map(|joint| joint[i].to_string()));
            }
            out += &(row.join(",") + "\n");
        }
        out
    }
}

/// `series[i][j]` (time i, joint j) as `out[j][i]`.
fn per_joint<const N: usize>(series: &[SVector<f64, N>]) -> Vec<Vec<f64>> {
    (0..N)
        .map(|j| series.iter().map(|v| v[j]).collect())
        .collect()
}

fn episode_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    bound: &Bound<N, NX>,
    record: bool,
) -> Result<AnyEpisode, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let options = EpisodeOptionsN {
        record_trajectory: record,
        ..bound.options
    };
    let e = episode(tool, bound.task.task(), &options)?;
    Ok(AnyEpisode {
        metrics: e.metrics,
        perturbation: options.total_perturbation().iter().copied().collect(),
        trajectory: e.trajectory.as_ref().map(TrajectoryTable::from_trajectory),
    })
}

/// The task variable of one episode on the output grid, per joint, with the goal.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTrace {
    pub t: Vec<f64>,
    /// `value[j][i]`: joint j at `t[i]`.
    pub value: Vec<Vec<f64>>,
    pub goal: Vec<f64>,
}

fn trace_of<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize>(
    tool: &ToolN<M, N, NX, NP, NZ>,
    bound: &Bound<N, NX>,
    kind: TaskKind,
) -> Result<TaskTrace, ModelSimulationError>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    let options = EpisodeOptionsN {
        record_trajectory: true,
        ..bound.options
    };
    let task = bound.task.task();
    let tr = episode(tool, task, &options)?
        .trajectory
        .expect("a recorded episode has a trajectory");
    let (series, goal) = match kind.error_term() {
        Term::Theta => (&tr.theta, task.goal_theta),
        Term::ThetaDot => (&tr.theta_dot, task.goal_theta_dot),
        Term::ThetaDdot => (&tr.theta_ddot, task.goal_theta_ddot),
        Term::U => (&tr.u, SVector::zeros()),
    };
    Ok(TaskTrace {
        t: tr.t.clone(),
        value: per_joint(series),
        goal: goal.iter().copied().collect(),
    })
}
