"""The functions a model exports: each pairs SymPy closed forms (for code) with a CasADi evaluator
(for checks and test vectors) and a sampler of valid inputs."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Callable

import mpmath
import numpy as np
import sympy as sp

from .exact import Exact

from .numeric import CasadiModel
from .symbolic import Derivation


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
    # CasADi's values at a sample, exactly (see exact.py): what the test vectors record.
    casadi: Callable[[dict[str, np.ndarray]], list[Exact]]
    # Called ~10^3 times per episode with the same parameters: emit its parameter-only factors as
    # a per-tool coefficient struct and a `<name>_with` that takes it (see hoist.py).
    per_tool_coefficients: bool = False

    def rng(self) -> np.random.Generator:
        """A generator seeded from the function's name, so test vectors are the same on every run.
        Only its integers are used (`integers`), which are the same on every CPU."""
        return np.random.default_rng(int(hashlib.sha256(self.name.encode()).hexdigest()[:16], 16))


def _vector_reads(symbols: list[sp.Symbol]) -> list[tuple[sp.Symbol, int, int]]:
    return [(s, i, 0) for i, s in enumerate(symbols)]


# Test points are exactly representable dyadic rationals built from the seeded generator's
# integers alone: no transcendental function or LAPACK call touches them, so they are the same
# bits on every CPU (numpy's vectorised exp/log and LAPACK's kernels differ in the last bit
# between AVX-512, AVX2 and SSE machines).
GRID = 2.0 ** -16          # states and controls: multiples of 2^-16
PARAMETER_BITS = 24         # parameters: 24 significant bits


def _grid_uniform(rng: np.random.Generator, lo: float, hi: float, n: int, step: float = GRID) -> np.ndarray:
    """n multiples of `step` drawn uniformly from [lo, hi]."""
    return rng.integers(math.ceil(lo / step), math.floor(hi / step), size=n, endpoint=True) * step


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, n: int) -> np.ndarray:
    """n values log-uniform in [lo, hi]: exp of a uniform 2^-32 grid point, in 30-digit integer
    arithmetic (mpmath), rounded to PARAMETER_BITS significant bits."""
    with mpmath.workdps(30):
        a, b = mpmath.log(mpmath.mpf(lo)), mpmath.log(mpmath.mpf(hi))
        values = []
        for k in rng.integers(0, 2**32, size=n, endpoint=True):
            v = mpmath.exp(a + (b - a) * mpmath.mpf(int(k)) / 2**32)
            e = int(mpmath.floor(mpmath.log(v, 2))) - PARAMETER_BITS + 1
            values.append(math.ldexp(int(mpmath.nint(mpmath.ldexp(v, -e))), e))
    return np.array(values)


def _sample_parameters(k: int):
    # Half the points in the paper's domain [0.1, 0.6], half log-uniform over [0.02, 5] so the
    # closed forms are exercised well outside it.
    def sample(rng: np.random.Generator) -> np.ndarray:
        if rng.integers(0, 2) == 0:
            v = _grid_uniform(rng, 0.1, 0.6, k, 2.0 ** -PARAMETER_BITS)
        else:
            v = _log_uniform(rng, 0.02, 5.0, k)
        return v.reshape(k, 1)
    return sample


def _sample_state(n: int):
    def sample(rng: np.random.Generator) -> np.ndarray:
        return np.concatenate([_grid_uniform(rng, -math.pi, math.pi, n),
                               _grid_uniform(rng, -3.0, 3.0, n)]).reshape(2 * n, 1)
    return sample


def _sample_control(n: int):
    return lambda rng: _grid_uniform(rng, -2.0, 2.0, n).reshape(n, 1)


def _sample_precision(n: int):
    """A random symmetric positive-definite matrix P = L D L^T, exactly: L unit lower triangular
    with entries k/8 (|k| <= 12), D diagonal with entries 2^e (e in [-7, 7], eigenvalues spread over
    ~[1e-2, 1e2] like the precisions users give). Products and sums of these few-bit dyadics are
    exact in double precision, which the sampler asserts."""
    def sample(rng: np.random.Generator) -> np.ndarray:
        lower = [[Fraction(int(rng.integers(-12, 12, endpoint=True)), 8) if j < i else Fraction(int(i == j))
                  for j in range(n)] for i in range(n)]
        d = [Fraction(2) ** int(rng.integers(-7, 7, endpoint=True)) for _ in range(n)]
        p = [[sum(lower[i][k] * d[k] * lower[j][k] for k in range(n)) for j in range(n)] for i in range(n)]
        out = np.array([[float(x) for x in row] for row in p])
        assert all(Fraction(out[i, j]) == p[i][j] for i in range(n) for j in range(n)), "inexact precision"
        return out
    return sample


def build_functions(d: Derivation, cm: CasadiModel) -> list[Function]:
    m = d.model
    n, nx, k = m.dof, m.state_dim, len(m.parameters)
    state_names = " ".join(s.name for s in m.state)
    # The entries as code (`[force]`): in the generated docs, a bracketed lone name would be an
    # intra-doc link.
    x = Arg("x", f"state X = `[{state_names}]`", (nx, 1), _vector_reads(d.x), False, _sample_state(n))
    u = Arg("u", f"control U = `[{' '.join(s.name for s in m.u)}]`", (n, 1), _vector_reads(d.u), False,
            _sample_control(n))
    p = Arg("params", f"tool parameters `[{' '.join(s.name for s in m.parameters)}]`", (k, 1),
            _vector_reads(d.params), False, _sample_parameters(k))
    eqs = ", ".join(m.equations)

    fns = [
        Function(
            "dynamics",
            "The generative process X_dot = f(X, U; p): joint rates and the nonlinear joint accelerations.",
            eqs, [x, u, p], [Output("x_dot", "X_dot", d.f)],
            lambda v: cm.dynamics.checked(v["x"], v["u"], v["params"]),
            per_tool_coefficients=True,
        ),
        Function(
            "dynamics_jacobian",
            "Jacobians (df/dX, df/dU) of the generative process at any state and control.",
            eqs, [x, u, p], [Output("f_x", "df/dX", d.f_x), Output("f_u", "df/dU", d.f_u)],
            lambda v: cm.jacobian.checked(v["x"], v["u"], v["params"]),
            per_tool_coefficients=True,
        ),
        Function(
            "state_matrix",
            "A = df/dX at the equilibrium (X^e, U^e): the generative model's state matrix.",
            "eq. (LTI)", [p], [Output("a", "A", d.a)],
            lambda v: [cm.linearisation(v["params"])[0]],
        ),
        Function(
            "input_matrix",
            "B = df/dU at the equilibrium (X^e, U^e): the generative model's input matrix.",
            "eq. (LTI)", [p], [Output("b", "B", d.b)],
            lambda v: [cm.linearisation(v["params"])[1]],
        ),
    ]

    for td in d.tasks:
        task = td.task
        terms = task.sensitivity_terms

        def sens_eval(v, task=task, terms=terms):
            s = cm.sensitivity_exact(task, v["params"])
            return [s[t] for t in terms]

        fns.append(Function(
            task.sensitivity_function,
            f"{task.title}: the sensitivities d(task variable)/dU the controller uses, "
            f"in the order ({', '.join('d_' + t + '_du' for t in terms)}).",
            "appendix \"Task specific controllers\"", [p],
            [Output(f"d_{t}_du", f"d{t}/dU = {task.sensitivity[t]}", td.sensitivity[t]) for t in terms],
            sens_eval,
        ))

        prec_args = [
            Arg(f"p_{t}", f"precision P of {task.argument_doc(t)} (symmetric; the upper triangle is read)", (n, n),
                td.precision_reads[t], True, _sample_precision(n))
            for t in task.precision_terms
        ]

        def conf_eval(v, task=task, terms=terms):
            prec = {t: v[f"p_{t}"] for t in task.precision_terms}
            return [cm.control_confidence(task, v["params"], prec)]

        fns.append(Function(
            task.confidence_function,
            f"{task.title}: the control confidence Pi^U = d2F/dU2 = "
            + " + ".join(f"S_{t}^T P_{t} S_{t}" for t in terms) + f" + P_{task.control_term}.",
            "eq. (control_conf) and the closed forms after it", [p] + prec_args,
            [Output("pi_u", "Pi^U (symmetric)", td.confidence, symmetric=True)], conf_eval,
        ))

        def gradient_eval(v, task=task, terms=terms):
            return cm.logdet_gradient(task).checked(v["params"], *[v[f"p_{t}"] for t in task.precision_terms],
                                                      cancelling=True)

        fns.append(Function(
            task.gradient_function,
            f"{task.title}: the gradient of the confidence term, d ln|Pi^U| / dp = "
            "tr((Pi^U)^-1 dPi^U/dp_i) for every tool parameter p_i (Jacobi's formula), what a tool "
            "design search climbs.",
            "eq. (control_conf) differentiated in the tool parameters", [p] + prec_args,
            [Output("gradient", "d ln|Pi^U| / dp, one entry per tool parameter", td.logdet_gradient)],
            gradient_eval,
        ))
    # Every model has a tip (a planar chain's free end, an explicit model's [tip] position).
    q = Arg("q", f"joint positions q = `[{' '.join(s.name for s in m.q)}]`", (n, 1), _vector_reads(d.q), False,
            lambda rng: _sample_state(n)(rng)[:n])
    where = "the chain's free end" if m.dynamics_kind == "planar_chain" else "the description's [tip] position"
    fns.append(Function(
        "tip",
        f"The tip y(q; p) in the base frame ({where}; z = 0 in the plane of a planar arm) and its Jacobian "
        "J = dy/dq.",
        "forward kinematics of the tip", [q, p],
        [Output("position", "y (m, base frame)", d.tip), Output("jacobian", "J = dy/dq", d.tip_jacobian)],
        lambda v: cm.tip.checked(v["q"], v["params"]),
    ))
    q_dot = Arg("q_dot", f"joint velocities q_dot = `[{' '.join(s.name for s in m.q_dot)}]`", (n, 1),
                _vector_reads(d.q_dot), False, lambda rng: _sample_state(n)(rng)[n:])
    fns.append(Function(
        "tip_bias",
        "The tip's acceleration at rest joints' acceleration, Jdot(q, q_dot) q_dot = d(J q_dot)/dq q_dot "
        "(base frame), so that y_ddot = J(q) q_ddot + tip_bias(q, q_dot).",
        "forward kinematics of the tip, differentiated twice in time", [q, q_dot, p],
        [Output("bias", "Jdot q_dot (m/s^2, base frame)", d.tip_bias)],
        lambda v: cm.tip_bias.checked(v["q"], v["q_dot"], v["params"]),
    ))
    return fns

