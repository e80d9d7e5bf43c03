"""A batch of episodes on a Dask cluster: every tool under every perturbation with
``toolconf.dask.simulate_batch``, here on a LocalCluster of 2 worker processes on this machine.

    pip install "./python[dask]"          # every worker needs toolconf too
    python examples/python/dask_batch.py

For a real cluster, give ``Client`` the scheduler's address instead ("tcp://scheduler:8786").
The result equals ``toolconf.simulate_batch``'s on one machine, entry for entry.
"""

import logging

import numpy as np
import pandas as pd
from distributed import Client, LocalCluster

import toolconf.dask

# 300 arm2 tools (m1, m2, l1, l2 uniform on [0.1, 0.6)), each under three constant torques.
TOOLS = 0.1 + 0.5 * np.random.default_rng(7).random((300, 4))
PERTURBATIONS = [-0.5, 0.0, 0.5]  # N m on every joint


def main():
    # One thread per worker, and rayon's threads to match, so that the workers do not compete
    # for the cores.
    with LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1",
                      dashboard_address=None, silence_logs=logging.ERROR,
                      env={"RAYON_NUM_THREADS": "1"}) as cluster, Client(cluster) as client:
        batch = toolconf.dask.simulate_batch("arm2", TOOLS, "position",
                                             perturbations=PERTURBATIONS, client=client)
    # One row per (tool, perturbation), tool-major, as a DataFrame.
    rows = pd.DataFrame(batch)
    rows["perturbation"] = np.array(PERTURBATIONS)[rows["perturbation"]]
    print(f"{len(rows)} episodes, {rows['error'].notna().sum()} failed")
    print(rows.groupby("perturbation")["task_error"].describe().to_string())
    # The most robust tool: the smallest worst-case task error over the perturbations.
    worst = rows.groupby("tool")["task_error"].max()
    best = worst.idxmin()
    print(f"most robust: tool {best}, m1 m2 l1 l2 = {TOOLS[best].round(4).tolist()}, "
          f"worst task error {worst[best]:.6e}")


if __name__ == "__main__":
    main()
