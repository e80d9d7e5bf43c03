"""toolconf: confidence-aware decision-making and control for tool selection.

After Anil Meera & Lanillos, "Confidence-Aware Decision-Making and Control for Tool Selection".
The runtime is Rust (the ``toolconf`` crate); this package exposes it over NumPy arrays:

* ``confidence(model, params, task)``: A, B, sensitivities, control confidence Π^U and
  ln|Π^U| of one tool (1-D ``params``) or of many (2-D, one tool per row), in one call.
* ``simulate(model, params, task, **episode_options)``: one closed-loop episode's metrics and
  trajectory.
* ``rank(tools, task, screen=None, objective="free-energy")``: ``toolconf rank`` as a dict of
  columns (``pandas.DataFrame(toolconf.rank(...))``).
* ``dynamics(model, params, state, control)``: a robot's own rigid-body dynamics
  Ẋ = [q̇; q̈] (U the joint torques), for one state or a batch.
* ``models()``: the generated models, their parameter names, equilibria and valid tools.

A task is ``"position"``, ``"velocity"`` or ``"acceleration"`` (the paper's tasks 1-3), a task
file's path, or a dict with a task file's keys. Bad input raises ``ValueError`` with the
command line's message; a failed episode raises ``SimulationError`` (``tool``, ``time``,
``reason``).
"""

from ._toolconf import SimulationError, confidence, dynamics, models, rank, simulate

__all__ = ["SimulationError", "confidence", "dynamics", "models", "rank", "simulate"]
