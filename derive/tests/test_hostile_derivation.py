"""Hostile descriptions, URDFs and task files through the real commands (derive/derive.py and
derive/make_crate.py): each is one line on stderr naming the file and key, exit status 2, no
traceback, nothing executed (a canary file the payloads would create must not appear), nothing
written, and within a time bound.

    derive/.venv/bin/python -m unittest discover -s derive/tests -p 'test_hostile_derivation.py'
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

from urdf_model_text import urdf_model_head

ROOT = Path(__file__).resolve().parents[2]
DERIVE = ROOT / "derive" / "derive.py"
MAKE_CRATE = ROOT / "derive" / "make_crate.py"
PENDULUM = (ROOT / "tests" / "fixtures" / "pendulum.toml").read_text()
TASKS = (ROOT / "derive" / "tasks.toml").read_text()
# A refusal is immediate; the bound is the interpreter's start and SymPy's import on a busy
# machine, far below the 30 s that 9**9**9 ran past.
SECONDS = 30
KEY_EQ_Q = "equilibrium.q[0]"

# Three joints (a URDF tool's tip has three components, which a tip term stores in the joints'
# slots); each case breaks link a or joint j1.
URDF = """<?xml version="1.0"?><robot name="test">
<link name="base"/>
<link name="a"><inertial><origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="{mass}"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="{izz}"/></inertial></link>
<link name="b"><inertial><origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="0.5"/>
<inertia ixx="0.005" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.005"/></inertial></link>
<link name="c"><inertial><origin xyz="0 0 0.05" rpy="0 0 0"/><mass value="0.3"/>
<inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial></link>
<link name="flange"/>
<joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="{xyz}" rpy="0 0 0"/>
<axis xyz="0 0 1"/><limit lower="-4" upper="4" effort="10" velocity="1"/></joint>
<joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.2" rpy="0 0 0"/>
<axis xyz="0 1 0"/><limit lower="-4" upper="4" effort="10" velocity="1"/></joint>
<joint name="j3" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0 0.2" rpy="0 0 0"/>
<axis xyz="1 0 0"/><limit lower="-4" upper="4" effort="10" velocity="1"/></joint>
<joint name="fix" type="fixed"><parent link="c"/><child link="flange"/><origin xyz="0 0 0.1" rpy="0 0 0"/></joint>
</robot>"""
URDF_MODEL = urdf_model_head("{file}") + """[impedance]
stiffness = [50.0, 50.0, 50.0]
damping = [5.0, 5.0, 5.0]
[equilibrium]
q = ["0.3", "0.2", "0.1"]
q_dot = ["{q_dot}", "0", "0"]
u = ["{u}", "0", "0"]
"""


def edit(text: str, old: str, new: str) -> str:
    if old not in text:
        raise AssertionError(f"the fixture no longer contains {old!r}")
    return text.replace(old, new, 1)


class Hostile(unittest.TestCase):
    def setUp(self):
        self.tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        self.canary = self.tmp / "canary"

    def payload(self) -> str:
        """The reported payload: attribute access and escaped strings to os.system, creating the canary."""
        return ('(1).__add__.__globals__[\\"\\\\137\\\\137builtins\\\\137\\\\137\\"][\\"\\\\137\\\\137import\\\\137\\\\137\\"]'
                f'(\\"\\\\157\\\\163\\").system(\\"touch {self.canary}\\")')

    def run_command(self, cmd: list[str]) -> subprocess.CompletedProcess:
        start = time.monotonic()
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=SECONDS, cwd=ROOT)
        self.assertLess(time.monotonic() - start, SECONDS)
        return r

    def assert_refused(self, r: subprocess.CompletedProcess, prefix: str, problem: str, status: int = 2) -> None:
        self.assertEqual(r.returncode, status, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        lines = r.stderr.splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertTrue(lines[0].startswith(prefix), lines[0])
        self.assertIn(problem, lines[0])
        self.assertFalse(self.canary.exists(), "the payload ran")

    def derive(self, model: str | None = None, tasks: str | None = None, model_path: Path | None = None,
               tasks_path: Path | None = None) -> subprocess.CompletedProcess:
        if model_path is None:
            model_path = self.tmp / "m.toml"
            model_path.write_text(model if model is not None else PENDULUM)
        if tasks_path is None:
            tasks_path = self.tmp / "tasks.toml"
            tasks_path.write_text(tasks if tasks is not None else TASKS)
        out = self.tmp / "out"
        out.mkdir(exist_ok=True)
        r = self.run_command([sys.executable, str(DERIVE), str(model_path), "--tasks", str(tasks_path),
                              "--out", str(out / "m.json"), "--vectors", "1"])
        self.assertEqual(list(out.iterdir()), [], "nothing written")
        return r

    def model_refused(self, model: str, key: str, problem: str) -> None:
        self.assert_refused(self.derive(model), f"derive: {self.tmp / 'm.toml'}: {key}: ", problem)

    def equilibrium(self, text: str) -> str:
        return edit(PENDULUM, 'q = ["-pi/2"]', f'q = ["{text}"]')

    # --- expressions in a description ---------------------------------------------------------

    def test_code_in_an_equilibrium_does_not_run(self):
        self.model_refused(self.equilibrium(self.payload()), KEY_EQ_Q, "unexpected character '.'")

    def test_attribute_access_in_a_goal(self):
        self.model_refused(edit(PENDULUM, 'theta = ["pi/4"]', 'theta = ["().__class__"]'), "goals.position.theta[0]",
                           "unexpected character '.' at character 3")

    def test_division_by_zero_in_an_equilibrium(self):
        self.model_refused(self.equilibrium("1/0"), KEY_EQ_Q, "division by zero")

    def test_huge_power_in_an_equilibrium_is_refused_at_once(self):
        self.model_refused(self.equilibrium("9**9**9"), KEY_EQ_Q, "larger than 16 in magnitude")

    def test_infinite_number_in_an_equilibrium(self):
        self.model_refused(self.equilibrium("pi*1e400"), KEY_EQ_Q, "the number 1e400 is not finite")

    def test_a_200000_term_sum(self):
        model = edit(PENDULUM, '"3/(m*l**2)', '"' + "+".join(["m"] * 200_000) + ' + 3/(m*l**2)')
        self.model_refused(model, "dynamics.q_ddot[0]", "longer than 20000 characters")

    def test_a_value_out_of_range(self):
        self.model_refused(self.equilibrium("1e308"), KEY_EQ_Q, "is not a number within [-1e+06, 1e+06]")

    # --- task formulas ---------------------------------------------------------------------------

    def tasks_refused(self, old: str, new: str, key: str, problem: str) -> None:
        r = self.derive(tasks=edit(TASKS, old, new))
        self.assert_refused(r, f"derive: {self.tmp / 'tasks.toml'}: {key}: ", problem)

    def test_code_in_a_task_formula_does_not_run(self):
        self.tasks_refused('sensitivity.theta_ddot = "I"', f'sensitivity.theta_ddot = "{self.payload()}"',
                           "task[0].sensitivity.theta_ddot", "unexpected character '.'")
        self.tasks_refused('sensitivity.theta_ddot = "I"',
                           f'sensitivity.theta_ddot = "__import__(os)"', "task[0].sensitivity.theta_ddot",
                           "'__import__' is not defined")

    def test_division_by_zero_and_a_huge_power_in_a_task_formula(self):
        self.tasks_refused('sensitivity.theta_ddot = "I"', 'sensitivity.theta_ddot = "I/0"',
                           "task[0].sensitivity.theta_ddot", "division by zero")
        self.tasks_refused('sensitivity.theta_ddot = "I"', 'sensitivity.theta_ddot = "I * 9**9**9"',
                           "task[0].sensitivity.theta_ddot", "a task formula has no powers")
        self.tasks_refused('sensitivity.theta_ddot = "I"', 'sensitivity.theta_ddot = "().__class__"',
                           "task[0].sensitivity.theta_ddot", "unexpected character '.'")

    # --- files that are not description files ----------------------------------------------------

    def test_dev_zero_a_fifo_and_a_folder_as_a_description(self):
        fifo = self.tmp / "fifo.toml"
        os.mkfifo(fifo)
        for path, what in ((Path("/dev/zero"), "a character device"), (fifo, "a FIFO"), (self.tmp, "a folder")):
            with self.subTest(path=path):
                r = self.derive(model_path=path)
                self.assert_refused(r, f"derive: {path}: ", f"{what}, not a description file")

    def test_dev_zero_as_the_task_file(self):
        r = self.derive(tasks_path=Path("/dev/zero"))
        self.assert_refused(r, "derive: /dev/zero: ", "a character device, not a task file")

    def test_a_description_that_is_not_utf8(self):
        path = self.tmp / "m.toml"
        path.write_bytes(PENDULUM.encode().replace(b"# ", b"# \xff", 1))
        r = self.derive(model_path=path)
        self.assert_refused(r, f"derive: {path}: ", "not UTF-8 text: invalid start byte at byte")

    # --- URDFs -----------------------------------------------------------------------------------

    def urdf_refused(self, urdf_file: str, problem: str, where: str, q_dot: str = "0", u: str = "0",
                     urdf: str | None = None) -> None:
        if urdf is not None:
            (self.tmp / "robot.urdf").write_text(urdf)
        (self.tmp / "m.toml").write_text(URDF_MODEL.format(file=urdf_file, q_dot=q_dot, u=u))
        r = self.derive(model_path=self.tmp / "m.toml")
        self.assert_refused(r, f"derive: {where}", problem)

    def good_urdf(self, mass: str = "1.0", izz: str = "0.01", xyz: str = "0 0 0") -> str:
        return URDF.format(mass=mass, izz=izz, xyz=xyz)

    def test_the_small_urdf_arm_derives(self):
        # The fixture of the URDF cases is itself good: each case breaks one thing.
        (self.tmp / "robot.urdf").write_text(self.good_urdf())
        (self.tmp / "m.toml").write_text(URDF_MODEL.format(file="robot.urdf", q_dot="0", u="0"))
        out = self.tmp / "good"
        out.mkdir()
        r = self.run_command([sys.executable, str(DERIVE), str(self.tmp / "m.toml"), "--out", str(out / "m.json"),
                              "--vectors", "1"])
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_inertia_and_origin_out_of_range(self):
        robot = self.tmp / "robot.urdf"
        self.urdf_refused("robot.urdf", "'1e300' is outside [-100000, 100000] kg m^2", f"{robot}: link 'a' inertia izz",
                          urdf=self.good_urdf(izz="1e300"))
        self.urdf_refused("robot.urdf", "'0 0 1e308' is outside [-100, 100] m", f"{robot}: joint 'j1' origin xyz",
                          urdf=self.good_urdf(xyz="0 0 1e308"))
        self.urdf_refused("robot.urdf", "'1e5' is outside [-10000, 10000] kg", f"{robot}: link 'a' mass value",
                          urdf=self.good_urdf(mass="1e5"))

    def test_dev_zero_and_a_fifo_as_the_urdf(self):
        fifo = self.tmp / "robot.fifo"
        os.mkfifo(fifo)
        self.urdf_refused("/dev/zero", "a character device, not a URDF file", "/dev/zero: ")
        self.urdf_refused(str(fifo), "a FIFO, not a URDF file", f"{fifo}: ")

    def test_an_entity_bomb(self):
        bomb = ('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">' +
                "".join(f'<!ENTITY {c} "{("&" + p + ";") * 10}">' for p, c in zip("abcdefgh", "bcdefghi")) +
                ']><robot name="&i;"/>')
        robot = self.tmp / "robot.urdf"
        self.urdf_refused("robot.urdf", "refused XML", f"{robot}: ", urdf=bomb)

    def test_a_moving_urdf_equilibrium_is_refused_not_replaced(self):
        (self.tmp / "robot.urdf").write_text(self.good_urdf())
        self.urdf_refused("robot.urdf", "'0.5' is not 0", f"{self.tmp / 'm.toml'}: equilibrium.q_dot[0]", q_dot="0.5")
        self.urdf_refused("robot.urdf", "'1' is not 0", f"{self.tmp / 'm.toml'}: equilibrium.u[0]", u="1")

    # --- make crate ------------------------------------------------------------------------------

    def make_crate(self, models: Path, *extra: str) -> subprocess.CompletedProcess:
        return self.run_command([sys.executable, str(MAKE_CRATE), "--models", str(models), "--out",
                                 str(self.tmp / "mycrate"), *extra])

    def test_make_crate_on_a_non_utf8_description_and_a_fifo(self):
        models = self.tmp / "models"
        models.mkdir()
        bad = models / "bad.toml"
        bad.write_bytes(b"[model]\nname = \"x\xff\"\n")
        self.assert_refused(self.make_crate(models), f"derive: {bad}: ", "not UTF-8 text")
        bad.unlink()
        os.mkfifo(models / "fifo.toml")
        # A writer that never comes: an open that blocked would hang until the timeout.
        self.assert_refused(self.make_crate(models), f"derive: {models / 'fifo.toml'}: ", "a FIFO, not a description")
        self.assertFalse((self.tmp / "mycrate").exists())

    def test_make_crate_with_dev_zero_as_the_task_file(self):
        models = self.tmp / "models"
        models.mkdir()
        (models / "pendulum.toml").write_text(PENDULUM)
        self.assert_refused(self.make_crate(models, "--tasks", "/dev/zero"), "make crate: TASKS=/dev/zero: ",
                            "a character device, not a task file")
        self.assertEqual(sorted(p.name for p in self.tmp.iterdir()), ["models"], "nothing written")


if __name__ == "__main__":
    unittest.main()
