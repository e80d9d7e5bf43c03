"""toolconf: confidence-aware decision-making and control for tool selection.

After Anil Meera & Lanillos, "Confidence-Aware Decision-Making and Control for Tool Selection".
The runtime is Rust (the ``toolconf`` crate); this package exposes it over NumPy arrays:

* ``confidence(model, params, task)``: A, B, sensitivities, control confidence Π^U and
  ln|Π^U| of one tool (1-D ``params``) or of many (2-D, one tool per row), in one call.
* ``simulate(model, params, task, **episode_options)``: one closed-loop episode's metrics and
  trajectory.
* ``simulate_batch(model, params_2d, task, perturbations=..., **episode_options)``: the
  episodes of many tools under many perturbations, one row of metrics each.
* ``rank(tools, task, screen=None, objective="free-energy", screen_by=None)``: ``toolconf
  rank`` on a tools file, a pandas DataFrame, a dict of 1-D arrays or a NumPy structured array,
  each tool's predicted cost beside its episode's; a DataFrame for a DataFrame, else a dict of
  columns.
* ``design(model, task, design)``: ``toolconf design --json``, which tool to build.
* ``reproduce(model, task, tools=... | sample=N)``: ``toolconf reproduce --model``, the
  paper's evaluation (Figs. 2-7) on any model, task and tool population: its tables as
  DataFrames and a verdict for each claim.
* ``dynamics(model, params, state, control)``: a robot's own rigid-body dynamics
  Ẋ = [q̇; q̈] (U the joint torques), for one state or a batch.
* ``tip(model, params, q, q_dot=None)``: the tool's tip in the base frame and its Jacobian
  (3 × n), for one joint configuration or a batch; with ``q_dot``, also J̇ q̇ (``bias``), so that
  the tip's acceleration is J q̈ + J̇ q̇.
* ``tool_from_urdf(urdf, root, tip, opening=..., flange=...)``: ``toolconf tool --urdf``, a
  tool's tools-file row (mass, centre of mass, full inertia, tip in the flange frame) from its
  own URDF, as a dict.
* ``models()``: the models (generated and loaded), their parameter names, equilibria and valid
  tools.
* ``load_model(path, name=None)``: a model library built by ``make model`` (a robot the
  repository does not ship), loaded next to the built-in models with no rebuild; every function
  here, and ``toolconf.dask``'s workers, then take it by name. ``TOOLCONF_MODEL_PATH``
  (``:``-separated, ``NAME=PATH`` entries allowed) loads libraries at import.
* ``toolconf.dask`` (``pip install "./python[dask]"``): ``rank``, ``simulate_batch`` and
  ``reproduce`` on a Dask cluster, with the same results.
* ``ranges()``: the valid range of every number the package and the command line take.
* ``terms()``: the free-energy terms, whose names key a task's goals and precisions.

A task is ``"position"``, ``"velocity"`` or ``"acceleration"`` (the paper's tasks 1-3), a task
file's path, or a dict with a task file's keys. Bad input (a value outside ``ranges()``
included) raises ``ValueError`` with the command line's message, and a Python value of the wrong
type ``TypeError`` (a bool or a float for an integer; an array of booleans, complex numbers or
text for numbers); an output that does not fit in memory raises ``MemoryError``; a failed
episode raises ``SimulationError`` (``tool``, ``time``, ``reason``).
"""

import os
from typing import TYPE_CHECKING, Any, Literal, Mapping, Optional, Union

import numpy as np

from . import _toolconf
from ._tables import native_tools
from ._toolconf import (
    SimulationError,
    confidence,
    design,
    dynamics,
    models,
    ranges,
    simulate,
    simulate_batch,
    terms,
    tip,
    tool_from_urdf,
)

__all__ = [
    "SimulationError",
    "confidence",
    "design",
    "dynamics",
    "load_model",
    "models",
    "ranges",
    "rank",
    "reproduce",
    "simulate",
    "simulate_batch",
    "terms",
    "tip",
    "tool_from_urdf",
]


# (path, name) of every library load_model loaded, in order: what toolconf.dask's workers load
# before they run anything.
_LOADED: list = []


def load_model(path: Union[str, "os.PathLike[str]"], name: Optional[str] = None) -> str:
    """Loads a model library built by ``make model`` and returns the name every function takes
    it by (the library's own, or ``name``): see ``toolconf._toolconf.load_model``. The library is
    native code run with this interpreter's privileges: load only libraries you built.

    Raises:
        ValueError: one line naming the file and what is wrong with it.
        TypeError: ``path`` is not a str or path-like, or ``name`` not a str.
    """
    # Resolved once, here: the path recorded for toolconf.dask's workers must not depend on
    # the folder a worker was started in.
    path = os.path.abspath(os.path.expanduser(os.fspath(path)))
    loaded = _toolconf.load_model(path, name)
    entry = (path, name)
    if entry not in _LOADED:
        _LOADED.append(entry)
    return loaded


def _ensure_loaded(entries) -> None:
    """On a Dask worker: loads the client's libraries (a no-op for those already loaded)."""
    for path, name in entries:
        load_model(path, name)


def _load_environment() -> None:
    """Loads TOOLCONF_MODEL_PATH's libraries, its entries read by the command line's rule
    (``:``-separated, ``NAME=PATH`` allowed); a refusal names the variable."""
    try:
        for path, name in _toolconf._model_path_entries():
            load_model(path, name)
    except ValueError as e:
        raise ValueError(f"TOOLCONF_MODEL_PATH: {e}") from None


_load_environment()


if TYPE_CHECKING:
    import pandas

    from ._toolconf import Columns, Task


def rank(
    tools: Union[str, "os.PathLike[str]", "pandas.DataFrame", Mapping[str, Any], np.ndarray],
    task: "Task",
    screen: Optional[int] = None,
    objective: Literal["free-energy", "cost-j", "confidence"] = "free-energy",
    skip_bad_rows: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    *,
    screen_by: Optional[Literal["predicted", "confidence"]] = None,
) -> Union["pandas.DataFrame", "Columns"]:
    """Ranks your tools on a task, as ``toolconf rank`` does, with the same numbers.

    First every tool's control confidence ln|Π^U| in closed form (no simulation); then an
    episode for every tool, or with ``screen=K`` only for K of them chosen without simulating
    (``screen_by``: by default the K whose episode the closed loop linearised at the equilibrium
    predicts cheapest); then the ranking by ``objective``. Episodes run on rayon's threads
    without the GIL; results do not depend on the number of threads.

    Args:
        tools: the tools, one per row, with a tools file's columns (``name``, ``model``, and the
            models' parameters such as ``m1, m2, l1, l2``), as any of
            a tools file's path (CSV, or JSON by the ``.json`` extension);
            a pandas DataFrame;
            a dict of 1-D arrays or lists, one per column;
            a NumPy structured array, one field per column.
            In memory, NaN and None are empty cells (a model's missing parameter, or ``arm2``
            for an empty ``model``); the checks are the file's, and a bad row's message names
            ``row N`` (1-based, the result's ``row``) where a file's names the line, e.g.
            ``tools DataFrame, row 7: m2 = 'heavy' is not a number (tool 'mallet')``.
        task: a built-in task name, a task file's path, or a dict with a task file's keys.
        screen: simulate only K tools (an integer in [1, 2⁶⁴ − 1], the command line's
            ``--screen K``), chosen by ``screen_by``; ``None`` simulates all.
        objective: ``"free-energy"`` (the paper's ∫F dt, the default), ``"cost-j"`` (∫J dt) or
            ``"confidence"`` (ln|Π^U|).
        skip_bad_rows: warn about a bad row (``UserWarning``) and go on without it, instead of
            raising.
        method: the integrator, as the command line's ``--method``: ``"fast"`` (the default),
            ``"explicit"`` (exactly MATLAB ode45, the paper's numerics), ``"auto"`` or
            ``"stiff"``.
        screen_by: with ``screen``, which K tools (the command line's ``--screen-by``):
            ``"predicted"``, the K with the lowest predicted cost (∫F dt, or ∫J dt with
            ``objective="cost-j"``, of the closed loop linearised at the equilibrium; a tool
            without a prediction comes after every tool with one, in row order), or
            ``"confidence"``, the K most confident (the largest ln|Π^U|); ties: the earlier
            row. ``None`` (the default): ``"predicted"``, or ``"confidence"`` with
            ``objective="confidence"``, as the command line. Without ``screen`` it changes
            nothing.

    Returns:
        The ranked tools, best first, with the columns ``rank``, ``row`` (1-based in the file
        or table), ``name``, ``model``, one per parameter of the models present (NaN where a
        tool's model has none), ``logdet``, ``task_error``, ``free_energy``, ``cost_j`` (NaN
        for a failed episode), on a position task (joint or tip) ``progress`` (1 − e(T)/e(0)
        with e the distance to the goal; NaN for a failed episode), ``rhs_evals`` (-1 for one),
        ``error`` (None, or why the episode failed: such tools rank last, in row order), the
        episode's cost predicted by the closed loop linearised at the equilibrium
        (``predicted_task_error``, ``predicted_free_energy``, ``predicted_cost_j``,
        ``predicted_perturbation_effect``; NaN without a prediction) and ``prediction_note``
        (None, or why there is no prediction, e.g. the linearised loop is unstable). A pandas
        DataFrame when ``tools``
        was one; otherwise a dict of columns (NumPy arrays and lists), so that pandas stays
        optional (``pandas.DataFrame(result)`` makes the same frame). The numbers are
        ``toolconf rank --json``'s for the same rows.

    Raises:
        ValueError: a bad tools file, table or row (naming the file or table, the line or row
            and the value), a bad task (naming the key), an unknown objective or
            ``screen_by``, or ``screen`` outside [1, 2⁶⁴ − 1]; the command line's message.
        TypeError: a ``screen`` that is not an integer, a ``screen_by`` that is not a str, or
            a column of booleans or complex numbers.

    Warns:
        UserWarning: each bad row skipped (``skip_bad_rows``, the command line's ``toolconf:
            skipping …`` line); then, when a screen by prediction met tools without one, the
            command line's ``note:`` (how many, the first reason, and that they were ranked
            after every tool with one).
    """
    native, source, frame = native_tools(tools)
    table = _toolconf.rank(native, task, screen, objective, skip_bad_rows, method, source,
                           screen_by)
    if frame:
        import pandas

        return pandas.DataFrame(table)
    return table


# The counts of an evaluation, by their keyword arguments (the command line's --highlight-sample …).
_COUNTS = ("highlight_sample", "sweep_tools", "sweep_levels", "grid_trials", "grid_tools", "trials",
           "trial_tools", "resamples")


def _evaluation(out, frames: bool) -> dict:
    """The native evaluation as the package returns it: each table a DataFrame (a dict of
    columns without pandas), ``verdicts`` and ``summary`` as dicts."""
    import json

    summary = json.loads(out["summary"])
    result = {}
    if frames:
        import pandas

        for name, columns in out["tables"].items():
            result[name] = pandas.DataFrame(columns)
    else:
        result.update(out["tables"])
    result["verdicts"] = {key: v["verdict"] for key, v in summary["verdicts"].items()}
    result["summary"] = summary
    return result


def _wants_frames(frames: Optional[bool]) -> bool:
    if frames is not None:
        return bool(frames)
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True


def reproduce(
    model: str,
    task: "Task",
    tools: Union[None, str, "os.PathLike[str]", "pandas.DataFrame", Mapping[str, Any], np.ndarray] = None,
    sample: Optional[int] = None,
    *,
    seed: int = 0,
    box: Optional[Mapping[str, tuple[float, float]]] = None,
    quick: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    frames: Optional[bool] = None,
    **counts: Optional[int],
) -> dict:
    """The paper's evaluation (its Figs. 2-7) of ``model`` on ``task``, as ``toolconf reproduce
    --model`` runs it, with the same numbers: does control confidence predict the task error, and
    the reliability under a torque perturbation ΔT, on this robot and task?

    Every tool of the population runs without and with ΔT (the task file's ``[episode]
    perturbation``, else −10 % of each joint's rated torque on a URDF arm, the paper's −0.8 N m
    otherwise); the first ``sweep_tools`` also at every level of the sweep; the selection
    experiments choose among tools of the same population. Episodes run on rayon's threads
    without the GIL; results do not depend on the number of threads.

    Args:
        model: the model's name (``toolconf.models()``; a library loaded with ``load_model``).
        task: a built-in task name, a task file's path, or a dict with a task file's keys.
        tools: the population, as ``toolconf.rank`` takes tools (a tools file's path, a pandas
            DataFrame, a dict of columns, a structured array), every one a tool of ``model``.
        sample: or the population as this many random tools (1 … 10⁶) from the model's
            sampling box, drawn as ``toolconf select --models MODEL --tools N --seed SEED``
            draws them; 300 (the paper's Fig. 2) when neither is given.
        seed: the sample's seed and the master seed of the trials and bootstraps.
        box: with ``sample``, intervals replacing the sampling box's, ``{name: (lo, hi)}``.
        quick: the reduced counts (for tests), instead of the paper's.
        method: the integrator, as the command line's ``--method``.
        frames: return pandas DataFrames (the default when pandas is installed) or dicts of
            columns.
        counts: ``highlight_sample`` (20), ``sweep_tools`` (100), ``sweep_levels`` (11),
            ``grid_trials`` (25), ``grid_tools`` (5), ``trials`` (50), ``trial_tools`` (10),
            ``resamples`` (2000): the paper's counts by default.

    Returns:
        dict: one entry per table of ``toolconf reproduce --model``'s CSVs
        (``fig2_confidence_vs_error``, ``fig3_tools``, ``fig3_trajectories``,
        ``fig4_perturbation_change``, ``fig5_perturbation_sweep``, ``fig6_selection_grid``,
        ``fig7_benchmark``, ``fig7_choices``), each a DataFrame (or a dict of columns);
        ``verdicts``, each claim's verdict (``"holds"``, ``"reversed"``, ``"no relation"`` or
        ``"cannot be judged"``) by its key (``confidence_predicts_task_error``,
        ``confidence_predicts_reliability``, ``free_energy_choices_less_sensitive``); and
        ``summary``, the command line's ``--json`` object (the statistics, rules, ΔT, goal
        kind, population, counts).

    Raises:
        ValueError: bad input, with the command line's message (an unknown model, a task of
            another model, a population of 0 or more than 10⁶, a box naming a parameter the
            model lacks, a relative goal on a joint task, a count out of range, a ``seed``
            outside [0, 2⁶⁴ − 1]).
        TypeError: a count, ``sample`` or ``seed`` that is not an integer.
        RuntimeError: every tool's episode failed.
    """
    native, source, frame = (None, None, False) if tools is None else native_tools(tools)
    unknown = sorted(set(counts) - set(_COUNTS))
    if unknown:
        raise TypeError(f"reproduce() got an unexpected keyword argument '{unknown[0]}'")
    plan = _toolconf._reproduce_plan(quick, counts)
    boxes = _box_texts(box)
    out = _toolconf._reproduce(model, task, native, sample, seed, boxes, plan, method, source)
    return _evaluation(out, _wants_frames(frames) or frame)


def _box_texts(box) -> list:
    """``{name: (lo, hi)}`` as the command line's ``NAME=LO:HI`` texts."""
    if box is None:
        return []
    if not isinstance(box, Mapping):
        raise TypeError(f"box = {box!r:.60}: expected a dict of name: (lo, hi)")
    texts = []
    for name, bounds in box.items():
        try:
            lo, hi = (float(v) for v in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"box {name}: expected (lo, hi), got {bounds!r:.60}") from None
        texts.append(f"{name}={lo!r}:{hi!r}")
    return texts
