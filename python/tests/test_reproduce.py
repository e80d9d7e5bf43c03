"""toolconf.reproduce: the command line's ``reproduce --model``, number for number; its claims
against an independent computation from ``select --json`` with SciPy; toolconf.dask.reproduce
on a 2-worker LocalCluster against it; and its refusals."""

import csv
import json

import numpy as np
import pandas as pd
import pytest

import toolconf
import toolconf.dask as tdask

import independent_claims
from conftest import REPO

# A task no file of the repository states: the UR5 touching a point 4 cm out and 5 cm up from
# each tool's own tip, its precisions from the robot's own scales.
TASK = """kind = "tip_position"
description = "UR5: a point 4 cm out and 5 cm up from each tool's tip"
[goal]
tip_offset = [0.04, 0.0, 0.05]
"""
DT = "[-15.0, -15.0, -15.0, -2.8, -2.8, -2.8]"
QUICK = dict(quick=True, sample=16, seed=4)


def test_the_claims_equal_an_independent_computation_from_select(cli, cli_json, tmp_path):
    verdicts = independent_claims.check(cli, cli_json, [], "ur5", TASK, DT, tmp_path)
    assert set(verdicts) == {"confidence_predicts_task_error", "confidence_predicts_reliability",
                             "free_energy_choices_less_sensitive"}


def task_file(tmp_path):
    path = tmp_path / "task.toml"
    path.write_text(TASK + f"[episode]\nperturbation = {DT}\n")
    return path


def test_reproduce_is_the_command_lines(cli, tmp_path):
    task = task_file(tmp_path)
    out = tmp_path / "out"
    status, stdout, stderr = cli("reproduce", "--model", "ur5", "--task-file", task, "--quick",
                                 "--sample", 16, "--seed", 4, "--json", "--out", out)
    assert status == 0, stderr
    summary = json.loads(stdout)
    result = toolconf.reproduce("ur5", str(task), **QUICK)
    assert result["verdicts"] == {k: v["verdict"] for k, v in summary["verdicts"].items()}
    assert result["summary"]["verdicts"] == summary["verdicts"]
    for name, frame in result.items():
        if name in ("verdicts", "summary"):
            continue
        assert isinstance(frame, pd.DataFrame), name
        with (out / f"{name}.csv").open() as f:
            rows = list(csv.DictReader(f))
        assert list(frame.columns) == list(rows[0].keys()), name
        assert len(frame) == len(rows), name
        for column in frame.columns:
            ours = frame[column].tolist()
            theirs = [r[column] for r in rows]
            for a, b in zip(ours, theirs):
                if b == "":
                    assert a is None or (isinstance(a, float) and np.isnan(a)), (name, column, a)
                elif isinstance(a, str):
                    assert a == b, (name, column)
                else:
                    assert float(a) == float(b), (name, column, a, b)


def test_the_same_run_on_a_cluster_gives_the_same_numbers(dask_client, tmp_path):
    task = task_file(tmp_path)
    local = toolconf.reproduce("ur5", str(task), **QUICK)
    remote = tdask.reproduce("ur5", str(task), client=dask_client, tools_per_task=5, **QUICK)
    assert remote.keys() == local.keys()
    assert remote["verdicts"] == local["verdicts"]
    assert remote["summary"]["verdicts"] == local["summary"]["verdicts"]
    for name in local:
        if name not in ("verdicts", "summary"):
            pd.testing.assert_frame_equal(remote[name], local[name], check_exact=True)


def test_a_tools_table_is_a_population(tmp_path):
    tools = pd.read_csv(REPO / "examples" / "tools" / "ur5_tools.csv", comment="#")
    result = toolconf.reproduce("ur5", str(REPO / "examples" / "tasks" / "ur5_touch_point_relative.toml"),
                                tools, quick=True, frames=False)
    fig2 = result["fig2_confidence_vs_error"]
    assert list(fig2["name"]) == list(tools["name"])
    assert result["summary"]["goal"] == "relative"
    # Every tool starts 7.1 cm from its own goal.
    trajectories = pd.DataFrame(result["fig3_trajectories"])
    start = trajectories[trajectories["t"] == 0]["distance_to_goal"]
    assert np.allclose(start, np.sqrt(0.05**2 + 0.03**2 + 0.04**2), rtol=0, atol=1e-15)


@pytest.mark.parametrize("call, message", [
    (dict(model="kuka", task="tip_position"), "model = unknown model 'kuka'"),
    (dict(model="panda", task="tip_position", sample=0), "sample = 0: no tools"),
    (dict(model="panda", task="tip_position", sample=10**9), "more than the 1000000"),
    (dict(model="panda", task="tip_position", sample=5, box={"tool_lenght": (0.1, 0.2)}),
     "box tool_lenght: model panda has no parameter 'tool_lenght'"),
    (dict(model="panda", task={"kind": "position", "goal": {"tip_offset": [0.05, 0, 0]}}, sample=5),
     "task dict, key goal.tip_offset: a position task has no such goal"),
    (dict(model="ur5", task=str(REPO / "examples" / "tasks" / "panda_touch_point.toml"), sample=5),
     "key precision.u"),
    (dict(model="panda", task="tip_position", sample=5, trial_tools=1), "trial_tools = 1 must be"),
    (dict(model="arm2", task="position", sample=1, seed=-1), "seed = -1: must be at least 0"),
    (dict(model="arm2", task="position", sample=1, seed=2**64),
     "seed = 18446744073709551616: must be at most 18446744073709551615"),
])
def test_bad_input_is_one_line(call, message):
    with pytest.raises(ValueError) as raised:
        toolconf.reproduce(**call)
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_count_that_is_not_an_integer_is_a_type_error():
    with pytest.raises(TypeError):
        toolconf.reproduce("panda", "tip_position", sample=5, trials=2.5)
    with pytest.raises(TypeError, match="seed"):
        toolconf.reproduce("arm2", "position", sample=1, seed=True)
    with pytest.raises(TypeError):
        toolconf.reproduce("panda", "tip_position", sample=5, trails=3)
