#!/usr/bin/env python3
"""Does higher control confidence go with lower tip error? Measured on random tools.

For each tip task below, `toolconf select` (release binary) draws N random tools of the task's
robot from the model's own sampling box (generated/src/validity.rs: mass, centre of mass, principal
moments and products of inertia, tip 5-35 cm out), simulates every one on the task file as it is
(its tolerances chosen on physical grounds, not tuned here) and reports ln|Pi^U|, the task error
and the progress. This prints, per task, Spearman's rho between ln|Pi^U| and the task error (the
paper's claim is rho < 0: more confident tools do the task better), its 95 % interval by bootstrap
over the tools, the span of ln|Pi^U|, rho of the tip's length (tool_tip_z) against each, and the
progress (median and minimum) on position tasks.

    python3 benches/tip_confidence.py [N=1000] [SEED=7]

Spearman's rho is the Pearson correlation of the ranks (ties broken by order: the metrics are
continuous); no SciPy needed.
"""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
TASKS = [
    ("panda", "examples/tasks/panda_touch_point.toml"),
    ("panda", "examples/tasks/panda_draw_line.toml"),
    ("ur5", "examples/tasks/ur5_touch_point.toml"),
    ("ur5", "examples/tasks/ur5_draw_line.toml"),
    ("panda", "examples/tasks/panda_push_off.toml"),
    ("ur5", "examples/tasks/ur5_push_off.toml"),
]


def ranks(v: np.ndarray) -> np.ndarray:
    r = np.empty(len(v))
    r[np.argsort(v, kind="stable")] = np.arange(len(v))
    return r


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.corrcoef(ranks(x), ranks(y))[0, 1])


def bootstrap(x: np.ndarray, y: np.ndarray, seed: int, draws: int = 2000) -> tuple[float, float]:
    rng = np.random.default_rng(seed)
    values = [spearman(x[i], y[i]) for i in (rng.integers(0, len(x), len(x)) for _ in range(draws))]
    return float(np.percentile(values, 2.5)), float(np.percentile(values, 97.5))


def measure(model: str, task: str, n: int, seed: int) -> str:
    command = [str(ROOT / "target/release/toolconf"), "select", "--models", model, "--task-file", task,
               "--tools", str(n), "--seed", str(seed), "--json"]
    out = json.loads(subprocess.run(command, cwd=ROOT, check=True, capture_output=True, text=True).stdout)
    done = [t for t in out["tools"] if "task_error" in t]
    logdet = np.array([t["logdet"] for t in done])
    error = np.array([t["task_error"] for t in done])
    rho = spearman(logdet, error)
    lo, hi = bootstrap(logdet, error, seed)
    length = np.array([t["arm"]["tool_tip_z"] for t in done])
    line = (f"| {model} | `{Path(task).name}` | {len(done)}/{len(out['tools'])} | {rho:+.2f} "
            f"[{lo:+.2f}, {hi:+.2f}] | {logdet.max() - logdet.min():.2f} | "
            f"{spearman(length, logdet):+.2f} | {spearman(length, error):+.2f} |")
    progress = np.array([t["progress"] for t in done if "progress" in t])
    if len(progress):
        line += f" {np.median(progress):.3f} (min {progress.min():.3f}) |"
    else:
        line += " – |"
    return line


def main() -> int:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "toolconf"], cwd=ROOT, check=True)
    print("| robot | task | tools simulated | ρ(ln\\|Π^U\\|, task error) [95 %] | ln\\|Π^U\\| span "
          "| ρ(tip length, ln\\|Π^U\\|) | ρ(tip length, task error) | progress: median (min) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for model, task in TASKS:
        print(measure(model, task, n, seed))
    return 0


if __name__ == "__main__":
    sys.exit(main())
