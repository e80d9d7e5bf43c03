"""examples/python/load_model.py on the Panda's library that ``make loaded-models-test`` builds
from the committed IR (into ``TOOLCONF_TEST_LIBRARIES``; without it this test fails): the loaded
model, under another name, prints the built-in model's numbers bit for bit."""

import os
import re
import subprocess
import sys
from pathlib import Path

import toolconf

REPO = Path(__file__).resolve().parents[2]
LIBRARIES = Path(os.environ["TOOLCONF_TEST_LIBRARIES"])
# A hammer on the Panda's flange (the example's docstring gives the same).
HAMMER = [1.384, -0.0037, 0.0037, 0.1675, 0.0357, 0.0361, 0.0022,
          7.7e-4, -7.1e-4, 7.1e-4, 0.055, 0.0, 0.3684]


def test_the_example_prints_the_built_in_models_numbers():
    out = subprocess.run(
        [sys.executable, str(REPO / "examples" / "python" / "load_model.py"),
         str(LIBRARIES / "panda"), ",".join(map(repr, HAMMER)), "--name", "panda_example"],
        capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stderr
    heading, *rows = out.stdout.splitlines()
    assert heading.startswith("panda_example: 7 joints; parameters tool_mass, "), heading
    assert [row.split()[0] for row in rows] == ["position", "velocity", "acceleration"]
    for row in rows:
        task, logdet, task_error, free_energy = re.fullmatch(
            r"(\S+) +ln\|Pi\^U\| (\S+) +task error (\S+) +int F dt (\S+)", row).groups()
        episode = toolconf.simulate("panda", HAMMER, task)
        assert float(logdet) == toolconf.confidence("panda", HAMMER, task)["logdet"], row
        assert float(task_error) == episode["task_error"], row
        assert float(free_energy) == episode["free_energy"], row
