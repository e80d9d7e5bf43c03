"""Rank a pandas DataFrame of tools: the drawer and random designs, built in memory, ranked
without writing a file, then the paper's claim looked at with pandas.

    pip install "./python[pandas]"        # once, in your virtual environment (needs Rust)
    python examples/python/rank_dataframe.py

``toolconf.rank`` takes a DataFrame with a tools file's columns (``name``, ``model`` and the
models' parameters) and gives back a DataFrame, best tool first. With ``screen=K`` only K tools
are simulated, chosen without simulating: by default those whose episode the closed loop
linearised at the equilibrium predicts cheapest (``screen_by="confidence"``: the K most
confident, largest ln|Pi^U|).
"""

from pathlib import Path

import numpy as np
import pandas as pd

import toolconf

EXAMPLES = Path(__file__).resolve().parents[1]
TASK = EXAMPLES / "tasks" / "reach_45.toml"
SCREEN = 20


def tools(designs=200, seed=1):
    """The drawer's tools and ``designs`` random arm2 tools, every parameter uniform on
    [0.1, 0.6) kg or m."""
    drawer = pd.read_csv(EXAMPLES / "tools" / "drawer.csv")
    p = 0.1 + 0.5 * np.random.default_rng(seed).random((designs, 4))
    random = pd.DataFrame(p, columns=["m1", "m2", "l1", "l2"])
    random.insert(0, "name", [f"design {i}" for i in range(designs)])
    random.insert(1, "model", "arm2")
    return pd.concat([drawer, random], ignore_index=True)


def main():
    ranked = toolconf.rank(tools(), TASK, screen=SCREEN)
    print(ranked[["rank", "name", "logdet", "task_error", "free_energy"]].to_string(index=False))
    # The paper's claim: the more confident a tool, the smaller its task error. Spearman's rho
    # is the correlation of the ranks.
    rho = ranked["logdet"].rank().corr(ranked["task_error"].rank())
    print(f"Spearman's rho of ln|Pi^U| and the task error over {len(ranked)} tools: {rho:.3f}")


if __name__ == "__main__":
    main()
