#!/usr/bin/env python3
"""toolconf against what a Python user would otherwise write for a URDF arm, on one population of
tools, side by side in one run: SciPy's `solve_ivp(method="RK45")` with Pinocchio's `aba` in the
right-hand side on the same closed loop (urdf_loop.py: the same plant, impedance, controller,
formulation and tolerances, rtol 1e-3, atol 1e-6; on a tip task the tip observed with Pinocchio's
frame kinematics), and one Pinocchio `aba` call from Python.

The population: `--tools` random physical Panda tools (solid boxes, panda_study.random_tools,
seed 2023), each with its tip at the centre of the box's far face along the flange z,
(com_x, com_y, com_z + c/2), c the box's side along z (from its inertia: c^2 = 6 (ixx + iyy -
izz) / m), written to a temporary tools file (with tool_tip_x/y/z, products of inertia zero) that
toolconf's `benches/timing/model_timing.rs` times on one thread (median of `--repeat` runs per tool, the
default `fast` method, what `toolconf rank` runs). SciPy is timed with time.perf_counter around
`solve_ivp` only (model building, gains and metrics outside), once per tool; `aba` as the median
over `--calls` calls per tool at a random state. Per task: mean and p50/p90/p99 of the per-tool
times, the ratio, and how far the two task errors are apart (relative).

The reference: every tool's task error from toolconf's `explicit` DP5 at rtol 1e-10, atol 1e-12;
a row gives how far each side's task error at rtol 1e-3 is from it (relative).

Before timing, each task is checked on the first `--check` tools with both integrated tightly
(toolconf's `explicit` DP5 and SciPy's DOP853, rtol 1e-10, atol 1e-12; toolconf's tolerances
through a copy of the task file with them in its [episode]): the largest relative difference of
ln|Pi^U| and of the task error, a table of its own.

    benches/peers/run.sh --urdf [--tools 100] [--tasks position,velocity,...] [--check 5] [--write]

`--tools-for TASK=N` times task TASK (as written in --tasks) on the first N tools only.
--write puts the tables into docs/explanation/performance-peers.md between the `peers-urdf` markers.
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
from panda_study import random_tools, write_between  # noqa: E402
from pin_robot import ROOT, model_with_tool  # noqa: E402
from urdf_loop import ClosedLoop, Task  # noqa: E402

MODEL_TIMING = ROOT / "target" / "release" / "examples" / "model_timing"
DOC = ROOT / "docs" / "explanation" / "performance-peers.md"
BEGIN, END = "<!-- peers-urdf:begin (written by benches/peers/urdf_peers.py) -->", "<!-- peers-urdf:end -->"
ROBOT = "panda"
TASKS = ("position", "velocity", "examples/tasks/panda_wrist_turn.toml", "examples/tasks/panda_touch_point.toml",
         "examples/tasks/panda_draw_line.toml", "examples/tasks/panda_push_off.toml")


def stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    return {"mean": float(v.mean()), "p50": float(np.percentile(v, 50)), "p90": float(np.percentile(v, 90)),
            "p99": float(np.percentile(v, 99))}


TOOL_COLUMNS = ("tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz,tool_ixy,tool_ixz,tool_iyz,"
                "tool_tip_x,tool_tip_y,tool_tip_z")
# The check's tolerances: toolconf's `explicit` DP5 against SciPy's DOP853.
CHECK_RTOL, CHECK_ATOL = 1e-10, 1e-12


def with_tips(tools) -> list[list[float]]:
    """Each solid box (mass, com, principal moments) with its tip at the centre of its far face
    along the flange z: (com_x, com_y, com_z + c/2), its side c from c^2 = 6 (ixx + iyy - izz) / m;
    the products of inertia zero."""
    out = []
    for m, cx, cy, cz, ixx, iyy, izz in tools:
        c = float(np.sqrt(6.0 * (ixx + iyy - izz) / m))
        out.append([m, cx, cy, cz, ixx, iyy, izz, 0.0, 0.0, 0.0, cx, cy, cz + 0.5 * c])
    return out


def toolconf_run(tools, task: str, repeat: int, method: str | None = None) -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "tools.csv"
        path.write_text(f"model,{TOOL_COLUMNS}\n" + "".join(f"{ROBOT}," + ",".join(repr(float(x)) for x in t) + "\n"
                                                          for t in tools))
        command = [str(MODEL_TIMING), "--tools", str(path), "--task", task, "--repeat", str(repeat)]
        out = subprocess.run(command + (["--method", method] if method else []),
                             check=True, capture_output=True, text=True).stdout
    return json.loads(out)["tools"]


def task_path(name: str) -> str:
    return str(ROOT / name) if name.endswith(".toml") else name


def task_for(name: str) -> Task:
    path = Path(task_path(name))
    return Task.from_file(ROBOT, path) if path.suffix == ".toml" else Task.paper(ROBOT, name)


def scipy_run(tools, task: str, method: str = "RK45", rtol: float | None = None,
              atol: float | None = None) -> list[dict]:
    out = []
    for tool in tools:
        loop = ClosedLoop(ROBOT, tool, task_for(task))
        start = time.perf_counter()
        grid, states = loop.integrate(method, rtol, atol)
        seconds = time.perf_counter() - start
        m = loop.metrics(grid, states)
        out.append({"us": seconds * 1e6, "rhs_evals": m["rhs_evals"], "task_error": m["task_error"],
                    "logdet": m["logdet"]})
    return out


def tight_task_file(task: str, folder: Path) -> str:
    """The task (a name or a task file) as a task file with the check's tolerances in its [episode]."""
    lines = (Path(task_path(task)).read_text().splitlines() if task.endswith(".toml")
             else [f'kind = "{task}"'])
    tolerances = [f"rtol = {CHECK_RTOL!r}", f"atol = {CHECK_ATOL!r}"]
    if "[episode]" in lines:
        i = lines.index("[episode]") + 1
        lines[i:i] = tolerances
    else:
        lines += ["[episode]", *tolerances]
    path = folder / f"tight_{Path(task).stem}.toml"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def check(tools, task: str) -> dict:
    """ln|Pi^U| and the task error of toolconf and the peer on `tools`, both integrated tightly:
    the largest relative differences."""
    with tempfile.TemporaryDirectory() as tmp:
        ours = toolconf_run(tools, tight_task_file(task, Path(tmp)), 1, "explicit")
    theirs = scipy_run(tools, task, "DOP853", CHECK_RTOL, CHECK_ATOL)
    rel = lambda a, b: abs(a - b) / abs(b)  # noqa: E731
    return {"tools": len(tools),
            "logdet": max(rel(x["logdet"], y["logdet"]) for x, y in zip(ours, theirs)),
            "task_error": max(rel(x["task_error"], y["task_error"]) for x, y in zip(ours, theirs))}


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


def report(args, results, aba, checks) -> str:
    fewer = "".join(f"; {task} on the first {n}" for task, n in args.tools_for.items())
    lines = [f"{dt.date.today().isoformat()}, {platform.processor() or platform.machine()}, one thread each; "
             f"{args.tools} random Panda tools (solid boxes 0.05-3 kg, seed 2023, the tip at the centre of the "
             f"box's far face along the flange z{fewer}); SciPy {scipy.__version__}, "
             f"Pinocchio {pin.__version__}, numpy {np.__version__}. toolconf: `benches/timing/model_timing.rs`, method "
             f"`fast`, median of {args.repeat} runs per tool; SciPy: `solve_ivp(RK45, rtol=1e-3, atol=1e-6)` with "
             "`pin.aba` in the right-hand side (and Pinocchio's frame kinematics on a tip task), once per tool "
             "(benches/peers/urdf_loop.py: the same loop and formulation). The tight reference of the task error: "
             f"toolconf's `explicit` DP5 at rtol {CHECK_RTOL:g}, atol {CHECK_ATOL:g}, which the same loop in SciPy's "
             "DOP853 at those tolerances matches (the second table).", ""]
    lines += ["| per tool | mean | p50 | p90 | p99 |", "| --- | ---: | ---: | ---: | ---: |"]
    lines.append(row(f"Pinocchio `aba`, one call from Python [µs]", stats(aba)))
    for task, (ours, theirs, reference) in results.items():
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
        off_a, off_b = (stats([abs(x["task_error"] - r["task_error"]) / abs(r["task_error"])
                               for x, r in zip(run, reference)]) for run in (ours, theirs))
        lines.append(f"| {task}: task error against the tight reference, toolconf / SciPy | "
                     + " | ".join(f"{off_a[k]:.1e} / {off_b[k]:.1e}" for k in ("mean", "p50", "p90", "p99")) + " |")
    if checks:
        lines += ["", "The check, both integrated tightly (toolconf `explicit` DP5, SciPy DOP853; "
                  f"rtol {CHECK_RTOL:g}, atol {CHECK_ATOL:g}), on the first tools of the population: the largest "
                  "relative difference.", "",
                  "| task | tools | ln\\|Π^U\\| | task error |", "| --- | ---: | ---: | ---: |"]
        for task, c in checks.items():
            lines.append(f"| {task} | {c['tools']} | {c['logdet']:.1e} | {c['task_error']:.1e} |")
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tools", type=int, default=100)
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--tools-for", action="append", default=[], metavar="TASK=N",
                    help="time TASK on the first N tools only (repeatable)")
    ap.add_argument("--check", type=int, default=5, help="tools per task of the tight check (0: none)")
    ap.add_argument("--repeat", type=int, default=11)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--write", action="store_true")
    args = ap.parse_args()
    args.tools_for = {k: int(v) for k, v in (item.rsplit("=", 1) for item in args.tools_for)}
    tools = with_tips(random_tools(args.tools))
    tasks = args.tasks.split(",")
    checks = {}
    for task in tasks if args.check > 0 else ():
        checks[task] = check(tools[:args.check], task)
        print(f"check {task}: {checks[task]}", file=sys.stderr)
    aba = aba_times(tools, args.calls)
    results = {}
    for task in tasks:
        some = tools[:args.tools_for.get(task, len(tools))]
        with tempfile.TemporaryDirectory() as tmp:
            reference = toolconf_run(some, tight_task_file(task, Path(tmp)), 1, "explicit")
        results[task] = (toolconf_run(some, task_path(task), args.repeat), scipy_run(some, task), reference)
        print(f"timed {task}", file=sys.stderr)
    text = report(args, results, aba, checks)
    print(text)
    if args.write:
        write_between(DOC, BEGIN, END, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
