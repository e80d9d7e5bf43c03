"""The tasks on the tool's tip: tasks.toml's J and the tip sensitivities, checked against
what they mean rather than against the formulas that made them.

- J is padded: its first TIP_DIM rows are the tip's Jacobian dy/dq at q^e, the others exactly
  zero, in every namespace the formulas are evaluated in (SymPy, CasADi, the URDF code graph and
  the URDF reference), and a tip sensitivity of the paper's formulation is J times the joint one.
- The generated tip sensitivities (the test vectors, which the Rust reproduces to 1e-12) are the
  finite differences of the linearised model's response to a constant control U:
  - the static gain (the URDF arms' default): the rest X_inf(U) of Xdot = A X + B U, A X_inf = -B U,
    and y_inf(U) = y^e + J [I O] X_inf on the Panda and the UR5, and theta_inf = [I O] X_inf for
    the joint position task;
  - the paper's formula (arm2): its own definition, Xdot = A X + B U with dXdot/dU = E (zero jerk),
    so X(U) = A^-1 (E - B) U, y = y^e + J [I O] X and y_dot = J [O I] X; and the printed velocity
    choice of the tip velocity task, y_dot = J [I O] X_inf.
  The responses are linear in U, so central differences are exact but for rounding: 1e-6 relative
  (a micrometre per metre of tip response) is far above that and far below any physical effect.
"""

from __future__ import annotations

import json
import sys
import unittest
from pathlib import Path

import casadi as ca
import numpy as np
import sympy as sp

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))

from toolconf_derive.description import load_model, load_tasks, model_tasks  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.symbolic import derive, tidy_matrix  # noqa: E402
from toolconf_derive.urdf_model import UrdfDerivation, _sample_tool  # noqa: E402

MODELS = ROOT / "derive" / "models"
GENERATED = ROOT / "generated"
TASKS = load_tasks(ROOT / "derive" / "tasks.toml")
# Central differences of a linear response: exact but for rounding (see the module's docs).
RELATIVE = 1e-6
STEP = 1e-3      # N m: a constant torque small against the impedance's K (50-1034 N m/rad)
TOOLS = 4        # random tools of the vectors file per model


def vectors(model: str, function: str) -> list[dict]:
    """The generated function's test vectors (inputs and the reference outputs the Rust matches)."""
    document = json.loads((GENERATED / f"{model}.vectors.json").read_text())
    return next(f["vectors"] for f in document["functions"] if f["name"] == function)


def output(vector: dict, name: str, n: int) -> np.ndarray:
    return np.array(vector["outputs"][name]).reshape(n, n)


def central_differences(response, n: int) -> np.ndarray:
    """d response / dU (its rows by the columns of U) at U = 0, by central differences."""
    columns = []
    for j in range(n):
        step = np.zeros(n)
        step[j] = STEP
        columns.append((response(step) - response(-step)) / (2 * STEP))
    return np.column_stack(columns)


class TestCaseWithClose(unittest.TestCase):
    def assert_close(self, got: np.ndarray, want: np.ndarray, what: str) -> None:
        scale = max(float(np.max(np.abs(want))), 1e-300)
        err = float(np.max(np.abs(got - want)))
        self.assertLessEqual(err, RELATIVE * scale, f"{what}: max difference {err:.3e}, scale {scale:.3e}")


class PaddedJacobian(TestCaseWithClose):
    """(b) J's first TIP_DIM rows are dy/dq at q^e, the others exactly zero, in every namespace."""

    def test_symbolic_and_casadi_on_the_planar_and_explicit_models(self):
        for name in ("msd", "arm2", "arm3"):
            with self.subTest(model=name):
                model = load_model(MODELS / f"{name}.toml")
                cm = CasadiModel(model)
                n, k = model.dof, model.tip_dim
                self.assertEqual(k, {"msd": 1, "arm2": 2, "arm3": 2}[name])
                p = np.linspace(0.2, 0.5, len(model.parameters))
                j = cm.task_namespace(p)["J"].to_numpy()
                jacobian = cm.tip.checked(cm.x_e[:n], p)[1].to_numpy()
                self.assertEqual(j.shape, (n, n))
                np.testing.assert_array_equal(j[k:], 0.0)
                np.testing.assert_array_equal(j[:k], jacobian[:k])

    def test_a_paper_tip_sensitivity_is_j_times_the_joint_one_in_closed_form(self):
        model = load_model(MODELS / "arm2.toml")
        d = derive(model, TASKS)
        tasks = {t.task.name: t for t in d.tasks}
        at_e = dict(zip(d.q, d.x_e[:model.dof]))
        j = tidy_matrix(d.tip_jacobian[:2, :].subs(at_e))
        self.assertEqual(j, sp.Matrix([[d.params[2], d.params[3]], [0, 0]]))   # [[l1, l2], [0, 0]] hanging
        for tip, joint in (("tip", "theta"), ("tip_dot", "theta_dot")):
            difference = tidy_matrix(tasks["tip_position"].sensitivity[tip] - j @ tasks["position"].sensitivity[joint])
            self.assertEqual(difference, sp.zeros(2, 2), tip)

    def test_the_urdf_code_and_reference_namespaces(self):
        for name in ("panda", "ur5"):
            with self.subTest(model=name):
                model = load_model(MODELS / f"{name}.toml")
                dv = UrdfDerivation(model, model.chain, model_tasks(model, TASKS))
                n = dv.n
                p = _sample_tool(np.random.default_rng(3)).ravel()
                code = np.array(ca.Function("j", [dv.p], [dv.task_namespace_sx()["J"].sx()])(p))
                reference = dv.reference_namespace(p)["J"].to_numpy()
                jacobian = np.array(dv.tip(np.array(dv.q_e), p)[1])
                for what, j in (("code", code), ("reference", reference)):
                    self.assertEqual(j.shape, (n, n), what)
                    np.testing.assert_array_equal(j[3:], 0.0, what)
                    self.assert_close(j[:3], jacobian, f"{name} {what} J")


class StaticGain(TestCaseWithClose):
    """(a) The URDF arms' static-gain sensitivities are the linearised plant's steady-state response."""

    def check(self, name: str) -> None:
        model = load_model(MODELS / f"{name}.toml")
        tasks = {t.name: t for t in model_tasks(model, TASKS)}
        self.assertEqual(tasks["tip_position"].formulation, "static_gain")
        self.assertEqual(tasks["position"].formulation, "static_gain")
        dv = UrdfDerivation(model, model.chain, list(tasks.values()))
        n = dv.n
        for k, v in enumerate(vectors(name, "tip_position_sensitivity")[:TOOLS]):
            a, b, y_e, jacobian = self.linearised(dv, v)

            def rest(u):
                return np.linalg.solve(a, -b @ u)            # A X_inf + B U = 0

            dy = central_differences(lambda u: y_e.ravel() + jacobian @ rest(u)[:n], n)
            dy_dot = central_differences(lambda u: jacobian @ rest(u)[n:], n)
            d_tip, d_tip_dot = output(v, "d_tip_du", n), output(v, "d_tip_dot_du", n)
            np.testing.assert_array_equal(d_tip[3:], 0.0)
            self.assert_close(d_tip[:3], dy, f"{name} tool {k} d_tip_du")
            # At rest the tip does not move: zero, to the differences' rounding at the tip's scale.
            self.assertLessEqual(float(np.max(np.abs(dy_dot))), RELATIVE * float(np.max(np.abs(dy))))
            np.testing.assert_array_equal(d_tip_dot, 0.0)
        for k, v in enumerate(vectors(name, "position_sensitivity")[:TOOLS]):
            a, b, _, _ = self.linearised(dv, v)
            dtheta = central_differences(lambda u: np.linalg.solve(a, -b @ u)[:n], n)
            self.assert_close(output(v, "d_theta_du", n), dtheta, f"{name} tool {k} d_theta_du")
            np.testing.assert_array_equal(output(v, "d_theta_dot_du", n), 0.0)

    @staticmethod
    def linearised(dv: UrdfDerivation, vector: dict):
        """A, B (the reference graph's, by AD of the articulated-body algorithm), y(q^e) and
        dy/dq at q^e (AD of the inward tip composition) of the vector's tool, as doubles."""
        p = np.array(vector["inputs"]["params"])
        a, b = (m.to_numpy() for m in dv.reference_ab.checked(p))
        y_e, jacobian = (m.to_numpy() for m in dv.reference_tip.checked(dv.q_e, p))
        return a, b, y_e, jacobian

    def test_panda(self):
        self.check("panda")

    def test_ur5(self):
        self.check("ur5")


class PapersFormula(TestCaseWithClose):
    """(a) arm2 keeps the paper's formula; its tip sensitivities against the paper's own definition."""

    def test_arm2(self):
        model = load_model(MODELS / "arm2.toml")
        tasks = {t.name: t for t in model_tasks(model, TASKS)}
        self.assertEqual(tasks["tip_position"].formulation, "paper")
        cm = CasadiModel(model)
        n = model.dof
        tip, velocity = vectors("arm2", "tip_position_sensitivity"), vectors("arm2", "tip_velocity_sensitivity")
        eye = np.eye(n)
        e = np.vstack([eye, eye])
        for k in range(TOOLS):
            p = np.array(tip[k]["inputs"]["params"])
            a, b = (m.to_numpy() for m in cm.linearisation(p))
            y_e, jacobian = (m.to_numpy() for m in cm.tip.checked(cm.x_e[:n], p))
            jacobian = jacobian[:model.tip_dim]

            def state(u):
                return np.linalg.solve(a, (e - b) @ u)        # A X + B U = Xdot = E U

            dy = central_differences(lambda u: y_e.ravel()[:2] + jacobian @ state(u)[:n], n)
            dy_dot = central_differences(lambda u: jacobian @ state(u)[n:], n)
            self.assert_close(output(tip[k], "d_tip_du", n), dy, f"tool {k} d_tip_du")
            self.assert_close(output(tip[k], "d_tip_dot_du", n), dy_dot, f"tool {k} d_tip_dot_du")
            # Task 5: the printed choice, the rest position's response carried to the tip's velocity.
            p = np.array(velocity[k]["inputs"]["params"])
            a, b = (m.to_numpy() for m in cm.linearisation(p))
            jacobian = cm.tip.checked(cm.x_e[:n], p)[1].to_numpy()[:2]
            printed = central_differences(lambda u: jacobian @ np.linalg.solve(a, -b @ u)[:n], n)
            self.assert_close(output(velocity[k], "d_tip_dot_du", n), printed, f"tool {k} tip_velocity d_tip_dot_du")


if __name__ == "__main__":
    unittest.main()
