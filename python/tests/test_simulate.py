"""toolconf.simulate against the command line and against the trajectory it returns."""

import csv
import math

import numpy as np
import pytest

import toolconf

from conftest import REACH_45

PAPER_ARM = [0.3, 0.4, 0.5, 0.2]
METRICS = ["task_error", "free_energy", "cost_j", "logdet", "rhs_evals", "steps", "rejected_steps"]


@pytest.mark.parametrize("task", ["position", "velocity", "acceleration"])
def test_the_paper_arm_equals_the_command_line(task, cli_json):
    expected = cli_json("simulate", "--arm", "0.3,0.4,0.5,0.2", "--task", task)
    got = toolconf.simulate("arm2", PAPER_ARM, task)
    for key in METRICS:
        assert got[key] == expected[key], key


@pytest.mark.parametrize("method", ["explicit", "auto", "stiff"])
def test_each_method_equals_the_command_line(method, cli_json):
    expected = cli_json("simulate", "--arm", "0.3,0.4,0.5,0.2", "--task", "velocity", "--method", method)
    got = toolconf.simulate("arm2", PAPER_ARM, "velocity", method=method)
    for key in METRICS:
        assert got[key] == expected[key], key


def test_an_unknown_method_is_a_value_error():
    with pytest.raises(ValueError, match="method = 'rk4'"):
        toolconf.simulate("arm2", PAPER_ARM, "position", method="rk4")


def test_episode_options_equal_the_command_line_flags(cli_json, cli, tmp_path):
    flags = ["--perturb", "-0.8", "--t-end", "3", "--dt", "0.1", "--gamma", "2"]
    expected = cli_json("simulate", "--arm", "0.3,0.4,0.5,0.2", "--task", "position", *flags)
    got = toolconf.simulate(
        "arm2", PAPER_ARM, "position", perturbation=-0.8, t_end=3.0, dt=0.1, learning_rate=2.0
    )
    for key in METRICS:
        assert got[key] == expected[key], key
    # The trajectory is the command line's CSV, digit for digit.
    path = tmp_path / "traj.csv"
    status, _, stderr = cli("simulate", "--arm", "0.3,0.4,0.5,0.2", "--task", "position",
                            *flags, "--csv", path)
    assert status == 0, stderr
    rows = list(csv.DictReader(path.open()))
    assert got["t"].tolist() == [float(r["t"]) for r in rows]
    for name in ("theta", "theta_dot", "theta_ddot"):
        for j in (0, 1):
            column = [float(r[f"{name.replace('theta', f'theta{j + 1}', 1)}"]) for r in rows]
            assert got[name][:, j].tolist() == column, (name, j)
    assert got["u"].tolist() == [[float(r["u1"]), float(r["u2"])] for r in rows]


def test_a_task_file_with_options_over_it_equals_the_command_line(cli_json):
    expected = cli_json("simulate", "--arm", "0.3,0.4,0.5,0.2", "--task-file", REACH_45,
                        "--t-end", "2")
    got = toolconf.simulate("arm2", PAPER_ARM, REACH_45, t_end=2.0)
    for key in METRICS:
        assert got[key] == expected[key], key
    assert got["t"][-1] == 2.0


def test_the_metrics_are_sums_and_integrals_of_the_trajectory():
    # Recomputed in NumPy from the returned trajectory and the task's own numbers: the task
    # error is Σ (θ−θᵍ)ᵀP^θ(θ−θᵍ) over the grid, ∫J dt and ∫F dt = ∫J dt − ½ T ln|Π^U| by the
    # trapezoidal rule, J = ½[Σ eᵀPe + UᵀP^U U].
    p_theta = np.array([[120.0, 20.0], [20.0, 60.0]])
    p_theta_dot, p_theta_ddot, p_u = 50.0, 1.0, 2.0
    goal = np.array([0.7853981633974483, 0.0])
    task = {
        "kind": "position",
        "goal": {"theta": goal.tolist(), "theta_dot": [0.0, 0.0], "theta_ddot": [0.0, 0.0]},
        "precision": {"theta": p_theta, "theta_dot": p_theta_dot,
                      "theta_ddot": p_theta_ddot, "u": p_u},
    }
    for model, params in [("arm2", PAPER_ARM), ("arm2_exact", [0.3, 0.3, 0.4, 0.4])]:
        e = toolconf.simulate(model, params, task, t_end=4.0)
        err = e["theta"] - goal
        weighted = np.einsum("ti,ij,tj->t", err, p_theta, err)
        assert e["task_error"] == pytest.approx(weighted.sum(), rel=1e-12)
        j = 0.5 * (weighted + p_theta_dot * (e["theta_dot"] ** 2).sum(1)
                   + p_theta_ddot * (e["theta_ddot"] ** 2).sum(1) + p_u * (e["u"] ** 2).sum(1))
        cost_j = np.trapezoid(j, e["t"])
        assert e["cost_j"] == pytest.approx(cost_j, rel=1e-12)
        assert e["free_energy"] == pytest.approx(cost_j - 0.5 * 4.0 * e["logdet"], rel=1e-12)
        assert e["logdet"] == toolconf.confidence(model, params, task)["logdet"]


@pytest.mark.parametrize("model", ["arm3", "arm2_payload", "msd"])
def test_every_model_simulates_with_its_own_sizes(model, cli_json, tmp_path):
    # Models without a `simulate` subcommand: the command line's `rank` of a one-tool file runs
    # the same generic episode.
    info = toolconf.models()[model]
    params = np.linspace(0.2, 0.5, len(info["parameters"]))
    path = tmp_path / "one.csv"
    path.write_text("model," + ",".join(info["parameters"]) + "\n"
                    + model + "," + ",".join(repr(float(p)) for p in params) + "\n")
    expected = cli_json("rank", "--tools", path, "--task", "velocity")["tools"][0]
    e = toolconf.simulate(model, params, "velocity")
    for key in ("task_error", "free_energy", "cost_j", "logdet", "rhs_evals"):
        assert e[key] == expected[key], key
    n = info["dof"]
    assert e["t"].shape == (101,)
    for key in ("theta", "theta_dot", "theta_ddot", "u"):
        assert e[key].shape == (101, n), key
    assert e["u"][0].tolist() == [0.1] * n  # U0 = 0.1 on every joint


def test_a_failed_episode_raises_simulation_error_with_tool_time_and_reason(cli, tmp_path):
    # Torques at the edge of their valid range throw the arm past the divergence bound.
    wild = {"perturbation": 1e6, "initial_torque": 1e6, "t_end": 0.01, "dt": 0.01}
    path = tmp_path / "wild.toml"
    path.write_text('kind = "position"\n[episode]\n'
                    + "".join(f"{k} = {v}\n" for k, v in wild.items()))
    status, _, stderr = cli("simulate", "--arm", "0.3,0.4,0.25,0.2", "--task-file", path)
    assert status == 1
    with pytest.raises(toolconf.SimulationError) as caught:
        toolconf.simulate("arm2", [0.3, 0.4, 0.25, 0.2], "position", **wild)
    e = caught.value
    assert isinstance(e, RuntimeError)
    assert e.tool == "arm2(m1=0.3 m2=0.4 l1=0.25 l2=0.2)"
    assert e.time == 0.01
    assert e.reason.startswith("diverged: |state| = ")
    assert stderr == f"toolconf: error: {e}\n"


def test_a_divergence_names_its_time():
    with pytest.raises(toolconf.SimulationError) as caught:
        # A free mass (k, c at their smallest) pushed by 10⁶ N passes 10⁶ m near t = 1.4 s.
        toolconf.simulate("msd", [1.0, 1e-6, 1e-6], "velocity", learning_rate=1e-12,
                          perturbation=1e6, t_end=2.0)
    e = caught.value
    assert e.time is not None and 0.0 < e.time <= 2.0
    assert "diverged" in e.reason and math.isfinite(e.time)
