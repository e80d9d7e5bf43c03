"""Type stubs of the native module (python/src/*.rs).

Every function raises ``ValueError`` for bad input (the command line's message), ``TypeError``
for a Python value of the wrong type (a bool where an integer is expected; an array of
booleans, complex numbers, text or other objects where numbers are), and ``MemoryError`` when an
output sized by the input does not fit in memory.
"""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, TypedDict, Union

from typing_extensions import Unpack

import numpy as np
import numpy.typing as npt

Task = Union[str, "os.PathLike[str]", Mapping[str, Any]]
"""A built-in task name (``"position"``, ``"velocity"``, ``"acceleration"`` or ``"1"``-``"3"``),
a task file's path, or a dict with a task file's keys (``kind``, ``goal``, ``precision``,
``episode``)."""

Params = Union[npt.ArrayLike, Sequence[float], Sequence[Sequence[float]]]

class EpisodeOptions(TypedDict, total=False):
    """The episode's settings a call may override (a task file's ``[episode]`` keys)."""
    t_end: Optional[float]
    dt: Optional[float]
    perturbation: Optional[Union[float, Sequence[float]]]
    learning_rate: Optional[float]
    initial_theta: Optional[Sequence[float]]
    initial_theta_dot: Optional[Sequence[float]]
    initial_torque: Optional[Union[float, Sequence[float]]]
    rtol: Optional[float]
    atol: Optional[float]

class Equilibrium(TypedDict):
    q: list[float]
    q_dot: list[float]
    u: list[float]

class Domains(TypedDict):
    parameters: dict[str, str]
    constraints: list[str]
    sample: dict[str, list[float]]
    defaults: dict[str, float]

class ModelInfo(TypedDict):
    title: str
    dof: int
    parameters: list[str]
    equilibrium: Equilibrium
    domains: Domains
    has_tip: bool

class SimulationError(RuntimeError):
    """An episode that failed: the integrator gave up or the state diverged."""

    tool: str
    """The tool, as ``model(m1=… m2=… …)``."""
    time: Optional[float]
    """When it failed (s), if the failure has a time."""
    reason: str
    """Why, in words."""

def models() -> dict[str, ModelInfo]:
    """The models, generated then loaded (``load_model``): ``{name: {"title", "dof", "parameters",
    "equilibrium", "domains"}}`` in registry order."""

def load_model(path: Union[str, "os.PathLike[str]"], name: Optional[str] = None) -> str:
    """Loads a model library built by ``make model`` (its OUT folder or the .so) next to the
    built-in models and returns the name every function takes it by. Raises ``ValueError``
    naming the file and what is wrong with it."""

def _model_path_entries() -> list[tuple[str, Optional[str]]]:
    """TOOLCONF_MODEL_PATH's entries as ``[(path, name or None), ...]``, read by the command
    line's rule: what ``import toolconf`` loads."""

def dynamics(model: str, params: Params, state: npt.ArrayLike, control: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The robot's own rigid-body dynamics Ẋ = [q̇; q̈], M(q) q̈ + C(q, q̇) q̇ + g(q) = U with U the
    joint torques (for ``panda`` and ``ur5`` without the joint impedance of their plant): shape
    (state size,) when every argument is 1-D, else (k, state size). Raises ``ValueError`` for bad
    input."""

class Tip(TypedDict, total=False):
    position: npt.NDArray[np.float64]
    jacobian: npt.NDArray[np.float64]
    bias: npt.NDArray[np.float64]

def tip(model: str, params: Params, q: npt.ArrayLike, q_dot: Optional[npt.ArrayLike] = None) -> Tip:
    """The tool's tip y(q) in the base frame (m) and its Jacobian dy/dq: ``position`` (3,) and
    ``jacobian`` (3, n) for 1-D arguments, else (k, 3) and (k, 3, n); with ``q_dot`` (q's shape),
    also ``bias`` = J̇(q, q̇) q̇ (m/s², ``position``'s shape), so that ÿ = J q̈ + J̇ q̇. Raises
    ``ValueError`` for a model without a tip or bad input."""

ToolRow = TypedDict(
    "ToolRow",
    {
        "name": str,
        "model": Optional[str],
        "tool_mass": float,
        "tool_com_x": float,
        "tool_com_y": float,
        "tool_com_z": float,
        "tool_ixx": float,
        "tool_iyy": float,
        "tool_izz": float,
        "tool_ixy": float,
        "tool_ixz": float,
        "tool_iyz": float,
        "tool_tip_x": float,
        "tool_tip_y": float,
        "tool_tip_z": float,
    },
)
"""A tools file's row of a URDF tool, in the flange frame (kg, m, kg m² about the centre of
mass; ``tool_ixy`` is I[0][1], URDF's ``<inertia ixy>``)."""

def tool_from_urdf(
    urdf: Union[str, "os.PathLike[str]"],
    root: str,
    tip: str,
    *,
    flange: Optional[str] = None,
    opening: Optional[float] = None,
    joints: Optional[Mapping[str, float]] = None,
    name: Optional[str] = None,
    model: Optional[str] = None,
) -> ToolRow:
    """``toolconf tool --urdf``: the links at and below ``root`` merged into one rigid body,
    movable joints held at ``opening`` (mimics follow their joint) or ``joints[name]``, in the
    frame of ``flange`` (default ``root``); the tip is ``tip``'s origin. Raises ``ValueError``
    with the command line's one line for bad input, ``TypeError`` for a position that is not a
    real number."""

class RangeInfo(TypedDict):
    low: float
    high: float
    low_open: bool
    unit: str

def ranges() -> dict[str, RangeInfo]:
    """Every documented valid range, e.g. ``ranges()["tool_parameter"]`` (``[1e-6, 1e6]``).

    A value outside its range raises ``ValueError`` before any work starts.
    """

class TermInfo(TypedDict):
    name: str
    symbol: str
    doc: str
    label: str
    unit: str
    goal_range: Optional[str]
    sensitivity: Optional[str]

def terms() -> list[TermInfo]:
    """The free-energy terms, in order: ``name`` keys a task's ``goal`` and ``precision`` and a
    trajectory's arrays; ``goal_range`` names the ``ranges()`` entry of its goal (``None``: the
    control's term, without a goal); ``sensitivity`` the key of its ∂(term)/∂U in
    ``confidence``'s ``sensitivities``."""

def confidence(model: str, params: Params, task: Task) -> dict[str, Any]:
    """The closed-form control confidence Π^U = ∂²F/∂U² of one tool or of many.

    Returns ``A``, ``B``, ``sensitivities`` (dict), ``pi_u`` (arrays) and ``logdet`` (float for
    a 1-D ``params``; every entry gains a leading per-tool axis for a 2-D ``params``).
    Raises ``ValueError`` for bad input.
    """

def simulate(
    model: str,
    params: Params,
    task: Task,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    **episode_options: Unpack[EpisodeOptions],
) -> dict[str, Any]:
    """One closed-loop episode: metrics (``task_error``, ``free_energy``, ``cost_j``,
    ``logdet``, ``control_effort``, counters) and the trajectory (``t`` and one array per
    term of ``terms()``, under its name). Raises ``ValueError`` for bad input and
    ``SimulationError`` for a failed episode."""

Columns = dict[str, Union[npt.NDArray[np.float64], npt.NDArray[np.int64], list[Optional[str]], list[str]]]
"""A table as a dict of columns: NumPy arrays for numbers, lists for text (None when empty)."""

ToolColumns = Union[Mapping[str, Any], Sequence[tuple[str, Any]]]
"""Tools in memory: a mapping of column name to a 1-D array or list, or (name, values) pairs."""

def rank(
    tools: Union[str, "os.PathLike[str]", ToolColumns],
    task: Task,
    screen: Optional[int] = None,
    objective: Literal["free-energy", "cost-j", "confidence"] = "free-energy",
    skip_bad_rows: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    source: Optional[str] = None,
    screen_by: Optional[Literal["predicted", "confidence"]] = None,
) -> Columns:
    """``toolconf rank`` as a dict of columns, best tool first: ``rank``, ``row``, ``name``,
    ``model``, the parameters, ``logdet``, ``task_error``, ``free_energy``, ``cost_j``,
    (``progress``), ``rhs_evals``, ``error``, ``predicted_task_error``,
    ``predicted_free_energy``, ``predicted_cost_j``, ``predicted_perturbation_effect`` (NaN
    without a prediction), ``prediction_note``. ``tools`` is a tools file or columns in memory
    (``source`` names them in errors); ``screen`` keeps K tools by ``screen_by`` (default
    ``"predicted"``, ``"confidence"`` with ``objective="confidence"``). ``toolconf.rank`` wraps
    this for DataFrames and structured arrays. Raises ``ValueError`` for bad input (``screen``
    outside [1, 2⁶⁴ − 1], an unknown ``screen_by`` included); warns (``UserWarning``) of each
    bad row skipped and of the tools a screen by prediction found without one."""

def simulate_batch(
    model: str,
    params: Params,
    task: Task,
    perturbations: Optional[Union[Sequence[Union[float, Sequence[float]]], npt.ArrayLike]] = None,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    first_tool: Optional[int] = 0,
    **episode_options: Unpack[EpisodeOptions],
) -> Columns:
    """The episodes of every tool (a row of ``params``) under every perturbation: one row of
    metrics per (tool, perturbation), tool-major, equal to a loop of ``simulate``: ``tool``,
    ``perturbation`` (indices), ``task_error``, ``free_energy``, ``cost_j``, ``logdet``,
    ``control_effort`` (NaN for a failed episode), ``rhs_evals``, ``steps``,
    ``rejected_steps``, ``jacobian_evals``, ``factorisations`` (-1 for one) and ``error``.
    A failed episode never stops the batch; bad input raises ``ValueError``. ``first_tool`` is
    an integer in [0, 2⁶³ − 1 − the number of tools] (``tool`` is int64)."""

def _simulate_batch(
    model: str,
    params: Params,
    task: "PortableTask",
    perturbations: Optional[Union[Sequence[Union[float, Sequence[float]]], npt.ArrayLike]] = None,
    method: str = "fast",
    first_tool: Optional[int] = 0,
    **episode_options: Any,
) -> Columns:
    """``simulate_batch`` on one block of ``toolconf.dask.simulate_batch``, the task as
    ``_portable_task`` sent it (a task file as its text)."""

def design(
    model: str,
    task: Task,
    design: Union[str, "os.PathLike[str]", Mapping[str, Any]],
    sweep: Optional[str] = None,
) -> dict[str, Any]:
    """``toolconf design --json`` as a dict: the tool to build (``params``, ``logdet``), the
    confidence optimum's checks (``gradient_check``, ``kkt_residual``), the random comparison
    and the ``verification`` episodes; with ``sweep``, the front. Raises ``ValueError`` for
    bad input or infeasible constraints, ``RuntimeError`` for a design that failed."""

# The steps toolconf.dask spreads over a cluster (python/src/dask_steps.rs); blocks are dicts of
# columns (Columns) that pickle exactly.

PortableTask = Union[str, Mapping[str, Any], tuple[str, str, str]]

def _portable_task(
    task: Task,
    screen: Optional[int] = None,
    objective: str = "free-energy",
    method: str = "fast",
    screen_by: Optional[str] = None,
) -> PortableTask:
    """The task as workers read it (a task file as its text); checks the options as ``rank``."""

def _screen_block(
    tools: ToolColumns,
    task: PortableTask,
    first_row: int,
    screen: Optional[int] = None,
    skip_bad_rows: bool = False,
    source: str = "tools DataFrame",
    objective: str = "free-energy",
    screen_by: Optional[str] = None,
) -> dict[str, Any]:
    """The cheap stage over one block of rows numbered from ``first_row``: ``kept``
    (candidates, with their predictions when the screen is by prediction), ``read``,
    ``without_confidence``, ``first_confidence_error``, ``without_prediction``,
    ``first_prediction_error``, ``skipped``, ``rows``."""

def _merge_screens(
    blocks: list[dict[str, Any]],
    task: PortableTask,
    screen: Optional[int] = None,
    source: str = "tools DataFrame",
    objective: str = "free-energy",
    screen_by: Optional[str] = None,
) -> tuple[Columns, Optional[str]]:
    """The blocks' screens (in row order) absorbed into the global top ``screen`` by
    ``screen_by``, with the whole table's checks: the kept candidates, and the warning of the
    tools without a prediction (or None)."""

def _episodes(
    block: Columns,
    task: PortableTask,
    objective: str = "free-energy",
    method: str = "fast",
) -> Columns:
    """The episodes of a block of candidates: a block of simulated tools."""

def _rank_table(blocks: list[Columns]) -> Columns:
    """Simulated blocks ranked into ``rank``'s table."""

# The evaluation of `toolconf reproduce --model` (python/src/evaluate.rs): toolconf.reproduce
# calls _reproduce; toolconf.dask.reproduce its three steps (population, blocks, finish).

class Evaluation(TypedDict):
    tables: dict[str, Columns]
    summary: str

class Population(TypedDict):
    params: list[list[float]]
    names: list[Optional[str]]
    rows: list[int]
    source: str
    box: Optional[list[tuple[str, float, float]]]

def _reproduce_plan(quick: bool, counts: Mapping[str, Optional[int]]) -> str:
    """The evaluation's counts (the paper's, or the quick ones, with ``counts`` over them) as
    JSON text; raises ``ValueError`` for a count out of range, ``TypeError`` for a non-integer."""

def _reproduce_population(
    model: str,
    tools: Union[None, str, "os.PathLike[str]", ToolColumns] = None,
    sample: Optional[int] = None,
    seed: Optional[int] = None,
    box: Sequence[str] = ...,
    source: Optional[str] = None,
) -> Population:
    """The population: the tools' rows (all of ``model``), or ``sample`` random tools of it."""

def _reproduce_block(
    model: str,
    task: PortableTask,
    params: Sequence[Sequence[float]],
    first: int,
    plan: str,
    method: str,
) -> list[str]:
    """A block of tools' records (confidence and episodes), numbers carried as their bits."""

def _reproduce_finish(
    model: str,
    task: PortableTask,
    population: Population,
    records: list[str],
    seed: int,
    plan: str,
    method: str,
) -> Evaluation:
    """The evaluation from its population and every tool's record: tables and summary."""

def _reproduce(
    model: str,
    task: PortableTask,
    tools: Union[None, str, "os.PathLike[str]", ToolColumns],
    sample: Optional[int],
    seed: int,
    box: Sequence[str],
    plan: str,
    method: str,
    source: Optional[str] = None,
) -> Evaluation:
    """The whole evaluation in one call (what ``toolconf.reproduce`` runs)."""
