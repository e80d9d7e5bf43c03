//! Tools as Python tables (dicts of columns): what `toolconf.rank` returns, and the blocks of
//! tools that travel between the client and Dask's workers (`toolconf.dask`). One writer and
//! one reader per kind of row, so a block read back is the rows written, bit for bit.
//!
//! Columns, each one entry per tool: `row` (1-based in the whole input), `name` (str or None),
//! `model`, one column per parameter of the models present (NaN where a tool's model has no
//! such parameter), `logdet` (ln|Π^U|, NaN without one); ranked tools add `task_error`,
//! `free_energy`, `cost_j` (NaN for a failed episode), `rhs_evals` (-1 for one) and `error`.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::rank::{objective_value, order_by_score, Candidate, ModelTasks, RankedTool};
use toolconf::select::Objective;
use toolconf_model::inputs::tools_file::ToolRow;
use toolconf_model::model::Metrics;
use toolconf_model::registry::{AnyTool, ModelKind};

use crate::errors::Failure;

/// A simulated tool as the table holds it: the metrics the table shows, and the objective's
/// score (what ranks it), or the episode's error.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub tool: ToolRow,
    pub logdet: Option<f64>,
    pub episode: Result<Shown, String>,
}

/// The metrics a ranked table shows.
#[derive(Debug, Clone, Copy)]
pub struct Shown {
    pub task_error: f64,
    pub free_energy: f64,
    pub cost_j: f64,
    pub rhs_evals: i64,
    /// 1 − e(T)/e(0) on a position task (joint or tip), `None` on the others.
    pub progress: Option<f64>,
    /// What the objective minimises ([`objective_value`]).
    pub score: f64,
}

impl Outcome {
    pub fn new(r: RankedTool, objective: Objective) -> Self {
        let shown = |m: Metrics| Shown {
            task_error: m.task_error,
            free_energy: m.free_energy,
            cost_j: m.cost_j,
            rhs_evals: m.rhs_evals as i64,
            progress: m.progress,
            score: objective_value(objective, &m),
        };
        Outcome {
            tool: r.row,
            logdet: r.logdet.ok(),
            episode: r.episode.map(shown).map_err(|e| e.to_string()),
        }
    }
}

/// The parameter columns of the models present, in the models' order (as the CLI's CSV).
fn parameter_columns<'a>(tools: impl Iterator<Item = &'a ToolRow> + Clone) -> Vec<&'static str> {
    let mut columns = Vec::new();
    for model in ModelKind::all() {
        if tools.clone().any(|t| t.tool.model() == model) {
            for p in model.parameter_names() {
                if !columns.contains(p) {
                    columns.push(*p);
                }
            }
        }
    }
    columns
}

fn floats<'py, T>(
    py: Python<'py>,
    items: &[&T],
    f: impl Fn(&T) -> Option<f64>,
) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, items.iter().map(|t| f(t).unwrap_or(f64::NAN)).collect())
}

/// `row`, `name`, `model` and the parameter columns of `tools` into `out`.
fn put_tools(out: &Bound<'_, PyDict>, tools: &[&ToolRow]) -> PyResult<()> {
    let py = out.py();
    let rows: Vec<i64> = tools.iter().map(|t| t.row as i64).collect();
    out.set_item("row", PyArray1::from_vec(py, rows))?;
    let names: Vec<Option<&str>> = tools.iter().map(|t| t.name.as_deref()).collect();
    out.set_item("name", names)?;
    let models: Vec<&str> = tools.iter().map(|t| t.tool.model().name()).collect();
    out.set_item("model", models)?;
    for p in parameter_columns(tools.iter().copied()) {
        let value = |t: &ToolRow| {
            let params = t.tool.named_parameters();
            params.iter().find(|(n, _)| *n == p).map(|(_, v)| *v)
        };
        out.set_item(p, floats(py, tools, value))?;
    }
    Ok(())
}

/// Candidates (after the screen) as a block: the tool columns and `logdet`.
pub fn candidates_to_py<'py>(py: Python<'py>, kept: &[Candidate]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let tools: Vec<&ToolRow> = kept.iter().map(|c| &c.row).collect();
    put_tools(&out, &tools)?;
    out.set_item(
        "logdet",
        floats(py, &kept.iter().collect::<Vec<_>>(), |c| {
            c.logdet.as_ref().ok().copied()
        }),
    )?;
    Ok(out)
}

/// `outcomes` in `order`: the ranked table (with `rank`) or a block (with `score`).
fn outcomes_to_py<'py>(
    py: Python<'py>,
    outcomes: &[Outcome],
    order: &[usize],
    ranked: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let items: Vec<&Outcome> = order.iter().map(|&i| &outcomes[i]).collect();
    let out = PyDict::new(py);
    if ranked {
        let ranks: Vec<i64> = (1..=items.len() as i64).collect();
        out.set_item("rank", PyArray1::from_vec(py, ranks))?;
    }
    put_tools(&out, &items.iter().map(|o| &o.tool).collect::<Vec<_>>())?;
    out.set_item("logdet", floats(py, &items, |o| o.logdet))?;
    let shown = |f: fn(&Shown) -> f64| floats(py, &items, move |o| o.episode.as_ref().ok().map(f));
    out.set_item("task_error", shown(|s| s.task_error))?;
    out.set_item("free_energy", shown(|s| s.free_energy))?;
    out.set_item("cost_j", shown(|s| s.cost_j))?;
    // A position task's column (NaN only for a failed episode); other tasks have none, rather
    // than a column of NaN. A block, the workers' own exchange, always carries it.
    let progress = items
        .iter()
        .any(|o| o.episode.as_ref().is_ok_and(|s| s.progress.is_some()));
    if progress || !ranked {
        let value = |o: &Outcome| o.episode.as_ref().ok().and_then(|s| s.progress);
        out.set_item("progress", floats(py, &items, value))?;
    }
    let evals: Vec<i64> = items
        .iter()
        .map(|o| o.episode.as_ref().map_or(-1, |s| s.rhs_evals))
        .collect();
    out.set_item("rhs_evals", PyArray1::from_vec(py, evals))?;
    let errors: Vec<Option<&str>> = items
        .iter()
        .map(|o| o.episode.as_ref().err().map(String::as_str))
        .collect();
    out.set_item("error", errors)?;
    if !ranked {
        out.set_item("score", shown(|s| s.score))?;
    }
    Ok(out)
}

/// The ranked table: best first by the objective's score, ties by row, failed episodes last
/// in row order (the library's [`order_by_score`], as `toolconf rank` orders).
pub fn ranked_to_py<'py>(py: Python<'py>, outcomes: &[Outcome]) -> PyResult<Bound<'py, PyDict>> {
    let scored: Vec<(Option<f64>, usize)> = outcomes
        .iter()
        .map(|o| (o.episode.as_ref().ok().map(|s| s.score), o.tool.row))
        .collect();
    outcomes_to_py(py, outcomes, &order_by_score(&scored), true)
}

/// Simulated tools as a block, in their order.
pub fn block_to_py<'py>(py: Python<'py>, outcomes: &[Outcome]) -> PyResult<Bound<'py, PyDict>> {
    let order: Vec<usize> = (0..outcomes.len()).collect();
    outcomes_to_py(py, outcomes, &order, false)
}

/// A block's column, or the error naming it.
fn column<'py, T: FromPyObjectOwned<'py>>(
    block: &Bound<'py, PyDict>,
    key: &str,
) -> Result<T, Failure> {
    let value = block
        .get_item(key)
        .ok()
        .flatten()
        .ok_or_else(|| Failure::Input(format!("tools block: no column '{key}'")))?;
    value.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        Failure::Input(format!("tools block, column '{key}': {e}"))
    })
}

fn float_column(block: &Bound<'_, PyDict>, key: &str) -> Result<Vec<f64>, Failure> {
    numeric_column(block, key, "float64")
}

fn numeric_column<T: numpy::Element + Copy>(
    block: &Bound<'_, PyDict>,
    key: &str,
    dtype: &str,
) -> Result<Vec<T>, Failure> {
    let value: Bound<'_, PyAny> = column(block, key)?;
    let (shape, values) = crate::arrays::values(&value, dtype)
        .map_err(|e| Failure::python(&format!("tools block, column '{key}'"), e))?;
    if shape.len() != 1 {
        return Err(Failure::Input(format!(
            "tools block, column '{key}': not 1-D"
        )));
    }
    Ok(values)
}

/// The tools of a block written by [`put_tools`] (their parameters checked again).
fn tools_from_py(block: &Bound<'_, PyDict>) -> Result<Vec<ToolRow>, Failure> {
    let rows: Vec<i64> = numeric_column(block, "row", "int64")?;
    let names: Vec<Option<String>> = column(block, "name")?;
    let models: Vec<String> = column(block, "model")?;
    if names.len() != rows.len() || models.len() != rows.len() {
        return Err(Failure::Input(
            "tools block: columns of different lengths".into(),
        ));
    }
    let mut params: Vec<(&'static str, Vec<f64>)> = Vec::new();
    let mut tools = Vec::with_capacity(rows.len());
    for (i, ((row, name), model)) in rows.into_iter().zip(names).zip(models).enumerate() {
        let model: ModelKind = model.parse().map_err(Failure::Input)?;
        let mut values = Vec::with_capacity(model.parameter_names().len());
        for &p in model.parameter_names() {
            if !params.iter().any(|(n, _)| *n == p) {
                params.push((p, float_column(block, p)?));
            }
            let column = &params.iter().find(|(n, _)| *n == p).expect("just read").1;
            values.push(*column.get(i).ok_or_else(|| {
                Failure::Input(format!("tools block: column '{p}' is too short"))
            })?);
        }
        let tool = AnyTool::new(model, &values).map_err(Failure::input)?;
        let row = usize::try_from(row)
            .map_err(|_| Failure::Input(format!("tools block: row {row} is not a row number")))?;
        // A block carries every parameter column (float_column refuses a missing one).
        tools.push(ToolRow {
            row,
            name,
            tool,
            defaulted: Vec::new(),
        });
    }
    Ok(tools)
}

/// The candidates of a block written by [`candidates_to_py`]: a tool without a confidence
/// (NaN) gets its error again from `tasks`, the same function of the tool and the task.
pub fn candidates_from_py(
    block: &Bound<'_, PyDict>,
    tasks: &ModelTasks,
) -> Result<Vec<Candidate>, Failure> {
    let tools = tools_from_py(block)?;
    let logdets = float_column(block, "logdet")?;
    Ok(tools
        .into_iter()
        .zip(logdets)
        .map(|(row, l)| {
            let logdet = if l.is_nan() {
                tasks.logdet(&row.tool)
            } else {
                Ok(l)
            };
            Candidate {
                row,
                logdet,
                prediction: None,
            }
        })
        .collect())
}

/// The outcomes of a block written by [`block_to_py`].
pub fn outcomes_from_py(block: &Bound<'_, PyDict>) -> Result<Vec<Outcome>, Failure> {
    let tools = tools_from_py(block)?;
    let logdet = float_column(block, "logdet")?;
    let task_error = float_column(block, "task_error")?;
    let free_energy = float_column(block, "free_energy")?;
    let cost_j = float_column(block, "cost_j")?;
    let progress = float_column(block, "progress")?;
    let score = float_column(block, "score")?;
    let evals: Vec<i64> = numeric_column(block, "rhs_evals", "int64")?;
    let errors: Vec<Option<String>> = column(block, "error")?;
    let n = tools.len();
    if [
        logdet.len(),
        task_error.len(),
        free_energy.len(),
        cost_j.len(),
        progress.len(),
        score.len(),
        evals.len(),
        errors.len(),
    ]
    .iter()
    .any(|&l| l != n)
    {
        return Err(Failure::Input(
            "tools block: columns of different lengths".into(),
        ));
    }
    Ok(tools
        .into_iter()
        .enumerate()
        .zip(errors)
        .map(|((i, tool), error)| Outcome {
            tool,
            logdet: Some(logdet[i]).filter(|l| !l.is_nan()),
            episode: match error {
                Some(e) => Err(e),
                None => Ok(Shown {
                    task_error: task_error[i],
                    free_energy: free_energy[i],
                    cost_j: cost_j[i],
                    rhs_evals: evals[i],
                    progress: Some(progress[i]).filter(|p| !p.is_nan()),
                    score: score[i],
                }),
            },
        })
        .collect())
}
