"""URDF robots (description kind `urdf`): every refusal, and the rigid-body derivation against
three independent sources.

- A bad URDF or description stops derive.py with one line naming the file, the joint or link and
  the reason, status 2 (each case below).
- (a) A planar two-link URDF of uniform rods moves as `arm2_exact` (its Lagrangian, CasADi side)
  after the change from relative to absolute angles, to 1e-10.
- (b) SymPy's Lagrangian of a 3-DOF spatial chain (tilted axes, rotated origins, full inertia
  tensors, a tool) built from the raw URDF numbers, not from urdf.py, agrees to 1e-10.
- (c) Pinocchio's crba, rnea and aba agree on the Panda and the UR5 with random tools at 100
  random states each, and so does the generated plant `dynamics` (aba with the impedance torque).
- (d) How a URDF is read (urdf.py's rule): an xArm7-style chain (its quarter turns written
  1.5708) derives and matches Pinocchio on the literal file; Kinova-style 1.57079632679 are exact
  quarter turns; a rotation that is not orthonormal, an equilibrium outside the joint limits and a
  moving side branch are refused naming the file, the joint and the value; <dynamics> is noted
  as ignored; an equilibrium failure names the joints and the likely cause.

    derive/.venv/bin/python -m unittest discover -s derive/tests      (part of make test)
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET
from pathlib import Path

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "derive"))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.rigid_body import ChainDynamics, ldl_apply, ldl_factor  # noqa: E402
from toolconf_derive.urdf import read_chain  # noqa: E402
from toolconf_derive.urdf_model import UrdfDerivation, _sample_tool  # noqa: E402
from urdf_model_text import urdf_model_head  # noqa: E402

DERIVE = ROOT / "derive" / "derive.py"
PANDA = ROOT / "derive" / "models" / "panda.toml"
UR5 = ROOT / "derive" / "models" / "ur5.toml"
TOLERANCE = 1e-10


def _inertial(mass, com=(0.0, 0.0, 0.0), moments=(0.01, 0.01, 0.01), rpy="0 0 0", products=(0.0, 0.0, 0.0)):
    ixx, iyy, izz = moments
    ixy, ixz, iyz = products
    return (f'<inertial><origin xyz="{" ".join(map(repr, com))}" rpy="{rpy}"/><mass value="{mass!r}"/>'
            f'<inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/></inertial>')


def _joint(name, kind, parent, child, xyz="0 0 0", rpy="0 0 0", axis="0 0 1", extra=""):
    # A revolute or prismatic joint has a <limit> (the URDF specification's rule): a wide one.
    if kind in ("revolute", "prismatic") and "<limit" not in extra:
        extra += '<limit lower="-4" upper="4" effort="10" velocity="1"/>'
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>{extra}</joint>')


def _robot(*parts):
    return '<?xml version="1.0"?><robot name="test">' + "".join(parts) + "</robot>"


def _link(name, inertial=""):
    return f'<link name="{name}">{inertial}</link>'


# Three joints: a URDF tool's tip has three components, which a tip term stores in the joints' slots.
GOOD = [_link("base"), _link("a", _inertial(1.0, (0.0, 0.0, 0.1))), _link("b", _inertial(0.5, (0.0, 0.0, 0.1))),
        _link("c", _inertial(0.3, (0.0, 0.0, 0.05))), _link("flange"), _joint("j1", "revolute", "base", "a"),
        _joint("j2", "revolute", "a", "b", "0 0 0.2", axis="0 1 0"),
        _joint("j3", "revolute", "b", "c", "0 0 0.2", axis="1 0 0"), _joint("fix", "fixed", "c", "flange", "0 0 0.2")]

MODEL = urdf_model_head("{file}") + """[impedance]
stiffness = [{k1}, 50.0, 50.0]
damping = [5.0, 5.0, 5.0]
[equilibrium]
q = ["0", "0.3", "0.2"]
q_dot = ["0", "0", "0"]
u = ["0", "0", "0"]
"""


class Refusals(unittest.TestCase):
    """Each bad URDF: derive.py exits 2 with one line naming the URDF file, the joint or link, and
    what is wrong."""

    def derive(self, urdf: str, k1: str = "50.0", model: str = MODEL):
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "robot.urdf").write_text(urdf)
        (tmp / "three.toml").write_text(model.format(file="robot.urdf", k1=k1))
        r = subprocess.run([sys.executable, str(DERIVE), str(tmp / "three.toml"), "--out", str(tmp / "three.json"),
                            "--vectors", "1"], capture_output=True, text=True)
        return r, tmp

    def stops(self, urdf: str, where: str, problem: str, k1: str = "50.0", in_model: bool = False):
        r, tmp = self.derive(urdf, k1)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        lines = r.stderr.splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        file = tmp / ("three.toml" if in_model else "robot.urdf")
        self.assertTrue(lines[0].startswith(f"derive: {file}: {where}"), lines[0])
        self.assertIn(problem, lines[0])
        self.assertEqual(sorted(p.name for p in tmp.iterdir()), ["robot.urdf", "three.toml"], "nothing written")

    def test_the_good_chain_derives(self):
        r, tmp = self.derive(_robot(*GOOD))
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_floating_planar_and_unknown_joints(self):
        for kind in ("floating", "planar"):
            urdf = _robot(*GOOD).replace('name="j2" type="revolute"', f'name="j2" type="{kind}"')
            self.stops(urdf, "joint 'j2'", f"type '{kind}' is not supported")
        urdf = _robot(*GOOD).replace('name="j2" type="revolute"', 'name="j2" type="ball"')
        self.stops(urdf, "joint 'j2'", "type 'ball' is not a URDF joint type")

    def test_mimic_joint(self):
        urdf = _robot(*GOOD).replace('<axis xyz="0 1 0"/>', '<axis xyz="0 1 0"/><mimic joint="j1"/>')
        self.stops(urdf, "joint 'j2'", "mimic joint")

    def test_branch(self):
        urdf = _robot(*GOOD, _link("side", _inertial(0.2)), _joint("jside", "revolute", "a", "side"))
        self.stops(urdf, "joint 'jside'", "(revolute) is a moving side branch at link 'a'")
        # Off the base too: it would be a degree of freedom the chain does not have.
        urdf = _robot(*GOOD, _link("side", _inertial(0.2)), _joint("jside", "prismatic", "base", "side"))
        self.stops(urdf, "joint 'jside'", "(prismatic) is a moving side branch at link 'base'")
        # Beyond the flange everything is dropped, moving or not (the tool replaces the hand).
        beyond = _robot(*GOOD, _link("finger", _inertial(0.2)), _joint("jf", "revolute", "flange", "finger"))
        self.assertEqual(self.chain(beyond).dof, 3)

    def test_fixed_side_links_merge_but_a_fixed_side_link_with_a_moving_child_is_a_branch(self):
        merged = _robot(*GOOD, _link("cam", _inertial(0.2, (0.05, 0.0, 0.0))), _joint("jcam", "fixed", "a", "cam"))
        chain = self.chain(merged)
        self.assertAlmostEqual(chain.bodies[0].mass, 1.2)
        deeper = _robot(*GOOD, _link("cam"), _joint("jcam", "fixed", "a", "cam"), _link("lens", _inertial(0.1)),
                        _joint("jlens", "prismatic", "cam", "lens"))
        self.stops(deeper, "joint 'jlens'", "is a moving side branch at link 'cam'")

    def chain(self, urdf: str):
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "r.urdf").write_text(urdf)
        return read_chain(tmp / "r.urdf", "base", "flange")

    def test_loop(self):
        urdf = _robot(*GOOD, _joint("back", "fixed", "base", "b"))
        self.stops(urdf, "link 'b'", "has two parents")

    def test_missing_inertial_on_a_moving_body(self):
        urdf = _robot(*GOOD).replace(_link("b", _inertial(0.5, (0.0, 0.0, 0.1))), _link("b"))
        self.stops(urdf, "link 'b'", "has no <inertial>, but a moving joint carries it")

    def test_mass_zero_or_negative(self):
        for mass in (0.0, -1.0):
            urdf = _robot(*GOOD).replace(_inertial(0.5, (0.0, 0.0, 0.1)), _inertial(mass, (0.0, 0.0, 0.1)))
            self.stops(urdf, "link 'b'", "must be > 0")

    def test_inertia_not_positive_definite(self):
        urdf = _robot(*GOOD).replace(_inertial(0.5, (0.0, 0.0, 0.1)), _inertial(0.5, moments=(0.01, 0.01, -0.01)))
        self.stops(urdf, "link 'b'", "not positive definite")
        urdf = _robot(*GOOD).replace(_inertial(0.5, (0.0, 0.0, 0.1)),
                                     _inertial(0.5, moments=(0.01, 0.01, 0.01), products=(0.02, 0.0, 0.0)))
        self.stops(urdf, "link 'b'", "not positive definite")

    def test_triangle_inequality(self):
        urdf = _robot(*GOOD).replace(_inertial(0.5, (0.0, 0.0, 0.1)), _inertial(0.5, moments=(0.01, 0.01, 0.03)))
        self.stops(urdf, "link 'b'", "violate the triangle inequality")

    def test_flange_not_below_the_base_and_undefined_links(self):
        # The flange above the base: the one root.
        urdf = _robot(*GOOD).replace(_joint("fix", "fixed", "c", "flange", "0 0 0.2"),
                                     _joint("fix", "fixed", "flange", "base"))
        self.stops(urdf, "link 'flange'", "is not below the base")
        # Under a second root: not a URDF (its links are one tree).
        urdf = _robot(*GOOD, _link("elsewhere")).replace(_joint("fix", "fixed", "c", "flange", "0 0 0.2"),
                                                         _joint("fix", "fixed", "elsewhere", "flange"))
        self.stops(urdf, "2 root links ('base', 'elsewhere')", "one tree with one root")
        self.stops(_robot(*GOOD).replace('<child link="flange"/>', '<child link="nowhere"/>'),
                   "joint 'fix'", "its child link 'nowhere' is not defined")

    def test_too_many_joints_and_too_large_a_file(self):
        parts = [_link("base")]
        for i in range(13):
            parts += [_link(f"l{i}", _inertial(0.5, (0.0, 0.0, 0.1))),
                      _joint(f"j{i}", "revolute", "base" if i == 0 else f"l{i - 1}", f"l{i}", "0 0 0.1")]
        parts += [_link("flange"), _joint("fix", "fixed", "l12", "flange")]
        self.stops(_robot(*parts), "link 'flange'", "13 moving joints")
        self.stops(_robot(*GOOD) + " " * (4 * 1024 * 1024), "", "larger than 4194304 bytes (4 MiB), more than a URDF file needs")

    def test_not_xml(self):
        self.stops("<robot><link name='a'></robot>", "", "not valid XML")

    def test_singular_a_names_the_joint(self):
        # j1 turns about the vertical: gravity gives it no stiffness, so without K it has none.
        self.stops(_robot(*GOOD), "impedance.stiffness", "along joints j1", k1="0.0", in_model=True)

    def test_fewer_joints_than_the_tip_has_components(self):
        # A URDF tool's tip has 3 components, which a tip term stores in the joints' slots.
        two = GOOD[:3] + [GOOD[4], GOOD[5], GOOD[6], _joint("fix", "fixed", "b", "flange", "0 0 0.2")]
        model = (MODEL.replace("dof = 3", "dof = 2").replace("[{k1}, 50.0, 50.0]", "[{k1}, 50.0]")
                 .replace("[5.0, 5.0, 5.0]", "[5.0, 5.0]").replace('["0", "0.3", "0.2"]', '["0", "0.3"]')
                 .replace('["0", "0", "0"]', '["0", "0"]'))
        r, tmp = self.derive(_robot(*two), model=model)
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertEqual(r.stderr.splitlines(), [
            f"derive: {tmp / 'three.toml'}: model.dof: is 2: model 'three' (dynamics.kind = 'urdf') has a tip of 3 "
            "components (x, y, z of the tool's tip), more than its joints: a tip term's vectors are stored padded in "
            "the joints' slots"])

    def test_description_keys(self):
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "robot.urdf").write_text(_robot(*GOOD))
        for text, key in ((MODEL.replace("dof = 3", "dof = 4"), "model.dof"),
                          (MODEL.replace("damping = [5.0, 5.0, 5.0]", "damping = [5.0]"), "impedance.damping"),
                          (MODEL + '[[parameters]]\nname = "m"\n', "parameters"),
                          (MODEL.replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, -9.81]"), "urdf.gravity")):
            (tmp / "three.toml").write_text(text.format(file="robot.urdf", k1="50.0"))
            with self.assertRaises(DescriptionError) as caught:
                load_model(tmp / "three.toml")
            self.assertIn(f": {key}: ", str(caught.exception))


def _rod_urdf(m1, l1, m2, l2) -> str:
    """Two uniform rods in the x-y plane (joint axes z), gravity along -y."""
    def rod(m, l):
        return _inertial(m, (l / 2, 0.0, 0.0), (m * 1e-6, m * l * l / 12, m * l * l / 12))
    return _robot(_link("base"), _link("rod1", rod(m1, l1)), _link("rod2", rod(m2, l2)), _link("tip"),
                  _joint("j1", "revolute", "base", "rod1"), _joint("j2", "revolute", "rod1", "rod2", f"{l1!r} 0 0"),
                  _joint("tip", "fixed", "rod2", "tip", f"{l2!r} 0 0"))


def _raw_dynamics(dyn: ChainDynamics, tool=None):
    """(q, q_dot, tau[, tool]) -> q_ddot of the rigid-body dynamics alone (no impedance):
    CRBA + RNEA + LDL^T, the code's route."""
    n = dyn.n
    q, qd, tau = ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("tau", n)
    p = ca.SX.sym("p", 10)
    last = dyn.tool_parameters([p[i] for i in range(10)]) if tool else dyn.link_parameters(n - 1)
    qs, qds = [q[i] for i in range(n)], [qd[i] for i in range(n)]
    trig = [(ca.sin(q[i]), ca.cos(q[i])) for i in range(n)]
    mass = dyn.mass_matrix(qs, trig, last)
    bias = dyn.rnea(qs, trig, qds, [0.0] * n, last)
    acc = ldl_apply(ldl_factor(mass), [tau[i] - bias[i] for i in range(n)])
    mass_sx = ca.vertcat(*[ca.horzcat(*row) for row in mass])
    inverse = dyn.rnea(qs, trig, qds, [0.0] * n, last)
    fns = (ca.Function("fd", [q, qd, tau, p], [ca.vertcat(*acc)]), ca.Function("crba", [q, p], [mass_sx]),
           ca.Function("bias", [q, qd, p], [ca.vertcat(*inverse)]))

    def inertial(tool):
        """A tool's ten inertial numbers: a 7-number tool's products are zero, a 13-number tool's
        tip is dropped (it does not move the dynamics)."""
        t = [float(v) for v in np.asarray(tool).ravel()]
        return (t + [0.0] * 3)[:10] if len(t) == 7 else t[:10]
    return tuple((lambda *a, f=f: f(*a[:-1], inertial(a[-1]))) for f in fns)


class CheckedOnSeveralProcesses(unittest.TestCase):
    """make model checks a URDF model's functions on every core (derive.py --jobs): the IR and the
    test vectors are the same bytes as one process writes, and a bad --jobs is one line."""

    def test_jobs_write_the_same_bytes(self):
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "robot.urdf").write_text(_robot(*GOOD))
        (tmp / "three.toml").write_text(MODEL.format(file="robot.urdf", k1="50.0"))
        written = {}
        for jobs in (1, 3):
            out = tmp / f"jobs{jobs}"
            out.mkdir()
            r = subprocess.run([sys.executable, str(DERIVE), str(tmp / "three.toml"), "--out", str(out / "three.json"),
                                "--vectors", "2", "--jobs", str(jobs)], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            written[jobs] = [(out / n).read_bytes() for n in ("three.json", "three.vectors.json")]
        self.assertEqual(written[1], written[3])
        r = subprocess.run([sys.executable, str(DERIVE), str(tmp / "three.toml"), "--out", str(tmp / "x.json"),
                            "--jobs", "0"], capture_output=True, text=True)
        self.assertEqual((r.returncode, r.stderr.strip()), (2, "derive: --jobs 0: need at least one process"))


class PlanarRods(unittest.TestCase):
    """(a) The URDF route on two uniform rods is arm2_exact after q1 = theta1, q2 = theta2 - theta1."""

    def test_moves_as_arm2_exact(self):
        exact = CasadiModel(load_model(ROOT / "derive" / "models" / "arm2_exact.toml")).dynamics.f
        rng = np.random.default_rng(23)
        worst = 0.0
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        for tool in range(20):
            m1, m2, l1, l2 = (float(v) for v in rng.uniform(0.1, 0.6, 4))
            (tmp / "rods.urdf").write_text(_rod_urdf(m1, l1, m2, l2))
            dyn = ChainDynamics(read_chain(tmp / "rods.urdf", "base", "tip"), [0.0, -9.81, 0.0])
            fd, _, _ = _raw_dynamics(dyn)

            def urdf_rhs(x, u):
                q = np.array([x[0], x[1] - x[0]])
                qd = np.array([x[2], x[3] - x[2]])
                a = np.array(fd(q, qd, u, np.zeros(7))).ravel()
                return np.array([x[2], x[3], a[0], a[0] + a[1]])

            def exact_rhs(x, u):
                return np.array(exact(x, u, [m1, m2, l1, l2])).ravel()

            for _ in range(10):
                x = np.concatenate([rng.uniform(-math.pi, math.pi, 2), rng.uniform(-3, 3, 2)])
                u = rng.uniform(-2, 2, 2)
                want = exact_rhs(x, u)
                worst = max(worst, np.max(np.abs(urdf_rhs(x, u) - want)) / np.max(np.abs(want)))
            if tool >= 3:
                continue
            # The motion: 2 s of RK4 from rest off the hanging pose under a constant torque.
            xa = xb = np.array([-1.2, -1.9, 0.0, 0.0])
            u = np.array([0.3, -0.1])
            h = 1e-3
            for _ in range(2000):
                xa, xb = _rk4(urdf_rhs, xa, u, h), _rk4(exact_rhs, xb, u, h)
            worst = max(worst, np.max(np.abs(xa - xb)) / np.max(np.abs(xb)))
        self.assertLess(worst, TOLERANCE, f"worst normwise relative difference {worst:.2e}")


def _worst_against_pinocchio(pm, dynamics, tool, samples, q_pin=lambda q: q) -> float:
    """The worst normwise relative difference of `dynamics` (fd, crba, bias of _raw_dynamics, with
    `tool`) from Pinocchio's aba, crba and rnea on model `pm`, over `samples` (q, q_dot, tau);
    `q_pin` is Pinocchio's configuration of q."""
    import pinocchio as pin
    fd, crba, bias = dynamics
    data = pm.createData()
    worst = 0.0
    for q, qd, tau in samples:
        qp = q_pin(q)
        m_pin = pin.crba(pm, data, qp)
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        for got, want in ((crba(q, tool), m_pin), (bias(q, qd, tool), pin.rnea(pm, data, qp, qd, np.zeros(len(qd)))),
                          (fd(q, qd, tau, tool), pin.aba(pm, data, qp, qd, tau))):
            got = np.array(got, dtype=float).reshape(np.shape(want))
            worst = max(worst, float(np.max(np.abs(got - want)) / np.max(np.abs(want))))
    return worst


def _rk4(f, x, u, h):
    k1 = f(x, u)
    k2 = f(x + h / 2 * k1, u)
    k3 = f(x + h / 2 * k2, u)
    k4 = f(x + h * k3, u)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


# A 3-DOF spatial chain with tilted axes, rotated joint origins and inertial frames, full inertia
# tensors and offset centres of mass: (joint origin xyz, rpy, axis, mass, com, inertial rpy,
# (ixx, iyy, izz, ixy, ixz, iyz)).
SPATIAL = [
    ((0.0, 0.0, 0.3), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 2.0, (0.01, -0.02, 0.1), (0.0, 0.0, 0.0),
     (0.03, 0.025, 0.01, 0.001, -0.002, 0.0015)),
    ((0.05, 0.0, 0.1), (-math.pi / 2, 0.0, 0.3), (0.0, 0.6, 0.8), 1.2, (0.2, 0.01, 0.0), (0.1, 0.2, 0.0),
     (0.004, 0.02, 0.021, -0.0005, 0.0002, 0.0001)),
    ((0.4, 0.0, 0.0), (0.2, -0.1, 0.5), (1.0, 0.0, 0.0), 0.7, (0.1, 0.0, 0.03), (0.0, 0.0, 0.4),
     (0.002, 0.006, 0.007, 0.0, 0.0004, -0.0003)),
]
FLANGE = ((0.15, 0.0, 0.02), (0.0, 0.3, 0.0))


def _spatial_urdf() -> str:
    parts = [_link("base")]
    parent = "base"
    for i, (xyz, rpy, axis, m, com, irpy, inertia) in enumerate(SPATIAL):
        ixx, iyy, izz, ixy, ixz, iyz = inertia
        parts.append(_link(f"l{i}", _inertial(m, com, (ixx, iyy, izz), " ".join(map(repr, irpy)), (ixy, ixz, iyz))))
        parts.append(_joint(f"j{i}", "revolute", parent, f"l{i}", " ".join(map(repr, xyz)), " ".join(map(repr, rpy)),
                            " ".join(map(repr, axis))))
        parent = f"l{i}"
    parts += [_link("flange"), _joint("f", "fixed", parent, "flange", " ".join(map(repr, FLANGE[0])),
                                      " ".join(map(repr, FLANGE[1])))]
    return _robot(*parts)


def _sympy_lagrangian(tool):
    """q_ddot(q, q_dot, tau) of SPATIAL with `tool` at the flange by Lagrange's equations, from the
    raw numbers above: forward kinematics, T = sum m |v_c|^2/2 + w^T I w/2 with w from R_dot R^T,
    V = sum m g z_c."""
    import sympy as sp

    def rpy(r, p, y):
        rx = sp.Matrix([[1, 0, 0], [0, sp.cos(r), -sp.sin(r)], [0, sp.sin(r), sp.cos(r)]])
        ry = sp.Matrix([[sp.cos(p), 0, sp.sin(p)], [0, 1, 0], [-sp.sin(p), 0, sp.cos(p)]])
        rz = sp.Matrix([[sp.cos(y), -sp.sin(y), 0], [sp.sin(y), sp.cos(y), 0], [0, 0, 1]])
        return rz * ry * rx

    def about(axis, angle):
        a = sp.Matrix(axis) / sp.sqrt(sum(x * x for x in axis))
        k = sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        return sp.eye(3) + sp.sin(angle) * k + (1 - sp.cos(angle)) * k * k

    n = len(SPATIAL)
    q = sp.symbols(f"q0:{n}")
    rot, pos = sp.eye(3), sp.zeros(3, 1)
    bodies = []
    for i, (xyz, angles, axis, m, com, irpy, inertia) in enumerate(SPATIAL):
        pos = pos + rot * sp.Matrix(xyz)
        rot = rot * rpy(*angles) * about(axis, q[i])
        ixx, iyy, izz, ixy, ixz, iyz = inertia
        r_in = rpy(*irpy)
        local = r_in * sp.Matrix([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) * r_in.T
        bodies.append((m, pos + rot * sp.Matrix(com), rot, local))
    m_t, c_t, moments = tool[0], tool[1:4], tool[4:7]
    r_f = rot * rpy(0, FLANGE[1][1], 0)
    bodies.append((m_t, pos + rot * sp.Matrix(FLANGE[0]) + r_f * sp.Matrix(c_t), r_f, sp.diag(*moments)))
    # T = q_dot^T M q_dot / 2 with M = sum m J_v^T J_v + J_w^T I J_w (v = J_v q_dot, and
    # w_body = J_w q_dot from [w_body]x = R^T R_dot); Lagrange's equations then give
    # M q_ddot + sum_k (dM/dq_k q_dot) q_dot_k - [q_dot^T dM/dq_k q_dot / 2]_k + dV/dq = tau.
    qv = sp.Matrix(q)
    mass, potential = sp.zeros(n, n), 0
    for m, c, r, inertia in bodies:
        j_v = c.jacobian(qv)
        j_w = sp.zeros(3, n)
        for j in range(n):
            w = r.T * r.diff(q[j])
            j_w[:, j] = sp.Matrix([w[2, 1], w[0, 2], w[1, 0]])
        mass += m * j_v.T * j_v + j_w.T * inertia * j_w
        potential += m * 9.81 * c[2]
    d_mass = [mass.diff(q[k]) for k in range(n)]
    gravity = sp.Matrix([potential]).jacobian(qv).T
    evaluate = sp.lambdify([q], [mass, gravity, *d_mass], modules="numpy", cse=True)

    def terms(q_value, qd_value):
        m_num, g_num, *dm = (np.array(a, dtype=float) for a in evaluate(q_value))
        bias = sum(dm[k] @ qd_value * qd_value[k] for k in range(n))
        bias = bias - 0.5 * np.array([qd_value @ dm[k] @ qd_value for k in range(n)]) + g_num.ravel()
        return m_num, bias
    return terms


class SpatialLagrangian(unittest.TestCase):
    """(b) SymPy's Lagrangian of a 3-DOF spatial chain with a tool agrees with the URDF route."""

    def test_agrees_with_sympy(self):
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "spatial.urdf").write_text(_spatial_urdf())
        dyn = ChainDynamics(read_chain(tmp / "spatial.urdf", "base", "flange"), [0.0, 0.0, -9.81])
        fd, crba, _ = _raw_dynamics(dyn, tool=True)
        tool = [0.6, 0.02, -0.01, 0.09, 0.003, 0.004, 0.002]
        lagrange = _sympy_lagrangian(tool)
        rng = np.random.default_rng(5)
        worst = 0.0
        for _ in range(100):
            q, qd, tau = rng.uniform(-math.pi, math.pi, 3), rng.uniform(-3, 3, 3), rng.uniform(-5, 5, 3)
            mass, bias = lagrange(q, qd)
            want = np.linalg.solve(mass, tau - bias)
            got = np.array(fd(q, qd, tau, tool)).ravel()
            worst = max(worst, np.max(np.abs(got - want)) / np.max(np.abs(want)),
                        np.max(np.abs(np.array(crba(q, tool)) - mass)) / np.max(np.abs(mass)))
        self.assertLess(worst, TOLERANCE, f"worst normwise relative difference {worst:.2e}")


LIMIT = '<limit effort="10" velocity="1" lower="-4" upper="4"/>'


def _quarter_turn(angle: float) -> float:
    k = round(angle / (math.pi / 2))
    return k * (math.pi / 2) if abs(angle - k * (math.pi / 2)) < 1e-9 else angle


class PinocchioCheck:
    """Pinocchio (pin, derive/requirements.txt) on a model's URDF cut at the flange, the tool
    added as a fixed link: crba, rnea, aba and the generated plant at random tools and states."""

    def pinocchio_model(self, model, tool):
        import pinocchio as pin
        root = ET.parse(model.chain.path).getroot()
        keep = self.chain_links(root, model.chain.flange)
        for tag in ("link", "joint"):
            for e in list(root.findall(tag)):
                name = e.get("name") if tag == "link" else e.find("child").get("link")
                if name not in keep:
                    root.remove(e)
        # The reader takes rpy angles within 1e-9 of a multiple of pi/2 as that multiple (urdf.py):
        # give Pinocchio the same angles, written as the double nearest it (UR5's 1.57079632679
        # otherwise makes a robot 5e-12 rad away, 8e-11 apart); other angles stay literal.
        for origin in root.iter("origin"):
            if origin.get("rpy"):
                origin.set("rpy", " ".join(repr(_quarter_turn(float(v))) for v in origin.get("rpy").split()))
        m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = (float(v) for v in tool[:10])
        root.append(ET.fromstring(_link("tool", _inertial(m, (cx, cy, cz), (ixx, iyy, izz),
                                                          products=(ixy, ixz, iyz)))))
        root.append(ET.fromstring(_joint("tool_joint", "fixed", model.chain.flange, "tool")))
        built = pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))
        return built, built.createData()

    @staticmethod
    def chain_links(root, flange):
        """Every link but those below the flange."""
        children = {}
        for j in root.findall("joint"):
            children.setdefault(j.find("parent").get("link"), []).append(j.find("child").get("link"))
        below, stack = set(), list(children.get(flange, []))
        while stack:
            link = stack.pop()
            below.add(link)
            stack += children.get(link, [])
        return {l.get("name") for l in root.findall("link")} - below

    def check_robot(self, path: Path, states: int = 100) -> dict:
        import pinocchio as pin
        model = load_model(path)
        dv = UrdfDerivation(model, model.chain, load_tasks(ROOT / "derive" / "tasks.toml"))
        n = dv.n
        fd, crba, bias = _raw_dynamics(dv.dyn, tool=True)
        plant = ca.Function("f", [dv.x, dv.u, dv.p], [dv.dynamics_with(dv.x, dv.u, dv.coefficients(dv.p))])
        rng = np.random.default_rng(7)
        worst = dict.fromkeys(("crba", "rnea", "aba", "plant"), 0.0)
        for k in range(states):
            tool = _sample_tool(rng).ravel()
            pm, data = self.pinocchio_model(model, tool)
            self.assertEqual(pm.nq, n)
            q, qd = rng.uniform(-math.pi, math.pi, n), rng.uniform(-3, 3, n)
            tau, u = rng.uniform(-20, 20, n), rng.uniform(-2, 2, n)

            def rel(a, b):
                return float(np.max(np.abs(np.asarray(a, dtype=float) - b)) / np.max(np.abs(b)))

            m_pin = pin.crba(pm, data, q)
            m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
            worst["crba"] = max(worst["crba"], rel(crba(q, tool), m_pin))
            worst["rnea"] = max(worst["rnea"], rel(np.array(bias(q, qd, tool)).ravel(),
                                                   pin.rnea(pm, data, q, qd, np.zeros(n))))
            worst["aba"] = max(worst["aba"], rel(np.array(fd(q, qd, tau, tool)).ravel(), pin.aba(pm, data, q, qd, tau)))
            # The generated plant: aba with tau = U + K (q^e - q) - D q_dot + g(q^e).
            q_e = np.array(dv.q_e)
            g_e = pin.computeGeneralizedGravity(pm, data, q_e)
            torque = u + np.array(dv.stiffness) * (q_e - q) - np.array(dv.damping) * qd + g_e
            want = np.concatenate([qd, pin.aba(pm, data, q, qd, torque)])
            worst["plant"] = max(worst["plant"], rel(np.array(plant(np.concatenate([q, qd]), u, tool)).ravel(), want))
        for what, err in worst.items():
            self.assertLess(err, TOLERANCE, f"{path.stem} {what}: worst normwise relative difference {err:.2e}")
        return worst


class Pinocchio(PinocchioCheck, unittest.TestCase):
    """(c) Pinocchio (pin, derive/requirements.txt) on the same URDF cut at the flange, the tool
    added as a fixed link."""

    # urdfdom (Pinocchio's parser) wants limits on revolute and prismatic joints; toolconf checks q^e against them.
    def test_a_prismatic_joint_and_a_continuous_one(self):
        """A chain the arms do not have: a prismatic joint along a tilted axis between a
        continuous and a revolute joint, with a tool, against crba, rnea and aba."""
        import pinocchio as pin
        links = [_link("base"), _link("a", _inertial(1.5, (0.02, 0.0, 0.1), (0.02, 0.018, 0.01), "0.1 0 0.2",
                                                      (0.001, 0.0, 0.0))),
                 _link("b", _inertial(0.7, (0.0, 0.05, 0.0), (0.005, 0.004, 0.006))),
                 _link("c", _inertial(0.4, (0.1, 0.0, 0.02), (0.001, 0.003, 0.0035))), _link("flange")]
        joints = [_joint("j1", "continuous", "base", "a", "0 0 0.1"),
                  _joint("j2", "prismatic", "a", "b", "0.05 0 0.2", "0.3 0 0", "0 0.6 0.8", LIMIT),
                  _joint("j3", "revolute", "b", "c", "0 0.1 0", "0 1.2 0", "1 0 0", LIMIT),
                  _joint("f", "fixed", "c", "flange", "0.2 0 0", "0 0 0.4")]
        tool = [0.5, 0.01, 0.02, 0.07, 0.002, 0.003, 0.001]
        tool_link = [_link("tool", _inertial(tool[0], tuple(tool[1:4]), tuple(tool[4:7]))),
                     _joint("tj", "fixed", "flange", "tool")]
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / "slide.urdf").write_text(_robot(*links, *joints))
        dyn = ChainDynamics(read_chain(tmp / "slide.urdf", "base", "flange"), [0.0, 0.0, -9.81])
        fd, crba, bias = _raw_dynamics(dyn, tool=True)
        pm = pin.buildModelFromXML(_robot(*links, *joints, *tool_link))
        rng = np.random.default_rng(11)
        samples = [(rng.uniform(-math.pi, math.pi, 3), rng.uniform(-3, 3, 3), rng.uniform(-5, 5, 3)) for _ in range(100)]
        worst = _worst_against_pinocchio(pm, (fd, crba, bias), tool, samples,
                                         # continuous: (cos, sin)
                                         q_pin=lambda q: np.array([math.cos(q[0]), math.sin(q[0]), q[1], q[2]]))
        self.assertLess(worst, TOLERANCE, f"worst normwise relative difference {worst:.2e}")

    def test_panda(self):
        self.check_robot(PANDA)

    def test_ur5(self):
        self.check_robot(UR5)


# UFactory's xArm7 (xarm7.urdf, example-robot-data 6.0.0), its first four joints: origins, axes,
# limits, <dynamics>, masses, centres of mass and inertias as the file writes them, its quarter
# turns 1.5708 (3.7e-6 rad from pi/2: a different angle, which Pinocchio and the reader use as
# written). (joint, origin xyz, rpy, lower, upper, damping, link mass, com, (ixx iyy izz), (ixy ixz iyz)).
XARM = [
    ("joint1", "0 0 0.267", "0 0 0", -6.283185307179586, 6.283185307179586, 10, 2.382, (-0.0002, 0.02905, -0.01233),
     (0.0056905, 0.0049566, 0.003316654), (-1.579e-05, 5.125e-06, -0.000873378)),
    ("joint2", "0 0 0", "-1.5708 0 0", -2.059, 2.0944, 10, 1.869, (0.00022, -0.12856, 0.01735),
     (0.0095989, 0.00382472, 0.007565669), (1.541e-06, 5.56e-06, -0.00317156)),
    ("joint3", "0 -0.293 0", "1.5708 0 0", -6.283185307179586, 6.283185307179586, 5, 1.6383, (0.0466, -0.02463, -0.00768),
     (0.00310955, 0.00264483, 0.0026624), (0.00030837, -0.00058453, 0.000338893)),
    ("joint4", "0.0525 0 0", "1.5708 0 0", -0.19198, 3.927, 5, 1.7269, (0.07047, -0.11575, 0.012),
     (0.005889, 0.00359703, 0.00543244), (0.00137112, 0.00088143, -0.001762155)),
]
XARM_MODEL = urdf_model_head("xarm.urdf", "xarm", 4, "link_base", "link_eef") + """[impedance]
stiffness = [50.0, 50.0, 50.0, 50.0]
damping = [5.0, 5.0, 5.0, 5.0]
[equilibrium]
q = ["0", "{q2}", "0", "1.0"]
q_dot = ["0", "0", "0", "0"]
u = ["0", "0", "0", "0"]
"""


def _xarm_urdf() -> str:
    parts = [_link("link_base", _inertial(0.88556, (-0.021131, -0.0016302, 0.056488), (0.0030595, 0.0037783, 0.0020125),
                                           products=(0.00012259, -0.00062705, 0.00027023)))]
    parent = "link_base"
    for i, (name, xyz, rpy, lower, upper, damping, m, com, moments, products) in enumerate(XARM):
        child = f"link{i + 1}"
        parts.append(_link(child, _inertial(m, com, moments, products=products)))
        parts.append(_joint(name, "revolute", parent, child, xyz, rpy, extra=(
            f'<limit effort="50" lower="{lower!r}" upper="{upper!r}" velocity="3.14"/>'
            f'<dynamics damping="{damping}" friction="1"/>')))
        parent = child
    parts += [_link("link_eef"), _joint("joint_eef", "fixed", parent, "link_eef", "0.0775 -0.3425 0", "1.5708 0 0")]
    return _robot(*parts)


# The Kinova Gen2 (kinova.urdf, example-robot-data 6.0.0) writes pi/2 and pi as 1.57079632679 and
# 3.14159265359 (5e-12 and 3.6e-12 off: quarter turns), alone, together, and beside a generic
# angle (its fingers: -1.570796327, 2e-10 off); the fingers hang beside the flange.
KINOVA = [
    ("j1", "0 0 0.15675", "0 3.14159265359 0"),
    ("j2", "0 0.0016 -0.11875", "-1.57079632679 0 3.14159265359"),
    ("j3", "0 -0.410 0", "1.57079632679 0.649262481663582 0.3"),
]
KINOVA_FINGER = "-1.570796327 .649262481663582 1.57079632679490"


def _kinova_urdf(finger: str = "fixed") -> str:
    parts = [_link("base")]
    parent = "base"
    for i, (name, xyz, rpy) in enumerate(KINOVA):
        child = f"l{i + 1}"
        parts.append(_link(child, _inertial(0.6 + 0.1 * i, (0.01, -0.02 * i, 0.05), (0.004, 0.003 + 0.001 * i, 0.002),
                                            rpy="0 1.57079632679 0", products=(0.0001, 0.0, -0.0002))))
        parts.append(_joint(name, "revolute", parent, child, xyz, rpy, axis="0 0 1", extra=LIMIT))
        parent = child
    parts += [_link("flange"), _joint("end_effector", "fixed", parent, "flange", "0 0 -0.16",
                                      "3.14159265359 1.57079632679 0"),
              _link("finger_1", _inertial(0.01, (0.022, 0.0, 0.0), (1e-6, 1e-6, 1e-6))),
              _joint("finger_joint_1", finger, parent, "finger_1", "-0.0025 0.03095 -0.11482", KINOVA_FINGER,
                     extra=LIMIT)]
    return _robot(*parts)


def _entry_snapped_rotation(rpy):
    """The reader's former rule (the bug): each rotation entry within 1e-9 of 0 or +-1 snapped."""
    import mpmath
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (mpmath.cos(r), mpmath.sin(r), mpmath.cos(p), mpmath.sin(p), mpmath.cos(y), mpmath.sin(y))
    m = mpmath.matrix([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                       [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], [-sp, cp * sr, cp * cr]])

    def snap(x):
        return next((mpmath.mpf(t) for t in (0, 1, -1) if abs(x - t) < mpmath.mpf("1e-9")), x)
    return mpmath.matrix([[snap(m[i, j]) for j in range(3)] for i in range(3)])


def _orthonormality(rotation) -> float:
    r = np.array(rotation, dtype=float)
    return float(np.max(np.abs(r.T @ r - np.eye(3))))


class HowAUrdfIsRead(PinocchioCheck, unittest.TestCase):
    """(d) urdf.py's rule ("How a URDF is read", docs/reference/urdf-arms.md): angles snapped to quarter turns
    within 1e-9 rad and otherwise literal, as Pinocchio reads them; joint limits, <dynamics> and
    side branches."""

    def files(self, urdf: str, name: str, model: str | None = None) -> tuple[Path, Path | None]:
        tmp = Path(self.enterContext(tempfile.TemporaryDirectory()))
        (tmp / name).write_text(urdf)
        if model is not None:
            (tmp / "xarm.toml").write_text(model)
        return tmp / name, (tmp / "xarm.toml" if model is not None else None)

    def derive(self, model: Path, status: int) -> list[str]:
        """The derivation of `model`, which must end with `status`: its lines on stderr."""
        r = subprocess.run([sys.executable, str(DERIVE), str(model), "--out", str(model.with_suffix(".json")),
                            "--vectors", "1"], capture_output=True, text=True)
        self.assertEqual(r.returncode, status, r.stderr)
        return r.stderr.splitlines()

    def test_xarm7_style_angles_are_literal_and_match_pinocchio_on_the_file(self):
        import pinocchio as pin
        urdf, _ = self.files(_xarm_urdf(), "xarm.urdf")
        chain = read_chain(urdf, "link_base", "link_eef")
        # 1.5708 is no quarter turn: its cosine is kept, and the rotation stays one.
        c, s = math.cos(1.5708), math.sin(1.5708)
        self.assertEqual(chain.bodies[2].rotation, ((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c)))
        for b in chain.bodies:
            self.assertLess(_orthonormality(b.rotation), 1e-15, b.joint)
        fd, crba, bias = _raw_dynamics(ChainDynamics(chain, [0.0, 0.0, -9.81]))
        pm = pin.buildModelFromUrdf(str(urdf))      # the literal file
        self.assertEqual(pm.nq, 4)
        rng = np.random.default_rng(31)
        samples = [(rng.uniform(-math.pi, math.pi, 4), rng.uniform(-3, 3, 4), rng.uniform(-20, 20, 4)) for _ in range(100)]
        worst = _worst_against_pinocchio(pm, (fd, crba, bias), np.zeros(7), samples)
        self.assertLess(worst, TOLERANCE, f"worst normwise relative difference {worst:.2e}")

    def test_xarm7_style_chain_derives_and_its_plant_matches_pinocchio(self):
        urdf, model = self.files(_xarm_urdf(), "xarm.urdf", XARM_MODEL.format(q2="0.3"))
        # The URDF's <dynamics> are not the plant's damping: said once, on stderr.
        self.assertEqual(self.derive(model, 0), [
            f"derive: {urdf}: note: <dynamics> damping/friction of joints joint1, joint2, joint3, joint4 ignored: "
            "the plant's joint damping is the description's [impedance]"])
        self.check_robot(model, states=20)

    def test_kinova_style_quarter_turns_are_exact(self):
        import pinocchio as pin
        urdf, _ = self.files(_kinova_urdf(), "kinova.urdf")
        chain = read_chain(urdf, "base", "flange")
        # All quarter turns: entries exactly 0 and +-1 (no 1e-12 residues in the generated code).
        self.assertEqual(chain.bodies[0].rotation, ((-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, -1.0)))
        self.assertEqual(chain.bodies[1].rotation, ((-1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.0, -1.0, 0.0)))
        self.assertEqual(chain.flange_rotation, ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0), (-1.0, 0.0, 0.0)))
        # A quarter turn beside generic angles: still a rotation to the last bit.
        self.assertLess(_orthonormality(chain.bodies[2].rotation), 1e-15)
        self.assertEqual(chain.bodies[2].rotation[2][2], 0.0)
        # The fixed fingers are merged into the last body.
        self.assertAlmostEqual(chain.bodies[2].mass, 0.81, places=15)
        root = ET.fromstring(_kinova_urdf())
        for origin in root.iter("origin"):
            origin.set("rpy", " ".join(repr(_quarter_turn(float(v))) for v in origin.get("rpy").split()))
        fd, _, _ = _raw_dynamics(ChainDynamics(chain, [0.0, 0.0, -9.81]))
        worst = 0.0
        literal = pin.buildModelFromUrdf(str(urdf))
        for pm in (pin.buildModelFromXML(ET.tostring(root, encoding="unicode")), literal):
            data = pm.createData()
            rng = np.random.default_rng(37)
            for _ in range(100):
                q, qd, tau = rng.uniform(-math.pi, math.pi, 3), rng.uniform(-3, 3, 3), rng.uniform(-5, 5, 3)
                want = pin.aba(pm, data, q, qd, tau)
                got = np.array(fd(q, qd, tau, np.zeros(7)), dtype=float).ravel()
                worst = max(worst, float(np.max(np.abs(got - want)) / np.max(np.abs(want))))
        self.assertLess(worst, TOLERANCE, f"worst normwise relative difference {worst:.2e}")

    def test_a_moving_finger_beside_the_flange_is_refused(self):
        urdf, _ = self.files(_kinova_urdf("revolute"), "kinova.urdf")
        with self.assertRaises(DescriptionError) as caught:
            read_chain(urdf, "base", "flange")
        self.assertEqual(str(caught.exception).splitlines(), [
            f"{urdf}: joint 'finger_joint_1': (revolute) is a moving side branch at link 'l3': the branch moves "
            "and does not hold the flange 'flange'; only fixed side branches are merged into the chain"])

    def test_a_rotation_that_is_not_orthonormal_is_refused(self):
        # The former entry snapping of 1.5708 (sin -> 1, cos kept at -3.7e-6) is no rotation.
        from unittest import mock
        import toolconf_derive.urdf as urdf_module
        urdf, _ = self.files(_xarm_urdf(), "xarm.urdf")
        with mock.patch.object(urdf_module, "rpy_rotation", _entry_snapped_rotation):
            with self.assertRaises(DescriptionError) as caught:
                read_chain(urdf, "link_base", "link_eef")
        self.assertEqual(str(caught.exception), f"{urdf}: joint 'joint2' origin rpy: rotation is not orthonormal: "
                                                "max |R^T R - I| = 1.35e-11 > 1.0e-12")

    def test_an_equilibrium_outside_the_joint_limits_is_refused(self):
        urdf, model = self.files(_xarm_urdf(), "xarm.urdf", XARM_MODEL.format(q2="2.5"))
        self.assertEqual(self.derive(model, 2), [
            f"derive: {model}: equilibrium.q[1]: '2.5' = 2.5 is outside joint 'joint2''s limits [-2.059, 2.0944] "
            f"({urdf} <limit lower upper>)"])
        # A limit's absent side is 0, as the URDF specification has it.
        text = _xarm_urdf().replace('lower="-2.059" ', "")
        urdf, model = self.files(text, "xarm.urdf", XARM_MODEL.format(q2="0.5"))
        self.assertEqual(load_model(model).chain.limits[1], (0.0, 2.0944))

    def test_an_equilibrium_failure_names_the_joints_and_the_cause(self):
        # With the former entry snapping let through, gravity fed forward by the code (RNEA) and
        # by the reference (the potential's gradient) disagree at q^e: derivation stops there.
        from unittest import mock
        import mpmath
        import toolconf_derive.urdf as urdf_module
        from toolconf_derive import ir_types as irt
        from toolconf_derive.ir import IR_SCHEMA
        from toolconf_derive.urdf_functions import urdf_documents
        urdf, model_path = self.files(_xarm_urdf(), "xarm.urdf", XARM_MODEL.format(q2="0.3"))
        with mock.patch.object(urdf_module, "rpy_rotation", _entry_snapped_rotation), \
                mock.patch.object(urdf_module, "ORTHONORMAL", mpmath.mpf(1)):
            model = load_model(model_path)
        generator = irt.Generator(command="", model="", tasks="", ir="", vectors="", derive="", render="")
        with self.assertRaises(DescriptionError) as caught:
            urdf_documents(model, load_tasks(ROOT / "derive" / "tasks.toml"), generator, 1, IR_SCHEMA)
        message = str(caught.exception)
        self.assertNotIn("characters)", message)
        self.assertRegex(message, rf"^{re.escape(str(model_path))}: equilibrium: not an equilibrium: "
                                  r"\|f\(X\^e, U\^e\)\| = \d\.\d\de-10 > 1e-12, largest at joint 'joint2' \d\.\d\de-10 rad/s\^2, ")
        self.assertTrue(message.endswith("likely cause: the rotation of joint 'joint2' origin is not orthonormal "
                                         f"(|R^T R - I| = 1.35e-11) in {urdf.name}"), message)


if __name__ == "__main__":
    unittest.main()
