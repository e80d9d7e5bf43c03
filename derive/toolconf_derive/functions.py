"""The functions a model exports: each pairs SymPy closed forms (for code) with a CasADi evaluator
(for checks and test vectors) and a sampler of valid inputs."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Callable

import numpy as np
import sympy as sp

from .numeric import CasadiModel
from .symbolic import Derivation

TERM_DOC = {
    "theta": "joint angles theta",
    "theta_dot": "joint velocities theta_dot",
    "theta_ddot": "joint accelerations theta_ddot",
    "u": "control U",
}


@dataclass
class Arg:
    name: str
    doc: str
    shape: tuple[int, int]
    reads: list[tuple[sp.Symbol, int, int]]   # which symbol is which element
    symmetric: bool
    sample: Callable[[np.random.Generator], np.ndarray]


@dataclass
class Output:
    name: str
    doc: str
    value: sp.Matrix
    # Symmetric outputs are emitted as their upper triangle and mirrored, so the result is
    # symmetric to the bit whatever rounding the two triangles' expressions would have.
    symmetric: bool = False


@dataclass
class Function:
    name: str
    doc: str
    equation: str
    args: list[Arg]
    outputs: list[Output]
    casadi: Callable[[dict[str, np.ndarray]], list[np.ndarray]]
    # Called ~10^3 times per episode with the same parameters: emit its parameter-only factors as
    # a per-tool coefficient struct and a `<name>_with` that takes it (see hoist.py).
    per_tool_coefficients: bool = False

    def rng(self) -> np.random.Generator:
        """A generator seeded from the function's name, so test vectors are the same on every run."""
        return np.random.default_rng(int(hashlib.sha256(self.name.encode()).hexdigest()[:16], 16))


def _vector_reads(symbols: list[sp.Symbol]) -> list[tuple[sp.Symbol, int, int]]:
    return [(s, i, 0) for i, s in enumerate(symbols)]


def _sample_parameters(k: int):
    # Half the points in the paper's domain [0.1, 0.6], half log-uniform over [0.02, 5] so the
    # closed forms are exercised well outside it.
    def sample(rng: np.random.Generator) -> np.ndarray:
        if rng.random() < 0.5:
            v = rng.uniform(0.1, 0.6, k)
        else:
            v = np.exp(rng.uniform(np.log(0.02), np.log(5.0), k))
        return v.reshape(k, 1)
    return sample


def _sample_state(n: int):
    def sample(rng: np.random.Generator) -> np.ndarray:
        return np.concatenate([rng.uniform(-np.pi, np.pi, n), rng.uniform(-3.0, 3.0, n)]).reshape(2 * n, 1)
    return sample


def _sample_control(n: int):
    return lambda rng: rng.uniform(-2.0, 2.0, (n, 1))


def _sample_precision(n: int):
    # A random symmetric positive-definite matrix with eigenvalues log-uniform in [1e-2, 1e2].
    def sample(rng: np.random.Generator) -> np.ndarray:
        q, _ = np.linalg.qr(rng.normal(size=(n, n)))
        lam = np.exp(rng.uniform(np.log(1e-2), np.log(1e2), n))
        m = q @ np.diag(lam) @ q.T
        return 0.5 * (m + m.T)
    return sample


def build_functions(d: Derivation, cm: CasadiModel) -> list[Function]:
    m = d.model
    n, nx, k = m.dof, m.state_dim, len(m.parameters)
    state_names = " ".join(s.name for s in m.state)
    x = Arg("x", f"state X = [{state_names}]", (nx, 1), _vector_reads(d.x), False, _sample_state(n))
    u = Arg("u", f"control U = [{' '.join(s.name for s in m.u)}]", (n, 1), _vector_reads(d.u), False,
            _sample_control(n))
    p = Arg("params", f"tool parameters [{' '.join(s.name for s in m.parameters)}]", (k, 1),
            _vector_reads(d.params), False, _sample_parameters(k))
    eqs = ", ".join(m.equations)

    def flat(a: np.ndarray) -> np.ndarray:
        return a.reshape(-1)

    fns = [
        Function(
            "dynamics",
            "The generative process X_dot = f(X, U; p): joint rates and the nonlinear joint accelerations.",
            eqs, [x, u, p], [Output("x_dot", "X_dot", d.f)],
            lambda v: [np.array(cm.dynamics(flat(v["x"]), flat(v["u"]), flat(v["params"])))],
            per_tool_coefficients=True,
        ),
        Function(
            "dynamics_jacobian",
            "Jacobians (df/dX, df/dU) of the generative process at any state and control.",
            eqs, [x, u, p], [Output("f_x", "df/dX", d.f_x), Output("f_u", "df/dU", d.f_u)],
            lambda v: [np.array(j) for j in cm.jacobian(flat(v["x"]), flat(v["u"]), flat(v["params"]))],
            per_tool_coefficients=True,
        ),
        Function(
            "state_matrix",
            "A = df/dX at the equilibrium (X^e, U^e): the generative model's state matrix.",
            "eq. (LTI)", [p], [Output("a", "A", d.a)],
            lambda v: [np.array(cm.linearisation(flat(v["params"]))[0])],
        ),
        Function(
            "input_matrix",
            "B = df/dU at the equilibrium (X^e, U^e): the generative model's input matrix.",
            "eq. (LTI)", [p], [Output("b", "B", d.b)],
            lambda v: [np.array(cm.linearisation(flat(v["params"]))[1])],
        ),
    ]

    for td in d.tasks:
        task = td.task
        terms = task.sensitivity_terms

        def sens_eval(v, task=task, terms=terms):
            s = cm.sensitivity(task, flat(v["params"]))
            return [s[t] for t in terms]

        fns.append(Function(
            f"{task.name}_sensitivity",
            f"{task.title}: the sensitivities d(task variable)/dU the controller uses, "
            f"in the order ({', '.join('d_' + t + '_du' for t in terms)}).",
            "appendix \"Task specific controllers\"", [p],
            [Output(f"d_{t}_du", f"d{t}/dU = {task.sensitivity[t]}", td.sensitivity[t]) for t in terms],
            sens_eval,
        ))

        prec_args = [
            Arg(f"p_{t}", f"precision P of the {TERM_DOC[t]} (symmetric; the upper triangle is read)", (n, n),
                td.precision_reads[t], True, _sample_precision(n))
            for t in terms + ["u"]
        ]

        def conf_eval(v, task=task, terms=terms):
            prec = {t: v[f"p_{t}"] for t in terms + ["u"]}
            return [cm.control_confidence(task, flat(v["params"]), prec)]

        fns.append(Function(
            f"{task.name}_control_confidence",
            f"{task.title}: the control confidence Pi^U = d2F/dU2 = "
            + " + ".join(f"S_{t}^T P_{t} S_{t}" for t in terms) + " + P_u.",
            "eq. (control_conf) and the closed forms after it", [p] + prec_args,
            [Output("pi_u", "Pi^U (symmetric)", td.confidence, symmetric=True)], conf_eval,
        ))
    return fns

