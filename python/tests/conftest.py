"""Shared fixtures: the repository, and the command line built in the same target directory."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DRAWER = REPO / "examples" / "tools" / "drawer.csv"
REACH_45 = REPO / "examples" / "tasks" / "reach_45.toml"


def stdout_per_thread_count(script, *args):
    """``script`` (with ``args``) run by this Python on one and on two rayon threads
    (``RAYON_NUM_THREADS``): its output each time."""
    outputs = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        out = subprocess.run([sys.executable, "-c", script, *args], env=env, capture_output=True,
                             text=True, check=True)
        outputs.append(out.stdout)
    return outputs


@pytest.fixture(scope="session")
def cli():
    """Runs ``toolconf ARGS``; returns (exit status, stdout, stderr). The binary is TOOLCONF_BIN
    (make test: the one its ``cargo test --workspace`` built) or the one ``cargo build`` makes in
    the workspace's target directory."""
    given = os.environ.get("TOOLCONF_BIN")
    if given:
        binary = Path(given)
    else:
        subprocess.run(["cargo", "build", "--quiet", "--bin", "toolconf"], cwd=REPO, check=True)
        binary = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "debug" / "toolconf"

    def run(*args):
        out = subprocess.run(
            [str(binary), *map(str, args)], capture_output=True, text=True, cwd=REPO
        )
        return out.returncode, out.stdout, out.stderr

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """``toolconf ARGS --json`` parsed; fails the test unless the command succeeded."""

    def run(*args):
        status, stdout, stderr = cli(*args, "--json")
        assert status == 0, stderr
        return json.loads(stdout)

    return run


@pytest.fixture(scope="session")
def cli_error(cli):
    """The one-line message ``toolconf ARGS`` prints for bad input (status 2), without the
    ``toolconf: error: `` prefix."""

    def run(*args):
        status, _, stderr = cli(*args)
        assert status == 2, stderr
        lines = stderr.strip().splitlines()
        assert len(lines) == 1, stderr
        prefix = "toolconf: error: "
        assert lines[0].startswith(prefix), stderr
        return lines[0][len(prefix):]

    return run


@pytest.fixture(scope="session")
def dask_client():
    """A ``distributed`` cluster of 2 worker processes (one thread and one rayon thread each) on
    the loopback interface, and a client of it. The workers are started with this Python, so
    they import the same ``toolconf`` (checked in test_dask.py)."""
    import logging

    import distributed

    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None, silence_logs=logging.ERROR, env={"RAYON_NUM_THREADS": "1"},
    )
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()
