//! `toolconf.simulate_batch`: the episodes of many tools under many perturbations, one row of
//! metrics per (tool, perturbation).

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use toolconf::model::Metrics;
use toolconf::registry::ModelKind;
use toolconf::task_file::TaskSpec;

use crate::errors::{detached, Failure};
use crate::models::model_kind;
use crate::task::task_spec;

/// Every tool of `params` (k × NP, row major) under every task of `specs` (one per
/// perturbation): k × P results, tool-major, each the episode's metrics or its error message.
/// Bad input (a task that does not fit the model, a bad parameter) fails the whole batch, as
/// it would the first `simulate` of a loop; a bad tool is named `tool i` (i counted from
/// `first_tool`) unless `first_tool` is `None` (one tool, given as a 1-D array). A failed
/// episode is its row's error only. Episodes
/// run on rayon's threads, each a pure function of its tool and task, so the rows do not depend
/// on the number of threads.
pub fn batch(
    kind: ModelKind,
    specs: &[TaskSpec],
    params: &[f64],
    first_tool: Option<usize>,
) -> Result<Vec<Result<Metrics, String>>, Failure> {
    let model = kind.model();
    let bound = specs
        .iter()
        .map(|spec| {
            let task = model.bind(spec).map_err(Failure::input)?;
            match task.episode_error() {
                Some(e) => Err(Failure::input(e)),
                None => Ok(task),
            }
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let np = kind.parameter_names().len();
    let tools = params
        .chunks_exact(np)
        .enumerate()
        .map(|(i, p)| {
            model.check_tool(p).map(|()| p).map_err(|e| {
                Failure::Input(match first_tool {
                    None => e.to_string(),
                    Some(first) => format!(
                        "tool {} ({}): {e}",
                        first + i,
                        crate::confidence::named(kind.parameter_names(), p)
                    ),
                })
            })
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let pairs = tools.len() * bound.len();
    Ok((0..pairs)
        .into_par_iter()
        .with_min_len(1)
        .map(|i| {
            let (tool, task) = (tools[i / bound.len()], &bound[i % bound.len()]);
            task.simulate(tool).map_err(|e| e.to_string())
        })
        .collect())
}

/// The episodes of many tools, each under every perturbation: one row of metrics per
/// (tool, perturbation), tool by tool.
///
/// Every episode is ``toolconf.simulate``'s, with the same numbers: this equals a loop of
/// ``simulate(model, params[i], task, method, **episode_options, perturbation=p)`` over the tools
/// and, for each, over ``perturbations``, except that a failed episode does not stop the batch:
/// its row carries the error (the message ``simulate`` raises) and NaN metrics. Episodes run on
/// rayon's threads without the GIL; results do not depend on the number of threads.
///
/// Args:
///     model: a generated model's name (``toolconf.models()``).
///     params: a 2-D array, one tool per row, in the model's parameter order (a 1-D array is one
///         tool).
///     task: a built-in task name, a task file's path, or a dict with a task file's keys.
///     perturbations: the constant torques ΔT (N m) to run every tool under, each one number
///         (every joint) or one per joint; e.g. ``[-0.8, 0.0, 0.8]`` or a 2-D array. ``None``
///         runs each tool once under the task's own ``perturbation``.
///     method: the integrator, as in ``simulate``.
///     first_tool: the index of ``params``' first row in a larger array, for the ``tool``
///         column and errors (``toolconf.dask.simulate_batch`` sends chunks); 0 by default.
///     **episode_options: ``simulate``'s (the keys of a task file's ``[episode]`` table), for
///         every episode; ``perturbation`` only when ``perturbations`` is not given.
///
/// Returns:
///     dict of arrays, one entry per (tool, perturbation), tool-major (row ``i * P + j`` is
///     tool ``i`` under perturbation ``j``): ``tool`` and ``perturbation`` (the 0-based indices),
///     ``task_error``, ``free_energy``, ``cost_j``, ``logdet``, ``control_effort`` (NaN for a
///     failed episode), ``rhs_evals``, ``steps``, ``rejected_steps``, ``jacobian_evals``,
///     ``factorisations`` (-1 for one) and ``error`` (a list: None, or why the episode failed).
///
/// Raises:
///     ValueError: bad input (model, parameters, task, perturbation or episode option), naming
///         the tool's row or the key, before any episode runs.
#[pyfunction]
#[pyo3(signature = (model, params, task, perturbations=None, method="fast", first_tool=0, **episode_options))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_batch<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    task: &Bound<'py, PyAny>,
    perturbations: Option<&Bound<'py, PyAny>>,
    method: &str,
    first_tool: usize,
    episode_options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let np = kind.parameter_names().len();
    let (shape, values) = crate::arrays::float_argument("params", params)?;
    if !matches!(shape.as_slice(), [n] | [_, n] if *n == np) {
        return Err(Failure::Input(format!(
            "params of shape {shape:?}: model {kind} takes {np} parameters ({}), as a 2-D array \
             with one tool per row (or a 1-D array for one tool)",
            kind.parameter_names().join(",")
        ))
        .into_pyerr(py));
    }
    let method = crate::task::method(method).map_err(|f| f.into_pyerr(py))?;
    let mut specs = Vec::new();
    for options in episode_tables(py, perturbations, episode_options)? {
        let mut spec = task_spec(task, Some(&options))?;
        spec.episode.method = Some(method);
        specs.push(spec);
    }
    let first = (shape.len() == 2).then_some(first_tool);
    let rows = detached(py, || batch(kind, &specs, &values, first))?;
    to_dict(py, rows, specs.len(), first_tool)
}

/// The episode options of each perturbation: `options` with `perturbation` set, or `options`
/// alone when there are no perturbations.
fn episode_tables<'py>(
    py: Python<'py>,
    perturbations: Option<&Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let base = match options {
        Some(o) => o.copy()?,
        None => PyDict::new(py),
    };
    let Some(perturbations) = perturbations.filter(|p| !p.is_none()) else {
        return Ok(vec![base]);
    };
    if base.contains("perturbation")? {
        return Err(Failure::Input(
            "perturbation and perturbations: give the perturbations to run (a list) or one \
             perturbation for all, not both"
                .into(),
        )
        .into_pyerr(py));
    }
    // A NumPy array as its Python list; a str is a sequence, but not of torques.
    let plain = perturbations
        .call_method0("tolist")
        .unwrap_or_else(|_| perturbations.clone());
    let items: Vec<Bound<'py, PyAny>> = plain
        .extract()
        .ok()
        .filter(|_| !plain.is_instance_of::<pyo3::types::PyString>())
        .ok_or_else(|| {
            Failure::Input(format!(
                "perturbations = {}: expected a list of torques (each one number or one per joint)",
                crate::tools::short_repr(perturbations)
            ))
            .into_pyerr(py)
        })?;
    if items.is_empty() {
        return Err(Failure::Input(
            "perturbations = []: give at least one perturbation (or None for the task's own)"
                .into(),
        )
        .into_pyerr(py));
    }
    items
        .into_iter()
        .map(|p| {
            let o = base.copy()?;
            o.set_item("perturbation", p)?;
            Ok(o)
        })
        .collect()
}

fn to_dict(
    py: Python<'_>,
    rows: Vec<Result<Metrics, String>>,
    perturbations: usize,
    first_tool: usize,
) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    let p = perturbations;
    let tool: Vec<i64> = (0..rows.len())
        .map(|i| (first_tool + i / p) as i64)
        .collect();
    let perturbation: Vec<i64> = (0..rows.len()).map(|i| (i % p) as i64).collect();
    out.set_item("tool", PyArray1::from_vec(py, tool))?;
    out.set_item("perturbation", PyArray1::from_vec(py, perturbation))?;
    let floats = |f: fn(&Metrics) -> f64| {
        PyArray1::from_vec(
            py,
            rows.iter()
                .map(|r| r.as_ref().map_or(f64::NAN, f))
                .collect(),
        )
    };
    for (key, f) in [
        (
            "task_error",
            (|m: &Metrics| m.task_error) as fn(&Metrics) -> f64,
        ),
        ("free_energy", |m| m.free_energy),
        ("cost_j", |m| m.cost_j),
        ("logdet", |m| m.logdet),
        ("control_effort", |m| m.control_effort),
    ] {
        out.set_item(key, floats(f))?;
    }
    let counts = |f: fn(&Metrics) -> usize| {
        PyArray1::from_vec(
            py,
            rows.iter()
                .map(|r| r.as_ref().map_or(-1, |m| f(m) as i64))
                .collect(),
        )
    };
    for (key, f) in [
        (
            "rhs_evals",
            (|m: &Metrics| m.rhs_evals) as fn(&Metrics) -> usize,
        ),
        ("steps", |m| m.steps),
        ("rejected_steps", |m| m.rejected_steps),
        ("jacobian_evals", |m| m.jacobian_evals),
        ("factorisations", |m| m.factorisations),
    ] {
        out.set_item(key, counts(f))?;
    }
    let errors: Vec<Option<&str>> = rows
        .iter()
        .map(|r| r.as_ref().err().map(String::as_str))
        .collect();
    out.set_item("error", errors)?;
    Ok(out)
}
