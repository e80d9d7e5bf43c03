"""Type stubs of the native module (python/src/*.rs)."""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, TypedDict, Union

import numpy as np
import numpy.typing as npt

Task = Union[str, "os.PathLike[str]", Mapping[str, Any]]
"""A built-in task name (``"position"``, ``"velocity"``, ``"acceleration"`` or ``"1"``-``"3"``),
a task file's path, or a dict with a task file's keys (``kind``, ``goal``, ``precision``,
``episode``)."""

Params = Union[npt.ArrayLike, Sequence[float], Sequence[Sequence[float]]]

class Equilibrium(TypedDict):
    q: list[float]
    q_dot: list[float]
    u: list[float]

class Domains(TypedDict):
    parameters: dict[str, str]
    constraints: list[str]
    sample: dict[str, list[float]]

class ModelInfo(TypedDict):
    title: str
    dof: int
    parameters: list[str]
    equilibrium: Equilibrium
    domains: Domains

class SimulationError(RuntimeError):
    """An episode that failed: the integrator gave up or the state diverged."""

    tool: str
    """The tool, as ``model(m1=… m2=… …)``."""
    time: Optional[float]
    """When it failed (s), if the failure has a time."""
    reason: str
    """Why, in words."""

def models() -> dict[str, ModelInfo]:
    """The generated models: ``{name: {"title", "dof", "parameters", "equilibrium", "domains"}}``
    in registry order."""

def dynamics(model: str, params: Params, state: npt.ArrayLike, control: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The robot's own rigid-body dynamics Ẋ = [q̇; q̈], M(q) q̈ + C(q, q̇) q̇ + g(q) = U with U the
    joint torques (for ``panda`` and ``ur5`` without the joint impedance of their plant): shape
    (state size,) when every argument is 1-D, else (k, state size). Raises ``ValueError`` for bad
    input."""

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
    *,
    t_end: Optional[float] = ...,
    dt: Optional[float] = ...,
    perturbation: Optional[Union[float, Sequence[float]]] = ...,
    learning_rate: Optional[float] = ...,
    initial_theta: Optional[Sequence[float]] = ...,
    initial_theta_dot: Optional[Sequence[float]] = ...,
    initial_torque: Optional[Union[float, Sequence[float]]] = ...,
    rtol: Optional[float] = ...,
    atol: Optional[float] = ...,
) -> dict[str, Any]:
    """One closed-loop episode: metrics (``task_error``, ``free_energy``, ``cost_j``,
    ``logdet``, ``control_effort``, counters) and the trajectory (``t``, ``theta``,
    ``theta_dot``, ``theta_ddot``, ``u`` as arrays). Raises ``ValueError`` for bad input and
    ``SimulationError`` for a failed episode."""

def rank(
    tools: Union[str, "os.PathLike[str]"],
    task: Task,
    screen: Optional[int] = None,
    objective: Literal["free-energy", "cost-j", "confidence"] = "free-energy",
    skip_bad_rows: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
) -> dict[str, Union[npt.NDArray[np.float64], npt.NDArray[np.int64], list[Optional[str]], list[str]]]:
    """``toolconf rank`` as a dict of columns, best tool first: ``rank``, ``row``, ``name``,
    ``model``, the parameters, ``logdet``, ``task_error``, ``free_energy``, ``cost_j``,
    ``rhs_evals``, ``error``. Raises ``ValueError`` for bad input."""
