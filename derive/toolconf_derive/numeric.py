"""The independent numerical side (CasADi): the same model built from the description's strings
with CasADi's own symbols, differentiated by algorithmic differentiation, and the task formulas
evaluated on the resulting numeric A and B.

SymPy never touches these values: they are what the symbolic closed forms (and, through the test
vectors, the generated Rust) are checked against.

The task algebra (inverses, products of A and B) runs in 50-digit arithmetic (mpmath) on
CasADi's double-precision A and B. Some task formulas cancel exactly, e.g. task 3's
[I O](A^2 A^-1 (E - B) + AB) = I for every arm, and evaluating them in double precision would
leave rounding of order |A||B| eps (up to ~1e-11 for light arms) in the *reference*; in 50 digits
the reference is exact to far below the tests' 1e-12 tolerance.
"""

from __future__ import annotations

import math

import casadi as ca
import mpmath
import numpy as np

from .chain import casadi_chain
from .description import Model, Task


class CasadiModel:
    def __init__(self, model: Model):
        self.model = model
        n = model.dof
        self.x = ca.SX.sym("x", 2 * n)
        self.u = ca.SX.sym("u", n)
        self.p = ca.SX.sym("p", len(model.parameters))
        names = {}
        for i, s in enumerate(model.q + model.q_dot):
            names[s.name] = self.x[i]
        for i, s in enumerate(model.u):
            names[s.name] = self.u[i]
        for i, s in enumerate(model.parameters):
            names[s.name] = self.p[i]
        for c in model.constants:
            names[c.name] = c.value
        functions = {"sin": ca.sin, "cos": ca.cos, "sqrt": ca.sqrt, "pi": math.pi}
        if model.dynamics_kind == "planar_chain":
            q_ddot = casadi_chain(
                [names[c.name] for c in model.q], [names[c.name] for c in model.q_dot], [names[c.name] for c in model.u],
                [names[link["mass"]] for link in model.links], [names[link["length"]] for link in model.links],
                names[model.gravity],
            )
        else:
            q_ddot = [eval(e, {"__builtins__": {}, **functions}, names) for e in model.q_ddot]  # noqa: S307
        f = ca.vertcat(self.x[n:], *q_ddot)
        self.dynamics = ca.Function("dynamics", [self.x, self.u, self.p], [f])
        self.jacobian = ca.Function(
            "dynamics_jacobian", [self.x, self.u, self.p], [ca.jacobian(f, self.x), ca.jacobian(f, self.u)]
        )
        plain = {"__builtins__": {}, "pi": math.pi}
        self.x_e = np.array([float(eval(v, plain)) for v in model.equilibrium_q + model.equilibrium_q_dot])  # noqa: S307
        self.u_e = np.array([float(eval(v, plain)) for v in model.equilibrium_u])  # noqa: S307

    def linearisation(self, p: np.ndarray) -> tuple[ca.DM, ca.DM]:
        a, b = self.jacobian(self.x_e, self.u_e, p)
        return a, b

    def task_namespace(self, p: np.ndarray) -> dict:
        n = self.model.dof
        a, b = (Exact.of(np.array(m, dtype=float)) for m in self.linearisation(p))
        eye, zero = Exact(mpmath.eye(n)), Exact(mpmath.zeros(n, n))
        e = Exact.vstack(eye, eye)
        return {
            "A": a, "B": b, "inv": Exact.inv, "I": eye, "O": zero,
            "IO": Exact.hstack(eye, zero), "OI": Exact.hstack(zero, eye),
            "E": e, "dX_dU": Exact.inv(a) @ (e - b),
        }

    def sensitivity_exact(self, task: Task, p: np.ndarray) -> dict[str, "Exact"]:
        ns = self.task_namespace(p)
        return {term: eval(task.sensitivity[term], {"__builtins__": {}}, dict(ns))  # noqa: S307
                for term in task.sensitivity_terms}

    def sensitivity(self, task: Task, p: np.ndarray) -> dict[str, np.ndarray]:
        return {term: s.to_numpy() for term, s in self.sensitivity_exact(task, p).items()}

    def control_confidence(self, task: Task, p: np.ndarray, precision: dict[str, np.ndarray]) -> np.ndarray:
        """Pi^U = sum over the task's terms of S^T P S, plus P^U (eq. control_conf and the closed forms after it)."""
        s = self.sensitivity_exact(task, p)
        pi = Exact.of(precision["u"])
        for term in task.sensitivity_terms:
            pi = pi + s[term].T @ Exact.of(precision[term]) @ s[term]
        return pi.to_numpy()


class Exact:
    """A matrix in 50-digit arithmetic with the operators the task formulas use."""

    DIGITS = 50

    def __init__(self, m: mpmath.matrix):
        self.m = m

    @classmethod
    def of(cls, a: np.ndarray) -> "Exact":
        with mpmath.workdps(cls.DIGITS):
            return cls(mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in np.atleast_2d(a)]))

    @staticmethod
    def inv(a: "Exact") -> "Exact":
        with mpmath.workdps(Exact.DIGITS):
            return Exact(mpmath.inverse(a.m))

    @staticmethod
    def hstack(a: "Exact", b: "Exact") -> "Exact":
        rows = [[a.m[i, j] for j in range(a.m.cols)] + [b.m[i, j] for j in range(b.m.cols)] for i in range(a.m.rows)]
        return Exact(mpmath.matrix(rows))

    @staticmethod
    def vstack(a: "Exact", b: "Exact") -> "Exact":
        rows = [[m.m[i, j] for j in range(m.m.cols)] for m in (a, b) for i in range(m.m.rows)]
        return Exact(mpmath.matrix(rows))

    def _op(self, f):
        with mpmath.workdps(self.DIGITS):
            return Exact(f())

    def __matmul__(self, o: "Exact") -> "Exact":
        return self._op(lambda: self.m * o.m)

    def __add__(self, o: "Exact") -> "Exact":
        return self._op(lambda: self.m + o.m)

    def __sub__(self, o: "Exact") -> "Exact":
        return self._op(lambda: self.m - o.m)

    def __neg__(self) -> "Exact":
        return self._op(lambda: -self.m)

    @property
    def T(self) -> "Exact":  # noqa: N802 - matches the matrix notation of the formulas
        return Exact(self.m.T)

    def to_numpy(self) -> np.ndarray:
        return np.array([[float(self.m[i, j]) for j in range(self.m.cols)] for i in range(self.m.rows)])
