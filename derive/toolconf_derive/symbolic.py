"""The symbolic derivation (SymPy): f(X, U; p), its Jacobians, the linearisation at the
equilibrium, the task sensitivities and the control confidence Pi^U.

Everything here is derived from the model description's equations of motion; the paper's printed
matrices are only read in paper.py, for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .planar_chain import sympy_chain
from .planar_chain import tip as planar_tip
from .description import Model, Task, model_tasks, sensitivity, task_formula
from . import progress
from .errors import DescriptionError
from .expression import ExpressionError, sympy_expression


def tidy(e: sp.Expr) -> sp.Expr:
    """A canonical, readable form of a rational expression in the parameters."""
    return sp.factor(sp.cancel(sp.together(e)))


def tidy_matrix(m: sp.Matrix) -> sp.Matrix:
    return m.applyfunc(tidy)


def parse(model: Model, text: str, symbols: dict[str, sp.Symbol], key: str, rational: bool = True) -> sp.Expr:
    """`text` as a SymPy expression over `symbols`, sin, cos, sqrt and pi, built from the grammar's
    tree (expression.py: a description is data, never code); anything else, or a result that is
    not finite (x/(l - l)), is an error naming the description's `key`."""
    try:
        e = sympy_expression(text, symbols, rational)
    except ExpressionError as err:
        raise DescriptionError(model.path, key, f"{err} in '{text}'") from err
    except (TypeError, ValueError, ArithmeticError) as err:  # SymPy refusing what the grammar let through
        raise DescriptionError(model.path, key, f"cannot build '{text}': {err}") from err
    if e.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
        raise DescriptionError(model.path, key, f"'{text}' is not finite ({e})")
    return e


def symmetric_matrix(name: str, n: int) -> tuple[sp.Matrix, list[tuple[sp.Symbol, int, int]]]:
    """An n x n symmetric matrix of symbols name_ij (i <= j) and the (symbol, i, j) it reads."""
    entries = {}
    reads = []
    for i in range(n):
        for j in range(i, n):
            s = sp.Symbol(f"{name}_{i}{j}", real=True)
            entries[(i, j)] = entries[(j, i)] = s
            reads.append((s, i, j))
    return sp.Matrix(n, n, lambda i, j: entries[(i, j)]), reads


def task_namespace(a: sp.Matrix, b: sp.Matrix, j: sp.Matrix, n: int, inv) -> dict:
    """The names the task formulas in tasks.toml may use (see that file's header); `j` is J, the
    padded n x n tip Jacobian at the equilibrium (padded_jacobian)."""
    eye, zero = sp.eye(n), sp.zeros(n, n)
    e = sp.Matrix.vstack(eye, eye)
    a_inv = inv(a)
    return {
        "A": a, "B": b, "inv": inv, "I": eye, "O": zero,
        "IO": sp.Matrix.hstack(eye, zero), "OI": sp.Matrix.hstack(zero, eye),
        "E": e, "dX_dU": a_inv @ (e - b), "J": j,
    }


def padded_jacobian(jacobian: sp.Matrix, at_q: dict, tip_dim: int, n: int) -> sp.Matrix:
    """tasks.toml's J: the first `tip_dim` rows of the tip's Jacobian dy/dq at the equilibrium
    (`at_q`, q -> q^e), in closed form in the parameters, and zero rows below them up to n."""
    rows = tidy_matrix(jacobian[:tip_dim, :].subs(at_q))
    return sp.Matrix.vstack(rows, sp.zeros(n - tip_dim, n)) if tip_dim < n else rows


@dataclass
class TaskDerivation:
    task: Task
    sensitivity: dict[str, sp.Matrix]      # term -> n x n, tidy closed form
    precision: dict[str, sp.Matrix]        # term -> symmetric symbol matrix (incl. 'u')
    precision_reads: dict[str, list]       # term -> [(symbol, i, j)]
    confidence: sp.Matrix                  # Pi^U, n x n, composed (not expanded)
    remarks: list[dict]
    # d ln|Pi^U| / dp, k x 1: tr(adj(Pi^U) dPi^U/dp_i) / |Pi^U| (Jacobi's formula), composed.
    logdet_gradient: sp.Matrix | None = None


@dataclass
class Derivation:
    model: Model
    params: list[sp.Symbol]
    constants: dict[sp.Symbol, float]
    q: list[sp.Symbol]
    q_dot: list[sp.Symbol]
    u: list[sp.Symbol]
    q_ddot: sp.Matrix          # the equations of motion as parsed
    f: sp.Matrix               # X_dot = f(X, U; p)
    f_x: sp.Matrix             # df/dX, anywhere
    f_u: sp.Matrix             # df/dU, anywhere
    x_e: sp.Matrix
    u_e: sp.Matrix
    a: sp.Matrix               # df/dX at the equilibrium (tidy)
    b: sp.Matrix               # df/dU at the equilibrium (tidy)
    tasks: list[TaskDerivation]
    # T, V, M(q) and Q of a Lagrangian model (None for explicit equations of motion).
    lagrangian: dict | None = None
    # The tip y(q; p) (3 x 1, base frame) and its Jacobian dy/dq (3 x n): every model has one.
    tip: sp.Matrix | None = None
    tip_jacobian: sp.Matrix | None = None
    # Jdot(q, q_dot) q_dot (3 x 1): the tip's acceleration at q_ddot = 0, d(J q_dot)/dq q_dot.
    tip_bias: sp.Matrix | None = None

    @property
    def x(self) -> list[sp.Symbol]:
        return self.q + self.q_dot

    @property
    def symbol_latex(self) -> dict[sp.Symbol, str]:
        m = self.model
        named = m.parameters + m.constants + m.q + m.q_dot + m.u
        syms = self.params + list(self.constants) + self.q + self.q_dot + self.u
        table = {s: n.latex for s, n in zip(syms, named)}
        for t in self.tasks:
            for term, reads in t.precision_reads.items():
                for s, i, j in reads:
                    table[s] = rf"P^{{{t.task.term(term).latex}}}_{{{i + 1}{j + 1}}}"
        return table


def derive(model: Model, tasks: list[Task]) -> Derivation:
    real = {"real": True}
    # Parameters are positive (masses, lengths), which lets SymPy simplify freely; all else is real.
    params = [sp.Symbol(p.name, positive=True) for p in model.parameters]
    consts = {sp.Symbol(c.name, **real): c.value for c in model.constants}
    q = [sp.Symbol(c.name, **real) for c in model.q]
    q_dot = [sp.Symbol(c.name, **real) for c in model.q_dot]
    u = [sp.Symbol(c.name, **real) for c in model.u]
    symbols = {str(s): s for s in params + list(consts) + q + q_dot + u}

    lagrangian = None
    if model.dynamics_kind == "planar_chain":
        masses = [symbols[link["mass"]] for link in model.links]
        lengths = [symbols[link["length"]] for link in model.links]
        payload = symbols[model.payload] if model.payload else None
        q_ddot, kinetic, potential, mass, forces = sympy_chain(q, q_dot, u, masses, lengths, symbols[model.gravity],
                                                               payload)
        lagrangian = {"T": kinetic, "V": potential, "M": mass, "Q": forces}
    else:
        q_ddot = sp.Matrix([parse(model, e, symbols, f"dynamics.q_ddot[{i}]") for i, e in enumerate(model.q_ddot)])

    x = q + q_dot
    f = sp.Matrix.vstack(sp.Matrix(q_dot), q_ddot)
    f_x = f.jacobian(x)
    f_u = f.jacobian(u)

    x_e, u_e = equilibrium(model)
    at_e = dict(zip(x, x_e)) | dict(zip(u, u_e))
    residual = tidy_matrix(f.subs(at_e))
    if any(r.has(sp.zoo, sp.nan, sp.oo, -sp.oo) for r in residual):
        raise DescriptionError(model.path, "equilibrium", f"f(X^e, U^e) = {list(residual)} is not finite there")
    if any(r != 0 for r in residual):
        names = [c.name for c in model.q_dot] + [f"{c.name}_ddot" for c in model.q]
        nonzero = ", ".join(f"{names[i]} = {r}" for i, r in enumerate(residual) if r != 0)
        raise DescriptionError(model.path, "equilibrium",
                               f"not an equilibrium: f(X^e, U^e) = {list(residual)} is not zero ({nonzero}): "
                               "the forces (gravity among them) are not balanced at q^e with U^e; choose q^e where "
                               "they are, or U^e that feeds them forward")

    progress.step("deriving", "equations of motion")
    a = tidy_matrix(f_x.subs(at_e))
    b = tidy_matrix(f_u.subs(at_e))
    if any(e.has(sp.zoo, sp.nan, sp.oo, -sp.oo) for e in list(a) + list(b)):
        raise DescriptionError(model.path, "equilibrium", "A or B is not finite there (a division by zero in "
                                                          "the derivatives at the equilibrium)")
    if a.det() == 0:
        raise DescriptionError(model.path, "equilibrium", "A is singular there; the task sensitivities need A^-1")
    tasks = model_tasks(model, tasks)
    tip = derive_tip(model, symbols, q, params)
    tip_jacobian = tidy_matrix(tip.jacobian(q))
    tip_bias = tidy_matrix((tip_jacobian * sp.Matrix(q_dot)).jacobian(q) * sp.Matrix(q_dot))
    j = padded_jacobian(tip_jacobian, dict(zip(q, x_e[:model.dof])), model.tip_dim, model.dof)
    ns = task_namespace(a, b, j, model.dof, lambda m: tidy_matrix(m.inv()))
    progress.step("deriving", "linearisation, tip and task namespace")
    derived_tasks = [derive_task(task, ns, model.dof) for task in tasks]
    progress.step("deriving", f"tasks' sensitivities and control confidence ({len(tasks)} tasks)")
    for t in derived_tasks:
        t.logdet_gradient = logdet_gradient(t.confidence, params)
        progress.step("deriving", f"{t.task.name}: d ln|Pi^U| / dp")
    return Derivation(model, params, consts, q, q_dot, u, q_ddot, f, f_x, f_u, x_e, u_e, a, b, derived_tasks, lagrangian,
                      tip, tip_jacobian, tip_bias)


def derive_tip(model: Model, symbols: dict, q: list, params: list) -> sp.Matrix:
    """The tip in the base frame: a planar chain's free end (x, y, 0), or an explicit model's
    `[tip] position` (which every explicit model has: the reader requires it), which may use the
    joint positions, the parameters and the constants."""
    if model.dynamics_kind == "planar_chain":
        lengths = [symbols[link["length"]] for link in model.links]
        x, y = planar_tip(q, lengths, sp.sin, sp.cos)
        return sp.Matrix([x, y, 0])
    allowed = set(q) | set(params) | {s for s in symbols.values() if str(s) in {c.name for c in model.constants}}
    entries = []
    for i, text in enumerate(model.tip):
        key = f"tip.position[{i}]"
        e = parse(model, text, symbols, key)
        extra = sorted(str(s) for s in e.free_symbols - allowed)
        if extra:
            raise DescriptionError(model.path, key, f"'{text}' uses {', '.join(extra)}: the tip depends on the joint "
                                                    "positions, the parameters and the constants only")
        entries.append(e)
    return sp.Matrix(entries)


def equilibrium(model: Model) -> tuple[sp.Matrix, sp.Matrix]:
    """X^e and U^e: numbers (pi, sqrt... allowed), not expressions in the parameters."""
    def values(label: str, texts: list[str]) -> list[sp.Expr]:
        return [parse(model, v, {}, f"equilibrium.{label}[{i}]") for i, v in enumerate(texts)]
    x_e = sp.Matrix(values("q", model.equilibrium_q) + values("q_dot", model.equilibrium_q_dot))
    return x_e, sp.Matrix(values("u", model.equilibrium_u))


def derive_task(task: Task, ns: dict, n: int) -> TaskDerivation:
    sens = {}
    for term in task.sensitivity_terms:
        key = f"sensitivity.{term}"
        sens[term] = tidy_matrix(sp.Matrix(sensitivity(task, term, ns)))
        if sens[term].shape != (n, n):
            raise DescriptionError(task.path, f"{task.key}.{key}",
                                   f"is {sens[term].shape[0]}x{sens[term].shape[1]}, not {n}x{n}")
    precision, reads = {}, {}
    for term in task.precision_terms:
        precision[term], reads[term] = symmetric_matrix(f"p_{term}", n)
    confidence = precision[task.control_term]
    for term in task.sensitivity_terms:
        s = sens[term]
        confidence = confidence + s.T @ precision[term] @ s
    remarks = []
    for i, r in enumerate(task.remarks):
        alt = tidy_matrix(sp.Matrix(task_formula(task, f"remarks[{i}].alternative", r.alternative, ns)))
        remarks.append({"remark": r, "alternative": alt, "used": sens[r.term]})
    return TaskDerivation(task, sens, precision, reads, confidence, remarks)


def cofactor_determinant(m: sp.Matrix) -> sp.Expr:
    """|m| by Laplace expansion along the first row, without simplification: SymPy's det methods
    cancel and factor, which for Pi^U's composed entries takes long and gains nothing before CSE."""
    n = m.rows
    if n == 1:
        return m[0, 0]
    if n == 2:
        return m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    return sum(((-1) ** j) * m[0, j] * cofactor_determinant(m.minor_submatrix(0, j)) for j in range(n))


def adjugate(m: sp.Matrix) -> sp.Matrix:
    """adj(m) = cofactor matrix transposed (m^-1 = adj(m)/|m|), unsimplified like cofactor_determinant."""
    n = m.rows
    if n == 1:
        return sp.Matrix([[1]])
    return sp.Matrix(n, n, lambda i, j: ((-1) ** (i + j)) * cofactor_determinant(m.minor_submatrix(j, i)))


def logdet_gradient(pi: sp.Matrix, params: list[sp.Symbol]) -> sp.Matrix:
    """d ln|Pi| / dp_i = tr(Pi^-1 dPi/dp_i) = tr(adj(Pi) dPi/dp_i) / |Pi| (Jacobi's formula), for
    every tool parameter: what a design search climbs (toolconf design)."""
    adj, det = adjugate(pi), cofactor_determinant(pi)
    rows = []
    for p in params:
        d_pi = pi.diff(p)
        rows.append(sum(adj[j, i] * d_pi[i, j] for i in range(pi.rows) for j in range(pi.cols)) / det)
    return sp.Matrix(rows)
