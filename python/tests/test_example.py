"""examples/python/rank_tools.py runs and writes its figure (when matplotlib is installed)."""

import subprocess
import sys

import pytest

from conftest import REPO


def test_the_example_ranks_the_drawer_and_plots(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "figure.png"
    run = subprocess.run(
        [sys.executable, str(REPO / "examples" / "python" / "rank_tools.py"), "--out", str(out)],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert run.returncode == 0, run.stderr
    assert "top-heavy" in run.stdout.splitlines()[1]  # the README's best tool for reach_45
    assert out.stat().st_size > 10_000
