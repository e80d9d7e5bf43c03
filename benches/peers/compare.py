#!/usr/bin/env python3
"""toolconf against two peers on the same episodes: SciPy `solve_ivp(method="RK45")` and CasADi's
`integrator("cvodes")`.

Every peer integrates the same closed loop (the paper's eq. U_dot_deriv on the nonlinear arm),
from the same initial state X0 = [-pi/2 -pi/2 0 0], U0 = [0.1 0.1], over t in [0, 5] with output
every 0.05 s (101 points, t = 0 included), with the same tolerances (rtol 1e-3, atol 1e-6), for the
same tools (`toolconf select --task position --tools 100 --seed 42 --json`). Both peers build the
model from the model description (derive/models/arm2.toml) through toolconf_derive, and the task
sensitivities from derive/tasks.toml via toolconf_derive.numeric.CasadiModel (CasADi AD for A and
B, the task formulas in 50-digit arithmetic), so no model equation is typed twice.

toolconf's metrics come from `toolconf select --json` (task error, RHS evaluations), its timing
from `benches/timing/peer_timing.rs` (one thread, median of repeated runs per tool). Peers are timed
with time.perf_counter around the integration call only (model building, sensitivities and the
task error are outside the timing).

Writes the tables into docs/explanation/performance-peers.md between the `peers` markers (the rest of the file is
left alone) and prints them. Run through benches/peers/run.sh, which creates the environment.

`--population` instead times the population that `benches/population.sh` ranks,
`toolconf select --task position --tools 2000 --seed 1 --json` (`draw_tools(2000, 1)`), on one
thread: per task the mean over tools and p50/p90/p99/max of the per-tool time of SciPy RK45,
CasADi cvodes, toolconf `--method explicit` (ode45-faithful DP5) and toolconf `--method fast`
(the command line's default), all on the same tools: every tool, or every `--stride`-th
(`--stiff-stride` for the stiff task 3, where RK45 needs ~20 000 RHS per tool), starting with
the first. It writes its tables between the `peers-population` markers.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import platform
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np
import scipy
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))
from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402

TOOLCONF = ROOT / "target" / "release" / "toolconf"
PEER_TIMING = ROOT / "target" / "release" / "examples" / "peer_timing"
DOC = ROOT / "docs" / "explanation" / "performance-peers.md"
BEGIN, END = "<!-- peers:begin (written by benches/peers/compare.py) -->", "<!-- peers:end -->"
POP_BEGIN = "<!-- peers-population:begin (written by benches/peers/compare.py --population) -->"
POP_END = "<!-- peers-population:end -->"

T_END, DT = 5.0, 0.05
U0 = 0.1
GAMMA = 1.0  # learning rate (toolconf's default)


def grid() -> np.ndarray:
    """toolconf's uniform_grid(0, 5, 0.05): t_i = i*dt for i < 100, then exactly 5."""
    n = math.ceil(T_END / DT - 1e-9 * T_END / DT)
    return np.array([i * DT for i in range(n)] + [T_END])


# --------------------------------------------------------------------------------------------
# The closed loop, built from the model description.


def python_q_ddot(model):
    """q_ddot(q..., q_dot..., u..., params...) as plain Python on floats, compiled from the
    description's expression strings (the same strings SymPy and CasADi parse)."""
    if model.dynamics_kind != "explicit":
        raise SystemExit(f"compare.py handles explicit models only, {model.name} is {model.dynamics_kind}")
    args = [s.name for s in model.q + model.q_dot + model.u] + [p.name for p in model.parameters]
    body = ", ".join(f"({' '.join(e.split())})" for e in model.q_ddot)
    src = f"def q_ddot({', '.join(args)}):\n    return ({body},)\n"
    ns = {"sin": math.sin, "cos": math.cos, "sqrt": math.sqrt, "pi": math.pi,
          **{c.name: c.value for c in model.constants}}
    exec(compile(src, f"<{model.name} q_ddot>", "exec"), ns)  # noqa: S102 - our own description
    return ns["q_ddot"]


class TaskSetup:
    """A task's goals, precisions and terms, as toolconf's Task::paper builds them."""

    def __init__(self, model, task):
        n = model.dof
        self.task, self.n = task, n
        plain = {"__builtins__": {}, "pi": math.pi}
        goals = model.goals.get(task.name, {})
        self.goal = {term: np.array([float(eval(v, plain)) for v in goals.get(term, ["0"] * n)])  # noqa: S307
                     for term in ("theta", "theta_dot", "theta_ddot")}
        self.precision = {term: task.default_precision.get(term, 0.0) * np.eye(n)
                          for term in ("theta", "theta_dot", "theta_ddot", "u")}
        self.terms = task.sensitivity_terms  # the kinematic terms the controller uses

    def gains(self, cm: CasadiModel, p: np.ndarray) -> dict[str, np.ndarray]:
        """K = S^T P for each kinematic term (zero for terms the task does not use)."""
        s = {term: e.to_numpy() for term, e in cm.sensitivity_exact(self.task, p).items()}
        return {term: (s[term].T @ self.precision[term] if term in s else np.zeros((self.n, self.n)))
                for term in ("theta", "theta_dot", "theta_ddot")}

    def error(self, theta, theta_dot, theta_ddot) -> float:
        """The task's weighted error at one instant (task 1 on theta, 2 on theta_dot, 3 on theta_ddot)."""
        term = {"position": "theta", "velocity": "theta_dot", "acceleration": "theta_ddot"}[self.task.name]
        e = {"theta": theta, "theta_dot": theta_dot, "theta_ddot": theta_ddot}[term] - self.goal[term]
        return float(e @ self.precision[term] @ e)


def scipy_rhs(q_ddot, setup: TaskSetup, params, gains):
    n = setup.n
    k = {t: gains[t].tolist() for t in gains}
    g = {t: setup.goal[t].tolist() for t in setup.goal}
    pu = setup.precision["u"].tolist()
    terms = [(k[t], g[t], t) for t in ("theta", "theta_dot", "theta_ddot") if np.any(gains[t])]
    params = list(params)

    def rhs(_t, z):
        z = z.tolist()
        q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
        qdd = q_ddot(*q, *qd, *u, *params)
        value = {"theta": q, "theta_dot": qd, "theta_ddot": qdd}
        grad = [sum(pu[i][j] * u[j] for j in range(n)) for i in range(n)]
        for kt, gt, t in terms:
            v = value[t]
            for i in range(n):
                grad[i] += sum(kt[i][j] * (v[j] - gt[j]) for j in range(n))
        return qd + list(qdd) + [-GAMMA * gi for gi in grad]

    return rhs


class CasadiClosedLoop:
    """One cvodes integrator per task; the tool's parameters and gains are its parameters."""

    def __init__(self, cm: CasadiModel, setup: TaskSetup, times: np.ndarray, rtol: float, atol: float):
        n, k = setup.n, len(cm.model.parameters)
        z = ca.SX.sym("z", 3 * n)
        p = ca.SX.sym("p", k + 3 * n * n)
        x, u = z[: 2 * n], z[2 * n:]
        f = cm.dynamics.f(x, u, p[:k])  # the CasADi function under the 50-digit evaluator
        value = {"theta": x[:n], "theta_dot": x[n:], "theta_ddot": f[n:]}
        grad = ca.DM(setup.precision["u"]) @ u
        for i, term in enumerate(("theta", "theta_dot", "theta_ddot")):
            gain = ca.reshape(p[k + i * n * n: k + (i + 1) * n * n], n, n)  # column-major
            grad = grad + gain @ (value[term] - ca.DM(setup.goal[term]))
        ode = ca.vertcat(f, -GAMMA * grad)
        self.k, self.n = k, n
        self.integrator = ca.integrator("closed_loop", "cvodes", {"x": z, "p": p, "ode": ode},
                                        float(times[0]), [float(t) for t in times],
                                        {"reltol": rtol, "abstol": atol})

    def parameters(self, params, gains) -> np.ndarray:
        return np.concatenate([np.asarray(params, float)] +
                              [gains[t].flatten(order="F") for t in ("theta", "theta_dot", "theta_ddot")])


# --------------------------------------------------------------------------------------------
# Runs.


def toolconf_json(*args: str) -> dict:
    out = subprocess.run([str(TOOLCONF), *args], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def arm_params(arm: dict) -> list[float]:
    return [arm["m1"], arm["m2"], arm["l1"], arm["l2"]]


def task_error_of(traj: np.ndarray, setup: TaskSetup, q_ddot, params) -> float:
    """Sum over the grid of the task's weighted error; traj is (3n, 101)."""
    n = setup.n
    total = 0.0
    for col in traj.T:
        q, qd, u = col[:n], col[n:2 * n], col[2 * n:]
        qdd = np.array(q_ddot(*q, *qd, *u, *params))
        total += setup.error(q, qd, qdd)
    return total


def run_scipy(q_ddot, setup, params, gains, z0, times, rtol, atol, repeat):
    rhs = scipy_rhs(q_ddot, setup, params, gains)
    elapsed = []
    for _ in range(repeat):
        start = time.perf_counter()
        sol = solve_ivp(rhs, (times[0], times[-1]), z0, method="RK45", rtol=rtol, atol=atol, t_eval=times)
        elapsed.append(time.perf_counter() - start)
    if sol.status != 0:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    return statistics.median(elapsed), sol.nfev, task_error_of(sol.y, setup, q_ddot, params)


def run_cvodes(loop: CasadiClosedLoop, q_ddot, setup, params, gains, z0, repeat):
    pvec = loop.parameters(params, gains)
    elapsed = []
    for _ in range(repeat):
        start = time.perf_counter()
        r = loop.integrator(x0=z0, p=pvec)
        elapsed.append(time.perf_counter() - start)
    stats = loop.integrator.stats()
    traj = np.array(r["xf"])
    return statistics.median(elapsed), int(stats["nfevals"]), int(stats["n_call_jacF"]), \
        task_error_of(traj, setup, q_ddot, params)


def rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def fmt_us(seconds: float) -> str:
    us = seconds * 1e6
    return f"{us:,.1f} µs" if us < 1e4 else f"{us / 1e3:,.1f} ms"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tools", type=int, default=100)
    ap.add_argument("--seed", type=int, default=42)
    ap.add_argument("--scipy-task3-tools", type=int, default=10,
                    help="SciPy RK45 on the stiff task 3 runs on the first N tools only")
    ap.add_argument("--repeat", type=int, default=3, help="runs per tool and peer (median), tasks 1-2")
    ap.add_argument("--toolconf-repeat", type=int, default=21)
    ap.add_argument("--tight-tools", type=int, default=10,
                    help="tools for the agreement check at rtol 1e-8, atol 1e-10 (0: skip)")
    ap.add_argument("--no-write", action="store_true", help="print only, leave docs/explanation/performance-peers.md alone")
    ap.add_argument("--method", default="auto",
                    help="toolconf's integration method in the 100-tool tables (select and peer_timing)")
    ap.add_argument("--population", action="store_true",
                    help="the population table instead (defaults: --tools 2000 --seed 1)")
    ap.add_argument("--tasks", default="position,velocity,acceleration",
                    help="--population: the tasks, comma-separated")
    ap.add_argument("--stride", type=int, default=1,
                    help="--population: time every N-th tool (from the first) on tasks 1 and 2")
    ap.add_argument("--stiff-stride", type=int, default=10,
                    help="--population: time every N-th tool (from the first) on task 3")
    args = ap.parse_args()
    if args.population:
        if "--tools" not in sys.argv[1:]:
            args.tools = 2000
        if "--seed" not in sys.argv[1:]:
            args.seed = 1
        if "--repeat" not in sys.argv[1:]:
            args.repeat = 1
        if "--toolconf-repeat" not in sys.argv[1:]:
            args.toolconf_repeat = 5
    for exe in (TOOLCONF, PEER_TIMING):
        if not exe.exists():
            raise SystemExit(f"{exe} is missing: cargo build --release --bin toolconf --example peer_timing")

    model = load_model(ROOT / "derive" / "models" / "arm2.toml")
    tasks = {t.name: t for t in load_tasks(ROOT / "derive" / "tasks.toml")}
    cm = CasadiModel(model)
    q_ddot = python_q_ddot(model)
    times = grid()
    n = model.dof
    x0 = [float(eval(v, {"__builtins__": {}, "pi": math.pi})) for v in  # noqa: S307
          model.equilibrium_q + model.equilibrium_q_dot]
    z0 = np.array(x0 + [U0] * n)
    rtol, atol = 1e-3, 1e-6

    select = ["--tools", str(args.tools), "--seed", str(args.seed), "--json"]
    base = toolconf_json("select", "--task", "position", *select, "--method", args.method)
    arms = [t["arm"] for t in base["tools"]]
    if args.population:
        text = population(args, model, tasks, cm, q_ddot, times, z0, arms)
        print(text)
        if not args.no_write:
            write_block(text, POP_BEGIN, POP_END, after=END)
        return

    # toolconf's episodes are short, so one timing pass is easily skewed by a burst of load from
    # elsewhere: time them in several passes spread over the run (one before and one after each
    # task's peers) and take, per tool, the median over the passes.
    passes: list[dict] = []

    def time_toolconf() -> None:
        passes.append(json.loads(subprocess.run(
            [str(PEER_TIMING), "--repeat", str(args.toolconf_repeat), "--method", args.method],
            input=json.dumps(base),
            check=True, capture_output=True, text=True).stdout))

    time_toolconf()

    results = {}
    for name in ("position", "velocity", "acceleration"):
        setup = TaskSetup(model, tasks[name])
        tc = toolconf_json("select", "--task", name, *select, "--method", args.method)
        if [t["arm"] for t in tc["tools"]] != arms:
            raise SystemExit(f"select --task {name} drew different tools")
        if any("error" in t for t in tc["tools"]):
            raise SystemExit(f"toolconf failed on a tool for {name}")
        loop = CasadiClosedLoop(cm, setup, times, rtol, atol)
        n_scipy = args.scipy_task3_tools if name == "acceleration" else len(arms)
        rows = []
        for i, arm in enumerate(arms):
            p = arm_params(arm)
            gains = setup.gains(cm, np.array(p))
            row = {"toolconf_error": tc["tools"][i]["task_error"], "toolconf_rhs": tc["tools"][i]["rhs_evals"]}
            row["cvodes_s"], row["cvodes_rhs"], row["cvodes_jac"], row["cvodes_error"] = run_cvodes(
                loop, q_ddot, setup, p, gains, z0, args.repeat)
            if i < n_scipy:
                row["scipy_s"], row["scipy_rhs"], row["scipy_error"] = run_scipy(
                    q_ddot, setup, p, gains, z0, times, rtol, atol, args.repeat if name != "acceleration" else 1)
            rows.append(row)
            print(f"{name} tool {i}: " + ", ".join(f"{k}={v:.6g}" for k, v in row.items()), file=sys.stderr)
        results[name] = rows
        time_toolconf()

    for name, rows in results.items():
        for i, row in enumerate(rows):
            per_pass = [ps[name]["tools"][i]["us"] for ps in passes]
            row["toolconf_s"] = statistics.median(per_pass) * 1e-6
            row["toolconf_jac"] = passes[0][name]["tools"][i].get("jacobian_evals", 0)
            if any(ps[name]["tools"][i]["task_error"] != row["toolconf_error"] for ps in passes):
                raise SystemExit(f"peer_timing and select disagree on {name} tool {i}")

    tight = {}
    if args.tight_tools > 0:
        t_rtol, t_atol = 1e-8, 1e-10
        sel = ["--tools", str(args.tight_tools), "--seed", str(args.seed), "--json",
               "--rtol", str(t_rtol), "--atol", str(t_atol)]
        for name in ("position", "velocity", "acceleration"):
            setup = TaskSetup(model, tasks[name])
            tc = toolconf_json("select", "--task", name, *sel, "--method", args.method)
            loop = CasadiClosedLoop(cm, setup, times, t_rtol, t_atol)
            rows = []
            for i, t in enumerate(tc["tools"]):
                p = arm_params(t["arm"])
                gains = setup.gains(cm, np.array(p))
                row = {"toolconf_error": t["task_error"]}
                *_, row["cvodes_error"] = run_cvodes(loop, q_ddot, setup, p, gains, z0, 1)
                if name != "acceleration" or i < 3:
                    *_, row["scipy_error"] = run_scipy(q_ddot, setup, p, gains, z0, times, t_rtol, t_atol, 1)
                rows.append(row)
                print(f"tight {name} tool {i}: {row}", file=sys.stderr)
            tight[name] = rows

    text = render(results, tight, args)
    print(text)
    if not args.no_write:
        write_doc(text)


# --------------------------------------------------------------------------------------------
# The population: ranking throughput per tool.

POP_METHODS = ("explicit", "fast")


def load_average() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def quantile(sorted_values: list[float], q: float) -> float:
    """benches/timing/population.rs's: the element at round((n - 1) q)."""
    return sorted_values[round((len(sorted_values) - 1) * q)]


def time_toolconf_methods(name: str, sub_arms: list, repeat: int, order) -> dict:
    """One pass of peer_timing per method (in `order`) on `sub_arms`; per method its output."""
    out = {}
    for method in order:
        out[method] = json.loads(subprocess.run(
            [str(PEER_TIMING), "--tasks", name, "--method", method, "--repeat", str(repeat)],
            input=json.dumps(sub_arms), check=True, capture_output=True, text=True).stdout)[name]
    return out


def population(args, model, tasks, cm, q_ddot, times, z0, arms) -> str:
    rtol, atol = 1e-3, 1e-6
    results = {}
    for name in args.tasks.split(","):
        stride = args.stiff_stride if name == "acceleration" else args.stride
        indices = list(range(0, len(arms), stride))
        sub_arms = [arms[i] for i in indices]
        setup = TaskSetup(model, tasks[name])
        loop = CasadiClosedLoop(cm, setup, times, rtol, atol)
        load_before = load_average()
        # toolconf: two passes per method before the peers and two after, the methods in turn,
        # so that drift of the shared machine hits both alike; per tool the median over passes.
        passes = [time_toolconf_methods(name, sub_arms, args.toolconf_repeat, POP_METHODS),
                  time_toolconf_methods(name, sub_arms, args.toolconf_repeat, POP_METHODS[::-1])]
        rows = []
        started = time.perf_counter()
        for k, (i, arm) in enumerate(zip(indices, sub_arms)):
            p = arm_params(arm)
            gains = setup.gains(cm, np.array(p))
            row = {"tool": i}
            row["cvodes_s"], row["cvodes_rhs"], row["cvodes_jac"], row["cvodes_error"] = run_cvodes(
                loop, q_ddot, setup, p, gains, z0, 3)
            row["scipy_s"], row["scipy_rhs"], row["scipy_error"] = run_scipy(
                q_ddot, setup, p, gains, z0, times, rtol, atol, args.repeat)
            rows.append(row)
            if k % 100 == 0 or k == len(sub_arms) - 1:
                print(f"{name}: {k + 1}/{len(sub_arms)} tools, {time.perf_counter() - started:.0f} s", file=sys.stderr)
        passes += [time_toolconf_methods(name, sub_arms, args.toolconf_repeat, POP_METHODS),
                   time_toolconf_methods(name, sub_arms, args.toolconf_repeat, POP_METHODS[::-1])]
        for method in POP_METHODS:
            first = passes[0][method]["tools"]
            for k, row in enumerate(rows):
                row[f"{method}_s"] = statistics.median(ps[method]["tools"][k]["us"] for ps in passes) * 1e-6
                row[f"{method}_rhs"] = first[k]["rhs_evals"]
                row[f"{method}_jac"] = first[k]["jacobian_evals"]
                row[f"{method}_error"] = first[k]["task_error"]
                if any(ps[method]["tools"][k]["task_error"] != row[f"{method}_error"] for ps in passes):
                    raise SystemExit(f"peer_timing --method {method} is not deterministic on {name} tool {row['tool']}")
        results[name] = {"rows": rows, "stride": stride, "load": (load_before, load_average())}
    return render_population(results, args, len(arms))


def ratio(r: float) -> str:
    return f"{r:,.2f}" if r < 10 else f"{r:,.0f}"


def commit() -> str:
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT)
    dirty = subprocess.run(["git", "diff", "--quiet"], cwd=ROOT).returncode != 0
    return head.stdout.strip() + (" (with local changes)" if dirty else "")


def opening(begin: str, measured_on: str, tools: int, seed: int, setup: str) -> list[str]:
    """A table block's first lines: its `begin` marker, when and where it was measured, and the
    command, the tools `toolconf select` drew and the `setup` of the episodes, in one paragraph."""
    cmd = "benches/peers/run.sh" + "".join(" " + shlex.quote(a) for a in sys.argv[1:])
    return [
        begin,
        "",
        f"Measured {dt.date.today().isoformat()} on {measured_on}.",
        "",
        f"Command: `{cmd}` (from the repository root). Tools: `toolconf select --task position "
        f"--tools {tools} --seed {seed} --json`" + setup,
        "",
    ]


def render_population(results: dict, args, n_tools: int) -> str:
    out = opening(
        POP_BEGIN, f"{machine()}, commit {commit()}; {versions()}", n_tools, args.seed,
        f" (`draw_tools({n_tools}, {args.seed})`, the population "
        "of `benches/population.sh`), every episode as in the tables above (rtol 1e-3, atol 1e-6, "
        "101 output points). On a subsample (stride N > 1: tools 0, N, 2N, … of the population, "
        "the same tools for every row) the means are over the subsample. Time per tool on one "
        f"thread: SciPy RK45 {f'the median of {args.repeat} runs' if args.repeat > 1 else 'one run'} per tool, "
        f"cvodes the median of 3 runs, toolconf the median of "
        f"{args.toolconf_repeat} runs per tool (`benches/timing/peer_timing.rs --method`) in 4 passes, "
        "two before and two after the peers, the methods in turn (median over passes). Columns: mean "
        "over tools of the per-tool time, its percentiles (the element at round((n − 1) q) of the "
        "sorted times, as `benches/timing/population.rs`), mean RHS (and Jacobian) evaluations per tool "
        "(counted as in the tables above), the mean time over toolconf `fast`'s mean on the same "
        "tools, and the task error's relative difference from toolconf `explicit` (median / max).")
    labels = (("fast", "toolconf `--method fast` (default)"),
              ("explicit", "toolconf `--method explicit` (ode45 DP5)"),
              ("scipy", "SciPy `solve_ivp` RK45"),
              ("cvodes", "CasADi `cvodes` (BDF)"))
    for index, name in ((1, "position"), (2, "velocity"), (3, "acceleration")):
        if name not in results:
            continue
        rows, stride = results[name]["rows"], results[name]["stride"]
        load_before, load_after = results[name]["load"]
        which = (f"all {len(rows)} tools" if stride == 1
                 else f"every {stride}th tool: {len(rows)} of {n_tools}")
        out += [f"### Population, task {index} ({name}), {which}", "",
                f"Load average {load_before} before this task, {load_after} after.", "",
                "| | mean per tool | p50 | p90 | p99 | max | mean RHS | mean / toolconf fast | "
                "task-error rel. difference from toolconf explicit (median / max) |",
                "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        fast_mean = statistics.fmean(r["fast_s"] for r in rows)
        for key, label in labels:
            t = sorted(r[f"{key}_s"] for r in rows)
            mean = statistics.fmean(t)
            rhs = statistics.fmean(r[f"{key}_rhs"] for r in rows)
            jac = statistics.fmean(r.get(f"{key}_jac", 0) for r in rows)
            work = f"{rhs:,.0f}" + (f" + {jac:,.1f} Jac." if jac else "")
            if key == "explicit":
                agree = "—"
            else:
                d = [rel(r[f"{key}_error"], r["explicit_error"]) for r in rows]
                agree = f"{statistics.median(d):.1e} / {max(d):.1e}"
            out.append(f"| {label} | {fmt_us(mean)} | {fmt_us(quantile(t, 0.5))} | {fmt_us(quantile(t, 0.9))} | "
                       f"{fmt_us(quantile(t, 0.99))} | {fmt_us(t[-1])} | {work} | {ratio(mean / fast_mean)}× | {agree} |")
        out.append("")
    out.append(POP_END)
    return "\n".join(out)


def machine() -> str:
    model_name = ""
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name:"):
                model_name = line.split(":", 1)[1].strip()
    except OSError:
        pass
    nproc = subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip()
    return f"`nproc` = {nproc}, `lscpu` model name: {model_name or 'unknown'}"


def versions() -> str:
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    return (f"{rustc}; Python {platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
            f"CasADi {ca.__version__}")


def render(results: dict, tight: dict, args) -> str:
    out = opening(
        BEGIN, f"{machine()}; {versions()}", args.tools, args.seed,
        ". Every episode: the paper's closed loop at "
        "the defaults (X0 = [-π/2 -π/2 0 0], U0 = [0.1 0.1], γ = 1, ΔT = 0), t ∈ [0, 5] with output "
        "every 0.05 s (101 points), rtol 1e-3, atol 1e-6; toolconf with "
        + ("`EpisodeOptions::default()`, i.e. the library's default integration method, `--method auto` "
           "(DP5 with ode45's step control on tasks 1 and 2; see `crates/integrators` for task 3)"
           if args.method == "auto" else f"`--method {args.method}`")
        + ". Times are per episode on one thread: "
        f"toolconf the median of {args.toolconf_repeat} runs per tool (`benches/timing/peer_timing.rs`), in "
        "4 passes spread over the run (median over passes), the "
        f"peers the median of {args.repeat} runs per tool (1 for SciPy on task 3) around the "
        "integration call only; the table gives the median over tools. RHS = closed-loop right-hand-side "
        "evaluations (toolconf: the integrator's count, without the 101 evaluations for θ̈ on the grid, "
        "plus its Jacobian evaluations if any; "
        "SciPy: `sol.nfev`; cvodes: `nfevals` from `stats()`, which excludes its Jacobian evaluations, "
        "given separately). Agreement: |e_toolconf − e_peer| / |e_peer| of the task error "
        "(Σ over the 101 grid points of the task's weighted error).")
    for index, name in enumerate(("position", "velocity", "acceleration"), start=1):
        rows = results[name]
        tc_t = statistics.median(r["toolconf_s"] for r in rows)
        tc_rhs = statistics.median(r["toolconf_rhs"] for r in rows)
        jac = statistics.median(r["toolconf_jac"] for r in rows)
        tc_jac = f" + {jac:,.0f} Jacobians" if jac else ""
        out += [f"### Task {index} ({name}), {len(rows)} tools", "",
                "| | time per episode (median) | RHS evaluations (median) | toolconf speed-up | "
                "task-error rel. difference (median / max) |",
                "|---|---:|---:|---:|---:|",
                f"| toolconf | {fmt_us(tc_t)} | {tc_rhs:,.0f}{tc_jac} | — | — |"]
        for peer, label in (("scipy", "SciPy `solve_ivp` RK45"), ("cvodes", "CasADi `cvodes` (BDF)")):
            sub = [r for r in rows if f"{peer}_s" in r]
            t = statistics.median(r[f"{peer}_s"] for r in sub)
            # Speed-up on the same tools as the peer ran.
            t_tc = statistics.median(r["toolconf_s"] for r in sub)
            rhs = statistics.median(r[f"{peer}_rhs"] for r in sub)
            d = [rel(r["toolconf_error"], r[f"{peer}_error"]) for r in sub]
            note = f" (first {len(sub)} tools)" if len(sub) < len(rows) else ""
            jac = (f" + {statistics.median(r['cvodes_jac'] for r in sub):,.0f} Jacobians"
                   if peer == "cvodes" else "")
            out.append(f"| {label}{note} | {fmt_us(t)} | {rhs:,.0f}{jac} | {t / t_tc:,.0f}× | "
                       f"{statistics.median(d):.1e} / {max(d):.1e} |")
        out.append("")
    if tight:
        out += ["### Agreement at tight tolerances (rtol 1e-8, atol 1e-10)", "",
                "The same episodes with all three integrators at rtol 1e-8, atol 1e-10: if the task errors "
                "agree much better than at rtol 1e-3, the differences above are the integrators' "
                "tolerance-bounded errors, not a difference in the model or the controller.", "",
                "| task | tools | vs SciPy RK45 (median / max) | vs CasADi cvodes (median / max) |",
                "|---|---:|---:|---:|"]
        for index, name in enumerate(("position", "velocity", "acceleration"), start=1):
            rows = tight[name]
            cells = []
            for peer in ("scipy", "cvodes"):
                d = [rel(r["toolconf_error"], r[f"{peer}_error"]) for r in rows if f"{peer}_error" in r]
                cells.append(f"{statistics.median(d):.1e} / {max(d):.1e} ({len(d)} tools)")
            out.append(f"| {index} ({name}) | {len(rows)} | {cells[0]} | {cells[1]} |")
        out.append("")
    out.append(END)
    return "\n".join(out)


def write_block(text: str, begin: str, end: str, after: str) -> None:
    """Replaces the block between `begin` and `end` in docs/explanation/performance-peers.md, or inserts it after
    the line holding `after` (with a blank line before it)."""
    doc = DOC.read_text()
    if begin in doc and end in doc:
        head, rest = doc.split(begin, 1)
        _, tail = rest.split(end, 1)
        DOC.write_text(head + text + tail)
    elif after in doc:
        head, tail = doc.split(after, 1)
        DOC.write_text(head + after + "\n\n" + text + tail)
    else:
        DOC.write_text(doc.rstrip("\n") + "\n\n" + text + "\n")


def write_doc(text: str) -> None:
    if DOC.exists():
        doc = DOC.read_text()
        if BEGIN in doc and END in doc:
            head, rest = doc.split(BEGIN, 1)
            _, tail = rest.split(END, 1)
            DOC.write_text(head + text + tail)
            return
        DOC.write_text(doc.rstrip("\n") + "\n\n## Peers\n\n" + text + "\n")
        return
    DOC.write_text("# Performance\n\n## Peers\n\n" + text + "\n")


if __name__ == "__main__":
    os.chdir(ROOT)
    main()
