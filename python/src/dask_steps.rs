//! The native steps `toolconf.dask` spreads over a cluster: `toolconf.rank` cut at the places
//! where its data can travel, each step the library's own code (the screen, its merge, the
//! episodes, the ranking), so that the pieces put together give `toolconf.rank`'s table.
//!
//! 1. [`screen_block`] on each partition: the cheap stage over its rows, numbered globally.
//! 2. [`merge_screens`] on the client: the partitions' screens absorbed in row order (the
//!    global top K by the screen's criterion, its predictions carried in the blocks; ties and
//!    tools without a prediction by global row) and the whole input's checks.
//! 3. [`episodes`] on the workers: the kept tools' episodes, a block at a time.
//! 4. [`rank_table`] on the client: the simulated blocks ranked into one table.
//!
//! Blocks are dicts of NumPy columns ([`crate::tool_tables`]), which pickle exactly. A task file is
//! sent as its text ([`portable_task`]), so workers need not see the client's files and its
//! errors still name the file.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use toolconf::rank::{check_screened, simulate_all, ModelTasks, Screen, ScreenBy, ScreenedBlock};
use toolconf_model::inputs::task_file::TaskSpec;

use crate::errors::{detached, Failure};
use crate::rank::{objective, screen_by, screen_limit};
use crate::task::{portable_spec, TASK_TEXT};
use crate::tool_tables::{
    block_to_py, candidates_from_py, candidates_to_py, outcomes_from_py, ranked_to_py, Outcome,
};
use crate::tools::Tools;

/// The task as workers can read it: a built-in name or a dict as it is, a task file as
/// ``("toolconf task file", name, text)``. Checks the options first, in ``toolconf.rank``'s
/// order and with its ``ValueError``: ``objective``, ``screen``, ``screen_by``, the task,
/// ``method``.
#[pyfunction]
#[pyo3(name = "_portable_task", signature = (task, screen=None, objective="free-energy", method="fast", screen_by=None))]
pub fn portable_task<'py>(
    task: &Bound<'py, PyAny>,
    screen: Option<&Bound<'py, PyAny>>,
    objective: &str,
    method: &str,
    screen_by: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let py = task.py();
    let objective = self::objective(objective).map_err(|f| f.into_pyerr(py))?;
    screen_limit(screen).map_err(|f| f.into_pyerr(py))?;
    self::screen_by(screen_by, objective).map_err(|f| f.into_pyerr(py))?;
    let spec = block_task(task)?;
    crate::task::method(method).map_err(|f| f.into_pyerr(py))?;
    if spec.file.is_empty() || task.cast::<PyDict>().is_ok() || task.cast::<PyTuple>().is_ok() {
        return Ok(task.clone());
    }
    let text = toolconf_model::inputs::bounded_read::read_text_file(
        std::path::Path::new(&spec.file),
        "task file",
    )
    .map_err(|m| Failure::Input(format!("{}: {m}", spec.file)).into_pyerr(py))?;
    Ok(PyTuple::new(py, [TASK_TEXT, spec.file.as_str(), text.as_str()])?.into_any())
}

/// A task as [`crate::task::task_spec`] takes it, or as [`portable_task`] sent it.
fn block_task(task: &Bound<'_, PyAny>) -> PyResult<TaskSpec> {
    portable_spec(task, None)
}

/// The screen's criterion of a block step: ``screen_by`` for ``objective`` with a screen; none
/// without (nothing is chosen, the episodes' stage predicts every tool), as ``toolconf.rank``.
fn block_screen_by(
    py: Python<'_>,
    limit: Option<usize>,
    screen_by: Option<&str>,
    objective: &str,
) -> PyResult<ScreenBy> {
    let objective = self::objective(objective).map_err(|f| f.into_pyerr(py))?;
    let by = self::screen_by(screen_by, objective).map_err(|f| f.into_pyerr(py))?;
    Ok(if limit.is_some() {
        by
    } else {
        ScreenBy::Confidence
    })
}

/// The cheap stage over one block of a table (a Dask partition), its rows numbered from
/// ``first_row`` (its first row's 1-based place in the whole table), without the whole
/// table's checks (``_merge_screens`` makes them).
///
/// Returns a dict: ``kept`` (the block's candidates: the ``screen`` best by ``screen_by`` for
/// ``objective``, with their predictions when by prediction, or all), ``read``,
/// ``without_confidence``, ``first_confidence_error``, ``without_prediction``,
/// ``first_prediction_error``, ``skipped`` (one warning per bad row skipped) and ``rows``.
/// Raises ``ValueError`` for the block's first bad row (unless ``skip_bad_rows``) or a tool the
/// task does not fit, with ``toolconf.rank``'s message.
#[pyfunction]
#[pyo3(name = "_screen_block", signature = (tools, task, first_row, screen=None, skip_bad_rows=false, source="tools DataFrame", objective="free-energy", screen_by=None))]
#[allow(clippy::too_many_arguments)]
pub fn screen_block<'py>(
    py: Python<'py>,
    tools: &Bound<'py, PyAny>,
    task: &Bound<'py, PyAny>,
    first_row: usize,
    screen: Option<&Bound<'py, PyAny>>,
    skip_bad_rows: bool,
    source: &str,
    objective: &str,
    screen_by: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let limit = screen_limit(screen).map_err(|f| f.into_pyerr(py))?;
    let by = block_screen_by(py, limit, screen_by, objective)?;
    let spec = block_task(task)?;
    let tools = Tools::from_py(tools, Some(source)).map_err(|f| f.into_pyerr(py))?;
    let rows = tools.rows().unwrap_or(0);
    let (block, skipped) = detached(py, || {
        let tasks = ModelTasks::new(&spec);
        if rows == 0 {
            // An empty partition: nothing to read (a whole table without rows is refused on
            // the client, by toolconf.rank's own message).
            return Ok((Screen::by(limit, by).into_block(), Vec::new()));
        }
        let screened = tools.screen(&tasks, (limit, by), skip_bad_rows, first_row.max(1), false)?;
        Ok((screened.screen.into_block(), screened.skipped))
    })?;
    let out = PyDict::new(py);
    out.set_item("kept", candidates_to_py(py, &block.kept)?)?;
    out.set_item("read", block.read)?;
    out.set_item("without_confidence", block.without_confidence)?;
    out.set_item("first_confidence_error", block.first_confidence_error)?;
    out.set_item("without_prediction", block.without_prediction)?;
    out.set_item("first_prediction_error", block.first_prediction_error)?;
    out.set_item("skipped", skipped)?;
    out.set_item("rows", rows)?;
    Ok(out)
}

/// The blocks' screens (``_screen_block``'s dicts, in row order; ``kept`` may be None when only
/// the counts matter) absorbed into one: the global ``screen`` best by ``screen_by`` for
/// ``objective`` (the blocks' own criterion), ties and tools without a prediction by the
/// global row, then the whole table's checks (some valid row, some tool with a confidence).
/// Returns ``(kept, note)``: the kept candidates as a block, and what ``toolconf.rank`` warns of
/// the tools without a prediction (None if nothing); raises ``ValueError`` as ``toolconf.rank``
/// does.
#[pyfunction]
#[pyo3(name = "_merge_screens", signature = (blocks, task, screen=None, source="tools DataFrame", objective="free-energy", screen_by=None))]
pub fn merge_screens<'py>(
    py: Python<'py>,
    blocks: &Bound<'py, PyList>,
    task: &Bound<'py, PyAny>,
    screen: Option<&Bound<'py, PyAny>>,
    source: &str,
    objective: &str,
    screen_by: Option<&str>,
) -> PyResult<(Bound<'py, PyDict>, Option<String>)> {
    let limit = screen_limit(screen).map_err(|f| f.into_pyerr(py))?;
    let by = block_screen_by(py, limit, screen_by, objective)?;
    let spec = block_task(task)?;
    let tasks = ModelTasks::new(&spec);
    let mut merged = Screen::by(limit, by);
    let mut skipped = 0;
    for block in blocks.iter() {
        let block = block.cast::<PyDict>()?;
        let item = |key: &str| -> PyResult<Bound<'py, PyAny>> {
            block.get_item(key)?.ok_or_else(|| {
                Failure::Input(format!("screen block: no key '{key}'")).into_pyerr(py)
            })
        };
        let kept = match block.get_item("kept")? {
            Some(k) if !k.is_none() => {
                candidates_from_py(k.cast::<PyDict>()?, &tasks).map_err(|f| f.into_pyerr(py))?
            }
            _ => Vec::new(),
        };
        merged.absorb(ScreenedBlock {
            kept,
            read: item("read")?.extract()?,
            without_confidence: item("without_confidence")?.extract()?,
            first_confidence_error: item("first_confidence_error")?.extract()?,
            without_prediction: item("without_prediction")?.extract()?,
            first_prediction_error: item("first_prediction_error")?.extract()?,
        });
        skipped += item("skipped")?.len()?;
    }
    check_screened(&merged, skipped, source, &tasks.kind.to_string())
        .map_err(|e| Failure::input(e).into_pyerr(py))?;
    let note = merged.unpredicted_note();
    Ok((candidates_to_py(py, &merged.finish())?, note))
}

/// The episodes of a block of candidates (``_screen_block``'s ``kept``, or a slice of
/// ``_merge_screens``'s) on this machine's rayon threads: a block of simulated tools, each with
/// its metrics and its score for ``objective``, or its episode's error.
#[pyfunction]
#[pyo3(name = "_episodes", signature = (block, task, objective="free-energy", method="fast"))]
pub fn episodes<'py>(
    py: Python<'py>,
    block: &Bound<'py, PyDict>,
    task: &Bound<'py, PyAny>,
    objective: &str,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let objective = self::objective(objective).map_err(|f| f.into_pyerr(py))?;
    let mut spec = block_task(task)?;
    spec.episode.method = Some(crate::task::method(method).map_err(|f| f.into_pyerr(py))?);
    let tasks = ModelTasks::new(&spec);
    let candidates = candidates_from_py(block, &tasks).map_err(|f| f.into_pyerr(py))?;
    let outcomes: Vec<Outcome> = detached(py, || {
        let results = simulate_all(candidates, &tasks, |_| Ok::<(), Failure>(()))?;
        Ok(results
            .into_iter()
            .map(|r| Outcome::new(r, objective))
            .collect())
    })?;
    block_to_py(py, &outcomes)
}

/// Simulated blocks (``_episodes``'s) ranked into one table, ``toolconf.rank``'s.
#[pyfunction]
#[pyo3(name = "_rank_table")]
pub fn rank_table<'py>(
    py: Python<'py>,
    blocks: &Bound<'py, PyList>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut outcomes = Vec::new();
    for block in blocks.iter() {
        outcomes.extend(outcomes_from_py(block.cast::<PyDict>()?).map_err(|f| f.into_pyerr(py))?);
    }
    ranked_to_py(py, &outcomes)
}
