"""Every free-text field of a model description and of a task file (titles, sources, units, docs,
LaTeX, equations' names, the printed matrices', the tip's, a URDF arm's, its impedance's and its
tool rule's sources; a task's title and doc, a term's symbol, LaTeX, doc, label and unit, a
remark's text, a formulation's doc) with any text Hypothesis draws: read back exactly as written when it is one
line of text (a paragraph field: lines), and otherwise (a control character, a line break, a
Unicode line or paragraph separator, a bidirectional control, a byte-order mark) refused with one
line naming the file and the key. The renderer's side, that no accepted text reaches generated
code but as a literal or a comment, is derive/render/tests/hostile_text.rs.

    derive/.venv/bin/python -m unittest derive/tests/test_text_fields.py           (in make test)
    TOOLCONF_FUZZ_CASES=20000 derive/.venv/bin/python -m unittest derive/tests/test_text_fields.py
"""

from __future__ import annotations

import os
import sys
import tempfile
import unittest
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.files import refused_character  # noqa: E402
from urdf_model_text import urdf_model_head  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
CASES = int(os.environ.get("TOOLCONF_FUZZ_CASES", "200"))

# The fixture pendulum with each text field a placeholder, and where the reader keeps it.
MODEL = """
[model]
name = "pendulum"
title = @title@
source = @source@
dof = 1

[[parameters]]
name = "m"
latex = @parameter_latex@
unit = @parameter_unit@
doc = @parameter_doc@

[[parameters]]
name = "l"
latex = "l"
unit = "m"
doc = "length of the rod"

[constants]
g = { value = 9.81, latex = @constant_latex@, unit = @constant_unit@, doc = @constant_doc@ }

[coordinates]
q = [{ name = "theta", latex = @q_latex@, unit = @q_unit@, doc = @q_doc@ }]
q_dot = [{ name = "theta_dot", latex = "\\\\dot{\\\\theta}" }]
u = [{ name = "torque", latex = "T" }]

[dynamics]
kind = "explicit"
equations = [@equation@]
q_ddot = ["3/(m*l**2) * (torque - m*g*l*cos(theta)/2)"]

[tip]
position = ["l*cos(theta)", "l*sin(theta)", "0"]
components = 1
source = @tip_source@

[printed]
where = @printed_where@

[equilibrium]
q = ["-pi/2"]
q_dot = ["0"]
u = ["0"]
"""
MODEL_FIELDS = {
    "title": ("model.title", lambda m: m.title),
    "source": ("model.source", lambda m: m.source),
    "parameter_latex": ("parameters[0].latex", lambda m: m.parameters[0].latex),
    "parameter_unit": ("parameters[0].unit", lambda m: m.parameters[0].unit),
    "parameter_doc": ("parameters[0].doc", lambda m: m.parameters[0].doc),
    "constant_latex": ("constants.g.latex", lambda m: m.constants[0].latex),
    "constant_unit": ("constants.g.unit", lambda m: m.constants[0].unit),
    "constant_doc": ("constants.g.doc", lambda m: m.constants[0].doc),
    "q_latex": ("coordinates.q[0].latex", lambda m: m.q[0].latex),
    "q_unit": ("coordinates.q[0].unit", lambda m: m.q[0].unit),
    "q_doc": ("coordinates.q[0].doc", lambda m: m.q[0].doc),
    "equation": ("dynamics.equations[0]", lambda m: m.equations[0]),
    "tip_source": ("tip.source", None),
    "printed_where": ("printed.where", lambda m: m.printed_where),
}

# derive/tasks.toml with its first term's and first task's text fields: (the text as the file
# has it) -> (the key, how the reader keeps it, whether it is a paragraph: lines allowed, kept as
# one line).
TASKS = (ROOT / "derive" / "tasks.toml").read_text()
TASK_FIELDS = {
    'symbol = "θ"': ("term[0].symbol", lambda ts: ts[0].all_terms[0].symbol, False),
    "latex = '\\theta'": ("term[0].latex", lambda ts: ts[0].all_terms[0].latex, False),
    'doc = "the joint angles"': ("term[0].doc", lambda ts: ts[0].all_terms[0].doc, False),
    'label = "joint angle"': ("term[0].label", lambda ts: ts[0].all_terms[0].label, False),
    'unit = "rad"': ("term[0].unit", lambda ts: ts[0].all_terms[0].unit, False),
    'title = "Task 1 (position control)"': ("task[0].title", lambda ts: ts[0].title, False),
    'doc = "Reach and hold a goal configuration of the joints (zero goal velocity and acceleration)."':
        ("task[0].doc", lambda ts: ts[0].doc, True),
    'text = """The paper takes': ("task[1].remarks[0].text", lambda ts: ts[1].remarks[0].text, True),
    'doc = """The stabilised plant': ("task[0].formulations.static_gain.doc",
                                      lambda ts: ts[0].formulations["static_gain"].doc, True),
}

# A URDF arm's own text fields (three joints: its tip has three components).
URDF = """<?xml version="1.0"?><robot name="three">
<link name="base"/><link name="flange"/>""" + "".join(
    f'<link name="l{i}"><inertial><origin xyz="0 0 0.1"/><mass value="1"/>'
    f'<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
    f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 0 else f"l{i - 1}"}"/><child link="l{i}"/>'
    f'<origin xyz="0 0 0.2"/><axis xyz="{"0 0 1" if i == 0 else "0 1 0"}"/>'
    f'<limit lower="-3" upper="3" effort="10" velocity="1"/></joint>' for i in range(3)) + \
    '<joint name="fix" type="fixed"><parent link="l2"/><child link="flange"/></joint></robot>'
URDF_MODEL = urdf_model_head("three.urdf") + """source = @urdf_source@
[impedance]
stiffness = [50.0, 50.0, 50.0]
damping = [5.0, 5.0, 5.0]
source = @impedance_source@
[tool]
source = @tool_source@
[equilibrium]
q = ["0", "0.3", "0.2"]
q_dot = ["0", "0", "0"]
u = ["0", "0", "0"]
"""
URDF_FIELDS = {"urdf_source": "urdf.source", "impedance_source": "impedance.source", "tool_source": "tool.source"}

TEXT = st.text(alphabet=st.one_of(
    st.characters(codec="utf-8"),
    st.sampled_from(list("\"\\'`*/#[]{}$;\n\r\t\0\x85\u2028\u2029\u202e\u2066\ufeff\x1b\x7f ")),
), max_size=60)


def toml_string(text: str) -> str:
    """A TOML basic string holding `text` exactly (every character TOML allows escaped as such)."""
    out = []
    for c in text:
        if c in '"\\':
            out.append("\\" + c)
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04X}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def replace_value(text: str, start: str, value: str) -> str:
    """`text` with the value of the assignment that starts with `start` (one line, or a
    triple-quoted string over lines) replaced by `value`."""
    i = text.index(start)
    name = start.split(" = ")[0]
    j = i + len(name) + 3
    end = text.index('"""', j + 3) + 3 if text.startswith('"""', j) else text.index("\n", j)
    return text[:i] + f"{name} = {value}" + text[end:]


def model_text(field: str, value: str) -> str:
    text = MODEL
    for name in MODEL_FIELDS:
        text = text.replace(f"@{name}@", toml_string(value) if name == field else '"x"')
    return text


class TextFields(unittest.TestCase):
    def read(self, text: str, reader):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "text.toml"
            path.write_text(text, encoding="utf-8")
            try:
                return reader(path), None, path
            except DescriptionError as err:
                return None, err, path

    def refused_naming(self, err: DescriptionError | None, path: Path, key: str, value: str) -> None:
        self.assertIsNotNone(err, f"{key} = {value!r} accepted")
        message = str(err)
        self.assertNotIn("\n", message)
        self.assertTrue(message.startswith(f"{path}: {key}: "), message)

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.sampled_from(sorted(MODEL_FIELDS)), TEXT)
    def test_a_description_text_field_is_read_exactly_or_refused_naming_its_key(self, field: str, value: str):
        key, kept = MODEL_FIELDS[field]
        model, err, path = self.read(model_text(field, value), load_model)
        if refused_character(value) is not None:
            self.refused_naming(err, path, key, value)
            return
        self.assertIsNone(err, f"{key} = {value!r}: {err}")
        if kept is not None:
            self.assertEqual(kept(model), value)

    @settings(max_examples=CASES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.sampled_from(sorted(TASK_FIELDS)), TEXT)
    def test_a_task_text_field_is_read_exactly_or_refused_naming_its_key(self, original: str, value: str):
        key, kept, paragraph = TASK_FIELDS[original]
        self.assertIn(original, TASKS)
        tasks, err, path = self.read(replace_value(TASKS, original, toml_string(value)), load_tasks)
        if refused_character(value, paragraph) is not None:
            self.refused_naming(err, path, key, value)
            return
        self.assertIsNone(err, f"{key} = {value!r}: {err}")
        self.assertEqual(kept(tasks), " ".join(value.split()) if paragraph else value)

    @settings(max_examples=max(1, CASES // 4), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(st.sampled_from(sorted(URDF_FIELDS)), TEXT)
    def test_a_urdf_arms_text_field_is_read_or_refused_naming_its_key(self, field: str, value: str):
        text = URDF_MODEL
        for name in URDF_FIELDS:
            text = text.replace(f"@{name}@", toml_string(value) if name == field else '"x"')
        with tempfile.TemporaryDirectory() as tmp:
            (Path(tmp) / "three.urdf").write_text(URDF)
            path = Path(tmp) / "three.toml"
            path.write_text(text, encoding="utf-8")
            try:
                model, err = load_model(path), None
            except DescriptionError as caught:
                model, err = None, caught
        if refused_character(value) is not None:
            self.refused_naming(err, path, URDF_FIELDS[field], value)
            return
        self.assertIsNone(err, f"{field} = {value!r}: {err}")
        if field == "impedance_source":
            self.assertEqual(model.impedance_source, value)
        if field == "tool_source":
            self.assertEqual(model.tool_rule["source"], value)

    def test_a_paragraph_may_have_lines_and_is_one_line_where_it_is_shown(self):
        doc = next(k for k in TASK_FIELDS if k.startswith('doc = "Reach'))
        text = TASKS.replace(doc, 'doc = """Two\nlines."""', 1)
        tasks, err, _ = self.read(text, load_tasks)
        self.assertIsNone(err)
        self.assertEqual(tasks[0].doc, "Two lines.")
        tasks, err, path = self.read(text.replace('"""Two\nlines."""', '"Two\\u2028lines."', 1), load_tasks)
        self.refused_naming(err, path, "task[0].doc", "Two\u2028lines.")



class ValuesAndNames(unittest.TestCase):
    """Numbers are ASCII decimals, names short ASCII identifiers, the tip an expression of the
    grammar: each refused when the description is read, before anything is derived."""

    def refused(self, text: str, key: str, words: str) -> None:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "m.toml"
            path.write_text(text, encoding="utf-8")
            with self.assertRaises(DescriptionError) as caught:
                load_model(path)
        message = str(caught.exception)
        self.assertTrue(message.startswith(f"{path}: {key}: "), message)
        self.assertIn(words, message)

    def test_digits_of_other_scripts_are_no_numbers(self):
        base = model_text("", "")
        for digits in ("\u0661", "\U0001d7cf", "\uff11", "1\u00a0"):
            self.refused(base.replace('q = ["-pi/2"]', f'q = ["{digits}"]'), "equilibrium.q[0]", "unexpected character")
            self.refused(base.replace("torque - m*g*l", f"torque - {digits}*m*g*l"), "dynamics.q_ddot[0]",
                         "unexpected character")

    def test_a_long_name_and_a_tip_that_is_not_an_expression_are_refused_on_reading(self):
        base = model_text("", "")
        self.refused(base.replace('name = "pendulum"', f'name = "{"p" * 300}"'), "model.name", "longer than 64")
        self.refused(base.replace('"l*sin(theta)"', '"__import__(\'os\').system(\'x\')"'), "tip.position[1]",
                     "unexpected character")
        self.refused(base.replace('"l*sin(theta)"', '"__import__"'), "tip.position[1]", "is not defined")
        self.refused(base.replace('"l*sin(theta)"', '"theta_dot"'), "tip.position[1]", "uses theta_dot")


if __name__ == "__main__":
    unittest.main()
