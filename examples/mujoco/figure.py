"""The side-by-side figure of the comparison (compare.py): the tips' paths, how far apart the
two engines' tips are against the bound, and each tool's task error and ∫F on both."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def _paths(ax, results: list[dict], goal: np.ndarray, colours) -> None:
    for result, colour in zip(results, colours):
        tc, mj = result["runs"]["toolconf"].tip, result["runs"]["mujoco"].tip
        ax.plot(tc[:, 0], tc[:, 2], "-", color=colour, lw=1.2, label=result["tool"].name)
        ax.plot(mj[::4, 0], mj[::4, 2], "o", color=colour, ms=2.5, mfc="none")
    ax.plot(goal[0], goal[2], "k*", ms=10, label="goal")
    ax.plot([], [], "k-", label="toolconf simulate (continuous)")
    ax.plot([], [], "ko", mfc="none", ms=3, label="MuJoCo, 1 kHz ticks (every 4th sample)")
    ax.set(xlabel="tip x [m] (base frame)", ylabel="tip z [m]", title="(a) the tips' paths, 5 s")
    ax.legend(fontsize=6, loc="upper right", ncol=2)


def _deviation(ax, results: list[dict], colours) -> None:
    for result, colour in zip(results, colours):
        tip, t = result["bounds"]["tip"], result["runs"]["toolconf"].t
        ax.semilogy(t[1:], tip["difference"][1:], "-", color=colour, lw=1)
        ax.semilogy(t[1:], tip["bound"][1:], ":", color=colour, lw=1)
    ax.plot([], [], "k-", label="|y_MuJoCo − y_toolconf|")
    ax.plot([], [], "k:", label="bound (ticks + integrators + rounding)")
    ax.set(xlabel="t [s]", ylabel="[m]", title="(b) the tips apart, per tool")
    ax.legend(fontsize=7)


def _metric(ax, rows: list[dict], key: str, title: str, logscale: bool) -> None:
    x = np.arange(len(rows))
    tc = [r[key]["toolconf"] for r in rows]
    mj = [r[key]["mujoco"] for r in rows]
    ax.bar(x - 0.2, tc, 0.4, label="toolconf simulate", color="tab:blue")
    ax.bar(x + 0.2, mj, 0.4, label="MuJoCo", color="tab:orange")
    for i, r in enumerate(rows):
        ax.annotate(f"{r[key]['difference'] / r[key]['toolconf']:+.1e}\n≤{r[key]['bound'] / r[key]['toolconf']:.1e}",
                    (i, max(tc[i], mj[i])), ha="center", va="bottom", fontsize=5)
    if logscale:
        ax.set_yscale("log")
    ax.set_xticks(x, [r["name"] for r in rows], rotation=60, ha="right", fontsize=6)
    ax.set(title=title)
    ax.legend(fontsize=7)


def draw(results: list[dict], rows: list[dict], goal: np.ndarray, path: Path) -> None:
    """Writes the figure to `path` (PNG); `rows` are compare.summary's, best ∫F first."""
    order = {r["name"]: i for i, r in enumerate(rows)}
    results = sorted(results, key=lambda r: order[r["tool"].name])
    colours = plt.cm.tab20(np.linspace(0, 1, len(results)))
    fig, axes = plt.subplots(2, 2, figsize=(12, 9.5))
    _paths(axes[0, 0], results, goal, colours)
    _deviation(axes[0, 1], results, colours)
    _metric(axes[1, 0], rows, "task_error",
            "(c) task error; above: Δ relative, ≤ its bound", True)
    _metric(axes[1, 1], rows, "free_energy",
            "(d) ∫F dt, by toolconf's ranking; above: Δ relative, ≤ its bound", True)
    fig.suptitle("The Panda's catalogue touching a point: toolconf simulate against the C ABI's "
                 "controller ticking at 1 kHz on MuJoCo", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=90, format="png")
    plt.close(fig)
