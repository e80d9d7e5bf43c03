//! `toolconf.rank`: `toolconf rank` as a dict of columns.

use std::path::{Path, PathBuf};

use numpy::PyArray1;
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::model::mixed::ModelKind;
use toolconf::rank::{ranking, screen_file, simulate_all, ModelTasks, RankedTool};
use toolconf::select::Objective;
use toolconf::task_file::TaskSpec;

use crate::errors::{detached, Failure};
use crate::task::task_spec;

/// The ranked tools (best first) and the bad rows skipped.
struct Ranked {
    results: Vec<RankedTool>,
    order: Vec<usize>,
    skipped: Vec<String>,
}

fn objective(name: &str) -> Result<Objective, Failure> {
    match name.replace('_', "-").as_str() {
        "free-energy" => Ok(Objective::FreeEnergy),
        "cost-j" => Ok(Objective::CostJ),
        "confidence" => Ok(Objective::Confidence),
        _ => Err(Failure::Input(format!(
            "objective '{name}': expected free-energy (the paper's ∫F dt), cost-j (∫J dt) or \
             confidence (ln|Π^U|)"
        ))),
    }
}

fn run(
    tools: &Path,
    spec: &TaskSpec,
    screen: Option<usize>,
    objective: Objective,
    skip_bad_rows: bool,
) -> Result<Ranked, Failure> {
    let tasks = ModelTasks::new(spec);
    let mut skipped = Vec::new();
    let task = tasks.kind.to_string();
    let (kept, _) = screen_file(tools, &tasks, &task, screen, skip_bad_rows, |bad| {
        skipped.push(format!("toolconf: skipping {bad}"))
    })
    .map_err(Failure::input)?;
    let results = simulate_all(kept.finish(), &tasks, |_| Ok::<(), Failure>(()))?;
    let order = ranking(&results, objective);
    Ok(Ranked {
        results,
        order,
        skipped,
    })
}

/// Ranks your tools on a task, as ``toolconf rank`` does, with the same numbers.
///
/// First every tool's control confidence ln|Π^U| in closed form (no simulation), streaming
/// through the file; then an episode for every tool, or with ``screen=K`` only for the K most
/// confident (ties: the earlier row); then the ranking by ``objective``. Episodes run on rayon's
/// threads without the GIL; results do not depend on the number of threads.
///
/// Args:
///     tools: a tools file's path: CSV (columns ``name``, ``model``, and the models' parameters
///         such as ``m1,m2,l1,l2``) or JSON (``.json``: an array of objects with those keys).
///     task: a built-in task name, a task file's path, or a dict with a task file's keys.
///     screen: simulate only the K most confident tools (K ≥ 1); ``None`` simulates all.
///     objective: ``"free-energy"`` (the paper's ∫F dt, the default), ``"cost-j"`` (∫J dt) or
///         ``"confidence"`` (ln|Π^U|).
///     skip_bad_rows: warn about a bad row (``UserWarning``) and go on without it, instead of
///         raising.
///     method: the integrator, as the command line's ``--method``: ``"fast"`` (the default),
///         ``"explicit"`` (exactly MATLAB ode45, the paper's numerics), ``"auto"`` or ``"stiff"``.
///
/// Returns:
///     dict of columns, best tool first (``pandas.DataFrame(toolconf.rank(...))``): ``rank``,
///     ``row`` (1-based in the file), ``name`` (str or None), ``model``, one column per
///     parameter of the models present (NaN for a tool whose model has no such parameter),
///     ``logdet``, ``task_error``, ``free_energy``, ``cost_j`` (NaN for a tool whose episode
///     failed), ``rhs_evals`` (-1 for those) and ``error`` (None, or why the episode failed:
///     such tools rank last, in file order). The numbers are ``toolconf rank --json``'s.
///
/// Raises:
///     ValueError: a bad tools file or row (naming the file, the line or tool and the value),
///         a bad task (naming the key), an unknown objective, or ``screen < 1``; the command
///         line's message.
#[pyfunction]
#[pyo3(signature = (tools, task, screen=None, objective="free-energy", skip_bad_rows=false, method="fast"))]
pub fn rank<'py>(
    py: Python<'py>,
    tools: PathBuf,
    task: &Bound<'py, PyAny>,
    screen: Option<i64>,
    objective: &str,
    skip_bad_rows: bool,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let objective = self::objective(objective).map_err(|f| f.into_pyerr(py))?;
    let screen = match screen {
        Some(k) if k < 1 => {
            return Err(Failure::Input(format!("screen = {k}: must be at least 1")).into_pyerr(py))
        }
        k => k.map(|k| k as usize),
    };
    let mut spec = task_spec(task, None)?;
    spec.episode.method = Some(crate::task::method(method).map_err(|f| f.into_pyerr(py))?);
    let ranked = detached(py, || run(&tools, &spec, screen, objective, skip_bad_rows))?;
    for warning in &ranked.skipped {
        let category = py.get_type::<PyUserWarning>();
        PyErr::warn(py, &category, &std::ffi::CString::new(warning.as_str())?, 1)?;
    }
    columns(py, &ranked)
}

/// The parameter columns of the models present, in the models' order (as the CLI's CSV).
fn parameter_columns(results: &[RankedTool]) -> Vec<&'static str> {
    let mut columns = Vec::new();
    for model in ModelKind::ALL {
        if results.iter().any(|r| r.row.tool.model() == model) {
            for p in model.parameter_names() {
                if !columns.contains(p) {
                    columns.push(*p);
                }
            }
        }
    }
    columns
}

fn columns<'py>(py: Python<'py>, ranked: &Ranked) -> PyResult<Bound<'py, PyDict>> {
    let tools: Vec<&RankedTool> = ranked.order.iter().map(|&i| &ranked.results[i]).collect();
    let out = PyDict::new(py);
    let ints = |f: &dyn Fn(usize, &RankedTool) -> i64| {
        PyArray1::from_vec(py, tools.iter().enumerate().map(|(k, r)| f(k, r)).collect())
    };
    let floats = |f: &dyn Fn(&RankedTool) -> Option<f64>| {
        PyArray1::from_vec(py, tools.iter().map(|r| f(r).unwrap_or(f64::NAN)).collect())
    };
    out.set_item("rank", ints(&|k, _| k as i64 + 1))?;
    out.set_item("row", ints(&|_, r| r.row.row as i64))?;
    out.set_item(
        "name",
        tools.iter().map(|r| r.row.name.clone()).collect::<Vec<_>>(),
    )?;
    out.set_item(
        "model",
        tools
            .iter()
            .map(|r| r.row.tool.model().name())
            .collect::<Vec<_>>(),
    )?;
    for p in parameter_columns(&ranked.results) {
        let value = |r: &RankedTool| {
            let params = r.row.tool.named_parameters();
            params.iter().find(|(n, _)| *n == p).map(|(_, v)| *v)
        };
        out.set_item(p, floats(&value))?;
    }
    out.set_item("logdet", floats(&|r| r.logdet.as_ref().ok().copied()))?;
    let metric = |f: fn(&toolconf::model::Metrics) -> f64| {
        floats(&move |r: &RankedTool| r.episode.as_ref().ok().map(f))
    };
    out.set_item("task_error", metric(|m| m.task_error))?;
    out.set_item("free_energy", metric(|m| m.free_energy))?;
    out.set_item("cost_j", metric(|m| m.cost_j))?;
    out.set_item(
        "rhs_evals",
        ints(&|_, r| r.episode.as_ref().map_or(-1, |m| m.rhs_evals as i64)),
    )?;
    let errors: Vec<Option<String>> = tools
        .iter()
        .map(|r| r.episode.as_ref().err().map(|e| e.to_string()))
        .collect();
    out.set_item("error", errors)?;
    Ok(out)
}
