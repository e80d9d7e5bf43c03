//! `toolconf.design`: which tool to build, as `toolconf design --json` answers it.

use std::path::PathBuf;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;
use toolconf::design::json::design_json;
use toolconf::design::sweep::{parse_sweep, run_sweep};
use toolconf::design::{design as run_design, DesignError, Setting};
use toolconf::rank::ModelTasks;
use toolconf_model::inputs::design_file::DesignSpec;

use crate::models::model_kind;
use crate::task::{table, task_spec};

/// How a design dict names itself in errors (`design dict, key bounds.m1: …`).
const DESIGN_DICT: &str = "design dict";

/// The tool to build for a task: the parameters that maximise the control confidence ln|Π^U|
/// within the design's bounds and linear constraints, verified against random feasible tools,
/// as ``toolconf design --json`` computes and prints it.
///
/// A feasible-point SQP climbs the derived gradient ∂ln|Π^U|/∂p from the feasible set's
/// centre and seeded random starts (with ``objective = "free_energy"`` a compass search on the
/// simulated ∫F dt follows); then the design and the most confident of ``[search] samples``
/// random feasible tools are simulated with and without the perturbation ΔT.
///
/// Args:
///     model: a generated model's name (``toolconf.models()``).
///     task: a built-in task name, a task file's path, or a dict with a task file's keys.
///     design: a design file's path (TOML), or a dict with its keys: ``objective``
///         (``"confidence"`` or ``"free_energy"``), ``constraints`` (a list of linear
///         constraints such as ``"l1 + l2 >= 0.7"``), ``bounds`` (``{"m1": [0.1, 0.6], ...}``
///         for every parameter not fixed), ``fixed`` and ``search`` (``seed``, ``starts``,
///         ``samples``, ``simulate``, ``perturbation``).
///     sweep: ``"LEFT <= A..B:K"`` (the command line's ``--sweep``): also re-solve with K right
///         sides for that left side, giving the best confidence against the budget.
///
/// Returns:
///     dict: ``toolconf design --json``'s object, key for key and number for number:
///     ``objective``, ``params`` (by name), ``logdet``, ``confidence_optimum``, ``gradient``,
///     ``gradient_check``, ``kkt_residual``, ``iterations``, ``start``,
///     ``free_energy_simulations``, ``perturbation``, ``random`` (``requested``, ``feasible``,
///     ``drawn``, ``best_logdet``), ``verification`` (one dict per simulated tool: ``tool``,
///     ``params``, ``logdet``, ``task_error``, ``free_energy``, ``task_error_perturbed``,
///     ``sensitivity``, or ``error``), ``model``, ``task`` and, with ``sweep``, ``sweep``.
///
/// Raises:
///     ValueError: bad input (model, task, design file or dict naming the key, sweep) or
///         constraints no tool satisfies, with the command line's message.
///     RuntimeError: the design could not be computed (the command line's status 1).
#[pyfunction]
#[pyo3(signature = (model, task, design, sweep=None))]
pub fn design<'py>(
    py: Python<'py>,
    model: &str,
    task: &Bound<'py, PyAny>,
    design: &Bound<'py, PyAny>,
    sweep: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = model_kind(model).map_err(|f| f.into_pyerr(py))?;
    let spec = task_spec(task, None)?;
    let tasks = ModelTasks::new(&spec);
    tasks
        .check(kind)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let names: Vec<&'static str> = kind.parameter_names().to_vec();
    let design_spec = if let Ok(dict) = design.cast::<PyDict>() {
        let t = table(dict, "", DESIGN_DICT).map_err(|f| f.into_pyerr(py))?;
        DesignSpec::from_table(t, DESIGN_DICT, kind)
    } else if let Ok(path) = design.extract::<PathBuf>() {
        DesignSpec::from_file(&path, kind)
    } else {
        return Err(PyValueError::new_err(format!(
            "design = {}: expected a design file's path or a dict with a design file's keys",
            crate::tools::short_repr(design)
        )));
    }
    .map_err(|e| raise(e.into()))?;
    let sweep = sweep
        .map(|s| parse_sweep(s, &names))
        .transpose()
        .map_err(PyValueError::new_err)?;
    let label = task_label(task, &spec.file);
    let value = py
        .detach(|| {
            let setting = Setting {
                model: kind,
                task: &spec,
                tasks: &tasks,
            };
            let result = run_design(&design_spec, &setting)?;
            result
                .check_finite(&names)
                .map_err(|e| DesignError::Failed(e.to_string()))?;
            let front = match &sweep {
                Some(s) => Some(run_sweep(&design_spec, &setting, s)?),
                None => None,
            };
            Ok(design_json(
                &design_spec,
                &result,
                kind,
                &label,
                front.as_deref(),
            ))
        })
        .map_err(raise)?;
    to_py(py, &value)
}

fn raise(e: DesignError) -> PyErr {
    match e {
        DesignError::Input(m) | DesignError::Infeasible(m) => PyValueError::new_err(m),
        DesignError::Failed(m) => PyRuntimeError::new_err(m),
    }
}

/// The task as the command line's `--task` names it in the JSON: the name or path given, or
/// the dict's source.
fn task_label(task: &Bound<'_, PyAny>, file: &str) -> String {
    if task.cast::<PyDict>().is_ok() {
        return file.to_string();
    }
    match task.extract::<PathBuf>() {
        Ok(path) => path.display().to_string(),
        Err(_) => file.to_string(),
    }
}

/// A JSON value as Python's `json.loads` makes it: objects as dicts (in order), integers as
/// int, other numbers as float.
pub fn to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}
