"""The independent numerical side (CasADi): the same model built from the description's strings
with CasADi's own symbols, differentiated by algorithmic differentiation, and the task formulas
evaluated on the resulting A and B.

SymPy never touches these values: they are what the symbolic closed forms (and, through the test
vectors, the generated Rust) are checked against.

CasADi's expression graphs are evaluated exactly (50 digits, `exact.ExactFunction`), so the
values written to the test vectors do not depend on the CPU's libm kernels; and the task algebra
(inverses, products of A and B) stays in 50 digits too. Some task formulas cancel exactly, e.g.
task 3's [I O](A^2 A^-1 (E - B) + AB) = I for every arm, and evaluating them in double precision
would leave rounding of order |A||B| eps (up to ~1e-11 for light arms) in the *reference*; in 50
digits the reference is exact to far below the tests' 1e-12 tolerance.
"""

from __future__ import annotations

import math

import casadi as ca
import mpmath
import numpy as np

from .planar_chain import casadi_chain
from .planar_chain import tip as casadi_tip
from .description import Model, Task, expression, sensitivity, value
from .exact import DIGITS, Exact, ExactFunction
from .expression import python_number


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
        functions = {"sin": ca.sin, "cos": ca.cos, "sqrt": ca.sqrt}
        if model.dynamics_kind == "planar_chain":
            q_ddot = casadi_chain(
                [names[c.name] for c in model.q], [names[c.name] for c in model.q_dot], [names[c.name] for c in model.u],
                [names[link["mass"]] for link in model.links], [names[link["length"]] for link in model.links],
                names[model.gravity], names[model.payload] if model.payload else None,
            )
        else:
            q_ddot = [expression(model.path, f"dynamics.q_ddot[{i}]", e, names).evaluate(
                {**names, "pi": math.pi}, functions, python_number) for i, e in enumerate(model.q_ddot)]
        f = ca.vertcat(self.x[n:], *q_ddot)
        self.dynamics = ExactFunction(ca.Function("dynamics", [self.x, self.u, self.p], [f]))
        self.jacobian = ExactFunction(ca.Function(
            "dynamics_jacobian", [self.x, self.u, self.p], [ca.jacobian(f, self.x), ca.jacobian(f, self.u)]
        ))
        self.tip = self._tip(names, functions)
        self.tip_bias = self._tip_bias()

        def values(label: str, texts: list[str]) -> list[float]:
            return [value(model.path, f"equilibrium.{label}[{i}]", v) for i, v in enumerate(texts)]
        self.x_e = np.array(values("q", model.equilibrium_q) + values("q_dot", model.equilibrium_q_dot))
        self.u_e = np.array(values("u", model.equilibrium_u))

    def _tip(self, names: dict, functions: dict) -> ExactFunction:
        """The tip y(q; p) from the description's strings (a planar chain's free end, or `[tip]
        position`, which every explicit model has) with CasADi's symbols, and dy/dq by algorithmic
        differentiation."""
        model, n = self.model, self.model.dof
        q = self.x[:n]
        if model.dynamics_kind == "planar_chain":
            lengths = [names[link["length"]] for link in model.links]
            x, y = casadi_tip([names[c.name] for c in model.q], lengths, ca.sin, ca.cos)
            y_tip = ca.vertcat(x, y, 0)
        else:
            y_tip = ca.vertcat(*[expression(model.path, f"tip.position[{i}]", e, names).evaluate(
                {**names, "pi": math.pi}, functions, python_number) for i, e in enumerate(model.tip)])
        q_sym = ca.SX.sym("q", n)
        y_q = ca.substitute(y_tip, q, q_sym)
        return ExactFunction(ca.Function("tip", [q_sym, self.p], [y_q, ca.jacobian(y_q, q_sym)]))

    def _tip_bias(self) -> ExactFunction:
        """Jdot(q, q_dot) q_dot as the second directional derivative of y along q_dot, by CasADi's
        forward mode twice (no Jacobian matrix formed, unlike the symbolic d(J q_dot)/dq q_dot)."""
        n = self.model.dof
        q, q_dot = ca.SX.sym("q", n), ca.SX.sym("q_dot", n)
        y = self.tip.f(q, self.p)[0]
        bias = ca.jtimes(ca.jtimes(y, q, q_dot), q, q_dot)
        return ExactFunction(ca.Function("tip_bias", [q, q_dot, self.p], [bias]))

    def linearisation(self, p: np.ndarray) -> tuple[Exact, Exact]:
        """A and B at the equilibrium, exactly (the equilibrium is taken as its doubles)."""
        a, b = self.jacobian.checked(self.x_e, self.u_e, p)
        return a, b

    def tip_jacobian(self, p: np.ndarray) -> Exact:
        """tasks.toml's J, exactly: CasADi's AD Jacobian of the tip at q^e (taken as its doubles),
        its first TIP_DIM rows, and zero rows below them up to n."""
        n, k = self.model.dof, self.model.tip_dim
        jacobian = self.tip.checked(self.x_e[:n], p)[1]
        with mpmath.workdps(DIGITS):
            return Exact(mpmath.matrix([[jacobian.m[i, j] if i < k else mpmath.mpf(0) for j in range(n)]
                                        for i in range(n)]))

    def task_namespace(self, p: np.ndarray) -> dict:
        n = self.model.dof
        a, b = self.linearisation(p)
        eye, zero = Exact(mpmath.eye(n)), Exact(mpmath.zeros(n, n))
        e = Exact.vstack(eye, eye)
        return {
            "A": a, "B": b, "inv": Exact.inv, "I": eye, "O": zero,
            "IO": Exact.hstack(eye, zero), "OI": Exact.hstack(zero, eye),
            "E": e, "dX_dU": Exact.inv(a) @ (e - b), "J": self.tip_jacobian(p),
        }

    def sensitivity_exact(self, task: Task, p: np.ndarray) -> dict[str, "Exact"]:
        ns = self.task_namespace(p)
        return {term: sensitivity(task, term, ns) for term in task.sensitivity_terms}

    def control_confidence(self, task: Task, p: np.ndarray, precision: dict[str, np.ndarray]) -> Exact:
        """Pi^U = sum over the task's terms of S^T P S, plus P^U (eq. control_conf and the closed forms after it)."""
        s = self.sensitivity_exact(task, p)
        pi = Exact.of(precision[task.control_term])
        for term in task.sensitivity_terms:
            pi = pi + s[term].T @ Exact.of(precision[term]) @ s[term]
        return pi

    def logdet_gradient(self, task: Task) -> ExactFunction:
        """d ln|Pi^U| / dp by CasADi's algorithmic differentiation of ln(det(Pi^U)), Pi^U built
        symbolically in CasADi from its own A(p), B(p) (the AD Jacobian at the equilibrium) and the
        task formulas, with the precisions as inputs (in the order the task's terms, then u).
        Nothing here comes from SymPy: it is what the closed form (Jacobi's formula) is checked
        against. Cached per task, since building the graph is the slow part."""
        cache = self.__dict__.setdefault("_gradient_cache", {})
        if task.name in cache:
            return cache[task.name]
        n = self.model.dof
        a, b = self.jacobian.f(ca.DM(self.x_e), ca.DM(self.u_e), self.p)
        eye, zero = ca.SX.eye(n), ca.SX.zeros(n, n)
        e = ca.vertcat(eye, eye)
        jacobian = self.tip.f(ca.DM(self.x_e[:n]), self.p)[1]
        j = ca.vertcat(jacobian[:self.model.tip_dim, :], ca.SX.zeros(n - self.model.tip_dim, n))
        ns = {
            "A": a, "B": b, "inv": ca.inv_minor, "I": eye, "O": zero,
            "IO": ca.horzcat(eye, zero), "OI": ca.horzcat(zero, eye),
            "E": e, "dX_dU": ca.inv_minor(a) @ (e - b), "J": j,
        }
        precisions = {t: ca.SX.sym(f"p_{t}", n, n) for t in task.precision_terms}
        pi = precisions[task.control_term]
        for term in task.sensitivity_terms:
            s = sensitivity(task, term, ns)
            pi = pi + s.T @ precisions[term] @ s
        gradient = ca.gradient(ca.log(ca.det(pi)), self.p)
        inputs = [self.p] + [precisions[t] for t in task.precision_terms]
        cache[task.name] = ExactFunction(ca.Function(f"{task.name}_logdet_gradient", inputs, [gradient]))
        return cache[task.name]
