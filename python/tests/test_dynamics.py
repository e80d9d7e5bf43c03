"""``toolconf.dynamics`` (the robots' own rigid-body dynamics) and ``models()[m]["equilibrium"]``
against Pinocchio (``pin``, in derive/requirements.txt) on the same URDF with the same tool, built
here from the URDF file, independently of toolconf's reader: Pinocchio's ``aba`` for Ẋ, its
``crba`` for B = [O; M⁻¹] at the equilibrium."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import toolconf

import pinocchio as pin  # in derive/requirements.txt: make test installs it; a missing pin fails here

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "bench" / "peers"))
import pin_robot  # noqa: E402
# Normwise relative, per state: the bound.
TOLERANCE = 1e-10


def pinocchio_model(name, tool):
    """The robot's URDF cut at its flange with the tool a fixed link there (bench/peers/pin_robot.py,
    which builds it from the URDF file and the description alone)."""
    return pin_robot.model_with_tool(name, tool)


def random_tool(rng, name):
    """A solid box of random sides (1-30 cm) and mass within the model's sampling box, its centre
    of mass anywhere in that box: a valid rigid body."""
    sample = toolconf.models()[name]["domains"]["sample"]
    m = rng.uniform(*sample["tool_mass"])
    com = [rng.uniform(*sample[k]) for k in ("tool_com_x", "tool_com_y", "tool_com_z")]
    a, b, c = rng.uniform(0.01, 0.30, 3)
    return [m, *com, m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12]


def relative(got, want):
    return float(np.max(np.abs(got - want)) / np.max(np.abs(want)))


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_dynamics_equals_pinocchio_aba(name):
    rng = np.random.default_rng(23)
    n = toolconf.models()[name]["dof"]
    tools, states, controls, want = [], [], [], []
    for _ in range(40):
        tool = random_tool(rng, name)
        model, data = pinocchio_model(name, tool)
        assert model.nq == n
        for _ in range(5):
            q, qd = rng.uniform(-math.pi, math.pi, n), rng.uniform(-3.0, 3.0, n)
            u = rng.uniform(-20.0, 20.0, n)
            tools.append(tool)
            states.append(np.concatenate([q, qd]))
            controls.append(u)
            want.append(np.concatenate([qd, pin.aba(model, data, q, qd, u)]))
    got = toolconf.dynamics(name, np.array(tools), np.array(states), np.array(controls))
    assert got.shape == (200, 2 * n)
    worst = max(relative(g, w) for g, w in zip(got, want))
    assert worst <= TOLERANCE, f"{name}: worst normwise relative difference {worst:.2e}"
    # One state: a 1-D array, the same numbers as the batch's row.
    one = toolconf.dynamics(name, tools[0], states[0], controls[0])
    assert one.shape == (2 * n,)
    np.testing.assert_array_equal(one, got[0])


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_b_at_the_equilibrium_is_the_inverse_mass_matrix(name):
    info = toolconf.models()[name]
    eq = info["equilibrium"]
    n = info["dof"]
    assert len(eq["q"]) == len(eq["q_dot"]) == len(eq["u"]) == n
    assert eq["q_dot"] == [0.0] * n and eq["u"] == [0.0] * n
    rng = np.random.default_rng(5)
    for _ in range(10):
        tool = random_tool(rng, name)
        model, data = pinocchio_model(name, tool)
        m = pin.crba(model, data, np.array(eq["q"]))
        m = np.triu(m) + np.triu(m, 1).T
        b = toolconf.confidence(name, tool, "position")["B"]
        assert b.shape == (2 * n, n)
        assert np.all(b[:n] == 0.0)
        assert relative(b[n:], np.linalg.inv(m)) <= TOLERANCE
        # At the equilibrium, with U = g(q^e) the arm is at rest: Ẋ = 0 (the plant's U^e = 0 is
        # this torque fed forward).
        x_e = np.array(eq["q"] + eq["q_dot"])
        g_e = pin.computeGeneralizedGravity(model, data, np.array(eq["q"]))
        rest = toolconf.dynamics(name, tool, x_e, g_e)
        assert np.max(np.abs(rest)) <= TOLERANCE * np.max(np.abs(np.linalg.inv(m) @ g_e))


def test_planar_models_dynamics_are_their_plant():
    """For a model whose plant is its rigid-body dynamics (no impedance), dynamics() is the
    plant: a torque on the paper's arm at rest accelerates it as M⁻¹U from the hanging pose."""
    tool = [0.3, 0.4, 0.5, 0.2]
    x_e = toolconf.models()["arm2"]["equilibrium"]["q"] + [0.0, 0.0]
    rest = toolconf.dynamics("arm2", tool, x_e, [0.0, 0.0])
    np.testing.assert_allclose(rest, 0.0, atol=1e-12)
    u = np.array([0.1, -0.2])
    b = toolconf.confidence("arm2", tool, "position")["B"]
    np.testing.assert_allclose(toolconf.dynamics("arm2", tool, x_e, u)[2:], b[2:] @ u, rtol=1e-12)


@pytest.mark.parametrize(
    "args, message",
    [
        (("panda", [0.5, 0, 0, 0.1, 1e-3, 1e-3], np.zeros(14), np.zeros(7)), "params of shape [6]"),
        (("panda", [0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3], np.zeros(13), np.zeros(7)), "state of shape [13]"),
        (("panda", [0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3], np.zeros((3, 14)), np.zeros((2, 7))), "have 3, 2 rows"),
        (("panda", [0.5, 0, 0, 1.5, 1e-3, 1e-3, 1e-3], np.zeros(14), np.zeros(7)),
         "invalid tool parameter tool_com_z = 1.5: must be a finite number in [-1, 1] m"),
        (("panda", [0.5, 0, 0, 0.1, 5e-3, 1e-3, 1e-3], np.zeros(14), np.zeros(7)),
         "invalid tool: tool_ixx <= tool_iyy + tool_izz"),
        (("panda", [-0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3], np.zeros(14), np.zeros(7)),
         "invalid arm parameter tool_mass = -0.5: must be a number in [1e-6, 1e6]"),
        (("panda", [0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3], np.full(14, np.nan), np.zeros(7)), "state entry NaN"),
        (("nope", [0.5], np.zeros(14), np.zeros(7)), "unknown model 'nope'"),
    ],
)
def test_bad_input_is_a_value_error_naming_it(args, message):
    with pytest.raises(ValueError) as e:
        toolconf.dynamics(*args)
    assert message in str(e.value)


def test_a_batch_names_the_bad_tool_row():
    tools = np.array([[0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3]] * 3)
    tools[2, 3] = 2.0
    with pytest.raises(ValueError, match="tool 2: invalid tool parameter tool_com_z = 2"):
        toolconf.dynamics("panda", tools, np.zeros((3, 14)), np.zeros(7))
