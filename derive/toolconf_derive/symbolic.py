"""The symbolic derivation (SymPy): f(X, U; p), its Jacobians, the linearisation at the
equilibrium, the task sensitivities and the control confidence Pi^U.

Everything here is derived from the model description's equations of motion; the paper's printed
matrices are only read in paper.py, for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .chain import sympy_chain
from .description import DescriptionError, Model, Task

TERM_LATEX = {
    "theta": r"\theta",
    "theta_dot": r"\dot{\theta}",
    "theta_ddot": r"\ddot{\theta}",
    "u": "U",
}


def tidy(e: sp.Expr) -> sp.Expr:
    """A canonical, readable form of a rational expression in the parameters."""
    return sp.factor(sp.cancel(sp.together(e)))


def tidy_matrix(m: sp.Matrix) -> sp.Matrix:
    return m.applyfunc(tidy)


def parse(model: Model, text: str, symbols: dict[str, sp.Symbol], where: str) -> sp.Expr:
    namespace = dict(symbols)
    namespace.update({"sin": sp.sin, "cos": sp.cos, "sqrt": sp.sqrt, "pi": sp.pi})
    try:
        return sp.sympify(text, locals=namespace, rational=True)
    except (sp.SympifyError, SyntaxError, TypeError) as err:
        raise DescriptionError(f"{model.path}: {where}: cannot parse '{text}': {err}") from err


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


def task_namespace(a: sp.Matrix, b: sp.Matrix, n: int, inv) -> dict:
    """The names the task formulas in tasks.toml may use (see that file's header)."""
    eye, zero = sp.eye(n), sp.zeros(n, n)
    e = sp.Matrix.vstack(eye, eye)
    a_inv = inv(a)
    return {
        "A": a, "B": b, "inv": inv, "I": eye, "O": zero,
        "IO": sp.Matrix.hstack(eye, zero), "OI": sp.Matrix.hstack(zero, eye),
        "E": e, "dX_dU": a_inv @ (e - b),
    }


def evaluate_formula(formula: str, namespace: dict, where: str):
    try:
        return eval(formula, {"__builtins__": {}}, dict(namespace))  # noqa: S307 - formulas come from tasks.toml
    except Exception as err:  # any error in a formula is a description error
        raise DescriptionError(f"{where}: cannot evaluate '{formula}': {err}") from err


@dataclass
class TaskDerivation:
    task: Task
    sensitivity: dict[str, sp.Matrix]      # term -> n x n, tidy closed form
    precision: dict[str, sp.Matrix]        # term -> symmetric symbol matrix (incl. 'u')
    precision_reads: dict[str, list]       # term -> [(symbol, i, j)]
    confidence: sp.Matrix                  # Pi^U, n x n, composed (not expanded)
    remarks: list[dict]


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
                    table[s] = rf"P^{{{TERM_LATEX[term]}}}_{{{i + 1}{j + 1}}}"
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
    stray = set().union(*(e.free_symbols for e in q_ddot)) - set(symbols.values())
    if stray:
        raise DescriptionError(f"{model.path}: dynamics use undeclared names: {sorted(map(str, stray))}")

    x = q + q_dot
    f = sp.Matrix.vstack(sp.Matrix(q_dot), q_ddot)
    f_x = f.jacobian(x)
    f_u = f.jacobian(u)

    x_e = sp.Matrix([parse(model, v, {}, "equilibrium") for v in model.equilibrium_q + model.equilibrium_q_dot])
    u_e = sp.Matrix([parse(model, v, {}, "equilibrium.u") for v in model.equilibrium_u])
    at_e = dict(zip(x, x_e)) | dict(zip(u, u_e))
    residual = tidy_matrix(f.subs(at_e))
    if any(r != 0 for r in residual):
        raise DescriptionError(f"{model.path}: f(X^e, U^e) = {list(residual)} is not zero: not an equilibrium")

    a = tidy_matrix(f_x.subs(at_e))
    b = tidy_matrix(f_u.subs(at_e))
    if a.det() == 0:
        raise DescriptionError(f"{model.path}: A is singular at the equilibrium; the task sensitivities need A^-1")

    n = model.dof

    def inv(m: sp.Matrix) -> sp.Matrix:
        return tidy_matrix(m.inv())

    ns = task_namespace(a, b, n, inv)
    derived_tasks = []
    for task in tasks:
        sens = {}
        for term in task.sensitivity_terms:
            value = evaluate_formula(task.sensitivity[term], ns, f"task {task.name}: sensitivity.{term}")
            sens[term] = tidy_matrix(sp.Matrix(value))
            if sens[term].shape != (n, n):
                raise DescriptionError(f"task {task.name}: sensitivity.{term} is {sens[term].shape}, not {n}x{n}")
        precision, reads = {}, {}
        for term in task.sensitivity_terms + ["u"]:
            precision[term], reads[term] = symmetric_matrix(f"p_{term}", n)
        confidence = precision["u"]
        for term in task.sensitivity_terms:
            s = sens[term]
            confidence = confidence + s.T @ precision[term] @ s
        remarks = []
        for r in task.remarks:
            alt = tidy_matrix(sp.Matrix(evaluate_formula(r.alternative, ns, f"task {task.name}: remark")))
            remarks.append({"remark": r, "alternative": alt, "used": sens[r.term]})
        derived_tasks.append(TaskDerivation(task, sens, precision, reads, confidence, remarks))

    return Derivation(model, params, consts, q, q_dot, u, q_ddot, f, f_x, f_u, x_e, u_e, a, b, derived_tasks, lagrangian)

