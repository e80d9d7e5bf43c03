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
sys.path.insert(0, str(REPO / "benches" / "peers"))
import pin_robot  # noqa: E402
# Normwise relative, per state: round-off of a few hundred double-precision operations, far below
# what a modelling slip (a wrong inertia or frame term) moves.
TOLERANCE = 1e-10


def pinocchio_model(name, tool):
    """The robot's URDF cut at its flange with the tool a fixed link there (benches/peers/pin_robot.py,
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


def random_rotation(rng):
    """A uniformly random rotation (QR of a Gaussian matrix, signs fixed, det +1)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    return q if np.linalg.det(q) > 0 else -q


def random_full_tool(rng, name):
    """random_tool's box turned by a random rotation about its centre of mass (an inertia tensor
    with products), with a tip anywhere in the model's sampling box: all 13 parameters."""
    tool = random_tool(rng, name)
    r = random_rotation(rng)
    tensor = r @ np.diag(tool[4:7]) @ r.T
    sample = toolconf.models()[name]["domains"]["sample"]
    tip = [rng.uniform(*sample[k]) for k in ("tool_tip_x", "tool_tip_y", "tool_tip_z")]
    return [*tool[:4], tensor[0, 0], tensor[1, 1], tensor[2, 2], tensor[0, 1], tensor[0, 2], tensor[1, 2], *tip]


def random_tools_in_pinocchio(rng, name, count):
    """``count`` random_full_tools of the model, each with Pinocchio's model and data of the
    robot with it (pinocchio_model)."""
    for _ in range(count):
        tool = random_full_tool(rng, name)
        yield (tool, *pinocchio_model(name, tool))


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


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_full_inertia_tensor_dynamics_equals_pinocchio_aba(name):
    """A tool whose inertia tensor has products (a box turned about its centre of mass): the
    dynamics with URDF's <inertia ixy ixz iyz> equal Pinocchio's aba on the same tool."""
    rng = np.random.default_rng(29)
    n = toolconf.models()[name]["dof"]
    worst = 0.0
    for tool, model, data in random_tools_in_pinocchio(rng, name, 30):
        q, qd, u = rng.uniform(-math.pi, math.pi, n), rng.uniform(-3.0, 3.0, n), rng.uniform(-20.0, 20.0, n)
        got = toolconf.dynamics(name, tool, np.concatenate([q, qd]), u)
        worst = max(worst, relative(got, np.concatenate([qd, pin.aba(model, data, q, qd, u)])))
    assert worst <= TOLERANCE, f"{name}: worst normwise relative difference {worst:.2e}"


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_tip_equals_pinocchio_frame_placement_and_jacobian(name):
    """toolconf.tip against Pinocchio with the tool's tip added as a frame: its placement and the
    linear rows of computeFrameJacobian (LOCAL_WORLD_ALIGNED), 100 random states and tools, to
    1e-10 (absolute: metres, and metres per radian)."""
    rng = np.random.default_rng(31)
    n = toolconf.models()[name]["dof"]
    tools, qs, positions, jacobians = [], [], [], []
    for tool, model, data in random_tools_in_pinocchio(rng, name, 100):
        frame = model.getFrameId("tool_tip")
        q = rng.uniform(-math.pi, math.pi, n)
        pin.framesForwardKinematics(model, data, q)
        tools.append(tool)
        qs.append(q)
        positions.append(data.oMf[frame].translation.copy())
        jacobians.append(pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)[:3])
    got = toolconf.tip(name, np.array(tools), np.array(qs))
    assert got["position"].shape == (100, 3) and got["jacobian"].shape == (100, 3, n)
    assert np.max(np.abs(got["position"] - np.array(positions))) <= TOLERANCE
    assert np.max(np.abs(got["jacobian"] - np.array(jacobians))) <= TOLERANCE
    one = toolconf.tip(name, tools[0], qs[0])
    assert one["position"].shape == (3,) and one["jacobian"].shape == (3, n)
    np.testing.assert_array_equal(one["jacobian"], got["jacobian"][0])


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_tip_bias_equals_pinocchio_frame_classical_acceleration(name):
    """toolconf.tip's ``bias`` J̇(q, q̇) q̇ against Pinocchio: the linear part of
    getFrameClassicalAcceleration (LOCAL_WORLD_ALIGNED) at the tool's tip frame after
    forwardKinematics(q, q̇, 0), 100 random states and tools, to 1e-10 relative to the largest
    (m/s²; it grows as q̇², up to ~10 m/s² at 3 rad/s)."""
    rng = np.random.default_rng(37)
    n = toolconf.models()[name]["dof"]
    tools, qs, vs, biases = [], [], [], []
    for tool, model, data in random_tools_in_pinocchio(rng, name, 100):
        frame = model.getFrameId("tool_tip")
        q, v = rng.uniform(-math.pi, math.pi, n), rng.uniform(-3.0, 3.0, n)
        pin.forwardKinematics(model, data, q, v, np.zeros(n))
        pin.updateFramePlacements(model, data)
        biases.append(pin.getFrameClassicalAcceleration(model, data, frame, pin.LOCAL_WORLD_ALIGNED).linear.copy())
        tools.append(tool)
        qs.append(q)
        vs.append(v)
    got = toolconf.tip(name, np.array(tools), np.array(qs), np.array(vs))
    want = np.array(biases)
    assert got["bias"].shape == (100, 3)
    assert np.max(np.abs(got["bias"] - want)) <= TOLERANCE * max(1.0, np.max(np.abs(want)))
    one = toolconf.tip(name, tools[0], qs[0], q_dot=vs[0])
    assert one["bias"].shape == (3,)
    np.testing.assert_array_equal(one["bias"], got["bias"][0])
    assert "bias" not in toolconf.tip(name, tools[0], qs[0])
    # One configuration shared by several tools (a 1-D q with 2-D params).
    shared = toolconf.tip(name, np.array(tools[:3]), qs[0], vs[0])
    assert shared["position"].shape == (3, 3) and shared["bias"].shape == (3, 3)
    np.testing.assert_array_equal(shared["bias"][0], got["bias"][0])
    with pytest.raises(ValueError, match="q_dot of shape"):
        toolconf.tip(name, tools[0], qs[0], q_dot=np.zeros(n + 1))
    with pytest.raises(ValueError, match="joint velocity NaN is not finite"):
        toolconf.tip(name, tools[0], qs[0], q_dot=np.full(n, np.nan))


def test_a_tool_of_seven_parameters_has_no_products_and_its_tip_at_the_flange():
    """The 7 parameters toolconf took before the products of inertia and the tip: the same
    dynamics as with those six given as zero, and the tip at the flange (Pinocchio's panda_link8)."""
    short = [0.5, 0.01, 0.0, 0.1, 1e-3, 2e-3, 2.5e-3]
    full = short + [0.0] * 6
    x = np.linspace(-1.0, 1.0, 14)
    np.testing.assert_array_equal(toolconf.dynamics("panda", short, x, np.ones(7)),
                                  toolconf.dynamics("panda", full, x, np.ones(7)))
    model, data = pinocchio_model("panda", full)
    pin.framesForwardKinematics(model, data, x[:7])
    flange = data.oMf[model.getFrameId("panda_link8")].translation
    assert np.max(np.abs(toolconf.tip("panda", short, x[:7])["position"] - flange)) <= TOLERANCE
    assert toolconf.models()["panda"]["domains"]["defaults"]["tool_tip_z"] == 0.0


def test_an_inertia_tensor_that_is_no_rigid_body_is_refused():
    """Moments that obey the triangle inequality on the diagonal, with a product that makes the
    tensor's eigenvalues break it (or the tensor indefinite): one ValueError naming the rule."""
    bad = [0.5, 0, 0, 0.1, 1e-3, 1e-3, 1e-3, 9e-4, 0, 0, 0, 0, 0.1]
    with pytest.raises(ValueError, match=r"the inertia tensor .* is positive definite with eigenvalues obeying the triangle inequality"):
        toolconf.dynamics("panda", bad, np.zeros(14), np.zeros(7))


def test_planar_tips_are_the_end_of_the_last_link():
    """arm2's tip (its description's [tip], the paper's absolute angles) equals the closed form
    y = Σ l_i (cos θ_i, sin θ_i, 0) and arm2_exact's (the planar chain's free end, derived from its
    links); arm3's likewise; J = ∂y/∂q in closed form (column i: l_i (−sin θ_i, cos θ_i, 0))."""
    rng = np.random.default_rng(37)
    for name in ("arm2", "arm2_exact", "arm3"):
        info = toolconf.models()[name]
        assert info["has_tip"]
        n, k = info["dof"], len(info["parameters"])
        for _ in range(20):
            params = rng.uniform(0.1, 0.6, k)
            q = rng.uniform(-math.pi, math.pi, n)
            lengths = [params[info["parameters"].index(f"l{i + 1}")] for i in range(n)]
            want = np.array([sum(l * math.cos(t) for l, t in zip(lengths, q)),
                             sum(l * math.sin(t) for l, t in zip(lengths, q)), 0.0])
            jac = np.array([[-l * math.sin(t) for l, t in zip(lengths, q)],
                            [l * math.cos(t) for l, t in zip(lengths, q)], [0.0] * n])
            got = toolconf.tip(name, params, q)
            np.testing.assert_allclose(got["position"], want, rtol=0, atol=1e-15)
            np.testing.assert_allclose(got["jacobian"], jac, rtol=0, atol=1e-15)
    # The paper's arm hangs at its equilibrium: the tip straight below the base.
    p = [0.3, 0.4, 0.5, 0.2]
    eq = toolconf.models()["arm2"]["equilibrium"]["q"]
    np.testing.assert_allclose(toolconf.tip("arm2", p, eq)["position"], [0.0, -0.7, 0.0], atol=1e-15)


def test_the_mass_spring_dampers_tip_is_its_mass():
    # derive/models/msd.toml: [tip] position = ["z", "0", "0"], components = 1 (the mass is the
    # tool's working point), so tip tasks run on it too.
    t = toolconf.tip("msd", [1.0] * len(toolconf.models()["msd"]["parameters"]), [0.3])
    np.testing.assert_array_equal(t["position"], [0.3, 0.0, 0.0])
    np.testing.assert_array_equal(t["jacobian"], [[1.0], [0.0], [0.0]])
