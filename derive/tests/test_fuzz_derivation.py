"""Fuzzing the derivation's readers (Hypothesis): expressions in a model description, URDF files
and task formulas, from the grammar's own tokens, code fragments and extreme numbers, in random
order. Each case must give a value, or a DescriptionError of one line naming the file (derive.py
prints it with status 2), within a time bound, running nothing: the code fragments would create
a canary file, which must never appear. The readers are called in-process for speed; a few cases
go through derive.py itself.

    derive/.venv/bin/python -m unittest discover -s derive/tests -p 'test_fuzz_derivation.py'
    TOOLCONF_FUZZ_CASES=5000 derive/.venv/bin/python -m unittest discover -s derive/tests -p 'test_fuzz_derivation.py'

(100 cases per reader by default; the second line is the long run, docs/reference/errors.md.)
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.description import load_model, load_tasks, sensitivity  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.symbolic import parse  # noqa: E402
from toolconf_derive.urdf import read_chain  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DERIVE = ROOT / "derive" / "derive.py"
PENDULUM = (ROOT / "tests" / "fixtures" / "pendulum.toml").read_text()
TASKS = (ROOT / "derive" / "tasks.toml").read_text()
CASES = int(os.environ.get("TOOLCONF_FUZZ_CASES", "100"))
SECONDS = 5.0
MAX_MESSAGE = 600
# What timed_or_refused gives for a file the reader refuses.
REFUSED = object()
CANARY = Path(tempfile.gettempdir()) / f"toolconf-fuzz-canary-{os.getpid()}"
RUN = f'__import__("os").system("touch {CANARY}")'
# Tokens of the grammar, of Python, and numbers at and past every bound.
TOKENS = ["m", "l", "g", "theta", "theta_dot", "torque", "pi", "sin", "cos", "sqrt", "x", "A", "B", "I", "O",
          "IO", "OI", "E", "dX_dU", "inv", "0", "1", "2", "9", "0.5", "1e-3", "1e308", "1e400", "9" * 120, "16",
          "17", "+", "-", "*", "/", "**", "@", "(", ")", ",", " ", ".", "[", "]", "{", "}", "'", '"', "\\137",
          "__class__", "__globals__", "__import__", "().__class__", "lambda", ":", "if", "for", "=", ";", "\n",
          "9**9**9", "1/0", RUN, "Π", "\0"]


LEAVES = st.sampled_from(["m", "l", "g", "theta", "torque", "pi", "A", "B", "I", "IO", "0", "2", "0.5", "1e-3",
                          "1e6", "1e308", "16"])
GRAMMATICAL = st.recursive(LEAVES, lambda inner: st.one_of(
    st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**", "@"]), inner).map(" ".join),
    inner.map(lambda e: f"-{e}"), inner.map(lambda e: f"({e})"),
    st.tuples(st.sampled_from(["sin", "cos", "sqrt", "inv"]), inner).map(lambda t: f"{t[0]}({t[1]})")),
    max_leaves=12)


@st.composite
def expressions(draw) -> str:
    """A text of the grammar (which may still be refused: 1e308**16, x/(2-2), names of the other
    place), or of tokens, sometimes one repeated (long sums, deep nesting)."""
    if draw(st.integers(0, 2)) == 0:
        return draw(GRAMMATICAL)
    parts = draw(st.lists(st.sampled_from(TOKENS), max_size=24))
    if draw(st.integers(0, 7)) == 0:
        parts.insert(draw(st.integers(0, len(parts))), draw(st.sampled_from(["(", "-", "m+", "m*", "**1"]))
                     * draw(st.integers(1, 30_000)))
    return "".join(parts)


def toml_string(text: str) -> str:
    """`text` as a TOML basic string (every character escaped where TOML needs it)."""
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ch == "\x7f":
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def replace_once(text: str, old: str, new: str) -> str:
    if old not in text:
        raise AssertionError(f"the fixture no longer contains {old!r}")
    return text.replace(old, new, 1)


# Where an expression goes in the pendulum's description.
PLACES = {
    "dynamics.q_ddot[0]": ('q_ddot = ["3/(m*l**2) * (torque - m*g*l*cos(theta)/2)"]', "q_ddot = [{}]"),
    "equilibrium.q[0]": ('q = ["-pi/2"]', "q = [{}]"),
    "equilibrium.u[0]": ('u = ["0"]', "u = [{}]"),
    "goals.position.theta[0]": ('theta = ["pi/4"]', "theta = [{}]"),
}

URDF = """<?xml version="1.0"?><robot name="fuzz">
<link name="base"/>
<link name="a"><inertial><origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="1.0"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
<link name="flange"/>
<joint name="j1" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0 0 0" rpy="0 0 0"/>
<axis xyz="0 0 1"/><limit lower="-4" upper="4" effort="10" velocity="1"/></joint>
<joint name="fix" type="fixed"><parent link="a"/><child link="flange"/><origin xyz="0 0 0.2" rpy="0 0 0"/></joint>
</robot>"""
URDF_TOKENS = ["<", ">", "/>", "</", '"', "=", " ", "link", "joint", "inertial", "mass", "value", "origin", "xyz",
               "rpy", "1e308", "1e300", "-1", "nan", "inf", "0", "1e5", "101", "&", "&a;", "<!DOCTYPE r [<!ENTITY a "
               '"aaaa">]>', "<!ENTITY", "SYSTEM", '"file:///etc/passwd"', "\xff", "\0", "revolute", "fixed",
               "continuous", "prismatic", "floating", "axis", "0 0 0", "1 2", "a", "base", "flange"]


@st.composite
def urdfs(draw) -> bytes:
    text = URDF
    for _ in range(draw(st.integers(1, 6))):
        at = draw(st.integers(0, len(text)))
        token = draw(st.sampled_from(URDF_TOKENS))
        if draw(st.booleans()):
            text = text[:at] + token + text[at:]
        else:
            text = text[:at] + token + text[at + draw(st.integers(1, 10)):]
    return text.encode("utf-8", "surrogateescape") if draw(st.integers(0, 9)) else draw(st.binary(max_size=300))


def numpy_namespace(n: int = 1) -> dict:
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2 * n, 2 * n)) + 3 * np.eye(2 * n), rng.normal(size=(2 * n, n))
    eye, zero = np.eye(n), np.zeros((n, n))
    e = np.vstack([eye, eye])
    return {"A": a, "B": b, "inv": np.linalg.inv, "I": eye, "O": zero, "IO": np.hstack([eye, zero]),
            "OI": np.hstack([zero, eye]), "E": e, "dX_dU": np.linalg.inv(a) @ (e - b)}


class DerivationReaderFuzz(unittest.TestCase):
    def setUp(self):
        CANARY.unlink(missing_ok=True)

    def tearDown(self):
        self.assertFalse(CANARY.exists(), "a fuzzed expression ran code")

    def one_line(self, err: DescriptionError, path: Path) -> None:
        message = str(err)
        self.assertNotIn("\n", message)
        self.assertTrue(message.startswith(f"{path}: "), message[:200])
        self.assertLessEqual(len(message), MAX_MESSAGE + len(str(path)), message[:200])

    def timed(self, call):
        start = time.monotonic()
        try:
            return call()
        finally:
            self.assertLess(time.monotonic() - start, SECONDS)

    def timed_or_refused(self, call, path: Path):
        """`call`'s value (in time), or REFUSED where it refuses `path` in one line naming it."""
        try:
            return self.timed(call)
        except DescriptionError as err:
            self.one_line(err, path)
            return REFUSED

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.sampled_from(sorted(PLACES)), expressions())
    def test_expressions_in_a_description(self, key: str, text: str) -> None:
        old, new = PLACES[key]
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "fuzz.toml"
            path.write_text(replace_once(PENDULUM, old, new.format(toml_string(text))), encoding="utf-8",
                            errors="surrogateescape")
            model = self.timed_or_refused(lambda: load_model(path), path)
            if model is REFUSED:
                return
            # Read: it is an expression of the grammar, and both arithmetics build it.
            self.timed_or_refused(lambda: self.build(model), path)

    @staticmethod
    def build(model) -> None:
        import sympy as sp
        symbols = {n.name: sp.Symbol(n.name, real=True) for n in model.parameters + model.constants + model.q
                   + model.q_dot + model.u}
        for i, text in enumerate(model.q_ddot):
            parse(model, text, symbols, f"dynamics.q_ddot[{i}]")
        for i, text in enumerate(model.equilibrium_q):
            parse(model, text, {}, f"equilibrium.q[{i}]")
        CasadiModel(model)

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.sampled_from(["theta", "theta_dot", "theta_ddot"]), expressions())
    def test_task_formulas(self, term: str, text: str) -> None:
        old = {"theta": 'sensitivity.theta = "IO @ inv(A) @ (E - B)"',
               "theta_dot": 'sensitivity.theta_dot = "OI @ inv(A) @ (E - B)"',
               "theta_ddot": 'sensitivity.theta_ddot = "I"'}[term]
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "tasks.toml"
            path.write_text(replace_once(TASKS, old, f"sensitivity.{term} = {toml_string(text)}"),
                            encoding="utf-8", errors="surrogateescape")
            tasks = self.timed_or_refused(lambda: load_tasks(path), path)
            if tasks is REFUSED:
                return
            value = self.timed_or_refused(lambda: sensitivity(tasks[0], term, numpy_namespace()), path)
            if value is REFUSED:
                return
            # Read and built: a finite matrix (numbers in a formula are bounded, its degree too).
            self.assertTrue(np.all(np.isfinite(np.asarray(value, dtype=float))), (text, value))

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(urdfs())
    def test_urdfs(self, data: bytes) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "fuzz.urdf"
            path.write_bytes(data)
            try:
                chain = self.timed(lambda: read_chain(path, "base", "flange"))
            except DescriptionError as err:
                self.one_line(err, path)
                return
            # Read: every number it holds is finite and in range.
            for body in chain.bodies:
                self.assertTrue(0 < body.mass <= 1e4, body)
                self.assertTrue(all(abs(x) <= 1e3 for x in body.translation), body)

    def test_a_few_cases_through_derive_py(self) -> None:
        """The same readers through the command: one line, status 2, no traceback."""
        cases = [("equilibrium.q[0]", RUN), ("dynamics.q_ddot[0]", "m" + "+m" * 9_000),
                 ("goals.position.theta[0]", "1e308*1e308"), ("equilibrium.u[0]", "(" * 40 + "0" + ")" * 40)]
        for key, text in cases:
            with self.subTest(key=key), tempfile.TemporaryDirectory() as tmp:
                old, new = PLACES[key]
                path = Path(tmp) / "fuzz.toml"
                path.write_text(replace_once(PENDULUM, old, new.format(toml_string(text))))
                start = time.monotonic()
                r = subprocess.run([sys.executable, str(DERIVE), str(path), "--out", str(Path(tmp) / "f.json"),
                                    "--vectors", "1"], capture_output=True, text=True, timeout=60)
                self.assertLess(time.monotonic() - start, 60)
                self.assertEqual(r.returncode, 2, r.stderr)
                self.assertNotIn("Traceback", r.stderr)
                self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)
                self.assertTrue(r.stderr.startswith(f"derive: {path}: {key}: "), r.stderr)


if __name__ == "__main__":
    unittest.main()
