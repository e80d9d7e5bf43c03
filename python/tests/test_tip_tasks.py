"""Tasks on the tool's tip from Python: simulate, rank, confidence and toolconf.dask take
tip tasks; an episode's tip series are the tip's forward kinematics (toolconf.tip at the
episode's joint angles); rank's progress column equals the command line's JSON; a tools table
without tip columns is refused by a tip task, naming the row and the columns."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import toolconf
import toolconf.dask as tdask

ROOT = Path(__file__).resolve().parents[2]
TOUCH = str(ROOT / "examples/tasks/panda_touch_point.toml")
DRAW = str(ROOT / "examples/tasks/panda_draw_line.toml")
PUSH = str(ROOT / "examples/tasks/panda_push_off.toml")
PANDA_TOOLS = ROOT / "examples/tools/panda_tools.csv"
# A 0.8 kg tool, its tip 25 cm out along the flange axis (flange frame).
TOOL = [0.8, 0.0, 0.0, 0.05, 3e-3, 3e-3, 1.5e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25]


def test_an_episodes_tip_is_the_tips_forward_kinematics_and_reaches_the_goal():
    e = toolconf.simulate("panda", TOOL, TOUCH)
    assert e["tip"].shape == (101, 3) and e["tip_dot"].shape == (101, 3)
    y = toolconf.tip("panda", np.array(TOOL), e["theta"])
    np.testing.assert_array_equal(e["tip"], y["position"])
    # The same J q̇, summed in another order (nalgebra's product, NumPy's einsum): a few ulps.
    np.testing.assert_allclose(e["tip_dot"], np.einsum("kij,kj->ki", y["jacobian"], e["theta_dot"]),
                               rtol=1e-13, atol=1e-16)
    goal = np.array([0.357, 0.030, 0.390])
    d = np.linalg.norm(e["tip"] - goal, axis=1)
    assert e["progress"] == pytest.approx(1 - d[-1] / d[0], rel=1e-12)
    assert e["progress"] > 0.8


def test_a_tip_acceleration_episodes_series_is_j_q_ddot_plus_the_bias():
    """ÿ along a tip acceleration episode is J(q) q̈ + J̇ q̇ from toolconf.tip at the episode's
    states (q̈ the plant's, as recorded), and the episode reads it: its tip first accelerates
    along the goal's x."""
    e = toolconf.simulate("panda", TOOL, PUSH)
    assert e["tip_ddot"].shape == (101, 3) and e["progress"] is None
    y = toolconf.tip("panda", np.array(TOOL), e["theta"], e["theta_dot"])
    expected = np.einsum("kij,kj->ki", y["jacobian"], e["theta_ddot"]) + y["bias"]
    np.testing.assert_allclose(e["tip_ddot"], expected, rtol=1e-12, atol=1e-15)
    assert e["tip_ddot"][10, 0] > 0.05 and abs(e["tip_ddot"][10, 1]) < 1e-3


def test_a_joint_task_has_no_tip_series_and_no_progress_off_position():
    e = toolconf.simulate("panda", TOOL, "velocity")
    assert "tip" not in e and "tip_dot" not in e and e["progress"] is None
    assert toolconf.simulate("panda", TOOL, "position")["progress"] is not None


def test_rank_of_a_tip_task_equals_the_command_lines_json(cli_json):
    got = toolconf.rank(str(PANDA_TOOLS), TOUCH)
    cli = cli_json("rank", "--tools", PANDA_TOOLS, "--task", TOUCH)["tools"]
    assert list(got["row"]) == [t["row"] for t in cli]
    for key in ("logdet", "task_error", "free_energy", "cost_j", "progress"):
        assert list(got[key]) == [t[key] for t in cli], key
    assert min(got["progress"]) >= 0.8
    # A velocity task measures no progress: no column (never a column of NaN).
    assert "progress" not in toolconf.rank(str(PANDA_TOOLS), DRAW)


def test_the_tip_spreads_confidence_where_joint_tasks_do_not():
    tips = toolconf.rank(str(PANDA_TOOLS), TOUCH, objective="confidence")["logdet"]
    assert max(tips) - min(tips) > 10 * 0.011


def test_a_tools_table_without_tips_is_refused_by_a_tip_task_naming_row_and_columns():
    table = {"model": ["panda"], "tool_mass": [0.5], "tool_com_x": [0.0], "tool_com_y": [0.0],
             "tool_com_z": [0.01], "tool_ixx": [1e-3], "tool_iyy": [1e-3], "tool_izz": [1e-3]}
    with pytest.raises(ValueError) as e:
        toolconf.rank(table, TOUCH)
    assert "tool 1: the tip_position task reads the tool's tip" in str(e.value)
    assert "tool_tip_x, tool_tip_y, tool_tip_z" in str(e.value)


def test_confidence_of_a_tip_task_has_the_tips_rows():
    c = toolconf.confidence("panda", TOOL, "tip_position")
    assert c["sensitivities"]["d_tip_du"].shape == (3, 7)
    # ∂y/∂U = J ∂θ/∂U, J at q^e: the panda's position tasks share the static gain formulation.
    q_e = np.array(toolconf.models()["panda"]["equilibrium"]["q"])
    j = toolconf.tip("panda", np.array(TOOL), q_e)["jacobian"]
    joints = toolconf.confidence("panda", TOOL, "position")["sensitivities"]["d_theta_du"]
    np.testing.assert_allclose(c["sensitivities"]["d_tip_du"], j @ joints, rtol=1e-10, atol=1e-16)


def test_dask_ranks_a_tip_task_as_toolconf_does(dask_client):
    frame = pd.read_csv(PANDA_TOOLS, comment="#")
    ddf = __import__("dask.dataframe", fromlist=["from_pandas"]).from_pandas(frame, npartitions=3)
    got = tdask.rank(ddf, TOUCH, client=dask_client)
    expected = toolconf.rank(frame, TOUCH)
    pd.testing.assert_frame_equal(got, expected, check_exact=True)
