"""toolconf.rank against `toolconf rank --json`."""

import json
import math
import os
import subprocess
import sys

import pytest

import toolconf

from conftest import DRAWER, REACH_45


def assert_same_as_cli(got, expected_tools):
    assert len(got["rank"]) == len(expected_tools)
    for k, t in enumerate(expected_tools):
        assert got["rank"][k] == t["rank"] and got["row"][k] == t["row"]
        assert got["name"][k] == t["name"] and got["model"][k] == t["model"]
        for p, v in t["parameters"].items():
            assert got[p][k] == v, p
        for key in ("logdet", "task_error", "free_energy", "cost_j", "rhs_evals"):
            if key in t:
                assert got[key][k] == t[key], (k, key)
            else:
                assert math.isnan(got[key][k]) if key != "rhs_evals" else got[key][k] == -1
        assert got["error"][k] == t.get("error"), k


@pytest.mark.parametrize(
    "task, screen, objective",
    [(REACH_45, None, "free-energy"), ("position", 5, "cost-j"), ("velocity", 3, "confidence")],
)
def test_rank_equals_the_command_line(task, screen, objective, cli_json):
    args = ["rank", "--tools", DRAWER, "--task", task, "--objective", objective]
    if screen:
        # Python's screen keeps the most confident: the command line's --screen-by confidence.
        args += ["--screen", screen, "--screen-by", "confidence"]
    expected = cli_json(*args)["tools"]
    got = toolconf.rank(DRAWER, task, screen=screen, objective=objective)
    assert_same_as_cli(got, expected)
    assert set(got) >= {"m1", "m2", "l1", "l2", "error"}


def test_failed_tools_rank_last_with_their_error(cli_json, tmp_path):
    # P^θ = e₁e₁ᵀ and P^U = e₂e₂ᵀ leave Π^U singular for a tool whose ∂θ₁/∂U₁ vanishes
    # (l1 = 1, m1 + 3 m2 = 3; tests/identities.rs).
    path = tmp_path / "t.csv"
    path.write_text("name,m1,m2,l1,l2\nok,0.3,0.3,0.3,0.3\nsingular,1.5,0.5,1.0,0.3\n"
                    "ok2,0.2,0.4,0.3,0.3\n")
    task = tmp_path / "singular.toml"
    task.write_text('kind = "position"\n[precision]\ntheta = [[1.0, 0.0], [0.0, 0.0]]\n'
                    "theta_dot = 0.0\ntheta_ddot = 0.0\nu = [[0.0, 0.0], [0.0, 1.0]]\n"
                    "[episode]\nt_end = 0.5\n")
    expected = cli_json("rank", "--tools", path, "--task", task)["tools"]
    got = toolconf.rank(path, task)
    assert_same_as_cli(got, expected)
    assert got["name"][-1] == "singular" and "not positive definite" in got["error"][-1]


def test_mixed_models_and_a_json_tools_file(cli_json, tmp_path):
    path = tmp_path / "t.json"
    path.write_text(json.dumps([
        {"name": "three", "model": "arm3", "m1": 0.3, "m2": 0.3, "m3": 0.2,
         "l1": 0.3, "l2": 0.3, "l3": 0.2},
        {"name": "two", "m1": 0.3, "m2": 0.4, "l1": 0.5, "l2": 0.2},
    ]))
    expected = cli_json("rank", "--tools", path, "--task", "position")["tools"]
    got = toolconf.rank(str(path), "position")
    assert_same_as_cli(got, expected)
    two = got["name"].index("two")
    assert math.isnan(got["m3"][two])


def test_results_do_not_depend_on_the_number_of_threads(tmp_path):
    script = (
        "import json, sys, toolconf, numpy as np\n"
        "r = toolconf.rank(sys.argv[1], 'position')\n"
        "c = toolconf.confidence('arm2', 0.1 + 0.5 * np.random.default_rng(3).random((3000, 4)),"
        " 'velocity')\n"
        "print(json.dumps({'rank': {k: list(map(repr, v)) for k, v in r.items()},"
        " 'logdet': list(map(repr, c['logdet']))}))\n"
    )
    outputs = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        out = subprocess.run([sys.executable, "-c", script, str(DRAWER)], env=env,
                             capture_output=True, text=True, check=True)
        outputs.append(out.stdout)
    assert outputs[0] == outputs[1]
