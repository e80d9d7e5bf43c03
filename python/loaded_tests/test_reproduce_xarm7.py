"""``toolconf reproduce --model`` on a robot the repository does not ship as a model: the UFactory
xArm7, loaded from the library ``make model`` built from its unedited URDF, on a task written
here. Its claims equal an independent computation from ``select --json`` on the same tools with
SciPy (python/tests/independent_claims.py), and its default ΔT is −10 % of the efforts its URDF
states (50, 50, 30, 30, 30, 20, 20 N m)."""

import importlib.util
import json
import os
from pathlib import Path

import toolconf

REPO = Path(__file__).resolve().parents[2]
LIBRARY = Path(os.environ["TOOLCONF_TEST_LIBRARIES"]) / "xarm7"
_spec = importlib.util.spec_from_file_location(
    "independent_claims", REPO / "python" / "tests" / "independent_claims.py")
independent_claims = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(independent_claims)

TASK = """kind = "tip_position"
description = "xArm7: a point 5 cm out and 3 cm down from each tool's tip"
[goal]
tip_offset = [0.05, 0.0, -0.03]
"""


def test_the_xarm7s_claims_equal_an_independent_computation(cli, cli_json, tmp_path):
    prefix = ["--model-path", LIBRARY]
    dt = "[-5.0, -5.0, -3.0, -3.0, -3.0, -2.0, -2.0]"
    independent_claims.check(cli, cli_json, prefix, "xarm7", TASK, dt, tmp_path)


def test_the_xarm7s_default_perturbation_comes_from_its_urdf(cli, tmp_path):
    task = tmp_path / "task.toml"
    task.write_text(TASK)
    status, stdout, stderr = cli("--model-path", LIBRARY, "reproduce", "--model", "xarm7",
                                 "--task-file", task, "--sample", 8, "--quick", "--json",
                                 "--out", tmp_path / "out")
    assert status == 0, stderr
    summary = json.loads(stdout)
    assert summary["perturbation"] == [-5.0, -5.0, -3.0, -3.0, -3.0, -2.0, -2.0]
    assert "xarm7.urdf" in summary["perturbation_source"]
    name = toolconf.load_model(LIBRARY)
    result = toolconf.reproduce(name, str(task), sample=8, quick=True)
    assert result["summary"]["verdicts"] == summary["verdicts"]
