"""toolconf on one process against toolconf.dask on a 2-worker LocalCluster of this machine.

Run by benches/dask/run.sh (a release wheel in its own venv). Every number is a median of
``--repeat`` runs, in one run of this script, on the same data:

* rank, screen stage: N arm2 tools (a DataFrame; a dask DataFrame of P partitions persisted
  on the workers first), screen K: confidence of every tool, episodes of K.
* rank, episode stage: M tools, no screen (every tool simulated).
* simulate_batch: T tools x 5 perturbations; and arm3 at rtol = 1e-10, ~3.6 ms per episode, a
  stand-in for the episodes of milliseconds the 6- and 7-DOF arms will cost.
* overhead per partition: the screen stage of 10^4 tools at P = 4 ... 256 partitions (the slope
  of the wall time against P), and per cluster task: 2000 empty tasks.

Both sides compute the same tables (checked), on the same 2 cores: the client process's rayon
uses both; each worker runs one task at a time on one rayon thread.
"""

import argparse
import json
import logging
import os
import statistics
import sys
import time
import warnings

import numpy as np
import pandas as pd

import dask.dataframe as dd
import distributed

import toolconf
import toolconf.dask


def median_time(f, repeat):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = f()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def tools(n, seed=1):
    rng = np.random.default_rng(seed)
    frame = pd.DataFrame(0.1 + 0.5 * rng.random((n, 4)), columns=["m1", "m2", "l1", "l2"])
    frame.insert(0, "model", "arm2")
    frame.insert(0, "name", [f"t{i}" for i in range(n)])
    return frame


def noop(x):
    return x


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small counts, for a smoke test")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    # The benchmark's own frames go into the graph (dd.from_pandas): known to be large.
    warnings.filterwarnings("ignore", message="Sending large graph")
    load_before = os.getloadavg()
    n, k, m, t, slow, parts = (10**6, 1000, 20_000, 2000, 400, 8) if not args.quick else (
        20_000, 100, 1000, 100, 20, 4)
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None, silence_logs=logging.ERROR, env={"RAYON_NUM_THREADS": "1"})
    client = distributed.Client(cluster)
    rows = []

    def compare(what, count, unit, local, on_cluster, same):
        assert same, what
        rows.append({"what": what, "count": count, "unit": unit,
                     "local_s": local, "dask_s": on_cluster,
                     "local_per_s": count / local, "dask_per_s": count / on_cluster})

    frame = tools(n)
    ddf = dd.from_pandas(frame, npartitions=parts).persist()
    distributed.wait(ddf)
    # The screen by confidence, what docs/tutorials/dask.md's figures measured (the default,
    # by prediction, also linearises every tool's loop).
    by = "confidence"
    local, a = median_time(
        lambda: toolconf.rank(frame, "position", screen=k, screen_by=by), args.repeat)
    remote, b = median_time(
        lambda: toolconf.dask.rank(ddf, "position", screen=k, screen_by=by, client=client),
        args.repeat)
    compare(f"rank screen={k}, {parts} partitions", n, "tools", local, remote, a.equals(b))

    few = tools(m, seed=2)
    fddf = dd.from_pandas(few, npartitions=parts).persist()
    distributed.wait(fddf)
    local, a = median_time(lambda: toolconf.rank(few, "position"), args.repeat)
    remote, b = median_time(lambda: toolconf.dask.rank(fddf, "position", client=client),
                            args.repeat)
    compare(f"rank, no screen, {parts} partitions", m, "episodes", local, remote, a.equals(b))

    params = tools(t, seed=3)[["m1", "m2", "l1", "l2"]].to_numpy()
    perturbations = [-1.0, -0.5, 0.0, 0.5, 1.0]
    local, a = median_time(lambda: toolconf.simulate_batch("arm2", params, "velocity",
                                                           perturbations), args.repeat)
    remote, b = median_time(lambda: toolconf.dask.simulate_batch(
        "arm2", params, "velocity", perturbations, client=client), args.repeat)
    same = all(np.array_equal(a[key], b[key], equal_nan=True) if key != "error"
               else a[key] == b[key] for key in a)
    compare("simulate_batch, 5 perturbations", t * 5, "episodes", local, remote, same)

    rng = np.random.default_rng(5)
    params = 0.1 + 0.5 * rng.random((slow, 6))
    tight = {"rtol": 1e-10, "atol": 1e-12}
    local, a = median_time(lambda: toolconf.simulate_batch("arm3", params, "position",
                                                           perturbations, **tight), 1)
    remote, b = median_time(lambda: toolconf.dask.simulate_batch(
        "arm3", params, "position", perturbations, client=client, **tight), 1)
    same = all(np.array_equal(a[key], b[key], equal_nan=True) if key != "error"
               else a[key] == b[key] for key in a)
    compare("simulate_batch arm3 rtol 1e-10 (ms episodes)", slow * 5, "episodes", local,
            remote, same)

    small = tools(10_000, seed=4)
    overhead = []
    for p in (4, 16, 64, 256):
        sddf = dd.from_pandas(small, npartitions=p).persist()
        distributed.wait(sddf)
        wall, _ = median_time(
            lambda: toolconf.dask.rank(sddf, "position", screen=10, screen_by=by, client=client),
            args.repeat)
        overhead.append((p, wall))
    slope, intercept = np.polyfit([p for p, _ in overhead], [w for _, w in overhead], 1)
    empty, _ = median_time(lambda: client.gather(client.map(noop, range(2000), pure=False)),
                           args.repeat)
    client.close()
    cluster.close()

    print(f"{'':44} {'one process':>22} {'LocalCluster 2x1':>22}")
    for r in rows:
        print(f"{r['what']:44} {r['local_s']:9.3f} s {r['local_per_s']:9.0f}/s "
              f"{r['dask_s']:9.3f} s {r['dask_per_s']:9.0f}/s  ({r['count']} {r['unit']})")
    print("screen of 10^4 tools, screen=10, by partitions: "
          + ", ".join(f"{p}: {w * 1e3:.0f} ms" for p, w in overhead))
    print(f"overhead per partition (slope): {slope * 1e3:.2f} ms; fixed: {intercept * 1e3:.0f} ms")
    print(f"an empty cluster task: {empty / 2000 * 1e3:.3f} ms (2000 tasks)")
    print(f"load average before {load_before[0]:.1f}, after {os.getloadavg()[0]:.1f} "
          f"({os.cpu_count()} cpus)")
    print(json.dumps({"rows": rows, "partitions": overhead, "per_partition_s": slope,
                      "fixed_s": intercept, "per_task_s": empty / 2000,
                      "cpus": os.cpu_count(), "load_before": load_before,
                      "load_after": os.getloadavg(),
                      "python": sys.version.split()[0]}))


if __name__ == "__main__":
    main()
