"""A malformed model or task description stops derive.py with one line on stderr naming the file,
the key and the problem, and exit status 2 (bad input): each case breaks one thing in a copy of
tests/fixtures/pendulum.toml (or derive/tasks.toml) and runs derive.py on it.

    derive/.venv/bin/python -m unittest discover -s derive/tests      (part of make test)
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))
DERIVE = ROOT / "derive" / "derive.py"
PENDULUM = (ROOT / "tests" / "fixtures" / "pendulum.toml").read_text()
TASKS = (ROOT / "derive" / "tasks.toml").read_text()


def edit(text: str, old: str, new: str) -> str:
    # The edit must apply: a fixture that changed under a test would otherwise test nothing.
    if old not in text:
        raise AssertionError(f"the fixture no longer contains {old!r}")
    return text.replace(old, new, 1)


class BrokenDescription(unittest.TestCase):
    def derive(self, model: str = PENDULUM, tasks: str = TASKS) -> tuple[subprocess.CompletedProcess, Path, Path]:
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        model_path, tasks_path = tmp / "broken.toml", tmp / "tasks.toml"
        model_path.write_text(model)
        tasks_path.write_text(tasks)
        r = subprocess.run([sys.executable, str(DERIVE), str(model_path), "--tasks", str(tasks_path),
                            "--out", str(tmp / "broken.json"), "--vectors", "1"], capture_output=True, text=True)
        return r, model_path, tasks_path

    def assert_stops(self, r: subprocess.CompletedProcess, path: Path, key: str, problem: str) -> None:
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        lines = r.stderr.splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertTrue(lines[0].startswith(f"derive: {path}: {key}: "), lines[0])
        self.assertIn(problem, lines[0])
        self.assertEqual(r.stdout, "")

    def model_stops(self, model: str, key: str, problem: str) -> None:
        r, path, _ = self.derive(model=model)
        self.assert_stops(r, path, key, problem)

    def tasks_stop(self, tasks: str, key: str, problem: str) -> None:
        r, _, path = self.derive(tasks=tasks)
        self.assert_stops(r, path, key, problem)

    # [tip]: three expressions of q, the parameters and the constants, required for kind explicit
    # (the tip terms read it), its components at most model.dof.
    TIP = 'position = ["l*cos(theta)", "l*sin(theta)", "0"]'

    def test_tip_needs_three_entries(self):
        self.model_stops(edit(PENDULUM, self.TIP, 'position = ["l*sin(theta)", "-l*cos(theta)"]'), "tip.position",
                         "has 2 entries, need 3")

    def test_tip_may_not_use_rates_or_controls(self):
        self.model_stops(edit(PENDULUM, self.TIP, 'position = ["l*sin(theta)", "theta_dot", "0"]'), "tip.position[1]",
                         "uses theta_dot")

    def test_tip_names_an_unknown_symbol(self):
        self.model_stops(edit(PENDULUM, self.TIP, 'position = ["l*sin(phi)", "0", "0"]'), "tip.position[0]", "phi")

    def test_an_explicit_model_without_a_tip(self):
        text = edit(edit(PENDULUM, "[tip]\n" + self.TIP + "\n", ""), "components = 1\n", "")
        self.model_stops(text, "tip", "missing (required for dynamics.kind = 'explicit'): the tip terms of "
                                      "derive/tasks.toml (tip, tip_dot) read the tip's position")

    def test_more_tip_components_than_joints(self):
        # A tip term's vectors are stored in the joints' slots: one joint holds one component.
        self.model_stops(edit(PENDULUM, "\ncomponents = 1", "\ncomponents = 2"), "tip.components",
                         "is 2, more than the model's 1 joint(s)")
        self.model_stops(edit(PENDULUM, "\ncomponents = 1", "\ncomponents = 4"), "tip.components", "must be 1, 2 or 3")

    def test_a_tip_goal_of_the_wrong_length(self):
        self.model_stops(PENDULUM + '\n[goals.tip_position]\ntip = ["0.1", "0"]\n', "goals.tip_position.tip",
                         "has 2 entries, the tip's components (TIP_DIM) is 1")
        self.model_stops(PENDULUM + '\n[goals.tip_velocity]\ntip_dot = []\n', "goals.tip_velocity.tip_dot",
                         "has 0 entries, the tip's components (TIP_DIM) is 1")

    # [formulation]: a task of tasks.toml = one of its formulations, or "paper".
    def test_an_unknown_formulation(self):
        self.model_stops(PENDULUM + '\n[formulation]\nposition = "magic"\n', "formulation.position",
                         "'magic' is not a formulation of task 'position' (known: paper, static_gain)")
        self.model_stops(PENDULUM + '\n[formulation]\nposture = "paper"\n', "formulation.posture",
                         "no task is named 'posture'")
        self.model_stops(PENDULUM + '\n[formulation]\nvelocity = 2\n', "formulation.velocity", "must be a string")

    def test_a_formulation_chosen_by_the_description_is_derived(self):
        from toolconf_derive.description import load_model, load_tasks, model_tasks
        path = Path(self.enterContext(tempfile.TemporaryDirectory())) / "p.toml"
        path.write_text(PENDULUM + '\n[formulation]\ntip_position = "static_gain"\nposition = "paper"\n')
        tasks = {t.name: t for t in model_tasks(load_model(path), load_tasks(ROOT / "derive" / "tasks.toml"))}
        self.assertEqual((tasks["tip_position"].formulation, tasks["tip_position"].chosen_by),
                         ("static_gain", "description"))
        self.assertEqual(tasks["tip_position"].sensitivity["tip"], "-J @ IO @ inv(A) @ B")
        self.assertEqual((tasks["position"].formulation, tasks["position"].chosen_by), ("paper", "description"))
        self.assertEqual(tasks["position"].sensitivity["theta"], "IO @ inv(A) @ (E - B)")
        self.assertEqual((tasks["velocity"].formulation, tasks["velocity"].chosen_by), ("paper", "default"))

    def test_a_formulation_in_tasks_toml(self):
        head = '[task.formulations.static_gain]\ndoc = """The stabilised'
        self.tasks_stop(edit(TASKS, 'default_for = ["urdf"]\nsensitivity.theta =', 'default_for = ["ode"]\nsensitivity.theta ='),
                        "task[0].formulations.static_gain.default_for[0]", "'ode' is not a dynamics kind")
        self.tasks_stop(edit(TASKS, 'sensitivity.theta_ddot = "I"\n\n[[task]]', 'sensitivity.jerk = "I"\n\n[[task]]'),
                        "task[0].formulations.static_gain.sensitivity.jerk", "unknown key")
        self.tasks_stop(edit(TASKS, head, head.replace("static_gain", "paper")), "task[0].formulations.paper",
                        "'paper' names the task's own sensitivity formulas")
        self.tasks_stop(edit(TASKS, 'sensitivity.theta = "-IO @ inv(A) @ B"', 'sensitivity.theta = "-IO @ inv(A) @ K"'),
                        "task[0].formulations.static_gain.sensitivity.theta", "'K' is not defined")
        twice = head + '"""\ndefault_for = ["urdf"]\nsensitivity.theta = "I"\n\n[task.formulations.other]\ndoc = """The stabilised'
        self.tasks_stop(edit(TASKS, head, twice), "task[0].formulations.other.default_for[0]",
                        "'urdf' already has formulation 'static_gain' by default")

    # Unknown keys, in every kind of table (a misspelt key must not be silently ignored).
    def test_unknown_top_level_table(self):
        self.model_stops(PENDULUM + "\n[extras]\nfoo = 1\n", "extras", "unknown key")

    def test_unknown_key_in_an_array_of_tables(self):
        self.model_stops(edit(PENDULUM, 'unit = "kg"', 'units = "kg"'), "parameters[0].units", "unknown key")

    def test_unknown_key_in_a_coordinate(self):
        self.model_stops(edit(PENDULUM, '{ name = "torque", latex = "T" }', '{ name = "torque", latx = "T" }'),
                         "coordinates.u[0].latx", "unknown key")

    def test_unknown_key_in_a_constant(self):
        self.model_stops(edit(PENDULUM, "g = { value = 9.81,", "g = { valu = 9.81,"), "constants.g.valu", "unknown key")

    def test_unknown_term_in_goals(self):
        self.model_stops(edit(PENDULUM, 'theta = ["pi/4"]', 'angle = ["pi/4"]'), "goals.position.angle", "unknown key")

    # Missing fields and wrong types.
    def test_missing_dynamics_kind(self):
        self.model_stops(edit(PENDULUM, 'kind = "explicit"\n', ""), "dynamics.kind", "missing")

    def test_missing_parameter_name(self):
        self.model_stops(edit(PENDULUM, 'name = "m"\n', ""), "parameters[0].name", "missing")

    def test_missing_equilibrium_table(self):
        self.model_stops(edit(PENDULUM, '[equilibrium]\nq = ["-pi/2"]\nq_dot = ["0"]\nu = ["0"]\n', ""),
                         "equilibrium", "missing")

    def test_dof_that_is_not_an_integer(self):
        self.model_stops(edit(PENDULUM, "dof = 1", 'dof = "one"'), "model.dof", "must be an integer")

    # Names in equations.
    def test_undefined_symbol_in_an_equation(self):
        self.model_stops(edit(PENDULUM, "3/(m*l**2)", "3/(mass*l**2)"), "dynamics.q_ddot[0]", "'mass' is not defined")

    def test_sympy_names_are_not_silently_taken(self):
        # SymPy would read E as Euler's number and I as the imaginary unit.
        self.model_stops(edit(PENDULUM, "(torque - ", "(I*torque - "), "dynamics.q_ddot[0]", "'I' is not defined")

    def test_a_parameter_in_the_equilibrium(self):
        self.model_stops(edit(PENDULUM, 'q_dot = ["0"]', 'q_dot = ["l"]'), "equilibrium.q_dot[0]", "'l' is not defined")

    # Unbalanced brackets.
    def test_bracket_never_closed(self):
        self.model_stops(edit(PENDULUM, "cos(theta)/2)", "cos(theta/2)"), "dynamics.q_ddot[0]",
                         "'(' at character 14 is never closed")

    def test_bracket_that_closes_nothing(self):
        self.model_stops(edit(PENDULUM, 'q = ["-pi/2"]', 'q = ["-pi/2)"]'), "equilibrium.q[0]",
                         "')' at character 6 closes nothing")

    def test_mismatched_brackets(self):
        self.model_stops(edit(PENDULUM, "cos(theta)/2)", "cos(theta]/2)"), "dynamics.q_ddot[0]",
                         "']' at character 39 closes '(' from character 33")

    # Shapes.
    def test_printed_a_of_the_wrong_shape(self):
        self.model_stops(PENDULUM + '\n[printed]\nA = [["0", "1"]]\n', "printed.A", "must be 2x2")

    def test_printed_b_of_the_wrong_shape(self):
        self.model_stops(PENDULUM + '\n[printed]\nB = [["0"], ["1"], ["2"]]\n', "printed.B", "must be 2x1")

    def test_goal_of_the_wrong_length(self):
        self.model_stops(edit(PENDULUM, 'theta = ["pi/4"]', 'theta = ["pi/4", "0"]'), "goals.position.theta",
                         "has 2 entries, model.dof is 1")

    def test_equilibrium_of_the_wrong_length(self):
        self.model_stops(edit(PENDULUM, 'u = ["0"]', 'u = ["0", "0"]'), "equilibrium.u", "has 2 entries")

    def test_goal_for_a_task_that_does_not_exist(self):
        self.model_stops(edit(PENDULUM, "[goals.position]", "[goals.posture]"), "goals.posture", "no task is named")

    # The equilibrium must be one.
    def test_not_an_equilibrium(self):
        # Hanging straight down is; lying horizontally (theta = 0) gravity turns the rod.
        self.model_stops(edit(PENDULUM, 'q = ["-pi/2"]', 'q = ["0"]'), "equilibrium", "not an equilibrium")

    def test_not_valid_toml(self):
        r, path, _ = self.derive(model=edit(PENDULUM, "dof = 1", "dof = "))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)
        self.assertIn(f"{path}: not valid TOML", r.stderr)

    # tasks.toml.
    def test_unknown_key_in_a_task(self):
        self.tasks_stop(edit(TASKS, "index = 2\n", "index = 2\nweight = 3\n"), "task[1].weight", "unknown key")

    def test_missing_sensitivity_of_a_used_term(self):
        self.tasks_stop(edit(TASKS, 'sensitivity.theta_dot = "-IO @ inv(A) @ B"\n', ""),
                        "task[1].sensitivity.theta_dot", "missing")

    def test_unbalanced_bracket_in_a_task_formula(self):
        self.tasks_stop(edit(TASKS, 'sensitivity.theta_ddot = "IO @ (A @ A', 'sensitivity.theta_ddot = "IO @ ((A @ A'),
                        "task[2].sensitivity.theta_ddot", "is never closed")

    def test_task_formula_of_the_wrong_shape(self):
        self.tasks_stop(edit(TASKS, 'sensitivity.theta_dot = "-IO @ inv(A) @ B"', 'sensitivity.theta_dot = "IO"'),
                        "task[1].sensitivity.theta_dot", "is 1x2, not 1x1")

    def test_unknown_term_in_a_task(self):
        self.tasks_stop(edit(TASKS, 'terms = ["theta_ddot", "u"]', 'terms = ["theta_ddot", "jerk"]'),
                        "task[2].terms[1]", "unknown term 'jerk'")

    def test_error_term_the_task_does_not_use(self):
        self.tasks_stop(edit(TASKS, 'error = "theta_dot"', 'error = "theta"'),
                        "task[1].error", "is not one of the task's kinematic terms")

    def test_missing_error_term(self):
        self.tasks_stop(edit(TASKS, 'error = "theta_ddot"\n', ""), "task[2].error", "missing")

    def test_model_name_taken_by_the_registry(self):
        name = PENDULUM.split('name = "', 1)[1].split('"', 1)[0]
        for taken in ("tasks", "lib", "trig", "powi"):
            self.model_stops(edit(PENDULUM, f'name = "{name}"', f'name = "{taken}"'), "model.name",
                             "taken by the generated registry")

    # Every name a description gives becomes a Rust name in the generated crate.
    def test_rust_keywords_are_refused_as_names(self):
        self.model_stops(edit(PENDULUM, 'name = "pendulum"', 'name = "fn"'), "model.name", "'fn' is a Rust keyword")
        self.model_stops(edit(edit(PENDULUM, 'name = "l"', 'name = "type"'), "m*l**2", "m*type**2"),
                         "parameters[1].name", "'type' is a Rust keyword")
        self.tasks_stop(edit(TASKS, 'name = "velocity"', 'name = "loop"'), "task[1].name", "'loop' is a Rust keyword")

    def test_names_must_be_ascii(self):
        # Python's isidentifier() takes them, Rust cannot name a module file after them.
        self.model_stops(edit(PENDULUM, 'name = "pendulum"', 'name = "péndulo"'), "model.name", "lower-case ASCII")
        self.model_stops(edit(PENDULUM, 'name = "m"', 'name = "_m"'), "parameters[0].name", "a letter, then")

    def test_a_parameter_named_after_a_tools_file_column(self):
        self.model_stops(edit(edit(PENDULUM, 'name = "l"', 'name = "model"'), "m*l**2", "m*model**2"),
                         "parameters[1].name", "a column of every tools file")

    def test_a_constant_named_after_a_generated_constant(self):
        self.model_stops(edit(edit(PENDULUM, "\ng = {", "\ndof = {"), "m*g*l", "m*dof*l"),
                         "constants.dof", "the Rust constant DOF")

    def test_a_name_the_generated_code_uses_itself(self):
        # It would shadow the generated value: `let (sin_theta, cos_theta) = sin_cos(theta)` after
        # `let cos_theta = u[0]` silently computes with the cosine instead of the torque.
        self.model_stops(edit(edit(PENDULUM, 'name = "torque"', 'name = "cos_theta"'), "(torque -", "(cos_theta -"),
                         "coordinates.u[0].name", "also a name the generated dynamics_with uses")
        self.model_stops(edit(PENDULUM, 'name = "theta_dot", latex', 'name = "k0", latex'),
                         "coordinates.q_dot[0].name", "also a name the generated")

    def test_the_generated_constants_are_the_templates(self):
        from toolconf_derive.description import MODULE_CONSTANTS
        template = (ROOT / "templates" / "model.rs.tera").read_text()
        self.assertEqual(sorted(MODULE_CONSTANTS), sorted(re.findall(r"^pub const ([A-Z_]+):", template, re.M)))


if __name__ == "__main__":
    unittest.main()
