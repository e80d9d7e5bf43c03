//! `toolconf.simulate_batch`: the episodes of many tools under many perturbations, one row of
//! metrics per (tool, perturbation).

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use toolconf_model::inputs::task_file::TaskSpec;
use toolconf_model::model::Metrics;
use toolconf_model::registry::ModelKind;

use crate::errors::{detached, Failure};
use crate::models::model_kind;
use crate::simulate::{COUNTS, MEASURES};
use crate::task::{portable_spec, task_spec};

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
    let k = params.len() / np;
    let what = format!(
        "simulate_batch of {k} tools × {} perturbations",
        bound.len()
    );
    let mut tools: Vec<&[f64]> = crate::arrays::with_capacity(k, &what)?;
    for (i, p) in params.chunks_exact(np).enumerate() {
        let tool = model.check_tool(p).map(|()| p).map_err(|e| {
            Failure::Input(match first_tool {
                None => e.to_string(),
                Some(first) => format!(
                    "tool {} ({}): {e}",
                    first + i,
                    crate::confidence::named(kind.parameter_names(), p)
                ),
            })
        })?;
        tools.push(tool);
    }
    let pairs = k.saturating_mul(bound.len());
    // Allocated before any episode runs: no hours of work lost to an allocation after them.
    let mut rows = crate::arrays::with_capacity(pairs, &what)?;
    (0..pairs)
        .into_par_iter()
        .with_min_len(1)
        .map(|i| {
            let (tool, task) = (tools[i / bound.len()], &bound[i % bound.len()]);
            task.simulate(tool).map_err(|e| e.to_string())
        })
        .collect_into_vec(&mut rows);
    Ok(rows)
}

/// `simulate_batch`'s entry points: one signature and one run, `$spec` reading the task.
macro_rules! simulate_batch_entry {
    ($(#[$attr:meta])* fn $name:ident, $spec:ident) => {
        #[pyfunction]
        $(#[$attr])*
        #[pyo3(signature = (model, params, task, perturbations=None, method="fast", first_tool=None, **episode_options))]
        #[allow(clippy::too_many_arguments)]
        pub fn $name<'py>(
            py: Python<'py>,
            model: &str,
            params: &Bound<'py, PyAny>,
            task: &Bound<'py, PyAny>,
            perturbations: Option<&Bound<'py, PyAny>>,
            method: &str,
            first_tool: Option<&Bound<'py, PyAny>>,
            episode_options: Option<&Bound<'py, PyDict>>,
        ) -> PyResult<Bound<'py, PyDict>> {
            let arguments = (model, params, task, perturbations, method, first_tool);
            run(py, arguments, episode_options, $spec)
        }
    };
}

simulate_batch_entry!(
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
    ///         column and errors (``toolconf.dask.simulate_batch`` sends chunks); 0 by default (or None),
    ///         an integer in [0, 2⁶³ − 1 − the number of tools] (``tool`` is int64).
    ///     **episode_options: ``simulate``'s (the keys of a task file's ``[episode]`` table), for
    ///         every episode; ``perturbation`` only when ``perturbations`` is not given.
    ///
    /// Returns:
    ///     dict of arrays, one entry per (tool, perturbation), tool-major (row ``i * P + j`` is
    ///     tool ``i`` under perturbation ``j``): ``tool`` and ``perturbation`` (the 0-based indices),
    ///     ``task_error``, ``free_energy``, ``cost_j``, ``logdet``, ``control_effort`` (NaN for a
    ///     failed episode), on a position task (joint or tip) ``progress`` (1 − e(T)/e(0), NaN
    ///     for a failed episode), ``rhs_evals``, ``steps``, ``rejected_steps``, ``jacobian_evals``,
    ///     ``factorisations`` (-1 for one) and ``error`` (a list: None, or why the episode failed).
    ///
    /// Raises:
    ///     ValueError: bad input (model, parameters, task, perturbation or episode option), naming
    ///         the tool's row or the key, before any episode runs.
    ///     TypeError: a ``params`` of booleans, complex numbers or text; a ``first_tool`` that is
    ///         not an integer.
    ///     MemoryError: rows for every (tool, perturbation) that do not fit in memory, before any
    ///         episode runs.
    fn simulate_batch,
    task_spec
);

simulate_batch_entry!(
    /// ``simulate_batch`` on a block of tools of ``toolconf.dask.simulate_batch``: the same, with
    /// the task as ``_portable_task`` sent it (a task file as its text).
    #[pyo3(name = "_simulate_batch")]
    fn simulate_batch_block,
    portable_spec
);

/// `simulate_batch`'s positional arguments: model, params, task, perturbations, method and
/// first_tool.
type Arguments<'a, 'py> = (
    &'a str,
    &'a Bound<'py, PyAny>,
    &'a Bound<'py, PyAny>,
    Option<&'a Bound<'py, PyAny>>,
    &'a str,
    Option<&'a Bound<'py, PyAny>>,
);

/// The checks in order (model, params, first_tool, method, task and perturbations), then the
/// episodes; `read_task` reads the task with one perturbation's episode options.
fn run<'py>(
    py: Python<'py>,
    (model, params, task, perturbations, method, first_tool): Arguments<'_, 'py>,
    episode_options: Option<&Bound<'py, PyDict>>,
    read_task: fn(&Bound<'py, PyAny>, Option<&Bound<'py, PyDict>>) -> PyResult<TaskSpec>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let np = kind.parameter_names().len();
    let (shape, values) = crate::arrays::tool_params(kind, params)?;
    if !matches!(shape.as_slice(), [n] | [_, n] if *n == np) {
        return Err(Failure::Input(format!(
            "params of shape {shape:?}: model {kind} takes {np} parameters ({}), as a 2-D array \
             with one tool per row (or a 1-D array for one tool)",
            kind.parameter_names().join(",")
        ))
        .into_pyerr(py));
    }
    // The `tool` column is int64: the last tool's index must fit.
    let last = i64::MAX as i128 - (values.len() / np) as i128;
    let first_tool = match first_tool.filter(|f| !f.is_none()) {
        Some(f) => crate::integers::integer("first_tool", f, 0, last)
            .map_err(|f| f.into_pyerr(py))? as usize,
        None => 0,
    };
    let method = crate::task::method(method).map_err(|f| f.into_pyerr(py))?;
    let mut specs = Vec::new();
    for options in episode_tables(py, perturbations, episode_options)? {
        let mut spec = read_task(task, Some(&options))?;
        spec.episode.method = Some(method);
        specs.push(spec);
    }
    let first = (shape.len() == 2).then_some(first_tool);
    let rows = detached(py, || batch(kind, &specs, &values, first))?;
    to_dict(py, rows, specs.len(), first_tool).map_err(|f| f.into_pyerr(py))
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
) -> Result<Bound<'_, PyDict>, Failure> {
    let what = format!("simulate_batch's {} rows", rows.len());
    let out = PyDict::new(py);
    let set = |key: &str, value: Bound<'_, PyAny>| {
        out.set_item(key, value)
            .map_err(|e| Failure::python("simulate_batch", e))
    };
    let p = perturbations;
    let ints = |f: &dyn Fn(usize, &Result<Metrics, String>) -> i64| {
        let column = crate::arrays::collect(rows.iter().enumerate().map(|(i, r)| f(i, r)), &what)?;
        Ok::<_, Failure>(PyArray1::from_vec(py, column).into_any())
    };
    set("tool", ints(&|i, _| (first_tool + i / p) as i64)?)?;
    set("perturbation", ints(&|i, _| (i % p) as i64)?)?;
    for (key, f) in MEASURES {
        let column = rows.iter().map(|r| r.as_ref().map_or(f64::NAN, f));
        let column = crate::arrays::collect(column, &what)?;
        set(key, PyArray1::from_vec(py, column).into_any())?;
    }
    // A position task's progress (NaN only for a failed episode); other tasks have no column.
    if rows
        .iter()
        .any(|r| r.as_ref().is_ok_and(|m| m.progress.is_some()))
    {
        let column = rows
            .iter()
            .map(|r| r.as_ref().ok().and_then(|m| m.progress).unwrap_or(f64::NAN));
        let column = crate::arrays::collect(column, &what)?;
        set("progress", PyArray1::from_vec(py, column).into_any())?;
    }
    for (key, f) in COUNTS {
        set(key, ints(&|_, r| r.as_ref().map_or(-1, |m| f(m) as i64))?)?;
    }
    let errors: Vec<Option<&str>> = crate::arrays::collect(
        rows.iter().map(|r| r.as_ref().err().map(String::as_str)),
        &what,
    )?;
    let errors = errors
        .into_pyobject(py)
        .map_err(|e| Failure::python("simulate_batch", e))?;
    set("error", errors.into_any())?;
    Ok(out)
}
