#!/usr/bin/env python3
"""toolconf against what a Python user would otherwise write for a URDF arm, on one population of
tools, side by side in one run: SciPy's `solve_ivp(method="RK45")` with Pinocchio's `aba` in the
right-hand side on the same closed loop (urdf_loop.py: the same plant, impedance, controller and
tolerances, rtol 1e-3, atol 1e-6), and one Pinocchio `aba` call from Python.

The population: `--tools` random physical Panda tools (solid boxes, panda_study.random_tools,
seed 2023), written to a temporary tools file that toolconf's `examples/model_timing.rs` times on
one thread (median of `--repeat` runs per tool, the default `fast` method, what `toolconf rank`
runs). SciPy is timed with time.perf_counter around `solve_ivp` only (model building, gains and
metrics outside), once per tool; `aba` as the median over `--calls` calls per tool at a random
state. Per task: mean and p50/p90/p99 of the per-tool times, the ratio, and how far the two
task errors are apart (relative).

    bench/peers/run.sh --urdf [--tools 100] [--tasks position,velocity] [--write]

--write puts the tables into docs/performance.md between the `peers-urdf` markers.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import scipy

sys.path.insert(0, str(Path(__file__).resolve().parent))
from panda_study import random_tools  # noqa: E402
from pin_robot import ROOT, model_with_tool  # noqa: E402
from urdf_loop import ClosedLoop, Task  # noqa: E402

MODEL_TIMING = ROOT / "target" / "release" / "examples" / "model_timing"
DOC = ROOT / "docs" / "performance.md"
BEGIN, END = "<!-- peers-urdf:begin (written by bench/peers/urdf_peers.py) -->", "<!-- peers-urdf:end -->"
ROBOT = "panda"


def stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    return {"mean": float(v.mean()), "p50": float(np.percentile(v, 50)), "p90": float(np.percentile(v, 90)),
            "p99": float(np.percentile(v, 99))}


def toolconf_times(tools, task: str, repeat: int) -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "tools.csv"
        names = "tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz"
        path.write_text(f"model,{names}\n" + "".join(f"{ROBOT}," + ",".join(repr(float(x)) for x in t) + "\n"
                                                  for t in tools))
        out = subprocess.run([str(MODEL_TIMING), "--tools", str(path), "--task", task, "--repeat", str(repeat)],
                             check=True, capture_output=True, text=True).stdout
    return json.loads(out)["tools"]


def task_for(name: str) -> Task:
    path = Path(name)
    return Task.from_file(ROBOT, path) if path.suffix == ".toml" else Task.paper(ROBOT, name)


def scipy_times(tools, task: str) -> list[dict]:
    out = []
    for tool in tools:
        loop = ClosedLoop(ROBOT, tool, task_for(task))
        start = time.perf_counter()
        grid, states = loop.integrate("RK45")
        seconds = time.perf_counter() - start
        m = loop.metrics(grid, states)
        out.append({"us": seconds * 1e6, "rhs_evals": m["rhs_evals"], "task_error": m["task_error"]})
    return out


def aba_times(tools, calls: int) -> list[float]:
    rng = np.random.default_rng(5)
    out = []
    for tool in tools:
        model, data = model_with_tool(ROBOT, tool)
        n = model.nq
        q, v, tau = rng.uniform(-np.pi, np.pi, n), rng.uniform(-3, 3, n), rng.uniform(-20, 20, n)
        runs = []
        for _ in range(7):
            start = time.perf_counter()
            for _ in range(calls):
                pin.aba(model, data, q, v, tau)
            runs.append((time.perf_counter() - start) / calls * 1e6)
        out.append(float(np.median(runs)))
    return out


def row(label, s) -> str:
    num = lambda x: f"{x:,.1f}".replace(",", " ")  # noqa: E731 - thousands apart, the label untouched
    return f"| {label} | {num(s['mean'])} | {num(s['p50'])} | {num(s['p90'])} | {num(s['p99'])} |"


def report(args, results, aba) -> str:
    lines = [f"{dt.date.today().isoformat()}, {platform.processor() or platform.machine()}, one thread each; "
             f"{args.tools} random Panda tools (solid boxes 0.05-3 kg, seed 2023); SciPy {scipy.__version__}, "
             f"Pinocchio {pin.__version__}, numpy {np.__version__}. toolconf: `examples/model_timing.rs`, method "
             f"`fast`, median of {args.repeat} runs per tool; SciPy: `solve_ivp(RK45, rtol=1e-3, atol=1e-6)` with "
             "`pin.aba` in the right-hand side, once per tool (bench/peers/urdf_loop.py: the same loop, checked "
             "against `toolconf rank`: ln|Π^U| equal, task error within 3.4e-7 with Radau at rtol 1e-8).", ""]
    lines += ["| per tool | mean | p50 | p90 | p99 |", "| --- | ---: | ---: | ---: | ---: |"]
    lines.append(row(f"Pinocchio `aba`, one call from Python [µs]", stats(aba)))
    for task, (ours, theirs) in results.items():
        a, b = stats([t["us"] for t in ours]), stats([t["us"] for t in theirs])
        lines.append(row(f"{task}: toolconf episode [µs]", a))
        lines.append(row(f"{task}: SciPy RK45 + `pin.aba` episode [µs]", b))
        ratio = stats([y["us"] / x["us"] for x, y in zip(ours, theirs)])
        lines.append(f"| {task}: ratio SciPy / toolconf, tool by tool | {ratio['mean']:.0f}× | {ratio['p50']:.0f}× | "
                     f"{ratio['p90']:.0f}× | {ratio['p99']:.0f}× |")
        evals_a = stats([t["rhs_evals"] for t in ours])
        evals_b = stats([t["rhs_evals"] for t in theirs])
        lines.append(f"| {task}: right-hand sides, toolconf / SciPy | {evals_a['mean']:.0f} / {evals_b['mean']:.0f} | "
                     f"{evals_a['p50']:.0f} / {evals_b['p50']:.0f} | {evals_a['p90']:.0f} / {evals_b['p90']:.0f} | "
                     f"{evals_a['p99']:.0f} / {evals_b['p99']:.0f} |")
        diff = stats([abs(x["task_error"] - y["task_error"]) / abs(y["task_error"]) for x, y in zip(ours, theirs)])
        lines.append(f"| {task}: task error, \\|toolconf − SciPy\\| / SciPy | {diff['mean']:.1e} | {diff['p50']:.1e} | "
                     f"{diff['p90']:.1e} | {diff['p99']:.1e} |")
    return "\n".join(lines) + "\n"


def write(text: str) -> None:
    doc = DOC.read_text()
    if BEGIN not in doc or END not in doc:
        raise SystemExit(f"{DOC}: no {BEGIN} ... {END} markers")
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(head + BEGIN + "\n" + text + END + tail)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tools", type=int, default=100)
    ap.add_argument("--tasks", default="position,velocity,examples/tasks/panda_wrist_turn.toml")
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--write", action="store_true")
    args = ap.parse_args()
    tools = random_tools(args.tools)
    aba = aba_times(tools, args.calls)
    results = {}
    for task in args.tasks.split(","):
        results[task] = (toolconf_times(tools, str(ROOT / task) if task.endswith(".toml") else task, args.repeat),
                         scipy_times(tools, str(ROOT / task) if task.endswith(".toml") else task))
    text = report(args, results, aba)
    print(text)
    if args.write:
        write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
