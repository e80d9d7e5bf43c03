//! `toolconf.rank`: `toolconf rank` as a dict of columns.

use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use toolconf::rank::{simulate_all, ModelTasks, ScreenBy};
use toolconf::select::Objective;
use toolconf_model::inputs::task_file::TaskSpec;

use crate::errors::{detached, Failure};
use crate::task::task_spec;
use crate::tool_tables::{ranked_to_py, Outcome};
use crate::tools::Tools;

pub fn objective(name: &str) -> Result<Objective, Failure> {
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

/// `screen_by` as the screen's criterion, the command line's `--screen-by`: by default the
/// prediction of what the ranking minimises, except when it ranks by confidence, which the
/// confidence screen keeps exactly.
pub fn screen_by(name: Option<&str>, objective: Objective) -> Result<ScreenBy, Failure> {
    match (name, objective) {
        (Some("confidence"), _) | (None, Objective::Confidence) => Ok(ScreenBy::Confidence),
        (Some("predicted"), _) | (None, _) => Ok(ScreenBy::Predicted(objective)),
        (Some(name), _) => Err(Failure::Input(format!(
            "screen_by '{}': expected predicted (the lowest predicted ∫F dt, or ∫J dt with \
             objective cost-j, of the closed loop linearised at the equilibrium) or confidence \
             (the largest ln|Π^U|)",
            toolconf_messages::Clip(name)
        ))),
    }
}

/// The cheap stage, then every kept tool's episode (the library's [`simulate_all`]); returns
/// the outcomes in row order, the bad rows skipped and what a screen by prediction says of the
/// tools without one ([`toolconf::rank::Screen::unpredicted_note`]).
fn run(
    tools: &Tools,
    spec: &TaskSpec,
    (screen, by): (Option<usize>, ScreenBy),
    objective: Objective,
    skip_bad_rows: bool,
) -> Result<(Vec<Outcome>, Vec<String>), Failure> {
    let tasks = ModelTasks::new(spec);
    // Without a screen nothing is chosen: the episodes' stage predicts every tool.
    let by = if screen.is_some() {
        by
    } else {
        ScreenBy::Confidence
    };
    let screened = tools.screen(&tasks, (screen, by), skip_bad_rows, 1, true)?;
    let note = screened.screen.unpredicted_note();
    let results = simulate_all(screened.screen.finish(), &tasks, |_| Ok::<(), Failure>(()))?;
    let outcomes = results
        .into_iter()
        .map(|r| Outcome::new(r, objective))
        .collect();
    let mut warnings = screened.skipped;
    warnings.extend(note);
    Ok((outcomes, warnings))
}

/// Ranks your tools on a task, as ``toolconf rank`` does, with the same numbers.
///
/// First every tool's control confidence ln|Π^U| in closed form (no simulation), streaming
/// through the file; then an episode for every tool, or with ``screen=K`` only for K of them,
/// chosen without simulating by ``screen_by``; then the ranking by ``objective``. Episodes run
/// on rayon's threads without the GIL; results do not depend on the number of threads.
///
/// Args:
///     tools: a tools file's path: CSV (columns ``name``, ``model``, and the models' parameters
///         such as ``m1,m2,l1,l2``) or JSON (``.json``: an array of objects with those keys);
///         or the same columns in memory, a mapping of column name to a 1-D array or list
///         (``toolconf.rank`` also takes a pandas DataFrame or a NumPy structured array and
///         makes this mapping of it). In memory, NaN and None are empty cells; rows are named
///         ``row N`` (1-based) in errors.
///     task: a built-in task name, a task file's path, or a dict with a task file's keys.
///     screen: simulate only K tools (K ≥ 1), as the command line's ``--screen K``; ``None``
///         simulates all.
///     screen_by: with ``screen``, which K (the command line's ``--screen-by``):
///         ``"predicted"``, the K with the lowest predicted cost (∫F dt, or ∫J dt with
///         ``objective="cost-j"``, of the closed loop linearised at the equilibrium; tools
///         without a prediction come after every tool with one, in row order, and a
///         ``UserWarning`` says how many and why), or ``"confidence"``, the K most confident
///         (the largest ln|Π^U|); ties: the earlier row. ``None``: ``"predicted"``, or
///         ``"confidence"`` with ``objective="confidence"``.
///     objective: ``"free-energy"`` (the paper's ∫F dt, the default), ``"cost-j"`` (∫J dt) or
///         ``"confidence"`` (ln|Π^U|).
///     skip_bad_rows: warn about a bad row (``UserWarning``) and go on without it, instead of
///         raising.
///     method: the integrator, as the command line's ``--method``: ``"fast"`` (the default),
///         ``"explicit"`` (exactly MATLAB ode45, the paper's numerics), ``"auto"`` or ``"stiff"``.
///     source: what errors call columns in memory (default ``"tools dict"``; ``toolconf.rank``
///         passes ``"tools DataFrame"`` or ``"tools array"``).
///
/// Returns:
///     dict of columns, best tool first (``toolconf.rank`` makes a pandas DataFrame of it when
///     it was given one): ``rank``, ``row`` (1-based in the file or table), ``name`` (str or None), ``model``, one column per
///     parameter of the models present (NaN for a tool whose model has no such parameter),
///     ``logdet``, ``task_error``, ``free_energy``, ``cost_j`` (NaN for a tool whose episode
///     failed), ``rhs_evals`` (-1 for those), ``error`` (None, or why the episode failed:
///     such tools rank last, in file order), ``predicted_task_error``,
///     ``predicted_free_energy``, ``predicted_cost_j``, ``predicted_perturbation_effect`` (the
///     closed loop linearised at the equilibrium; NaN without a prediction) and
///     ``prediction_note`` (None, or why there is no prediction). The numbers are
///     ``toolconf rank --json``'s.
///
/// Raises:
///     ValueError: a bad tools file or row (naming the file, the line or tool and the value),
///         a bad task (naming the key), an unknown objective or ``screen_by``, or ``screen``
///         outside [1, 2⁶⁴ − 1]; the command line's message.
///     TypeError: a ``screen`` that is not an integer (a bool, a float).
///
/// Warns:
///     UserWarning: each bad row skipped (``skip_bad_rows``), then, when a screen by prediction
///         met tools without one, the command line's ``note:`` (how many, and the first
///         reason).
#[pyfunction]
#[pyo3(signature = (tools, task, screen=None, objective="free-energy", skip_bad_rows=false, method="fast", source=None, screen_by=None))]
#[allow(clippy::too_many_arguments)]
pub fn rank<'py>(
    py: Python<'py>,
    tools: &Bound<'py, PyAny>,
    task: &Bound<'py, PyAny>,
    screen: Option<&Bound<'py, PyAny>>,
    objective: &str,
    skip_bad_rows: bool,
    method: &str,
    source: Option<&str>,
    screen_by: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let objective = self::objective(objective).map_err(|f| f.into_pyerr(py))?;
    let screen = screen_limit(screen).map_err(|f| f.into_pyerr(py))?;
    let by = self::screen_by(screen_by, objective).map_err(|f| f.into_pyerr(py))?;
    let mut spec = task_spec(task, None)?;
    spec.episode.method = Some(crate::task::method(method).map_err(|f| f.into_pyerr(py))?);
    let tools = Tools::from_py(tools, source).map_err(|f| f.into_pyerr(py))?;
    let (outcomes, warnings) = detached(py, || {
        run(&tools, &spec, (screen, by), objective, skip_bad_rows)
    })?;
    warn_skipped(py, &warnings)?;
    ranked_to_py(py, &outcomes)
}

/// `screen=K` as a limit: K in [1, 2⁶⁴ − 1] (the command line's `--screen`), or every tool.
pub fn screen_limit(screen: Option<&Bound<'_, PyAny>>) -> Result<Option<usize>, Failure> {
    let Some(screen) = screen.filter(|s| !s.is_none()) else {
        return Ok(None);
    };
    let k = crate::integers::integer("screen", screen, 1, u64::MAX.into())?;
    // More than there can be tools: every tool.
    Ok(Some(usize::try_from(k).unwrap_or(usize::MAX)))
}

/// One `UserWarning` per bad row skipped, in row order (then the screen's note, if any).
pub fn warn_skipped(py: Python<'_>, skipped: &[String]) -> PyResult<()> {
    for warning in skipped {
        let category = py.get_type::<PyUserWarning>();
        PyErr::warn(py, &category, &std::ffi::CString::new(warning.as_str())?, 1)?;
    }
    Ok(())
}
