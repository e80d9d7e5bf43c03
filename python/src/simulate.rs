//! `toolconf.simulate`: one closed-loop episode of any generated model.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf_generated::{Term, TERMS};
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::model::Metrics;
use toolconf_model::registry::{AnyTool, ModelKind};

use crate::errors::{detached, Failure};
use crate::models::model_kind;
use crate::task::task_spec;

/// An episode's metrics and its trajectory on the output grid, each series flat in C order
/// (time, joint).
pub struct Episode {
    pub metrics: Metrics,
    pub t: Vec<f64>,
    /// Every term's values by [`Term::index`], under its name, with its number of components
    /// (the joints, or the tip's; a tip term of a joint-space task has none and is left out).
    pub series: [(&'static str, usize, Vec<f64>); TERMS],
}

/// One episode of the tool `params` on `spec` bound to model `kind`, with the trajectory: the
/// generic runtime, which every model shares, through the registry.
pub fn episode_of(kind: ModelKind, spec: &TaskSpec, params: &[f64]) -> Result<Episode, Failure> {
    let tool = AnyTool::new(kind, params).map_err(Failure::input)?;
    let task = kind.model().bind(spec).map_err(Failure::input)?;
    if let Some(e) = task.episode_error() {
        return Err(Failure::input(e));
    }
    let e = task.episode(params, true).map_err(Failure::episode)?;
    e.metrics
        .check_finite(&tool.to_string())
        .map_err(Failure::from_error)?;
    let tr = e.trajectory.expect("a recorded episode has a trajectory");
    // Per joint on the grid as (time, joint), C order.
    let flat = |s: &[Vec<f64>]| -> Vec<f64> {
        (0..tr.t.len())
            .flat_map(|i| s.iter().map(move |joint| joint[i]))
            .collect()
    };
    Ok(Episode {
        metrics: e.metrics,
        series: Term::ALL.map(|term| (term.name(), tr.of(term).len(), flat(tr.of(term)))),
        t: tr.t,
    })
}

/// One closed-loop episode of the active-inference controller (U̇ = −γ ∂F/∂U) with one tool.
///
/// The model's equations are the plant; the episode is the paper's (t ∈ [0, 5] s, output every
/// 0.05 s, X0 the hanging equilibrium, U0 = 0.1, γ = 1, Dormand–Prince with ode45's tolerances;
/// on the acceleration task a switch to Rodas5P when the problem turns stiff) unless the task or
/// the keyword arguments say otherwise.
///
/// Args:
///     model: a generated model's name (``toolconf.models()``).
///     params: the tool's parameters, a 1-D array in the model's order (each in [1e-6, 1e6]).
///     task: a built-in task name, a task file's path, or a dict with a task file's keys.
///     method: the integrator, as the command line's ``--method``: ``"fast"`` (the default: ode45's
///         steps until a quick stiffness test fires, then Rodas5P), ``"explicit"`` (exactly
///         MATLAB ode45, the paper's numerics), ``"auto"`` or ``"stiff"``.
///     **episode_options: keys of a task file's ``[episode]`` table, over the task's:
///         ``t_end``, ``dt`` (s), ``perturbation`` (constant torque ΔT, N m: one number or one
///         per joint), ``learning_rate`` (γ), ``initial_theta``, ``initial_theta_dot``,
///         ``initial_torque`` (one number or one per joint), ``rtol``, ``atol``.
///
/// Returns:
///     dict: the metrics ``task_error`` (Σ of the task's weighted error over the grid),
///     ``free_energy`` (∫F dt), ``cost_j`` (∫J dt), ``logdet`` (ln|Π^U|), ``control_effort``
///     (∫|U|² dt), ``rhs_evals``, ``steps``, ``rejected_steps``, ``jacobian_evals``,
///     ``factorisations``; and the trajectory on the output grid: ``t`` (shape (T,)) and one
///     array per free-energy term, under the name task files give it (``toolconf.terms()``;
///     each shape (T, joints); the plant's acceleration is what the controller observes). For
///     arm2 the metrics are ``toolconf simulate --json``'s.
///
/// Raises:
///     ValueError: bad input (model, parameters, task or episode option), naming the value.
///     TypeError: ``params`` of booleans, complex numbers or text.
///     toolconf.SimulationError: the episode failed; ``tool``, ``time`` and ``reason`` say how.
#[pyfunction]
#[pyo3(signature = (model, params, task, method="fast", **episode_options))]
pub fn simulate<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    task: &Bound<'py, PyAny>,
    method: &str,
    episode_options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let np = kind.parameter_names().len();
    let (shape, values) = crate::arrays::tool_params(kind, params)?;
    if shape != [np] {
        return Err(Failure::Input(format!(
            "params of shape {shape:?}: model {kind} takes one tool's {np} parameters ({}) as a 1-D \
             array (rank many tools with toolconf.rank)",
            kind.parameter_names().join(",")
        ))
        .into_pyerr(py));
    }
    let mut spec = task_spec(task, episode_options)?;
    spec.episode.method = Some(crate::task::method(method).map_err(|f| f.into_pyerr(py))?);
    let e = detached(py, || episode_of(kind, &spec, &values))?;
    to_dict(py, e)
}

/// A metric: its key in the results and how it is read.
pub type Column<T> = (&'static str, fn(&Metrics) -> T);

/// A [`Column`] for each of these fields of [`Metrics`], keyed by the field's name.
macro_rules! columns {
    ($($field:ident),*) => {
        [$((stringify!($field), |m: &Metrics| m.$field)),*]
    };
}

/// The episode's measures, in the order the results list them.
pub const MEASURES: [Column<f64>; 5] =
    columns!(task_error, free_energy, cost_j, logdet, control_effort);

/// The integrator's counts, in the order the results list them.
pub const COUNTS: [Column<usize>; 5] = columns!(
    rhs_evals,
    steps,
    rejected_steps,
    jacobian_evals,
    factorisations
);

fn to_dict(py: Python<'_>, e: Episode) -> PyResult<Bound<'_, PyDict>> {
    let m = &e.metrics;
    let out = PyDict::new(py);
    for (key, f) in MEASURES {
        out.set_item(key, f(m))?;
    }
    for (key, f) in COUNTS {
        out.set_item(key, f(m))?;
    }
    let points = e.t.len();
    out.set_item("t", PyArray1::from_vec(py, e.t))?;
    out.set_item("progress", e.metrics.progress)?;
    for (key, components, series) in e.series {
        if components == 0 {
            continue;
        }
        out.set_item(
            key,
            PyArray1::from_vec(py, series).reshape([points, components])?,
        )?;
    }
    Ok(out)
}
