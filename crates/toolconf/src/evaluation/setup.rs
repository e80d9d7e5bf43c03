//! The task bound once per level of ΔT the experiments run at: without ΔT (Figs. 2, 6, 7), with
//! the task's ΔT (Figs. 3, 4, 7) and at every level of the sweep (Fig. 5).

use crate::rank::ModelTasks;
use toolconf_model::inputs::task_file::{PerJoint, TaskSpec};
use toolconf_model::registry::ModelKind;
use toolconf_model::robot_scales::{default_perturbation, Perturbation};

use super::{EvaluationError, Plan};

/// The task of an evaluation, bound at each level of ΔT.
#[derive(Debug, Clone)]
pub struct Setup {
    pub model: ModelKind,
    /// The task as given (its `[episode] perturbation`, if any, is the experiments' ΔT).
    pub spec: TaskSpec,
    /// ΔT per joint and where it came from.
    pub perturbation: Perturbation,
    /// The sweep's scales of ΔT ([`Plan::sweep_scales`]).
    pub scales: Vec<f64>,
    /// ΔT = 0.
    pub base: ModelTasks,
    /// ΔT as stated.
    pub perturbed: ModelTasks,
    /// One per scale; `None` for the scales 0 and 1, which are `base` and `perturbed`.
    sweep: Vec<Option<ModelTasks>>,
}

impl Setup {
    /// `spec` for `model`: the model must offer the task, the task fit the model, and ΔT (the
    /// task's, else [`default_perturbation`]) be one non-zero value per joint.
    pub fn new(model: ModelKind, spec: &TaskSpec, plan: &Plan) -> Result<Self, EvaluationError> {
        let offered = model.info().tasks;
        if !offered.contains(&spec.kind) {
            let names: Vec<&str> = offered.iter().map(|k| k.name()).collect();
            return Err(EvaluationError::Input(format!(
                "{}: model {model} does not offer a {} task (its tasks: {})",
                task_place(spec, "kind"),
                spec.kind,
                names.join(", ")
            )));
        }
        let perturbation = perturbation(model, spec)?;
        let at = |scale: f64| -> Result<ModelTasks, EvaluationError> {
            let mut s = spec.clone();
            let values = perturbation.values.iter().map(|v| scale * v).collect();
            s.episode.perturbation = Some(PerJoint::Each(values));
            let tasks = ModelTasks::new(&s);
            tasks
                .check(model)
                .map_err(|e| EvaluationError::Input(e.to_string()))?;
            Ok(tasks)
        };
        let (base, perturbed) = (at(0.0)?, at(1.0)?);
        let scales = plan.sweep_scales();
        let sweep = scales
            .iter()
            .map(|&s| match s {
                0.0 | 1.0 => Ok(None),
                _ => at(s).map(Some),
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            model,
            spec: spec.clone(),
            perturbation,
            scales,
            base,
            perturbed,
            sweep,
        })
    }

    /// The task at sweep level `k`: its own binding, or `base` (scale 0) or `perturbed` (1).
    pub fn level(&self, k: usize) -> &ModelTasks {
        match (&self.sweep[k], self.scales[k]) {
            (Some(tasks), _) => tasks,
            (None, 0.0) => &self.base,
            (None, _) => &self.perturbed,
        }
    }

    /// Whether sweep level `k` is run on its own (not shared with the base or perturbed run).
    pub fn own_level(&self, k: usize) -> bool {
        self.sweep[k].is_some()
    }

    /// Episodes the sweep adds per sweep tool.
    pub fn own_levels(&self) -> usize {
        self.sweep.iter().filter(|s| s.is_some()).count()
    }
}

/// "task.toml, key episode.perturbation" or "--task tip_position".
fn task_place(spec: &TaskSpec, key: &str) -> String {
    if spec.file.is_empty() {
        format!("--task {}", spec.kind)
    } else {
        format!("{}, key {key}", spec.file)
    }
}

/// ΔT per joint: the task file's `[episode] perturbation`, else the model's default.
fn perturbation(model: ModelKind, spec: &TaskSpec) -> Result<Perturbation, EvaluationError> {
    let n = model.dof();
    let stated = |values: Vec<f64>| Perturbation {
        values,
        source: "the task's [episode] perturbation".into(),
    };
    let dt = match &spec.episode.perturbation {
        Some(PerJoint::All(v)) => stated(vec![*v; n]),
        Some(PerJoint::Each(v)) if v.len() == n => stated(v.clone()),
        Some(PerJoint::Each(v)) => {
            return Err(EvaluationError::Input(format!(
                "{}: {} values, but model {model} has {n} joints",
                task_place(spec, "episode.perturbation"),
                v.len()
            )))
        }
        None => default_perturbation(model).map_err(|why| {
            EvaluationError::Input(format!(
                "{}: no ΔT is given, and the default (10 % of each joint's rated torque) needs \
                 the rated torques, which cannot be read ({why}): give [episode] perturbation \
                 in a task file",
                task_place(spec, "episode.perturbation")
            ))
        })?,
    };
    if dt.values.iter().all(|v| *v == 0.0) {
        return Err(EvaluationError::Input(format!(
            "{}: ΔT is 0 on every joint; the experiments under a perturbation need one",
            task_place(spec, "episode.perturbation")
        )));
    }
    Ok(dt)
}
