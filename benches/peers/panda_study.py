#!/usr/bin/env python3
"""What drives the Panda's control confidence under joint impedance, and does it predict task
error? The sweep behind docs/explanation/static-gain.md, "Confidence and task error on the Panda".

For random physical tools (solid boxes: 0.05-3 kg, centre of mass within 5 cm of the flange axis
and up to 25 cm out, sides 1-30 cm; seeded) it takes ln|Pi^U| in closed form and simulates each
tool's episode with the closed loop of urdf_loop.py (Pinocchio's aba, toolconf's controller,
its ln|Pi^U| equal to `toolconf rank`'s and its task error within 3.4e-7 of it on the wrist turn), integrated by SciPy's Radau
with Pinocchio's ABA derivatives at rtol 1e-8, atol 1e-10: far below the tool-to-tool spread of
the task error, which is ~1e-5 relative with the paper's precisions. Per setting it reports the
spread of ln|Pi^U| (standard deviation, max - min), Spearman's rho between ln|Pi^U| and the task
error (and each with the tool's mass), how far the arm got toward its goal (the mean over tools of
(theta(t_end) - q^e) . delta / |delta|^2, delta = goal - q^e; velocity: the final joint-7 speed over
its goal), and how many episodes failed.

Settings: the impedance K scaled by s with D by sqrt(s) (the damping ratio kept), D alone scaled,
the paper's precisions against precisions in physical units (below), the paper's goals against
goals within the Panda's rated torques.

    benches/peers/.venv/bin/python benches/peers/panda_study.py [--tools 200] [--workers 2] [--sweep impedance|precision] [--write]

--write puts the table into docs/explanation/static-gain.md between the `impedance-study` (or `precision-study`) markers.
--sweep precision varies the wrist turn's precisions (sigma_theta_dot, P^theta_ddot, sigma_U) at
libfranka's K and D instead (velocity task only).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pin_robot import ROOT, description, model_with_tool  # noqa: E402
from urdf_loop import ClosedLoop, Task  # noqa: E402

DOC = ROOT / "docs" / "explanation" / "static-gain.md"
BEGIN, END = "<!-- impedance-study:begin (written by benches/peers/panda_study.py) -->", "<!-- impedance-study:end -->"
RTOL, ATOL = 1e-8, 1e-10
ROBOT = "panda"
# The study measured the paper's task formulas (derive/tasks.toml's own, E = [I; I] on position),
# before toolconf made the static gain the URDF arms' position formulation (docs/explanation/static-gain.md, "The
# static gain"); urdf_loop's default is toolconf's, so the study names the paper's.
PAPER = "paper"


def random_tools(count: int, seed: int = 2023) -> list[list[float]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        m = rng.uniform(0.05, 3.0)
        com = [rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.25)]
        a, b, c = rng.uniform(0.01, 0.30, 3)
        out.append([m, *com, m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12])
    return out


def rated_torques() -> np.ndarray:
    """The URDF's effort limits (N m): Panda 87 on joints 1-4, 12 on 5-7."""
    model, _ = model_with_tool(ROBOT, [1.0, 0, 0, 0.05, 1e-3, 1e-3, 1e-3])
    return np.array(model.effortLimit, dtype=float)


def physical(kind: str) -> Task:
    """Precisions as 1/sigma^2 of stated tolerances, goals the rated torques allow under K.

    Position: sigma_theta = 0.01 rad (about 8 mm at the Panda's 0.8 m reach), sigma_theta_dot =
    0.1 rad/s, sigma_theta_ddot = 1 rad/s^2, sigma_U = 10 % of each joint's rated torque; the goal
    0.05 rad from q^e on joints 1, 2, 4, 6 (K delta = 30 N m, 7.5 N m: within 87 and 12 N m).
    Velocity: joint 7 at 0.04 rad/s (0.2 rad in 5 s, K_7 * 0.2 = 10 N m within its 12),
    sigma_theta_dot = 0.01 rad/s, the rest as for position. U0 = 0: the set point holds the arm."""
    t = Task.paper(ROBOT, kind, PAPER)
    n = len(t.goal["theta"])
    d = description(ROBOT)
    t.precision["u"] = np.diag(1.0 / (0.1 * rated_torques()) ** 2)
    t.precision["theta_ddot"] = np.eye(n)
    if kind == "position":
        t.goal["theta"] = d.q_e + np.array([0.05, 0.05, 0, 0.05, 0, 0.05, 0])
        t.precision["theta"], t.precision["theta_dot"] = 1e4 * np.eye(n), 100.0 * np.eye(n)
    else:
        t.goal["theta_dot"] = np.array([0, 0, 0, 0, 0, 0, 0.04])
        t.precision["theta_dot"] = 1e4 * np.eye(n)
    t.u0 = np.zeros(n)
    return t


def velocity_precisions(sigma_theta_dot: float, theta_ddot: float, u_fraction: float) -> Task:
    """The wrist turn's task (physical("velocity")) with sigma_theta_dot [rad/s], P^theta_ddot and
    sigma_U = u_fraction of each joint's rated torque changed: the precision sweep."""
    t = physical("velocity")
    n = len(t.goal["theta_dot"])
    t.precision["theta_dot"] = np.eye(n) / sigma_theta_dot ** 2
    t.precision["theta_ddot"] = theta_ddot * np.eye(n)
    t.precision["u"] = np.diag(1.0 / (u_fraction * rated_torques()) ** 2)
    return t


def episode(job):
    tool, kind, precisions, k_scale, d_scale = job
    if isinstance(precisions, tuple):
        task = velocity_precisions(*precisions)
    else:
        task = Task.paper(ROBOT, kind, PAPER) if precisions == "paper" else physical(kind)
    loop = ClosedLoop(ROBOT, tool, task, k_scale, d_scale)
    out = {"logdet": loop.logdet, "mass": tool[0]}
    try:
        grid, states = loop.integrate("Radau", RTOL, ATOL, max_evals=30_000)
        if not np.all(np.isfinite(states)) or np.max(np.abs(states)) > 1e6:
            raise RuntimeError("diverged")
    except (RuntimeError, ValueError) as e:
        out["error"] = str(e)
        return out
    m = loop.metrics(grid, states)
    out["task_error"] = m["task_error"]
    n = loop.n
    end = states[-1]
    if kind == "position":
        delta = task.goal["theta"] - loop.q_e
        out["progress"] = float((end[:n] - loop.q_e) @ delta / (delta @ delta))
    else:
        out["progress"] = float(end[n + 6] / task.goal["theta_dot"][6])
    return out


def spearman(a, b) -> float:
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1]) if np.std(a) > 0 and np.std(b) > 0 else float("nan")


SETTINGS = [
    # (label, K scale, D scale)
    ("libfranka (K, D)", 1.0, 1.0),
    ("0.1 K, 0.32 D", 0.1, math.sqrt(0.1)),
    ("0.3 K, 0.55 D", 0.3, math.sqrt(0.3)),
    ("3 K, 1.7 D", 3.0, math.sqrt(3.0)),
    ("K, 0.1 D", 1.0, 0.1),
    ("K, 0.01 D", 1.0, 0.01),
]


# The precision sweep (velocity, the wrist turn's goal, libfranka's K and D): (sigma_theta_dot
# [rad/s], P^theta_ddot, sigma_U as a fraction of the rated torque); the wrist turn's is (0.01, 1, 0.1).
PRECISIONS = [(0.1, 1.0, 0.1), (0.03, 1.0, 0.1), (0.01, 1.0, 0.1), (0.003, 1.0, 0.1),
              (0.01, 0.0, 0.1), (0.01, 1.0, 0.03), (0.01, 1.0, 0.3)]


def precision_label(p) -> str:
    return f"σ_θ̇ {p[0]:g} rad/s, P^θ̈ {p[1]:g}, σ_U {100 * p[2]:g} % rated"


def rows(tools, workers, sweep="impedance"):
    jobs, keys = [], []
    if sweep == "precision":
        for p in PRECISIONS:
            keys.append(("velocity", precision_label(p), "libfranka (K, D)"))
            jobs += [(t, "velocity", p, 1.0, 1.0) for t in tools]
    for kind in ("position", "velocity") if sweep == "impedance" else ():
        for precisions in ("paper", "physical"):
            for label, ks, ds in SETTINGS:
                if precisions == "physical" and label not in ("libfranka (K, D)", "0.1 K, 0.32 D"):
                    continue
                keys.append((kind, precisions, label))
                jobs += [(t, kind, precisions, ks, ds) for t in tools]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(episode, jobs, chunksize=8))
    out = []
    for i, key in enumerate(keys):
        rs = results[i * len(tools):(i + 1) * len(tools)]
        logdet = np.array([r["logdet"] for r in rs])
        ok = [r for r in rs if "error" in r] == []
        done = [r for r in rs if "error" not in r]
        row = {"key": key, "std": float(np.std(logdet)), "range": float(np.ptp(logdet)),
               "rho_mass_logdet": spearman([r["mass"] for r in rs], logdet), "failed": len(rs) - len(done)}
        if len(done) >= 3:
            err = np.array([r["task_error"] for r in done])
            row.update(rho=spearman([r["logdet"] for r in done], err),
                       rho_mass_error=spearman([r["mass"] for r in done], err),
                       error_spread=float(np.ptp(err) / np.mean(err)),
                       progress=float(np.mean([r["progress"] for r in done])))
        row["all_finite"] = ok
        out.append(row)
    return out


def table(results, count) -> str:
    lines = [f"{count} random tools per row; Radau at rtol {RTOL:g}, atol {ATOL:g}. rho: Spearman's rank "
             "correlation; *progress*: how far the arm got toward the goal at t = 5 s (1 = there, < 0 = away "
             "from it; velocity: joint 7's final speed over its goal); *spread*: (max - min)/mean of the task error.",
             "",
             "| task | precisions | impedance | std ln\\|Π^U\\| | range | ρ(ln\\|Π^U\\|, task error) | ρ(mass, ln\\|Π^U\\|) "
             "| ρ(mass, task error) | task-error spread | progress | failed |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in results:
        kind, precisions, label = r["key"]
        fmt = lambda key, f: (f.format(r[key]) if key in r else "—")  # noqa: E731
        lines.append(f"| {kind} | {precisions} | {label} | {r['std']:.2e} | {r['range']:.2e} | {fmt('rho', '{:+.2f}')} "
                     f"| {r['rho_mass_logdet']:+.2f} | {fmt('rho_mass_error', '{:+.2f}')} | "
                     f"{fmt('error_spread', '{:.1e}')} | {fmt('progress', '{:+.3f}')} | {r['failed']} |")
    return "\n".join(lines) + "\n"


def write_between(doc: Path, begin: str, end: str, text: str) -> None:
    """`text` in place of what stands between the markers `begin` and `end` of page `doc`."""
    page = doc.read_text()
    if begin not in page or end not in page:
        raise SystemExit(f"{doc}: no {begin} ... {end} markers")
    head, rest = page.split(begin, 1)
    _, tail = rest.split(end, 1)
    doc.write_text(head + begin + "\n" + text + end + tail)


def write(text: str, sweep: str) -> None:
    begin, end = (BEGIN, END) if sweep == "impedance" else (BEGIN.replace("impedance", "precision"),
                                                             END.replace("impedance", "precision"))
    write_between(DOC, begin, end, text)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tools", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sweep", choices=("impedance", "precision"), default="impedance",
                    help="impedance: K and D scaled, paper's vs physical precisions; precision: the wrist turn's "
                         "precisions varied at libfranka's K and D")
    ap.add_argument("--write", action="store_true", help="write the table into docs/explanation/static-gain.md")
    args = ap.parse_args()
    start = time.perf_counter()
    results = rows(random_tools(args.tools), args.workers, args.sweep)
    text = table(results, args.tools)
    print(text)
    print(f"({time.perf_counter() - start:.0f} s)", file=sys.stderr)
    if args.write:
        write(text, args.sweep)
    return 0


if __name__ == "__main__":
    sys.exit(main())
