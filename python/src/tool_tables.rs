//! Tools as Python tables (dicts of columns): what `toolconf.rank` returns, and the blocks of
//! tools that travel between the client and Dask's workers (`toolconf.dask`). One writer and
//! one reader per kind of row, so a block read back is the rows written, bit for bit.
//!
//! Columns, each one entry per tool: `row` (1-based in the whole input), `name` (str or None),
//! `model`, one column per parameter of the models present (NaN where a tool's model has no
//! such parameter), `logdet` (ln|Π^U|, NaN without one); ranked tools add `task_error`,
//! `free_energy`, `cost_j` (NaN for a failed episode), `rhs_evals` (-1 for one) and `error`;
//! both add the prediction's columns (`predicted_task_error`, …, NaN without one, and
//! `prediction_note`) where there is one: ranked tools always, candidates when the screen is by
//! prediction. Blocks also carry `predicted_abscissa`, so that a prediction read back is the one
//! written.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::rank::{objective_value, order_by_score, Candidate, ModelTasks, RankedTool};
use toolconf::select::Objective;
use toolconf_model::inputs::tools_file::ToolRow;
use toolconf_model::model::Metrics;
use toolconf_model::prediction::Prediction;
use toolconf_model::registry::{AnyTool, ModelKind};

use crate::errors::Failure;

/// A simulated tool as the table holds it: the metrics the table shows, and the objective's
/// score (what ranks it), or the episode's error.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub tool: ToolRow,
    pub logdet: Option<f64>,
    pub episode: Result<Shown, String>,
    /// The episode's predicted cost, or why there is none.
    pub prediction: Result<Prediction, String>,
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
            prediction: r.prediction.map_err(|e| e.reason()),
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

/// The prediction's columns, as `toolconf rank --json` names its fields: each value (NaN
/// without a prediction) and `prediction_note` (None, or why there is none); with `abscissa`
/// (a block's), also `predicted_abscissa`.
fn put_predictions(
    out: &Bound<'_, PyDict>,
    predictions: &[Result<&Prediction, &str>],
    abscissa: bool,
) -> PyResult<()> {
    let py = out.py();
    let items: Vec<&Result<&Prediction, &str>> = predictions.iter().collect();
    let column = |f: fn(&Prediction) -> f64| floats(py, &items, move |p| p.ok().map(f));
    out.set_item("predicted_task_error", column(|p| p.task_error))?;
    out.set_item("predicted_free_energy", column(|p| p.free_energy))?;
    out.set_item("predicted_cost_j", column(|p| p.cost_j))?;
    out.set_item(
        "predicted_perturbation_effect",
        column(|p| p.perturbation_effect),
    )?;
    if abscissa {
        out.set_item("predicted_abscissa", column(|p| p.abscissa))?;
    }
    let notes: Vec<Option<&str>> = predictions.iter().map(|p| p.err()).collect();
    out.set_item("prediction_note", notes)
}

/// Candidates (after the screen) as a block: the tool columns, `logdet` and, when the screen
/// predicted them, the predictions.
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
    // The screen predicts every tool it keeps, or none.
    let predictions: Option<Vec<_>> = kept.iter().map(|c| c.prediction.as_ref()).collect();
    if let Some(predictions) = predictions.filter(|p| !p.is_empty()) {
        let reasons: Vec<String> = predictions
            .iter()
            .map(|p| p.as_ref().err().map(|e| e.reason()).unwrap_or_default())
            .collect();
        let shown: Vec<Result<&Prediction, &str>> = predictions
            .iter()
            .zip(&reasons)
            .map(|(p, reason)| p.as_ref().map_err(|_| reason.as_str()))
            .collect();
        put_predictions(&out, &shown, true)?;
    }
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
    let predictions: Vec<Result<&Prediction, &str>> = items
        .iter()
        .map(|o| o.prediction.as_ref().map_err(String::as_str))
        .collect();
    put_predictions(&out, &predictions, !ranked)?;
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

/// The predictions of a block written by [`put_predictions`] with their abscissae, one per
/// tool of `n` (a prediction, or its note); `None` for a block without them.
fn predictions_from_py(
    block: &Bound<'_, PyDict>,
    n: usize,
) -> Result<Option<Vec<Result<Prediction, String>>>, Failure> {
    if !block.contains("prediction_note").unwrap_or(false) {
        return Ok(None);
    }
    let notes: Vec<Option<String>> = column(block, "prediction_note")?;
    let [task_error, free_energy, cost_j, perturbation_effect, abscissa] = [
        "predicted_task_error",
        "predicted_free_energy",
        "predicted_cost_j",
        "predicted_perturbation_effect",
        "predicted_abscissa",
    ]
    .map(|key| float_column(block, key));
    let (task_error, free_energy, cost_j) = (task_error?, free_energy?, cost_j?);
    let (perturbation_effect, abscissa) = (perturbation_effect?, abscissa?);
    let lengths = [
        notes.len(),
        task_error.len(),
        free_energy.len(),
        cost_j.len(),
        perturbation_effect.len(),
        abscissa.len(),
    ];
    if lengths.iter().any(|&l| l != n) {
        return Err(Failure::Input(
            "tools block: columns of different lengths".into(),
        ));
    }
    Ok(Some(
        notes
            .into_iter()
            .enumerate()
            .map(|(i, note)| match note {
                Some(note) => Err(note),
                None => Ok(Prediction {
                    task_error: task_error[i],
                    free_energy: free_energy[i],
                    cost_j: cost_j[i],
                    perturbation_effect: perturbation_effect[i],
                    abscissa: abscissa[i],
                }),
            })
            .collect(),
    ))
}

/// The candidates of a block written by [`candidates_to_py`]: a tool without a confidence
/// (NaN), or without a prediction where the block has them, gets its error again from
/// `tasks`, the same function of the tool and the task.
pub fn candidates_from_py(
    block: &Bound<'_, PyDict>,
    tasks: &ModelTasks,
) -> Result<Vec<Candidate>, Failure> {
    let tools = tools_from_py(block)?;
    let logdets = float_column(block, "logdet")?;
    if logdets.len() != tools.len() {
        return Err(Failure::Input(
            "tools block: columns of different lengths".into(),
        ));
    }
    let predictions = predictions_from_py(block, tools.len())?;
    Ok(tools
        .into_iter()
        .zip(logdets)
        .enumerate()
        .map(|(i, (row, l))| {
            let logdet = if l.is_nan() {
                tasks.logdet(&row.tool)
            } else {
                Ok(l)
            };
            let prediction = predictions.as_ref().map(|p| match &p[i] {
                Ok(p) => Ok(*p),
                Err(_) => tasks.predict(&row.tool),
            });
            Candidate {
                row,
                logdet,
                prediction,
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
    let predictions = predictions_from_py(block, n)?
        .ok_or_else(|| Failure::Input("tools block: no column 'prediction_note'".into()))?;
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
        .zip(predictions)
        .map(|(((i, tool), error), prediction)| Outcome {
            tool,
            prediction,
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
