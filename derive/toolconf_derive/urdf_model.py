"""The derivation of a URDF arm with a tool at its flange (description kind `urdf`), on CasADi SX.

The plant the active-inference controller sees (docs/explanation/real-arms.md, "The task formulation for real
arms"): a torque-controlled arm under joint impedance about the equilibrium pose q^e, with the
gravity of the arm and tool at q^e fed forward,

    tau = U + K (q^e - q) - D q_dot + g(q^e; p),     M(q; p) q_ddot + C(q, q_dot; p) q_dot + g(q; p) = tau,

so X^e = [q^e; 0] is an equilibrium with U^e = 0 for every tool, and

    A = [[O, I], [-M^-1 (dg/dq + K), -M^-1 D]],   B = [[O], [M^-1]]   at X^e.

Every function is built twice, by different routes, and the two are compared in 50-digit
arithmetic at every test point before code is written (`check`):

| function | code (what the Rust computes) | reference (what the test vectors hold) |
| --- | --- | --- |
| f(X, U) | CRBA M(q) + RNEA bias, LDL^T solve | articulated-body algorithm (6-D spatial) |
| df/dX, df/dU | -M^-1 [K + dID/dq, D + dID/dq_dot] at q_ddot = f, M^-1 | CasADi AD of the ABA graph |
| A, B | the structured form above, dg/dq by AD of RNEA | AD of the ABA graph at X^e |
| sensitivities, Pi^U | tasks.toml's formulas on SX, inv(A) in block form, J the geometric tip Jacobian | the same formulas in mpmath on the reference A, B (general inverse), J by AD of the inward tip |
| d ln|Pi^U|/dp | reverse AD of sum ln D_ii (LDL^T of Pi^U) | 50-digit forward differences of ln det Pi^U |

The tool's parameters reach everything through the last body's ten inertial numbers, so the
per-tool coefficients of f and df/dX (`DynamicsCoefficients`) are those ten numbers and the
constant torque K q^e + g(q^e; p).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable

import casadi as ca
import mpmath
import numpy as np
import sympy as sp

from .description import Model, Task, sensitivity
from .exact import DIGITS, Exact, ExactFunction
from .functions import _grid_uniform
from .rigid_body import ChainDynamics, aba, ldl_apply, ldl_factor
from .symbolic import parse
from .urdf import UrdfChain

# Code and reference graphs, both evaluated exactly, agree to this (normwise relative per output);
# they differ only by the double rounding of constants folded while the graphs were built.
AGREEMENT = 1e-10
# The tool's parameters: its ten inertial numbers (mass, centre of mass, moments, products), then its
# tip (urdf_description.TOOL_PARAMETERS).
INERTIAL = 10
# Forward-difference step of the 50-digit reference gradient (truncation ~h, far below 1e-12).
GRADIENT_STEP = mpmath.mpf("1e-20")


class UrdfMismatch(AssertionError):
    pass


@dataclass
class SeqArg:
    name: str
    doc: str
    rows: int
    cols: int
    symmetric: bool
    sample: Callable | None


@dataclass
class SeqOutput:
    name: str
    doc: str
    rows: int
    cols: int
    symmetric: bool = False


@dataclass
class SeqFunction:
    """One generated function: its code graph (`code`, inputs in `args` order), or for a per-tool
    function its coefficient graph `coefficients` (params -> k) and per-call graph `code_with`
    (args but params, then k), and the reference values at a sample."""
    name: str
    doc: str
    equation: str
    args: list[SeqArg]
    outputs: list[SeqOutput]
    code: ca.Function
    reference: Callable[[dict], list[Exact]]
    coefficients: ca.Function | None = None
    code_with: ca.Function | None = None
    unhoisted: ca.Function | None = None
    stats: dict = field(default_factory=dict)

    def rng(self) -> np.random.Generator:
        import hashlib
        return np.random.default_rng(int(hashlib.sha256(self.name.encode()).hexdigest()[:16], 16))


def _sample_tool(rng: np.random.Generator) -> np.ndarray:
    """A physical tool, exactly: mass on a 2^-16 grid in [0.05, 3] kg, centre of mass within 5 cm
    of the flange axis and up to 25 cm out, the inertia tensor of a solid box whose sides lie on
    the grid in [1, 30] cm, turned by a rational rotation (so it is a rigid body's), its tip within
    5 cm of the flange axis and 5-35 cm out; each number rounded once from exact rationals."""
    mass = Fraction(float(_grid_uniform(rng, 0.05, 3.0, 1)[0]))
    com = [float(v) for v in _grid_uniform(rng, -0.05, 0.05, 2)] + [float(_grid_uniform(rng, 0.0, 0.25, 1)[0])]
    a, b, c = (Fraction(float(v)) for v in _grid_uniform(rng, 0.01, 0.30, 3))
    moments = [mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12]
    r = _rational_rotation([Fraction(int(k), 8) for k in rng.integers(-4, 4, size=3, endpoint=True)])
    tensor = [[sum(r[i][k] * moments[k] * r[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    tip = [float(v) for v in _grid_uniform(rng, -0.05, 0.05, 2)] + [float(_grid_uniform(rng, 0.05, 0.35, 1)[0])]
    inertia = [tensor[0][0], tensor[1][1], tensor[2][2], tensor[0][1], tensor[0][2], tensor[1][2]]
    return np.array([float(mass), *com, *(float(m) for m in inertia), *tip]).reshape(INERTIAL + 3, 1)


def _rational_rotation(w: list[Fraction]) -> list[list[Fraction]]:
    """The Cayley transform (I - W)^-1 (I + W) of the skew matrix of w: a rotation with rational
    entries, exactly."""
    x, y, z = w
    d = 1 + x * x + y * y + z * z
    return [[(1 + x * x - y * y - z * z) / d, 2 * (x * y - z) / d, 2 * (x * z + y) / d],
            [2 * (x * y + z) / d, (1 - x * x + y * y - z * z) / d, 2 * (y * z - x) / d],
            [2 * (x * z - y) / d, 2 * (y * z + x) / d, (1 - x * x - y * y + z * z) / d]]


def _exact_sin_cos(values: list[float]) -> list[tuple[float, float]]:
    with mpmath.workdps(DIGITS):
        return [(float(mpmath.sin(mpmath.mpf(v))), float(mpmath.cos(mpmath.mpf(v)))) for v in values]


def _sx(rows):
    """A list of lists (floats or SX scalars) as an SX matrix with its zero floats structural."""
    out = ca.SX(len(rows), len(rows[0]))
    for i, row in enumerate(rows):
        for j, x in enumerate(row):
            if not (isinstance(x, float) and x == 0.0):
                out[i, j] = x
    return out


def _column(v):
    return _sx([[x] for x in v])


def _matvec_list(m, v):
    """m v for a 3 x 3 of floats and a list (skipping exact zeros)."""
    out = []
    for row in m:
        total = 0.0
        for a, b in zip(row, v):
            if a != 0.0:
                total = a * b if isinstance(total, float) and total == 0.0 else total + a * b
        out.append(total)
    return out


class UrdfDerivation:
    """The code and reference graphs of one URDF model (see the module docs)."""

    def __init__(self, model: Model, chain: UrdfChain, tasks: list[Task]):
        self.model, self.chain, self.tasks = model, chain, tasks
        n = self.n = chain.dof
        self.dyn = ChainDynamics(chain, model.urdf_gravity)
        self.stiffness = [float(v) for v in model.impedance_stiffness]
        self.damping = [float(v) for v in model.impedance_damping]
        self.q_e = equilibrium_values(model)
        self.trig_e = _exact_sin_cos(self.q_e)
        self.x_e = np.array(self.q_e + [0.0] * n)
        self.u_e = np.zeros(n)
        self.x = ca.SX.sym("x", 2 * n)
        self.u = ca.SX.sym("u", n)
        self.p = ca.SX.sym("params", len(model.parameters))
        self.k = ca.SX.sym("coefficients", 10 + n)
        self.revolute = [b.kind == "revolute" for b in chain.bodies]
        self._build_code()
        self._build_reference()

    # --- code graphs -------------------------------------------------------------------------

    def _symbolic_trig(self, q):
        return [(ca.sin(q[i]), ca.cos(q[i])) if self.revolute[i] else None for i in range(self.n)]

    def _last(self, p):
        return self.dyn.tool_parameters([p[i] for i in range(INERTIAL)])

    def _tip_offset(self, p):
        return [p[i] for i in range(INERTIAL, INERTIAL + 3)]

    def _gravity_at_equilibrium(self, last):
        return self.dyn.rnea(self.q_e, self.trig_e, [0.0] * self.n, [0.0] * self.n, last)

    def _acceleration(self, x, u, last, offset):
        """q_ddot = M^-1 (U - K q - D q_dot + offset - C q_dot - g): offset = K q^e + g(q^e)."""
        n = self.n
        q, qd = [x[i] for i in range(n)], [x[n + i] for i in range(n)]
        trig = self._symbolic_trig(q)
        mass = self.dyn.mass_matrix(q, trig, last)
        bias = self.dyn.rnea(q, trig, qd, [0.0] * n, last)
        rhs = [u[i] - self.stiffness[i] * q[i] - self.damping[i] * qd[i] + offset[i] - bias[i] for i in range(n)]
        factor = ldl_factor(mass)
        return q, qd, trig, factor, ldl_apply(factor, rhs)

    def _offset(self, last):
        g_e = self._gravity_at_equilibrium(last)
        return [self.stiffness[i] * self.q_e[i] + g_e[i] for i in range(self.n)]

    def _build_code(self):
        n, x, u, p, k = self.n, self.x, self.u, self.p, self.k
        last_k, offset_k = [k[i] for i in range(10)], [k[10 + i] for i in range(n)]
        self.coefficients = ca.Function("coefficients", [p], [ca.vertcat(*self._last(p), *self._offset(self._last(p)))])
        q, qd, trig, factor, acc = self._acceleration(x, u, last_k, offset_k)
        f_with = ca.vertcat(*qd, *acc)
        self.dynamics_with = ca.Function("dynamics_with", [x, u, k], [ca.cse(f_with)])
        # df/dX: M (dq_ddot/dq) = -(K + dID/dq) with ID(q, q_dot, alpha) the inverse dynamics at
        # alpha = q_ddot, likewise for q_dot; df/dU = M^-1 (the same factor for all columns).
        alpha = ca.SX.sym("alpha", n)
        inverse = ca.vertcat(*self.dyn.rnea(q, trig, qd, [alpha[i] for i in range(n)], last_k))
        d_q = ca.substitute(ca.jacobian(inverse, x[:n]), alpha, ca.vertcat(*acc))
        d_qd = ca.substitute(ca.jacobian(inverse, x[n:]), alpha, ca.vertcat(*acc))
        columns = []
        for j in range(n):
            columns.append([-(d_q[i, j] + (self.stiffness[i] if i == j else 0.0)) for i in range(n)])
        for j in range(n):
            columns.append([-(d_qd[i, j] + (self.damping[i] if i == j else 0.0)) for i in range(n)])
        for j in range(n):
            columns.append([1.0 if i == j else 0.0 for i in range(n)])
        solved = [ldl_apply(factor, c) for c in columns]
        f_x = ca.SX(2 * n, 2 * n)
        for i in range(n):
            f_x[i, n + i] = 1.0
        for j in range(2 * n):
            for i in range(n):
                f_x[n + i, j] = solved[j][i]
        f_u = ca.SX(2 * n, n)
        for j in range(n):
            for i in range(n):
                f_u[n + i, j] = solved[2 * n + j][i]
        self.jacobian_with = ca.Function("dynamics_jacobian_with", [x, u, k], [ca.cse(f_x), ca.cse(f_u)])
        # The same with the tool's parameters inline, for the hoisting's before/after count.
        inline = self.coefficients(p)
        self.dynamics_inline = ca.Function("dynamics", [x, u, p], [ca.cse(self.dynamics_with(x, u, inline))])
        self.jacobian_inline = ca.Function("dynamics_jacobian", [x, u, p],
                                           [ca.cse(e) for e in self.jacobian_with(x, u, inline)])
        self._build_rigid_body()
        self._build_linearisation()
        self._build_tip()

    def tip_with(self, q, trig, p):
        """The tip y(q; p) in the base frame and its Jacobian J = dy/dq (3 x n): the joint frames
        composed from the base outwards, then the flange and the tool's tip offset; J's columns are
        geometric, z_i x (y - o_i) for a revolute joint about the axis z_i through o_i, z_i for a
        prismatic one (both in the base frame)."""
        rot, pos = ca.SX.eye(3), ca.SX.zeros(3, 1)
        axes, origins = [], []
        for b, j in zip(self.chain.bodies, self.dyn.joints(q, trig)):
            pos = pos + rot @ _column(j.p)
            r0 = _sx([list(r) for r in b.rotation])
            axes.append(rot @ r0 @ _column(list(b.axis)))
            origins.append(pos)
            cols = [j.to_parent([1.0 if r == k else 0.0 for r in range(3)]) for k in range(3)]
            rot = rot @ ca.horzcat(*[_column(col) for col in cols])
        flange = pos + rot @ _column(list(self.chain.flange_translation))
        y = flange + rot @ _sx([list(r) for r in self.chain.flange_rotation]) @ _column(self._tip_offset(p))
        columns = [ca.cross(z, y - o) if kind else z for z, o, kind in zip(axes, origins, self.revolute)]
        return y, ca.horzcat(*columns)

    def _reference_tip(self, q, trig, p):
        """The same tip by the other composition order: the offset carried from the flange inwards,
        one parent frame at a time, and J by AD of that graph (not the geometric formula)."""
        v = [a + b for a, b in zip(_matvec_list(self.chain.flange_rotation, self._tip_offset(p)),
                                   self.chain.flange_translation)]
        for j in reversed(self.dyn.joints(q, trig)):
            v = [a + b for a, b in zip(j.to_parent(v), j.p)]
        return ca.vertcat(*v)

    def _build_tip(self):
        n, p = self.n, self.p
        q = ca.SX.sym("q", n)
        qs = [q[i] for i in range(n)]
        y, jac = self.tip_with(qs, self._symbolic_trig(qs), p)
        self.tip = ca.Function("tip", [q, p], [ca.cse(y), ca.cse(jac)])
        y_ref = self._reference_tip(qs, self._symbolic_trig(qs), p)
        self.reference_tip = ExactFunction(ca.Function("tip_ref", [q, p], [y_ref, ca.jacobian(y_ref, q)]))
        # Jdot q_dot: the code differentiates the geometric J q_dot along q_dot once (forward mode);
        # the reference differentiates the inward tip twice, never forming J.
        q_dot = ca.SX.sym("q_dot", n)
        self.tip_bias = ca.Function("tip_bias", [q, q_dot, p], [ca.cse(ca.jtimes(jac @ q_dot, q, q_dot))])
        self.reference_tip_bias = ExactFunction(ca.Function(
            "tip_bias_ref", [q, q_dot, p], [ca.jtimes(ca.jtimes(y_ref, q, q_dot), q, q_dot)]))
        # tasks.toml's J on the code side: the geometric Jacobian at q^e, its trigonometry exact.
        self.j_code = _padded(self.tip_with(self.q_e, self.trig_e, p)[1], self.n)

    def _build_rigid_body(self):
        """The robot's own rigid-body dynamics, U the joint torques and no impedance:
        q_ddot = M^-1 (U - C q_dot - g) by CRBA + RNEA bias + LDL^T, its per-tool coefficients
        the last body's ten numbers (toolconf.dynamics; Pinocchio's aba checks it)."""
        n, x, u, p = self.n, self.x, self.u, self.p
        k = ca.SX.sym("coefficients", 10)
        q, qd = [x[i] for i in range(n)], [x[n + i] for i in range(n)]
        trig = self._symbolic_trig(q)
        last = [k[i] for i in range(10)]
        mass = self.dyn.mass_matrix(q, trig, last)
        bias = self.dyn.rnea(q, trig, qd, [0.0] * n, last)
        acc = ldl_apply(ldl_factor(mass), [u[i] - bias[i] for i in range(n)])
        self.rigid_coefficients = ca.Function("rigid_coefficients", [p], [ca.vertcat(*self._last(p))])
        self.rigid_with = ca.Function("rigid_body_dynamics_with", [x, u, k], [ca.cse(ca.vertcat(*qd, *acc))])
        self.rigid_inline = ca.Function("rigid_body_dynamics", [x, u, p],
                                        [ca.cse(self.rigid_with(x, u, self.rigid_coefficients(p)))])

    def _gravity_stiffness(self, last):
        """dg/dq at q^e (a symmetric n x n list), by AD: the graph takes each revolute joint's
        (sin, cos) as symbols, so the chain rule d/dq = cos d/dsin - sin d/dcos evaluates at the
        exact trigonometric numbers and nothing is folded by libm."""
        n = self.n
        s, c, q = ca.SX.sym("s", n), ca.SX.sym("c", n), ca.SX.sym("q", n)
        p_in = ca.SX.sym("last", 10)
        trig = [(s[i], c[i]) if self.revolute[i] else None for i in range(n)]
        g = ca.vertcat(*self.dyn.rnea([q[i] for i in range(n)], trig, [0.0] * n, [0.0] * n,
                                      [p_in[i] for i in range(10)]))
        jac = ca.Function("dg", [s, c, q, p_in], [ca.jacobian(g, s), ca.jacobian(g, c), ca.jacobian(g, q)])
        sin_e = ca.DM([t[0] for t in self.trig_e])
        cos_e = ca.DM([t[1] for t in self.trig_e])
        j_s, j_c, j_q = jac(sin_e, cos_e, ca.DM(self.q_e), ca.vertcat(*last))
        out = [[None] * n for _ in range(n)]
        for i in range(n):
            for j in range(n):
                out[i][j] = (j_s[i, j] * self.trig_e[j][1] - j_c[i, j] * self.trig_e[j][0]) if self.revolute[j] \
                    else j_q[i, j]
        return out

    def _build_linearisation(self):
        """A and B at X^e as SX functions of the tool parameters (structured form)."""
        n, p = self.n, self.p
        last = self._last(p)
        mass = self.dyn.mass_matrix(self.q_e, self.trig_e, last)
        g_q = self._gravity_stiffness(last)
        stiff = [[g_q[i][j] + (self.stiffness[i] if i == j else 0.0) for j in range(n)] for i in range(n)]
        factor = ldl_factor(mass)
        eye = [[1.0 if i == j else 0.0 for i in range(n)] for j in range(n)]
        m_inv = [ldl_apply(factor, col) for col in eye]                       # columns of M^-1
        a21 = [ldl_apply(factor, [-stiff[i][j] for i in range(n)]) for j in range(n)]
        a22 = [ldl_apply(factor, [-(self.damping[i] if i == j else 0.0) for i in range(n)]) for j in range(n)]
        a = ca.SX(2 * n, 2 * n)
        b = ca.SX(2 * n, n)
        for i in range(n):
            a[i, n + i] = 1.0
            for j in range(n):
                a[n + i, j] = a21[j][i]
                a[n + i, n + j] = a22[j][i]
                b[n + i, j] = m_inv[j][i]
        self.a_code, self.b_code = a, b
        # A^-1 = [[-(dg/dq + K)^-1 D, -(dg/dq + K)^-1 M], [I, O]]: the block inverse of A's form.
        s_factor = ldl_factor(stiff)
        top_left = [ldl_apply(s_factor, [-(self.damping[i] if i == j else 0.0) for i in range(n)]) for j in range(n)]
        top_right = [ldl_apply(s_factor, [-mass[i][j] for i in range(n)]) for j in range(n)]
        a_inv = ca.SX(2 * n, 2 * n)
        for i in range(n):
            a_inv[n + i, i] = 1.0
            for j in range(n):
                a_inv[i, j] = top_left[j][i]
                a_inv[i, n + j] = top_right[j][i]
        self.a_inv_code = a_inv
        # M(q^e; p) and dg/dq(q^e; p) themselves, for the formulation study (derive/checks/).
        self.mass_at_equilibrium = ca.Function("mass_e", [p], [_sx(mass)])
        self.gravity_stiffness_at_equilibrium = ca.Function("g_q_e", [p], [_sx(g_q)])
        self.state_matrix = ca.Function("state_matrix", [p], [ca.cse(a)])
        self.input_matrix = ca.Function("input_matrix", [p], [ca.cse(b)])

    def task_namespace_sx(self) -> dict:
        """tasks.toml's names as matrix-level symbols (MatrixAlgebra): the formulas are expanded
        and A A^-1 cancelled before any SX is built, as SymPy's closed forms cancel them for the
        planar arms. Task 3's [I O](A^2 A^-1 (E - B) + AB) is then [I O] A E = I exactly, not a
        sum that rounds to 1e-12 of zero."""
        n = self.n
        eye, zero = ca.SX.eye(n), ca.SX(n, n)
        values = {"A": self.a_code, "B": self.b_code, "inv(A)": self.a_inv_code, "I": eye, "O": zero,
                  "IO": ca.horzcat(eye, zero), "OI": ca.horzcat(zero, eye), "E": ca.vertcat(eye, eye),
                  "J": self.j_code}
        ns = {name: MatrixAlgebra.symbol(name, values) for name in ("A", "B", "I", "O", "IO", "OI", "E", "J")}
        ns["inv"] = MatrixAlgebra.inverse
        ns["dX_dU"] = MatrixAlgebra.inverse(ns["A"]) @ (ns["E"] - ns["B"])
        return ns

    # --- reference graphs --------------------------------------------------------------------

    def _reference_f(self, x, u, p, trig):
        n = self.n
        last = self._last(p)
        q, qd = [x[i] for i in range(n)], [x[n + i] for i in range(n)]
        g_e = self._gravity_potential(last)
        tau = [u[i] + self.stiffness[i] * (self.q_e[i] - q[i]) - self.damping[i] * qd[i] + g_e[i] for i in range(n)]
        return ca.vertcat(*qd, *aba(self.dyn, q, trig, qd, tau, last))

    def _gravity_potential(self, last):
        """g(q^e) = dV/dq, V = -sum m_i gravity . c_i(q) from the forward kinematics of the
        bodies' centres of mass: a third route to the gravity torque (RNEA's is the code's)."""
        n = self.n
        s, c, q = ca.SX.sym("s", n), ca.SX.sym("c", n), ca.SX.sym("q", n)
        p_in = ca.SX.sym("last", 10)
        joints = self.dyn.joints([q[i] for i in range(n)], [(s[i], c[i]) if self.revolute[i] else None
                                                              for i in range(n)])
        rot = ca.SX.eye(3)
        pos = ca.SX.zeros(3, 1)
        potential = 0
        for i, j in enumerate(joints):
            pos = pos + rot @ _column(j.p)
            cols = [j.to_parent([1.0 if r == k else 0.0 for r in range(3)]) for k in range(3)]
            rot = rot @ ca.horzcat(*[_column(col) for col in cols])
            params = [p_in[r] for r in range(10)] if i == n - 1 else self.dyn.link_parameters(i)
            m, h = params[0], _column(params[1:4])
            # m * (pos + R c) with h = m c.
            potential = potential - ca.dot(_column(self.dyn.gravity), m * pos + rot @ h)
        grad = ca.Function("dv", [s, c, q, p_in], [ca.gradient(potential, s), ca.gradient(potential, c),
                                                   ca.gradient(potential, q)])
        sin_e = ca.DM([t[0] for t in self.trig_e])
        cos_e = ca.DM([t[1] for t in self.trig_e])
        g_s, g_c, g_q = grad(sin_e, cos_e, ca.DM(self.q_e), ca.vertcat(*last))
        return [(g_s[i] * self.trig_e[i][1] - g_c[i] * self.trig_e[i][0]) if self.revolute[i] else g_q[i]
                for i in range(n)]

    def _build_reference(self):
        n, x, u, p = self.n, self.x, self.u, self.p
        f = self._reference_f(x, u, p, self._symbolic_trig([x[i] for i in range(n)]))
        self.reference_dynamics = ExactFunction(ca.Function("dynamics_ref", [x, u, p], [f]))
        q, qd = [x[i] for i in range(n)], [x[n + i] for i in range(n)]
        rigid = ca.vertcat(*qd, *aba(self.dyn, q, self._symbolic_trig(q), qd, [u[i] for i in range(n)],
                                     self._last(p)))
        self.reference_rigid_body = ExactFunction(ca.Function("rigid_body_dynamics_ref", [x, u, p], [rigid]))
        self.reference_jacobian = ExactFunction(ca.Function(
            "dynamics_jacobian_ref", [x, u, p], [ca.jacobian(f, x), ca.jacobian(f, u)]))
        # A, B at X^e by AD of the ABA graph, as a function of p alone: (sin, cos) symbols and
        # the chain rule, evaluated at the exact trigonometric numbers of q^e.
        s, c, q, qd = ca.SX.sym("s", n), ca.SX.sym("c", n), ca.SX.sym("q", n), ca.SX.sym("qd", n)
        trig = [(s[i], c[i]) if self.revolute[i] else None for i in range(n)]
        f_sc = self._reference_f(ca.vertcat(q, qd), u, p, trig)
        jac = ca.Function("ab", [s, c, q, qd, u, p],
                          [ca.jacobian(f_sc, s), ca.jacobian(f_sc, c), ca.jacobian(f_sc, q), ca.jacobian(f_sc, qd),
                           ca.jacobian(f_sc, u)])
        sin_e = ca.DM([t[0] for t in self.trig_e])
        cos_e = ca.DM([t[1] for t in self.trig_e])
        j_s, j_c, j_q, j_qd, j_u = jac(sin_e, cos_e, ca.DM(self.q_e), ca.DM.zeros(n), ca.DM.zeros(n), p)
        a = ca.SX(2 * n, 2 * n)
        for i in range(2 * n):
            for j in range(n):
                a[i, j] = (j_s[i, j] * self.trig_e[j][1] - j_c[i, j] * self.trig_e[j][0] + j_q[i, j]) \
                    if self.revolute[j] else j_q[i, j]
                a[i, n + j] = j_qd[i, j]
        self.reference_ab = ExactFunction(ca.Function("ab_ref", [p], [a, j_u]))

    # --- reference values at a sample ---------------------------------------------------------

    def reference_namespace(self, p) -> dict:
        a, b = self.reference_ab.checked(p)
        jacobian = self.reference_tip.checked(self.q_e, p)[1]
        return exact_namespace(a, b, jacobian, self.n)

    def reference_sensitivity(self, task: Task, p) -> dict:
        ns = self.reference_namespace(p)
        return {t: sensitivity(task, t, ns) for t in task.sensitivity_terms}

    def reference_confidence(self, task: Task, p, precision: dict) -> Exact:
        s = self.reference_sensitivity(task, p)
        pi = Exact.of(precision[task.control_term])
        for t in task.sensitivity_terms:
            pi = pi + s[t].T @ Exact.of(precision[t]) @ s[t]
        return pi

    def reference_gradient(self, task: Task, p, precision: dict) -> Exact:
        """d ln det Pi^U / dp_i by forward differences in 50 digits: with the step GRADIENT_STEP
        (relative) the truncation error is ~1e-20 relative, far below any tolerance here, at 8
        evaluations of the reference A, B instead of central differences' 15."""
        def logdet(params):
            with mpmath.workdps(DIGITS):
                a, b = self.reference_ab.exact_at([params])
                jacobian = self.reference_tip.exact_at([[mpmath.mpf(v) for v in self.q_e], params])[1]
                ns = exact_namespace(a, b, jacobian, self.n)
                s = {t: sensitivity(task, t, ns) for t in task.sensitivity_terms}
                pi = Exact.of(precision[task.control_term])
                for t in task.sensitivity_terms:
                    pi = pi + s[t].T @ Exact.of(precision[t]) @ s[t]
                return mpmath.log(mpmath.det(pi.m))
        with mpmath.workdps(DIGITS):
            base = [mpmath.mpf(float(v)) for v in np.asarray(p).reshape(-1)]
            at_base = logdet(base)
            out = []
            for i in range(len(base)):
                up = list(base)
                h = GRADIENT_STEP * max(abs(base[i]), mpmath.mpf(1))
                up[i] += h
                out.append([(logdet(up) - at_base) / h])
            return Exact(mpmath.matrix(out))


class MatrixAlgebra:
    """A sum of products of named matrices, {(factor, ...): coefficient}: `@` distributes and
    cancels A inv(A), `I` drops out of products, `O` zeroes them; `sx()` builds the SX."""

    def __init__(self, terms: dict, values: dict):
        self.terms = {k: v for k, v in terms.items() if v != 0}
        self.values = values

    @classmethod
    def symbol(cls, name: str, values: dict) -> "MatrixAlgebra":
        return cls({(name,): 1}, values)

    @staticmethod
    def _reduce(factors: tuple) -> tuple | None:
        if "O" in factors:
            return None
        out: list = []
        for f in factors:
            if f == "I" and (out or len(factors) > 1):
                continue
            if out and {out[-1], f} == {"A", "inv(A)"}:
                out.pop()
                continue
            out.append(f)
        return tuple(out) if out else ("I",)

    def __matmul__(self, other: "MatrixAlgebra") -> "MatrixAlgebra":
        terms: dict = {}
        for a, ca_ in self.terms.items():
            for b, cb in other.terms.items():
                key = self._reduce(a + b)
                if key is not None:
                    terms[key] = terms.get(key, 0) + ca_ * cb
        return MatrixAlgebra(terms, self.values)

    def __add__(self, other: "MatrixAlgebra") -> "MatrixAlgebra":
        terms = dict(self.terms)
        for k, v in other.terms.items():
            terms[k] = terms.get(k, 0) + v
        return MatrixAlgebra(terms, self.values)

    def __neg__(self) -> "MatrixAlgebra":
        return MatrixAlgebra({k: -v for k, v in self.terms.items()}, self.values)

    def __sub__(self, other: "MatrixAlgebra") -> "MatrixAlgebra":
        return self + (-other)

    @staticmethod
    def inverse(m: "MatrixAlgebra") -> "MatrixAlgebra":
        if list(m.terms) == [("A",)] and m.terms[("A",)] == 1:
            return MatrixAlgebra({("inv(A)",): 1}, m.values)
        raise ValueError("inv() of anything but A has no block form here")

    def sx(self):
        total = None
        for factors, coefficient in self.terms.items():
            product = self.values[factors[0]]
            for f in factors[1:]:
                product = product @ self.values[f]
            term = product if coefficient == 1 else coefficient * product
            total = term if total is None else total + term
        return total


def equilibrium_values(model: Model) -> list[float]:
    """q^e as the doubles nearest the description's values (pi, sqrt... allowed): the same double
    the runtime's EQUILIBRIUM_STATE holds, whose sine and cosine the derivation takes exactly."""
    with mpmath.workdps(DIGITS):
        return [float(mpmath.mpf(sp.N(parse(model, v, {}, f"equilibrium.q[{i}]"), 40)))
                for i, v in enumerate(model.equilibrium_q)]


def exact_namespace(a: Exact, b: Exact, tip_jacobian: Exact, n: int) -> dict:
    """The names of tasks.toml's formulas over exact A and B (the general inverse) and the tip's
    3 x n Jacobian at q^e (J: padded to n x n with zero rows)."""
    eye, zero = Exact(mpmath.eye(n)), Exact(mpmath.zeros(n, n))
    e = Exact.vstack(eye, eye)
    with mpmath.workdps(DIGITS):
        rows = tip_jacobian.m.rows
        j = Exact(mpmath.matrix([[tip_jacobian.m[i, k] if i < rows else mpmath.mpf(0) for k in range(n)]
                                 for i in range(n)]))
    return {"A": a, "B": b, "inv": Exact.inv, "I": eye, "O": zero, "IO": Exact.hstack(eye, zero),
            "OI": Exact.hstack(zero, eye), "E": e, "dX_dU": Exact.inv(a) @ (e - b), "J": j}


def _padded(jacobian, n: int):
    """A 3 x n SX Jacobian as tasks.toml's J: n x n, the rows below the third structurally zero."""
    out = ca.SX(n, n)
    for i in range(jacobian.size1()):
        for k in range(n):
            out[i, k] = jacobian[i, k]
    return out
