"""One episode of the on-robot controller on MuJoCo's plant, and the same episode by `toolconf
simulate`, measured alike: the tip's path, the task error and ∫F on the task's output grid.

The MuJoCo episode is what a robot runs: every control period h = 1/rate the controller (the
model library's `toolconf_controller_tick`, its C ABI) reads the measured X = [q; q̇] and
returns the torque U, which is held until the next tick (zero-order hold); the joint impedance
and the gravity feed-forward are the plant's (`mujoco_arm`). MuJoCo integrates the arm between
ticks in `substeps` steps of h/substeps each, so no step straddles a change of U.

`toolconf simulate` integrates the same closed loop in continuous time: Ż = [f(X, U); U̇] with
U̇ = −γ ∂F/∂U evaluated at every integrator stage (DP5, or Rodas5P once the closed loop is found
stiff: `--method fast`, at ode45's tolerances unless the task file says otherwise).
"""

from __future__ import annotations

import csv
import io
import json
import math
import subprocess
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from model_library import ModelLibrary
from mujoco_arm import TIP_SITE, Description, arm_model, gravity_torque

# toolconf's defaults for a task file's [episode] (docs/reference/file-formats.md, "Task files"; `toolconf simulate --help`).
DEFAULT_EPISODE = {"t_end": 5.0, "dt": 0.05, "learning_rate": 1.0, "initial_torque": 0.0}
# The terms a tip_position task uses (derive/tasks.toml), the error term first.
TIP_TERMS = ("tip", "tip_dot", "u")


@dataclass
class Task:
    """A tip_position task file as the controller takes it: goals and precisions padded to the
    model's joints (docs/reference/c-abi.md, "Layout"), and the episode."""
    path: Path
    goals: np.ndarray          # terms × dof
    precisions: np.ndarray     # terms × dof × dof
    t_end: float
    dt: float
    learning_rate: float
    initial_torque: np.ndarray
    kind: str = "tip_position"


def _numbers(value, where: str) -> np.ndarray:
    """`value` as finite float64s, or a ValueError naming where it was read."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{where} = {value!r}: not a number or list of numbers") from None
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{where} = {value!r}: not finite")
    return array


def _block(value: np.ndarray, size: int, dof: int, where: str) -> np.ndarray:
    """A precision as a dof × dof block: a number is value·I on the term's `size` components,
    a matrix its size × size block; zeros elsewhere."""
    out = np.zeros((dof, dof))
    if value.ndim == 0:
        out[:size, :size] = float(value) * np.eye(size)
    elif value.shape == (size, size):
        out[:size, :size] = value
    else:
        raise ValueError(f"{where}: a number or a {size} × {size} matrix, not shape {value.shape}")
    return out


def read_task(path: str | Path, library: ModelLibrary) -> Task:
    """A task file of kind tip_position (goal, precision of tip, tip_dot and u, episode); its
    values' ranges are toolconf's to check (compare.py runs `toolconf rank` on it first)."""
    path = Path(path)
    try:
        spec = tomllib.loads(path.read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise ValueError(f"{path}: not a TOML task file: {e}") from None
    if spec.get("kind") != "tip_position":
        raise ValueError(f"{path}: kind = {spec.get('kind')!r}: this example runs tip_position tasks")
    n, terms = library.dof, library.term_names
    goals, precisions = np.zeros((len(terms), n)), np.zeros((len(terms), n, n))
    given_goals, given_precisions = dict(spec.get("goal", {})), dict(spec.get("precision", {}))
    for name in TIP_TERMS:
        size, i = (library.tip_dim if name.startswith("tip") else n), terms.index(name)
        goal = _numbers(given_goals.get(name, [0.0] * size), f"{path}: goal.{name}")
        if goal.shape != (size,):
            raise ValueError(f"{path}: goal.{name}: {goal.size} values, not {size}")
        goals[i, :size] = goal
        if name not in given_precisions:
            raise ValueError(f"{path}: precision.{name}: missing (this example takes it given)")
        where = f"{path}: precision.{name}"
        precisions[i] = _block(_numbers(given_precisions[name], where), size, n, where)
    episode = {**DEFAULT_EPISODE, **dict(spec.get("episode", {}))}
    number = {k: _numbers(episode.get(k, 0.0), f"{path}: episode.{k}")
              for k in ("t_end", "dt", "learning_rate", "initial_torque", "perturbation")}
    if number["perturbation"].any():
        raise ValueError(f"{path}: episode.perturbation: this example runs without one")
    try:
        u0 = np.broadcast_to(number["initial_torque"], (n,)).copy()
        t_end, dt, rate = (float(number[k]) for k in ("t_end", "dt", "learning_rate"))
    except (ValueError, TypeError):
        raise ValueError(f"{path}: episode: t_end, dt and learning_rate numbers, initial_torque "
                         f"a number or {n} numbers") from None
    return Task(path=path, goals=goals, precisions=precisions, t_end=t_end, dt=dt,
                learning_rate=rate, initial_torque=u0)


@dataclass
class Run:
    """One episode on the output grid: t, q, the tip y and ẏ (base frame), U, and the metrics
    as toolconf defines them (crates/model/src/model/closed_loop_n.rs, `Metrics`)."""
    t: np.ndarray
    q: np.ndarray
    tip: np.ndarray
    tip_dot: np.ndarray
    u: np.ndarray
    logdet: float
    metrics: dict = field(default_factory=dict)


def measure(run: Run, task: Task, library: ModelLibrary) -> Run:
    """Task error Σₖ (yₖ − y^g)ᵀ P^y (yₖ − y^g) over every grid sample, ∫F dt and ∫J dt by
    the trapezoidal rule on the grid (J = ½ Σ eᵀPe over tip, tip_dot and u; F = J − ½ ln|Π^U|),
    and progress 1 − |y(T) − y^g| / |y(0) − y^g|."""
    terms, d = library.term_names, library.tip_dim
    p_tip = task.precisions[terms.index("tip")][:d, :d]
    p_tip_dot = task.precisions[terms.index("tip_dot")][:d, :d]
    p_u = task.precisions[terms.index("u")]
    e = run.tip - task.goals[terms.index("tip")][:d]
    weighted = np.einsum("ki,ij,kj->k", e, p_tip, e)
    j = 0.5 * (np.einsum("ki,ij,kj->k", run.u, p_u, run.u) + weighted
               + np.einsum("ki,ij,kj->k", run.tip_dot, p_tip_dot, run.tip_dot))
    f = j - 0.5 * run.logdet
    distance = np.linalg.norm(e, axis=1)
    run.metrics = {
        "task_error": float(weighted.sum()),
        "free_energy": float(np.trapezoid(f, run.t)),
        "cost_j": float(np.trapezoid(j, run.t)),
        "logdet": run.logdet,
        "progress": float(1.0 - distance[-1] / distance[0]),
    }
    return run


def mujoco_episode(library: ModelLibrary, description: Description, tool: dict,
                   params: np.ndarray, task: Task, rate_hz: float = 1000.0, substeps: int = 1,
                   integrator: str = "RK4") -> Run:
    """The controller ticking at `rate_hz` on MuJoCo's plant (the module's docstring)."""
    ticks_per_sample = round(task.dt * rate_hz)
    if not math.isclose(ticks_per_sample, task.dt * rate_hz, rel_tol=1e-9) or ticks_per_sample < 1:
        raise ValueError(f"the output step {task.dt} s is not a whole number of ticks at {rate_hz} Hz")
    samples = round(task.t_end / task.dt)
    if not math.isclose(samples * task.dt, task.t_end, rel_tol=1e-9):
        raise ValueError(f"{task.path}: episode.t_end = {task.t_end} s is not a whole number of "
                         f"dt = {task.dt} s (this example samples both engines alike)")
    q_e = library.equilibrium_state[:library.dof]
    model = arm_model(description, q_e, tool, integrator, 1.0 / (rate_hz * substeps))
    data = mujoco.MjData(model)
    feed_forward = gravity_torque(model, q_e)
    data.qpos[:], data.qvel[:] = q_e, 0.0
    site = model.site(TIP_SITE).id
    jacobian = np.empty((3, model.nv))
    out = {k: [] for k in ("t", "q", "tip", "tip_dot", "u")}
    u = task.initial_torque.copy()
    with library.controller(params, task.kind, task.goals, task.precisions, task.learning_rate,
                            task.initial_torque, rate_hz) as controller:
        for k in range(samples * ticks_per_sample + 1):
            if k % ticks_per_sample == 0:
                mujoco.mj_forward(model, data)
                mujoco.mj_jacSite(model, data, jacobian, None, site)
                for key, value in (("t", k / rate_hz), ("q", data.qpos), ("u", u),
                                   ("tip", data.site_xpos[site]),
                                   ("tip_dot", jacobian @ data.qvel)):
                    out[key].append(np.array(value, copy=True))
            if k == samples * ticks_per_sample:
                break
            u = controller.tick(data.qpos, data.qvel).copy()
            data.qfrc_applied[:] = feed_forward + u
            mujoco.mj_step(model, data, nstep=substeps)
        logdet = controller.confidence
    _check_warnings(data, rate_hz, substeps)
    run = Run(**{k: np.array(v) for k, v in out.items()}, logdet=logdet)
    return measure(run, task, library)


def _check_warnings(data: mujoco.MjData, rate_hz: float, substeps: int) -> None:
    """MuJoCo answers a diverging state (a NaN or huge q, q̇ or q̈) by resetting the data to the
    model's rest pose with a warning and going on: such an episode is not a result."""
    for warning in (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                    mujoco.mjtWarning.mjWARN_BADQACC):
        if data.warning[warning].number:
            raise RuntimeError(f"MuJoCo's simulation diverged ({warning.name}, at "
                               f"t = {data.warning[warning].lastinfo} steps; {rate_hz} Hz, "
                               f"{substeps} steps per tick)")


def simulate(toolconf: Path, library: ModelLibrary, params: np.ndarray, task: Task,
             workdir: Path, extra: tuple = ()) -> Run:
    """`toolconf simulate --model M --params P --task-file T --json --csv FILE`: its metrics
    as printed and its trajectory from the CSV (columns theta<i>, u<i>, tip_x, tip_dot_x, …)."""
    path = workdir / "trajectory.csv"
    command = [str(toolconf), "simulate", "--model", library.name,
               "--params", ",".join(repr(float(v)) for v in params),
               "--task-file", str(task.path), "--json", "--csv", str(path), *extra]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: {done.stderr.strip()}")
    printed = json.loads(done.stdout)
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    path.unlink()
    joints = range(1, library.dof + 1)
    column = lambda names: np.array([[float(r[n]) for n in names] for r in rows])
    run = Run(t=column(["t"])[:, 0], q=column([f"theta{i}" for i in joints]),
              tip=column(["tip_x", "tip_y", "tip_z"]),
              tip_dot=column(["tip_dot_x", "tip_dot_y", "tip_dot_z"]),
              u=column([f"u{i}" for i in joints]), logdet=printed["logdet"])
    run.metrics = {k: printed[k] for k in ("task_error", "free_energy", "cost_j", "logdet",
                                           "progress")}
    return run
