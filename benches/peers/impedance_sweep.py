#!/usr/bin/env python3
"""How a URDF robot's results depend on its joint impedance: one tools file and one task, the
impedance K scaled by s and D by sqrt(s) (the damping ratio kept) around the description's values,
without re-deriving anything (docs/how-to/choose-impedance-gains.md, "Choose impedance gains for a robot without vendor
values").

Each episode is the closed loop of urdf_loop.py (Pinocchio's aba in the right-hand side,
toolconf's controller, sensitivities and metrics; it agrees with `toolconf rank`, see
docs/explanation/performance-peers.md) integrated by SciPy's solve_ivp with the task's own tolerances. Per scale it
prints the spread of ln|Pi^U| across the tools, Spearman's rho between ln|Pi^U| and the task
error, the progress of a position task (1 - e(T)/e(0), e the distance to the goal) and how many
episodes failed.

    benches/peers/run.sh --sweep --model panda --tools examples/tools/panda_tools.csv \\
        --task examples/tasks/panda_touch_point.toml [--scales 0.3,1,3] [--damping-only]

--model is a model of derive/models or the path of a description of kind urdf.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pin_robot import ROOT  # noqa: E402
from urdf_loop import ClosedLoop, Task  # noqa: E402

TOOL_COLUMNS = ("tool_mass", "tool_com_x", "tool_com_y", "tool_com_z", "tool_ixx", "tool_iyy", "tool_izz",
                "tool_ixy", "tool_ixz", "tool_iyz", "tool_tip_x", "tool_tip_y", "tool_tip_z")


def read_tools(path: Path) -> list[tuple[str, list[float]]]:
    """(name, the 13 parameters) of every row of a tools file; a column left out is zero, as in
    toolconf (the products and the tip)."""
    lines = [line for line in path.read_text().splitlines() if line.strip() and not line.lstrip().startswith("#")]
    out = []
    for i, row in enumerate(csv.DictReader(lines), start=1):
        try:
            values = [float(row[c]) if row.get(c) not in (None, "") else 0.0 for c in TOOL_COLUMNS]
        except ValueError as err:
            raise SystemExit(f"{path}, row {i}: {err}") from None
        if not all(math.isfinite(v) for v in values):
            raise SystemExit(f"{path}, row {i}: a parameter is not finite")
        out.append((row.get("name") or f"row {i}", values))
    if not out:
        raise SystemExit(f"{path}: no tools")
    return out


def task_for(model: str, task: str) -> Task:
    return Task.from_file(model, Path(task)) if task.endswith(".toml") else Task.paper(model, task)


def episode(job) -> dict:
    """One tool at one impedance scale: ln|Pi^U|, task error and progress, or why it failed."""
    model, task, tool, stiffness, damping = job
    try:
        loop = ClosedLoop(model, tool, task_for(model, task), stiffness, damping)
        grid, states = loop.integrate("RK45", max_evals=2_000_000)
        m = loop.metrics(grid, states)
        return {"logdet": m["logdet"], "task_error": m["task_error"], "progress": m.get("progress")}
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as err:
        return {"failed": str(err)}


def ranks(v: np.ndarray) -> np.ndarray:
    r = np.empty(len(v))
    r[np.argsort(v, kind="stable")] = np.arange(len(v))
    return r


def spearman(x, y) -> float:
    return float(np.corrcoef(ranks(np.asarray(x)), ranks(np.asarray(y)))[0, 1]) if len(x) > 2 else float("nan")


def row(label: str, results: list[dict]) -> str:
    done = [r for r in results if "failed" not in r]
    failed = len(results) - len(done)
    if not done:
        return f"| {label} | – | – | – | – | {failed} |"
    logdet = np.array([r["logdet"] for r in done])
    error = np.array([r["task_error"] for r in done])
    progress = [r["progress"] for r in done if r.get("progress") is not None]
    shown = f"{np.median(progress):.3f} (min {min(progress):.3f})" if progress else "–"
    return (f"| {label} | {logdet.max() - logdet.min():.3g} | {spearman(logdet, error):+.2f} | "
            f"{np.median(error):.4g} | {shown} | {failed} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True, help="a model of derive/models, or a description's path")
    ap.add_argument("--tools", required=True, type=Path)
    ap.add_argument("--task", required=True, help="a task file, or a task kind (the model's paper-style task)")
    ap.add_argument("--scales", default="0.3,1,3", help="the factors s of K (D by sqrt(s))")
    ap.add_argument("--damping-only", action="store_true", help="scale D alone by s, K as described")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    try:
        scales = [float(s) for s in args.scales.split(",")]
    except ValueError:
        raise SystemExit(f"--scales {args.scales!r}: give numbers separated by commas") from None
    if not all(math.isfinite(s) and s > 0 for s in scales):
        raise SystemExit(f"--scales {args.scales!r}: every scale must be finite and positive")
    tools = read_tools(args.tools)
    task = str(ROOT / args.task) if args.task.endswith(".toml") and not Path(args.task).is_absolute() else args.task
    print(f"{args.model}, {len(tools)} tools of {args.tools}, task {args.task}; "
          + ("D scaled by s, K as described" if args.damping_only else "K scaled by s, D by sqrt(s)"))
    print("\n| scale | ln\\|Π^U\\| span | ρ(ln\\|Π^U\\|, task error) | task error: median | progress: median (min) "
          "| failed |\n|---|---:|---:|---:|---:|---:|")
    with ProcessPoolExecutor(max_workers=max(1, args.workers)) as pool:
        for s in scales:
            k, d = (1.0, s) if args.damping_only else (s, math.sqrt(s))
            jobs = [(args.model, task, tool, k, d) for _, tool in tools]
            label = (f"D × {s:g}" if args.damping_only else f"K × {s:g}, D × {math.sqrt(s):.3g}")
            print(row(label, list(pool.map(episode, jobs))), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
