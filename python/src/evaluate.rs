//! `toolconf.reproduce`: the paper's evaluation on any model, task and population
//! (`toolconf::evaluation`, what `toolconf reproduce --model` runs), and the three steps
//! `toolconf.dask.reproduce` spreads over a cluster: the population on the client, the tools'
//! records in blocks on the workers, the rest on the client. Every step is the runtime's own
//! code, and records travel with their numbers as bits, so both give the same numbers.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use toolconf::evaluation::tables::{tables, Table};
use toolconf::evaluation::{
    check_population, evaluate, finish, parse_box, run_tools, Evaluation, Plan, Population, Setup,
    ToolRecord, MAX_TOOLS,
};
use toolconf_files::csv::Cell;
use toolconf_model::inputs::tools_file::{read_columns, read_tools, ToolRow};
use toolconf_model::registry::{AnyTool, ModelKind};

use crate::errors::{detached, Failure};
use crate::task::portable_spec;
use crate::tools::Tools;

fn model(name: &str) -> Result<ModelKind, Failure> {
    name.parse()
        .map_err(|e: String| Failure::Input(format!("model = {e}")))
}

/// The plan of `toolconf.reproduce`'s counts: JSON text the other steps read back.
///
/// Args:
///     quick: the reduced counts (for tests) instead of the paper's.
///     counts: the counts given (``highlight_sample``, ``sweep_tools``, ``sweep_levels``,
///         ``grid_trials``, ``grid_tools``, ``trials``, ``trial_tools``, ``resamples``), each
///         an integer; the others keep the paper's.
///
/// Returns:
///     str: the plan, as JSON.
///
/// Raises:
///     ValueError: an unknown count, or a count outside its range (naming it).
///     TypeError: a count that is not an integer.
#[pyfunction]
#[pyo3(name = "_reproduce_plan")]
pub fn reproduce_plan(quick: bool, counts: &Bound<'_, PyDict>) -> PyResult<String> {
    let py = counts.py();
    let mut plan = if quick { Plan::quick() } else { Plan::paper() };
    for (key, value) in counts.iter() {
        let name: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        let n = crate::integers::integer(&name, &value, 0, toolconf::evaluation::MAX_COUNT as i128)
            .map_err(|f| f.into_pyerr(py))? as usize;
        let slot = match name.as_str() {
            "highlight_sample" => &mut plan.highlight_sample,
            "sweep_tools" => &mut plan.sweep_tools,
            "sweep_levels" => &mut plan.sweep_levels,
            "grid_trials" => &mut plan.grid_trials,
            "grid_tools" => &mut plan.grid_tools,
            "trials" => &mut plan.trials,
            "trial_tools" => &mut plan.trial_tools,
            "resamples" => &mut plan.resamples,
            _ => {
                return Err(
                    Failure::Input(format!("{name}: not a count of the evaluation")).into_pyerr(py),
                )
            }
        };
        *slot = n;
    }
    plan.check().map_err(|(flag, message)| {
        let name = flag.trim_start_matches("--").replace('-', "_");
        Failure::Input(format!("{name} = {message}")).into_pyerr(py)
    })?;
    Ok(serde_json::to_string(&plan).expect("a plan is plain data"))
}

fn read_plan(plan: &str) -> Result<Plan, Failure> {
    serde_json::from_str(plan).map_err(|e| Failure::Input(format!("plan: {e}")))
}

/// Every row of `tools`, at most [`MAX_TOOLS`].
fn rows(tools: &Tools) -> Result<Vec<ToolRow>, Failure> {
    let mut rows = Vec::new();
    let mut each = |row: Result<ToolRow, toolconf_model::inputs::tools_file::ToolFileError>| {
        rows.push(row?);
        if rows.len() > MAX_TOOLS {
            return Err(toolconf_model::inputs::tools_file::ToolFileError {
                file: "tools".into(),
                place: String::new(),
                message: format!("more than {MAX_TOOLS} tools, the most one evaluation takes"),
                row_level: false,
            });
        }
        Ok(())
    };
    match tools {
        Tools::File(path) => read_tools(path, &mut each),
        Tools::Columns { source, columns } => read_columns(source, columns, 1, &mut each),
    }
    .map_err(Failure::input)?;
    Ok(rows)
}

/// The population: the tools' rows, or `sample` random tools.
fn population(
    model: ModelKind,
    tools: Option<&Bound<'_, PyAny>>,
    sample: Option<&Bound<'_, PyAny>>,
    seed: u64,
    sample_box: &[String],
    source: Option<&str>,
) -> Result<Population, Failure> {
    match (
        tools.filter(|t| !t.is_none()),
        sample.filter(|s| !s.is_none()),
    ) {
        (Some(_), Some(_)) => Err(Failure::Input("give tools= or sample=, not both".into())),
        (Some(t), None) => {
            if !sample_box.is_empty() {
                return Err(Failure::Input(
                    "box: a sampling box is for sample=, not tools=".into(),
                ));
            }
            let tools = Tools::from_py(t, source)?;
            let shown = match &tools {
                Tools::File(p) => toolconf_messages::ClipPath(&p.to_string_lossy()).to_string(),
                Tools::Columns { source, .. } => source.clone(),
            };
            let rows = rows(&tools)?;
            check_population(rows.len(), &format!("tools = {shown}")).map_err(Failure::Input)?;
            Population::from_rows(rows, model, &shown).map_err(Failure::Input)
        }
        (None, s) => {
            let n = match s {
                Some(s) => crate::integers::integer("sample", s, 0, i128::from(u64::MAX))? as u64,
                None => 300,
            };
            let n = usize::try_from(n).unwrap_or(usize::MAX);
            check_population(n, &format!("sample = {n}")).map_err(Failure::Input)?;
            let boxes = sample_box
                .iter()
                .map(|b| parse_box(b).map_err(|m| Failure::Input(m.replace("--box", "box"))))
                .collect::<Result<Vec<_>, _>>()?;
            Population::sample(model, n, seed, &boxes)
                .map_err(|m| Failure::Input(m.replace("--box", "box")))
        }
    }
}

/// The population as a dict that travels: `params` (tools × parameters), `names`, `rows`,
/// `source`, `box` (the sampling box, or None).
fn population_to_py<'py>(py: Python<'py>, p: &Population) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let params: Vec<Vec<f64>> = p.tools.iter().map(|t| t.parameters().to_vec()).collect();
    out.set_item("params", params)?;
    out.set_item("names", p.names.clone())?;
    out.set_item("rows", p.rows.clone())?;
    out.set_item("source", p.source.clone())?;
    out.set_item("box", p.sample_box.clone())?;
    Ok(out)
}

fn population_from_py(model: ModelKind, d: &Bound<'_, PyDict>) -> Result<Population, Failure> {
    let get = |key: &str| {
        d.get_item(key)
            .ok()
            .flatten()
            .ok_or_else(|| Failure::Input(format!("population: no '{key}'")))
    };
    fn bad(key: &'static str) -> impl Fn(PyErr) -> Failure {
        move |e| Failure::Input(format!("population, '{key}': {e}"))
    }
    let params: Vec<Vec<f64>> = get("params")?.extract().map_err(bad("params"))?;
    let tools = params
        .iter()
        .map(|p| AnyTool::new(model, p).map_err(Failure::input))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Population {
        tools,
        names: get("names")?.extract().map_err(bad("names"))?,
        rows: get("rows")?.extract().map_err(bad("rows"))?,
        source: get("source")?.extract().map_err(bad("source"))?,
        sample_box: get("box")?.extract().map_err(bad("box"))?,
    })
}

/// The population of an evaluation, as ``toolconf.dask.reproduce`` sends it: the tools' rows,
/// or ``sample`` random tools of ``model`` (``select``'s tools for the same seed).
///
/// Args:
///     model: the model's name.
///     tools: a tools file's path or columns in memory (as ``toolconf.rank`` takes), or None.
///     sample: how many random tools (1 … 10⁶; 300 when neither is given), or None.
///     seed: the sample's seed.
///     box: ``"NAME=LO:HI"`` texts replacing parameters' intervals of the sampling box.
///     source: what errors call columns in memory.
///
/// Returns:
///     dict: ``params`` (one list per tool), ``names``, ``rows``, ``source``, ``box``.
///
/// Raises:
///     ValueError: an unknown model, a bad tools file or row, a tool of another model, a
///         population of 0 or more than 10⁶, a box naming a parameter the model lacks.
#[pyfunction]
#[pyo3(name = "_reproduce_population", signature = (model, tools=None, sample=None, seed=None, r#box=Vec::new(), source=None))]
pub fn reproduce_population<'py>(
    py: Python<'py>,
    model: &str,
    tools: Option<&Bound<'py, PyAny>>,
    sample: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    r#box: Vec<String>,
    source: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = self::model(model).map_err(|f| f.into_pyerr(py))?;
    let seed = seed
        .map_or(Ok(0), crate::integers::seed)
        .map_err(|f| f.into_pyerr(py))?;
    let p = population(kind, tools, sample, seed, &r#box, source).map_err(|f| f.into_pyerr(py))?;
    population_to_py(py, &p)
}

/// The setup of `task` for `model` with `plan` and `method`.
fn setup(kind: ModelKind, task: &Bound<'_, PyAny>, plan: &Plan, method: &str) -> PyResult<Setup> {
    let py = task.py();
    let mut spec = portable_spec(task, None)?;
    spec.episode.method = Some(crate::task::method(method).map_err(|f| f.into_pyerr(py))?);
    Setup::new(kind, &spec, plan).map_err(|e| Failure::input(e).into_pyerr(py))
}

/// The records of a block of the population's tools (``toolconf.dask.reproduce``'s workers):
/// each tool's confidence and episodes, as text whose numbers are their bits.
///
/// Args:
///     model, task, plan, method: as for ``_reproduce_finish``.
///     params: the block's tools, one list of parameters per tool.
///     first: the block's first tool's place in the population.
///
/// Returns:
///     list of str: one record per tool, in order.
///
/// Raises:
///     ValueError: as ``toolconf.reproduce``.
#[pyfunction]
#[pyo3(name = "_reproduce_block")]
pub fn reproduce_block(
    py: Python<'_>,
    model: &str,
    task: &Bound<'_, PyAny>,
    params: Vec<Vec<f64>>,
    first: usize,
    plan: &str,
    method: &str,
) -> PyResult<Vec<String>> {
    let kind = self::model(model).map_err(|f| f.into_pyerr(py))?;
    let plan = read_plan(plan).map_err(|f| f.into_pyerr(py))?;
    let setup = setup(kind, task, &plan, method)?;
    let tools = params
        .iter()
        .map(|p| AnyTool::new(kind, p).map_err(Failure::input))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|f| f.into_pyerr(py))?;
    detached(py, || {
        let records = run_tools(&setup, &tools, first, plan.sweep_tools, &|_| {});
        Ok(records.iter().map(ToolRecord::to_wire).collect())
    })
}

/// The evaluation from its population and every tool's record (``_reproduce_block``'s, in
/// order): Fig. 3's runs, the trials, the statistics and the verdicts, as tables.
///
/// Args:
///     model: the model's name.
///     task: a task as ``toolconf.reproduce`` takes it (or a task file sent as text).
///     population: ``_reproduce_population``'s dict.
///     records: every tool's record, in the population's order.
///     seed: the evaluation's seed.
///     plan: ``_reproduce_plan``'s text.
///     method: the integrator (``"fast"``, ``"explicit"``, ``"auto"``, ``"stiff"``).
///
/// Returns:
///     dict: ``tables`` (name → dict of columns) and ``summary`` (JSON text).
///
/// Raises:
///     ValueError: a bad argument; RuntimeError: every tool's episode failed.
#[pyfunction]
#[pyo3(name = "_reproduce_finish")]
#[allow(clippy::too_many_arguments)]
pub fn reproduce_finish<'py>(
    py: Python<'py>,
    model: &str,
    task: &Bound<'py, PyAny>,
    population: &Bound<'py, PyDict>,
    records: Vec<String>,
    seed: &Bound<'py, PyAny>,
    plan: &str,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = self::model(model).map_err(|f| f.into_pyerr(py))?;
    let seed = crate::integers::seed(seed).map_err(|f| f.into_pyerr(py))?;
    let plan = read_plan(plan).map_err(|f| f.into_pyerr(py))?;
    let setup = setup(kind, task, &plan, method)?;
    let population = population_from_py(kind, population).map_err(|f| f.into_pyerr(py))?;
    let records = records
        .iter()
        .map(|r| ToolRecord::from_wire(r).map_err(Failure::Input))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|f| f.into_pyerr(py))?;
    let e = detached(py, || {
        finish(setup, population, records, &plan, seed, &|_| {}).map_err(evaluation_failure)
    })?;
    evaluation_to_py(py, &e)
}

fn evaluation_failure(e: toolconf::evaluation::EvaluationError) -> Failure {
    match e {
        toolconf::evaluation::EvaluationError::Input(m) => Failure::Input(m),
        toolconf::evaluation::EvaluationError::Failed(m) => Failure::Run(m),
    }
}

/// The paper's evaluation of ``model`` on ``task`` over a population in one call: what
/// ``toolconf.reproduce`` runs (``_reproduce_population``, then ``_reproduce_block`` of every
/// tool, then ``_reproduce_finish``, without the records leaving Rust).
///
/// Args:
///     model, task, tools, sample, seed, box, source: as ``_reproduce_population`` and
///         ``_reproduce_finish``.
///     plan: ``_reproduce_plan``'s text.
///     method: the integrator.
///
/// Returns:
///     dict: ``tables`` (name → dict of columns) and ``summary`` (JSON text).
///
/// Raises:
///     ValueError: bad input, as ``toolconf reproduce --model`` refuses it; RuntimeError:
///         every tool's episode failed.
#[pyfunction]
#[pyo3(name = "_reproduce", signature = (model, task, tools, sample, seed, r#box, plan, method, source=None))]
#[allow(clippy::too_many_arguments)]
pub fn reproduce<'py>(
    py: Python<'py>,
    model: &str,
    task: &Bound<'py, PyAny>,
    tools: Option<&Bound<'py, PyAny>>,
    sample: Option<&Bound<'py, PyAny>>,
    seed: &Bound<'py, PyAny>,
    r#box: Vec<String>,
    plan: &str,
    method: &str,
    source: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let kind = self::model(model).map_err(|f| f.into_pyerr(py))?;
    let seed = crate::integers::seed(seed).map_err(|f| f.into_pyerr(py))?;
    let plan = read_plan(plan).map_err(|f| f.into_pyerr(py))?;
    let setup = setup(kind, task, &plan, method)?;
    let p = population(kind, tools, sample, seed, &r#box, source).map_err(|f| f.into_pyerr(py))?;
    let e = detached(py, || {
        evaluate(setup, p, &plan, seed, &|_| {}).map_err(evaluation_failure)
    })?;
    evaluation_to_py(py, &e)
}

/// `tables` (name → columns) and `summary` (JSON text).
fn evaluation_to_py<'py>(py: Python<'py>, e: &Evaluation) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let all = PyDict::new(py);
    for table in tables(e) {
        all.set_item(table.name, table_to_py(py, &table)?)?;
    }
    out.set_item("tables", all)?;
    out.set_item("summary", e.summary_json().to_string())?;
    Ok(out)
}

/// A table as columns: text columns as lists (None for empty cells), integer columns as int64
/// arrays, the others as float64 arrays (NaN for empty cells).
fn table_to_py<'py>(py: Python<'py>, t: &Table) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for (j, name) in t.header.iter().enumerate() {
        let cells: Vec<&Cell> = t.rows.iter().map(|r| &r[j]).collect();
        let text = cells.iter().any(|c| matches!(c, Cell::Text(_)));
        let integers = !cells.is_empty() && cells.iter().all(|c| matches!(c, Cell::Int(_)));
        if text {
            let values: Vec<Option<String>> = cells
                .iter()
                .map(|c| match c {
                    Cell::Text(s) if s.is_empty() => None,
                    Cell::Text(s) => Some(s.clone()),
                    Cell::Int(i) => Some(i.to_string()),
                    Cell::Num(x) => Some(x.to_string()),
                    Cell::Empty => None,
                })
                .collect();
            out.set_item(name, PyList::new(py, values)?)?;
        } else if integers {
            let values: Vec<i64> = cells
                .iter()
                .map(|c| if let Cell::Int(i) = c { *i } else { 0 })
                .collect();
            out.set_item(name, PyArray1::from_vec(py, values))?;
        } else {
            let values: Vec<f64> = cells
                .iter()
                .map(|c| match c {
                    Cell::Num(x) => *x,
                    Cell::Int(i) => *i as f64,
                    _ => f64::NAN,
                })
                .collect();
            out.set_item(name, PyArray1::from_vec(py, values))?;
        }
    }
    Ok(out)
}
