"""The Python examples (examples/README.md) run as a user runs them, and print what an
independent computation gives for the same inputs: the command line's ranking (rank_tools.py,
rank_dataframe.py), Pinocchio's tip and Jacobian (tip.py), and the same batch on one machine
(dask_batch.py). The one that loads a model library is python/loaded_tests/'s."""

import math
import re
import runpy
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import toolconf

from conftest import DRAWER, REACH_45, REPO

sys.path.insert(0, str(REPO / "benches" / "peers"))
import pin_robot  # noqa: E402
import pinocchio as pin  # noqa: E402

EXAMPLES = REPO / "examples" / "python"


def run(script, *args, cwd=REPO):
    """``python examples/python/SCRIPT ARGS``: its standard output."""
    out = subprocess.run([sys.executable, str(EXAMPLES / script), *map(str, args)],
                         capture_output=True, text=True, cwd=cwd)
    assert out.returncode == 0, out.stderr
    return out.stdout


def module(script):
    """The example's globals, its main() not run (runpy writes no bytecode beside it)."""
    return runpy.run_path(str(EXAMPLES / script), run_name=script)


def printed(text, value):
    """Whether ``value``, printed in ``text``'s notation with as many decimals, is ``text``."""
    mantissa, e, _ = text.partition("e")
    decimals = len(mantissa.partition(".")[2])
    return f"{value:.{decimals}{'e' if e else 'f'}}" == text


def test_rank_tools_ranks_the_drawer_as_the_command_line_and_plots(tmp_path, cli_json):
    pytest.importorskip("matplotlib")
    out = tmp_path / "figure.png"
    lines = run("rank_tools.py", "--out", out, cwd=tmp_path).splitlines()
    want = cli_json("rank", "--tools", DRAWER, "--task", REACH_45)["tools"]
    rows = [re.match(r"\s*(\d+)  (.{20}) (\S+) +(\S+) +(\S+) +(\S+)$", line) for line in lines[1:-1]]
    assert len(rows) == len(want) and all(rows), lines
    for row, tool in zip(rows, want):
        assert int(row[1]) == tool["rank"] and row[2].strip() == tool["name"], row[0]
        assert row[3] == tool["model"], row[0]
        assert printed(row[4], tool["logdet"]) and printed(row[5], tool["task_error"]), row[0]
    assert out.stat().st_size > 10_000


def test_rank_dataframe_ranks_its_tools_as_the_command_line(tmp_path, cli_json):
    example = module("rank_dataframe.py")
    tools = tmp_path / "tools.csv"
    example["tools"]().to_csv(tools, index=False)  # Python's repr of each float: the same values
    # The example's screen is the default one, by prediction: the command line's default too.
    want = cli_json("rank", "--tools", tools, "--task", example["TASK"],
                    "--screen", example["SCREEN"])["tools"]
    by_confidence = cli_json("rank", "--tools", tools, "--task", example["TASK"],
                             "--screen", example["SCREEN"], "--screen-by", "confidence")["tools"]
    assert {t["row"] for t in want} != {t["row"] for t in by_confidence}
    lines = run("rank_dataframe.py").splitlines()
    rows = [re.match(r"\s*(\d+)\s+(.+?)\s+(\S+)\s+(\S+)\s+(\S+)$", line) for line in lines[1:-1]]
    assert len(rows) == len(want) == example["SCREEN"] and all(rows), lines
    for row, tool in zip(rows, want):
        assert int(row[1]) == tool["rank"] and row[2] == tool["name"], row[0]
        for text, key in zip(row.groups()[2:], ["logdet", "task_error", "free_energy"]):
            assert printed(text, tool[key]), (row[0], key, tool[key])
    rho = pd.Series([t["logdet"] for t in want]).rank().corr(
        pd.Series([t["task_error"] for t in want]).rank())
    assert lines[-1].endswith(f"over {len(want)} tools: {rho:.3f}"), lines[-1]


def test_tip_prints_pinocchios_tip_and_jacobian():
    example = module("tip.py")
    hammer = example["HAMMER"]
    lines = run("tip.py").splitlines()
    numbers = [[float(v) for v in re.findall(r"[-+]\d+\.\d+", line.partition(":")[2] or line)]
               for line in lines]
    model, data = pin_robot.model_with_tool("panda", hammer)
    frame = model.getFrameId("tool_tip")

    def tip(q):
        pin.framesForwardKinematics(model, data, q)
        jacobian = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)[:3]
        return data.oMf[frame].translation.copy(), jacobian

    q = np.array(toolconf.models()["panda"]["equilibrium"]["q"])
    position, jacobian = tip(q)
    # Each printed value is within half its last digit of Pinocchio's.
    assert lines[1].startswith("tip y(q)")
    np.testing.assert_allclose(numbers[1], position, rtol=0, atol=0.5e-6)
    np.testing.assert_allclose(numbers[3:6], jacobian, rtol=0, atol=0.5e-4)
    sweep = [n for line, n in zip(lines, numbers) if line.startswith("q1 = ")]
    assert len(sweep) == 5
    for q0, row in zip(np.linspace(-math.pi / 2, math.pi / 2, 5), sweep):
        np.testing.assert_allclose(row, tip(np.r_[q0, q[1:]])[0], rtol=0, atol=0.5e-4)


def test_dask_batch_finds_the_tool_a_single_machine_finds():
    example = module("dask_batch.py")
    lines = run("dask_batch.py").splitlines()
    local = pd.DataFrame(toolconf.simulate_batch(
        "arm2", example["TOOLS"], "position", perturbations=example["PERTURBATIONS"]))
    assert lines[0] == f"{len(local)} episodes, {local['error'].notna().sum()} failed"
    worst = local.groupby("tool")["task_error"].max()
    best = worst.idxmin()
    robust = re.fullmatch(r"most robust: tool (\d+), .* worst task error (\S+)", lines[-1])
    assert robust and int(robust[1]) == best, lines[-1]
    assert printed(robust[2], worst[best]), (lines[-1], worst[best])
