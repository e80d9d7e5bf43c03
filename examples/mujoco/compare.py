"""The on-robot controller on MuJoCo against `toolconf simulate`: every tool of a tools file on
one tip task, the same tool and task on both, and how far apart they may be.

    derive/.venv/bin/python examples/mujoco/compare.py --out results/mujoco/

(after `make test`'s set-up, or `make mujoco-test`, which installs the pinned mujoco into
derive/.venv). It builds the Panda's model library from the committed IR into a temporary folder
(`derive/make_model.py --ir generated/panda.json`, about 30 s; `--library DIR` takes one built
before) and the command line (`cargo build --bin toolconf`), then writes comparison.json, the
per-tool table comparison.csv and the figure comparison.png into --out, and prints the table.

What may differ, and by how much (docs/tutorials/mujoco.md): each quantity Q (the task error, ∫F, the tip
at each grid time) of the MuJoCo episode differs from the continuous closed loop's by the
controller's discretisation (a tick every h, the torque held: first order in h), by MuJoCo's
integration (RK4, steps of h/substeps) and toolconf's (its tolerances), and nothing else once the
two plants agree (the open-loop check, test_mujoco.py). Each is measured by halving its step:

* the tick: D₁ = Q(h) − Q(h/2), D₂ = Q(h/2) − Q(h/4). A first-order error c·h + O(h²) gives
  D₁/D₂ → 2; with the ratio r ≥ R_MIN the remaining error Q(h) − Q(0) = D₁(1 + 1/r + 1/r² + …)
  is at most |D₁|·R_MIN/(R_MIN − 1);
* MuJoCo's integrator: D_s = Q(steps of h/s) − Q(h/2s); any method of order p ≥ 1 halves its
  error at least, so Q − Q(Δt → 0) is at most 2·|D_s| (RK4: 16/15·|D_s|);
* toolconf's integrator: |Q(ode45's tolerances) − Q(rtol 1e-10, atol 1e-13)|, the tight run's
  own error being below its tolerance, orders of magnitude under the others.

The bound is their sum, plus ROUNDING·|Q|; the comparison holds when |Q_MuJoCo − Q_toolconf| is
within it. The tip's bound at each sample takes the tick's factor that the ratio test on the task
error and ∫F justifies (a ratio taken pointwise is noise where D₂ crosses zero).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import figure  # noqa: E402
from episode import Run, Task, mujoco_episode, read_task, simulate  # noqa: E402
from model_library import LibraryError, ModelLibrary  # noqa: E402
from mujoco_arm import Description, arm_spec, read_description  # noqa: E402

REPO = HERE.parents[1]
# The least ratio D₁/D₂ accepted as first-order behaviour (2 in the limit h → 0).
R_MIN = 1.7
RATIO_RANGE = (R_MIN, 2.3)
# The on-robot controller's rate (toolconf_core::RATE_HZ) and MuJoCo's steps per tick: RK4 at
# h/4 = 0.25 ms (docs/tutorials/mujoco.md, "The integrator").
RATE_HZ = 1000.0
SUBSTEPS = 4
# Two routes to the same double-precision number (MuJoCo's and toolconf's kinematics and
# dynamics, a few dozen operations each, each rounding by ε) differ by a few dozen ε at most:
# 100 ε relative covers it (measured: 2e-15 for the tip, test_mujoco.py).
ROUNDING = 100 * np.finfo(np.float64).eps
TIGHT = ("--rtol", "1e-10", "--atol", "1e-13")
METRICS = ("task_error", "free_energy")


@dataclass
class Tool:
    row: int
    name: str
    params: dict
    vector: np.ndarray


def catalogue(toolconf: Path, tools: Path, task: Path, library: ModelLibrary) -> list[Tool]:
    """The tools file's rows as toolconf reads them (`toolconf rank --json`: names, parameters
    with the defaults a row may leave out), in file order."""
    done = subprocess.run([str(toolconf), "rank", "--tools", str(tools), "--task", str(task),
                           "--json"], capture_output=True, text=True)
    if done.returncode != 0:
        # toolconf's one line: status 2 is bad input (the file, row and value named).
        error = ValueError if done.returncode == 2 else RuntimeError
        raise error(done.stderr.strip().removeprefix("toolconf: error: "))
    out = []
    for t in sorted(json.loads(done.stdout)["tools"], key=lambda t: t["row"]):
        name = t["name"] or f"row {t['row']}"
        if t.get("error"):
            print(f"compare.py: {tools}: {name}: not compared: toolconf's episode failed: "
                  f"{t['error']}", file=sys.stderr)
            continue
        vector = library.params([t["parameters"][n] for n in library.parameter_names])
        out.append(Tool(row=t["row"], name=name, params=t["parameters"], vector=vector))
    return out


def _quantities(run: Run) -> dict:
    """What is compared: the metrics and the tip at every grid time."""
    return {**{m: run.metrics[m] for m in METRICS}, "tip": run.tip}


def _difference(a: dict, b: dict) -> dict:
    return {k: a[k] - b[k] for k in a}


def error_bounds(runs: dict) -> dict:
    """The bound on |Q_MuJoCo − Q_toolconf| of each quantity (the module's docstring), from the
    runs by name: mujoco (h, s), mujoco_h2, mujoco_h4, mujoco_s2 (h, 2s), toolconf, tight."""
    q = {name: _quantities(run) for name, run in runs.items()}
    d1 = _difference(q["mujoco"], q["mujoco_h2"])
    d2 = _difference(q["mujoco_h2"], q["mujoco_h4"])
    ds = _difference(q["mujoco"], q["mujoco_s2"])
    dt = _difference(q["toolconf"], q["tight"])
    tick_factor = R_MIN / (R_MIN - 1.0)
    out = {}
    for k in q["mujoco"]:
        parts = {"tick": tick_factor * np.abs(d1[k]), "mujoco_integrator": 2.0 * np.abs(ds[k]),
                 "toolconf_integrator": np.abs(dt[k]), "rounding": ROUNDING * np.abs(q["toolconf"][k])}
        if k == "tip":
            parts = {p: np.linalg.norm(v, axis=1) for p, v in parts.items()}
        out[k] = {"bound": sum(parts.values()), "parts": parts,
                  "ratio": (d1[k] / d2[k]) if k != "tip" else None,
                  "difference": q["mujoco"][k] - q["toolconf"][k]}
    out["tip"]["difference"] = np.linalg.norm(out["tip"]["difference"], axis=1)
    return out


def compare_tool(library: ModelLibrary, description: Description, toolconf: Path, tool: Tool,
                 task: Task, workdir: Path) -> dict:
    """The six episodes of one tool and the comparison's numbers."""
    episode = lambda rate, s: mujoco_episode(library, description, tool.params, tool.vector,
                                             task, rate_hz=rate, substeps=s)
    runs = {
        "mujoco": episode(RATE_HZ, SUBSTEPS), "mujoco_h2": episode(2 * RATE_HZ, SUBSTEPS),
        "mujoco_h4": episode(4 * RATE_HZ, SUBSTEPS), "mujoco_s2": episode(RATE_HZ, 2 * SUBSTEPS),
        "toolconf": simulate(toolconf, library, tool.vector, task, workdir),
        "tight": simulate(toolconf, library, tool.vector, task, workdir, TIGHT),
    }
    return {"tool": tool, "runs": runs, "bounds": error_bounds(runs)}


def ranking(results: list[dict], run: str) -> list[str]:
    """The tools' names by ∫F of `run`, lowest (best) first."""
    return [r["tool"].name for r in sorted(results, key=lambda r: r["runs"][run].metrics["free_energy"])]


def tick_lead(run: Run, task: Task, library: ModelLibrary, period: float) -> dict:
    """What the tick should change, predicted from the continuous episode alone. The tick is
    an explicit Euler step of U̇: at t_k it returns ≈ U(t_k + h), held over [t_k, t_k + h),
    whose middle is t_k + h/2. The arm is driven by the torque h/2 ahead of the continuous
    controller's, and the closed loop, slow against h, runs h/2 ahead: y(t) moves by (h/2)ẏ(t)
    and the task error by (h/2) Σₖ d/dt[(yₖ − y^g)ᵀ P (yₖ − y^g)] = h Σₖ (yₖ − y^g)ᵀ P ẏₖ."""
    d = library.tip_dim
    p = task.precisions[library.term_names.index("tip")][:d, :d]
    e = run.tip - task.goals[library.term_names.index("tip")][:d]
    return {"task_error": float(period * np.einsum("ki,ij,kj->", e, p, run.tip_dot)),
            "tip": 0.5 * period * np.linalg.norm(run.tip_dot, axis=1)}


def summary(result: dict, library: ModelLibrary, task: Task) -> dict:
    """One tool's comparison as plain numbers (comparison.json, the table, the test)."""
    runs, bounds = result["runs"], result["bounds"]
    lead = tick_lead(runs["toolconf"], task, library, 1.0 / RATE_HZ)
    row = {"name": result["tool"].name, "row": result["tool"].row,
           "logdet": {"mujoco": runs["mujoco"].logdet, "toolconf": runs["toolconf"].logdet}}
    for m in METRICS:
        b, q = bounds[m], {name: run.metrics[m] for name, run in runs.items()}
        row[m] = {"mujoco": q["mujoco"], "toolconf": q["toolconf"],
                  "difference": float(b["difference"]), "bound": float(b["bound"]),
                  "bound_parts": {k: float(v) for k, v in b["parts"].items()},
                  "tick_ratio": float(b["ratio"]),
                  # Richardson's h -> 0 limit of the ticks (first order): 2 Q(h/2) - Q(h).
                  "extrapolated_difference": 2.0 * q["mujoco_h2"] - q["mujoco"] - q["toolconf"]}
    row["task_error"]["tick_lead_prediction"] = lead["task_error"]
    tip = bounds["tip"]
    worst = int(np.argmax(tip["difference"]))
    row["tip"] = {"max_difference": float(tip["difference"][worst]),
                  "bound_there": float(tip["bound"][worst]),
                  "worst_difference_over_bound": float(np.max(tip["difference"] / tip["bound"])),
                  "tick_lead_prediction": float(lead["tip"].max()),
                  # On the output grid: |y_MuJoCo − y_toolconf| and its bound, in m.
                  "difference": tip["difference"].tolist(), "bound": tip["bound"].tolist()}
    return row


def compare_all(library: ModelLibrary, description: Description, toolconf: Path, tools: Path,
                task: Task) -> tuple[list[dict], list[dict], int]:
    """Every tool's comparison, its summary rows ordered by toolconf's ∫F (best first), and how
    many tools could not be compared."""
    results, failed = [], 0
    with tempfile.TemporaryDirectory(prefix="toolconf-mujoco-") as workdir:
        for tool in catalogue(toolconf, tools, task.path, library):
            print(f"compare: {tool.name}", file=sys.stderr, flush=True)
            try:
                results.append(compare_tool(library, description, toolconf, tool, task,
                                            Path(workdir)))
            except (LibraryError, RuntimeError) as e:
                # One tool's failure is reported, and the others are compared.
                print(f"compare.py: {tool.name}: not compared: {e}", file=sys.stderr)
                failed += 1
    rows = {r["name"]: r for r in (summary(x, library, task) for x in results)}
    return results, [rows[name] for name in ranking(results, "toolconf")], failed


def table(rows: list[dict], mujoco_ranking: list[str]) -> str:
    """The comparison as text: per tool the relative differences and bounds."""
    lines = [f"{'tool':<32} {'task error':>12} {'Δ/TE':>9} {'bound':>8} {'∫F dt':>10} "
             f"{'Δ/∫F':>9} {'bound':>8} {'tip Δ max':>10} rank tc/mj"]
    for i, r in enumerate(rows):
        te, f = r["task_error"], r["free_energy"]
        lines.append(f"{r['name']:<32} {te['toolconf']:>12.6g} {te['difference'] / te['toolconf']:>+9.2e} "
                     f"{te['bound'] / te['toolconf']:>8.2e} {f['toolconf']:>10.6g} "
                     f"{f['difference'] / f['toolconf']:>+9.2e} {f['bound'] / f['toolconf']:>8.2e} "
                     f"{r['tip']['max_difference']:>10.2e} {i + 1:>4}/{mujoco_ranking.index(r['name']) + 1}")
    return "\n".join(lines)


def _write(path: Path, write) -> None:
    """Writes `path` through a temporary file beside it, renamed into place: an interrupted run
    keeps the old file; a symbolic link or anything but a regular file is not replaced."""
    if path.is_symlink() or (path.exists() and not path.is_file()):
        raise ValueError(f"{path}: exists and is not a regular file; not replaced")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        # mkstemp's file is private (0600); the result gets the permissions the umask gives.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_outputs(out: Path, results: list[dict], rows: list[dict], task: Task,
                  library: ModelLibrary) -> None:
    """comparison.json, comparison.csv and comparison.png in `out` (made if missing)."""
    out.mkdir(parents=True, exist_ok=True)
    mujoco_ranking = ranking(results, "mujoco")
    document = {"rate_hz": RATE_HZ, "substeps": SUBSTEPS, "integrator": "RK4",
                "ratio_range": RATIO_RANGE, "ranking_toolconf": [r["name"] for r in rows],
                "ranking_mujoco": mujoco_ranking, "tools": rows}
    _write(out / "comparison.json", lambda p: p.write_text(json.dumps(document, indent=1) + "\n"))
    columns = ["name", "task_error_toolconf", "task_error_mujoco", "task_error_bound",
               "free_energy_toolconf", "free_energy_mujoco", "free_energy_bound",
               "tip_max_difference", "tip_bound_there"]
    def csv_text(p: Path) -> None:
        with open(p, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(columns)
            for r in rows:
                w.writerow([r["name"], r["task_error"]["toolconf"], r["task_error"]["mujoco"],
                            r["task_error"]["bound"], r["free_energy"]["toolconf"],
                            r["free_energy"]["mujoco"], r["free_energy"]["bound"],
                            r["tip"]["max_difference"], r["tip"]["bound_there"]])
    _write(out / "comparison.csv", csv_text)
    goal = task.goals[library.term_names.index("tip")][:library.tip_dim]
    _write(out / "comparison.png", lambda p: figure.draw(results, rows, goal, p))


def build_library(ir: Path, folder: Path) -> Path:
    """The model library of a committed IR, built by make model into `folder`."""
    out = folder / "model"
    done = subprocess.run([sys.executable, str(REPO / "derive" / "make_model.py"), "--ir", str(ir),
                           "--out", str(out)], stdout=subprocess.DEVNULL, stderr=sys.stderr)
    if done.returncode != 0:
        raise RuntimeError(f"make_model.py --ir {ir} failed (status {done.returncode})")
    return out


def build_toolconf() -> Path:
    """The command line, as `cargo build --bin toolconf` makes it (up to date after make test)."""
    subprocess.run(["cargo", "build", "--quiet", "--bin", "toolconf"], cwd=REPO, check=True)
    return Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "debug" / "toolconf"


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"compare.py: {message}\n")


def main(argv=None) -> int:
    parser = _Parser(description="The on-robot controller on MuJoCo against toolconf simulate.")
    parser.add_argument("--out", type=Path, required=True,
                        help="folder for comparison.json, .csv and .png (made if missing)")
    parser.add_argument("--tools", type=Path, default=REPO / "examples/tools/panda_tools.csv")
    parser.add_argument("--task", type=Path, default=REPO / "examples/tasks/panda_touch_point.toml")
    parser.add_argument("--description", type=Path, default=REPO / "derive/models/panda.toml",
                        help="the model description whose URDF MuJoCo loads")
    parser.add_argument("--library", type=Path,
                        help="the model library's folder (make model); default: build it from "
                             "generated/<model>.json into a temporary folder")
    parser.add_argument("--toolconf", type=Path, help="the toolconf binary (default: cargo build)")
    args = parser.parse_args(argv)
    try:
        if args.out.exists() and not args.out.is_dir():
            raise ValueError(f"--out {args.out}: exists and is not a folder")
        description = read_description(args.description)
        with tempfile.TemporaryDirectory(prefix="toolconf-mujoco-lib-") as scratch:
            folder = args.library or build_library(
                REPO / "generated" / f"{description.name}.json", Path(scratch))
            library = ModelLibrary(folder)
            if library.name != description.name:
                raise ValueError(f"--library {folder}: the model {library.name}, not the "
                                 f"description's {description.name}")
            # The URDF as MuJoCo loads it, checked once before any tool.
            arm_spec(description, library.equilibrium_state[:library.dof], "RK4", 1e-3).compile()
            task = read_task(args.task, library)
            toolconf = args.toolconf or build_toolconf()
            results, rows, failed = compare_all(library, description, toolconf, args.tools, task)
            if not results:
                raise RuntimeError(f"{args.tools}: no tool could be compared")
            write_outputs(args.out, results, rows, task, library)
    except (OSError, ValueError, TypeError, LibraryError, ET.ParseError) as e:
        print(f"compare.py: {e}", file=sys.stderr)
        return 2
    except (RuntimeError, subprocess.CalledProcessError) as e:
        print(f"compare.py: {e}", file=sys.stderr)
        return 1
    print(table(rows, ranking(results, "mujoco")))
    print(f"compare.py: wrote {args.out}/comparison.json, comparison.csv, comparison.png")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
