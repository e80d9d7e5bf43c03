"""Rank a drawer of tools on a task, and plot confidence against task error.

    pip install ./python matplotlib        # once, in your virtual environment (needs Rust)
    python examples/python/rank_tools.py [TOOLS.csv] [TASK] [--screen K] [--out FIGURE.png]

TOOLS defaults to examples/tools/drawer.csv and TASK to examples/tasks/reach_45.toml (a task
file's path, or position / velocity / acceleration). The paper's claim is that the control
confidence ln|Π^U|, which costs microseconds per tool and needs no simulation, predicts how well
a tool will do: in the figure, the more confident tools should sit lower (less task error).
"""

import argparse
from pathlib import Path

import numpy as np

import toolconf

EXAMPLES = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tools", nargs="?", default=EXAMPLES / "tools" / "drawer.csv")
    parser.add_argument("task", nargs="?", default=EXAMPLES / "tasks" / "reach_45.toml")
    parser.add_argument("--screen", type=int, default=None,
                        help="simulate only the K tools predicted cheapest")
    parser.add_argument("--out", default="confidence_vs_task_error.png")
    args = parser.parse_args()

    ranked = toolconf.rank(args.tools, args.task, screen=args.screen)
    print(f"{'rank':>4}  {'name':<20} {'model':<11} {'ln|Pi^U|':>9} {'task error':>11} "
          f"{'int F dt':>10}")
    for k in range(len(ranked["rank"])):
        name = ranked["name"][k] or f"row {ranked['row'][k]}"
        if ranked["error"][k]:
            print(f"{ranked['rank'][k]:>4}  {name:<20} failed: {ranked['error'][k]}")
            continue
        print(f"{ranked['rank'][k]:>4}  {name:<20} {ranked['model'][k]:<11} "
              f"{ranked['logdet'][k]:>9.4f} {ranked['task_error'][k]:>11.4e} "
              f"{ranked['free_energy'][k]:>10.4e}")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = np.array([e is None for e in ranked["error"]])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for model in sorted(set(ranked["model"])):
        mine = ok & (np.array(ranked["model"]) == model)
        ax.scatter(ranked["logdet"][mine], ranked["task_error"][mine], label=model)
    for k in np.flatnonzero(ok):
        ax.annotate(ranked["name"][k] or str(ranked["row"][k]),
                    (ranked["logdet"][k], ranked["task_error"][k]),
                    fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("control confidence ln|Π^U|")
    ax.set_ylabel("task error")
    ax.set_yscale("log")
    ax.set_title(f"{Path(str(args.tools)).name} on {Path(str(args.task)).name}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
