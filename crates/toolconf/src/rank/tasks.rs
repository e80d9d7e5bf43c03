//! The task bound to every model of the registry ([`ModelTasks`]): what `rank`, `simulate
//! --model` and the confidence stage ask of a tool of any model, with the episode's results in
//! run-time-sized form ([`AnyEpisode`], [`TrajectoryTable`], [`TaskTrace`]).

use std::sync::Arc;

use toolconf_model::inputs::task_file::{TaskFileError, TaskSpec};
use toolconf_model::model::{Metrics, ModelSimulationError};
use toolconf_model::prediction::{LinearSystem, Prediction, PredictionError};
use toolconf_model::registry::{models, AnyTool, BoundTask, ModelKind};
use toolconf_model::{Error, TaskKind};

pub use toolconf_model::registry::{AnyEpisode, Linearisation, TaskTrace, TrajectoryTable};

/// The task bound to every model, in registry order. A task that does not fit a model (a goal
/// of the wrong length) is an error only once a tool of that model turns up
/// ([`ModelTasks::check`]).
#[derive(Debug, Clone)]
pub struct ModelTasks {
    pub kind: TaskKind,
    bound: Vec<Result<Arc<dyn BoundTask>, TaskFileError>>,
    /// What a model registered after the task was bound (a library loaded meanwhile) gets.
    late: TaskFileError,
}

/// `spec` bound to `model`: its goals and precisions checked against the model, then its
/// episode options, then the task's validation (as `key precision`).
fn bind(
    model: &dyn toolconf_model::registry::Model,
    spec: &TaskSpec,
) -> Result<Arc<dyn BoundTask>, TaskFileError> {
    let bound = model.bind(spec)?;
    if let Some(e) = bound.episode_error() {
        return Err(e.clone());
    }
    if let Some(e) = bound.validation_error() {
        return Err(TaskFileError {
            file: spec.file.clone(),
            place: "key precision".into(),
            message: e.to_string(),
        });
    }
    Ok(bound)
}

impl ModelTasks {
    pub fn new(spec: &TaskSpec) -> Self {
        Self {
            kind: spec.kind,
            bound: models().iter().map(|m| bind(*m, spec)).collect(),
            late: spec.error(
                "model",
                "the model was loaded after this task was read: read the task again".into(),
            ),
        }
    }

    fn bound(&self, model: ModelKind) -> Result<&dyn BoundTask, &TaskFileError> {
        match self.bound.get(model.index()) {
            Some(bound) => bound.as_deref(),
            None => Err(&self.late),
        }
    }

    /// The bound task of `tool`'s model, or the error saying why the task does not fit it.
    fn of(&self, tool: &AnyTool) -> Result<&dyn BoundTask, Error> {
        self.bound(tool.model())
            .map_err(|e| Error::Unsupported(e.to_string()))
    }

    /// Whether the task fits `model`.
    pub fn check(&self, model: ModelKind) -> Result<(), TaskFileError> {
        self.bound(model).map(|_| ()).map_err(Clone::clone)
    }

    /// ln|Π^U| of `tool` (eq. control_conf): the cheap stage.
    pub fn logdet(&self, tool: &AnyTool) -> Result<f64, Error> {
        self.of(tool)?.logdet(tool.parameters())
    }

    /// ln|Π^U| of `tool` and its gradient ∂ln|Π^U|/∂p (the generated closed form), in the
    /// model's parameter order: what `toolconf design` climbs.
    pub fn logdet_and_gradient(&self, tool: &AnyTool) -> Result<(f64, Vec<f64>), Error> {
        self.of(tool)?.logdet_and_gradient(tool.parameters())
    }

    /// A, B, the task's sensitivities, Π^U and ln|Π^U| of `tool` (`confidence --model`).
    pub fn linearisation(&self, tool: &AnyTool) -> Result<Linearisation, Error> {
        self.of(tool)?.linearisation(tool.parameters())
    }

    /// The episode's metrics.
    pub fn simulate(&self, tool: &AnyTool) -> Result<Metrics, ModelSimulationError> {
        self.of(tool)?.simulate(tool.parameters())
    }

    /// One episode of `tool` (`simulate --model`), with its trajectory if `record`.
    pub fn episode(
        &self,
        tool: &AnyTool,
        record: bool,
    ) -> Result<AnyEpisode, ModelSimulationError> {
        self.of(tool)?.episode(tool.parameters(), record)
    }

    /// The episode's cost predicted by the linearised closed loop ([`toolconf_model::prediction`]).
    pub fn predict(&self, tool: &AnyTool) -> Result<Prediction, PredictionError> {
        self.of(tool)?.predict(tool.parameters())
    }

    /// The linear system [`ModelTasks::predict`] steps.
    pub fn linear_system(&self, tool: &AnyTool) -> Result<LinearSystem, PredictionError> {
        self.of(tool)?.linear_system(tool.parameters())
    }

    /// The task variable (θ, θ̇ or θ̈ as the task kind says) over time, with its goal.
    pub fn trace(&self, tool: &AnyTool) -> Result<TaskTrace, ModelSimulationError> {
        self.of(tool)?.trace(tool.parameters())
    }
}
