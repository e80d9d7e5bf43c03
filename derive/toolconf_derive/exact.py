"""Exact arithmetic for everything the derivation writes to a file.

Why: numpy's vectorised transcendental functions, LAPACK and glibc's libm pick CPU-specific
kernels at run time (AVX-512, AVX2/FMA, SSE2), and their results can differ in the last bit.
A test vector computed in double precision on one machine then differs from the committed one
on another, and the drift check fails for a user whose CPU is not the committer's. So:

- `ExactFunction` evaluates a CasADi function by walking CasADi's own instruction list (the
  expression graph its algorithmic differentiation built) in 50-digit mpmath arithmetic. mpmath
  is integer arithmetic (in Python, or GMP through gmpy2 where installed: the same integers): the
  result is the same on every machine, and rounding it to double (`float(mpf)`, correctly
  rounded) gives the same bits everywhere. CasADi's double
  evaluation is still run, but only to check this interpreter (`check_interpreter`); it never
  reaches a file.
- `Exact` is a 50-digit matrix with the operators the task formulas use (A⁻¹, products, [I O]).
"""

from __future__ import annotations

import casadi as ca
import mpmath
import numpy as np

DIGITS = 50
# CasADi's double evaluation against the exact one: both run the same graph, so they differ only
# by double rounding along it.
INTERPRETER_TOLERANCE = 1e-9
# For a graph whose outputs cancel (task 3's d ln|Pi^U|/dp is exactly zero, from terms of order 1),
# double rounding leaves ~eps times the largest intermediate value in CasADi's output, which no
# output-relative tolerance accepts; there the bound is this times the largest intermediate.
INTERMEDIATE_TOLERANCE = 1e-12


class ExactEvaluationError(RuntimeError):
    """CasADi's graph uses an operation this interpreter does not know, or cannot be evaluated."""


def _unary():
    m = mpmath
    return {
        ca.OP_ASSIGN: lambda a: a, ca.OP_NEG: lambda a: -a, ca.OP_SQ: lambda a: a * a,
        ca.OP_TWICE: lambda a: 2 * a, ca.OP_INV: lambda a: 1 / a, ca.OP_SQRT: m.sqrt,
        ca.OP_EXP: m.exp, ca.OP_LOG: m.log, ca.OP_SIN: m.sin, ca.OP_COS: m.cos, ca.OP_TAN: m.tan,
        ca.OP_ASIN: m.asin, ca.OP_ACOS: m.acos, ca.OP_ATAN: m.atan, ca.OP_SINH: m.sinh,
        ca.OP_COSH: m.cosh, ca.OP_TANH: m.tanh, ca.OP_FABS: abs, ca.OP_SIGN: m.sign,
        ca.OP_FLOOR: m.floor, ca.OP_CEIL: m.ceil,
    }


def _binary():
    return {
        ca.OP_ADD: lambda a, b: a + b, ca.OP_SUB: lambda a, b: a - b, ca.OP_MUL: lambda a, b: a * b,
        ca.OP_DIV: lambda a, b: a / b, ca.OP_POW: lambda a, b: a ** b, ca.OP_CONSTPOW: lambda a, b: a ** b,
        ca.OP_ATAN2: mpmath.atan2, ca.OP_FMIN: min, ca.OP_FMAX: max,
        ca.OP_IF_ELSE_ZERO: lambda c, a: a if c != 0 else mpmath.mpf(0),
        ca.OP_LT: lambda a, b: mpmath.mpf(a < b), ca.OP_LE: lambda a, b: mpmath.mpf(a <= b),
        ca.OP_EQ: lambda a, b: mpmath.mpf(a == b), ca.OP_NE: lambda a, b: mpmath.mpf(a != b),
    }


class ExactFunction:
    """A CasADi SX function, evaluated instruction by instruction in 50-digit arithmetic."""

    def __init__(self, f: ca.Function):
        self.f = f
        self.unary, self.binary = _unary(), _binary()
        self.program = [(f.instruction_id(k), f.instruction_input(k), f.instruction_output(k),
                         f.instruction_constant(k)) for k in range(f.n_instructions())]
        self.out_shapes = [(f.size1_out(i), f.size2_out(i)) for i in range(f.n_out())]
        self.out_nz = [list(zip(*f.sparsity_out(i).get_triplet())) for i in range(f.n_out())]
        self.in_nz = [list(zip(*f.sparsity_in(i).get_triplet())) for i in range(f.n_in())]
        self.work_size = f.sz_w()
        for op, _, _, _ in self.program:
            if op not in self.unary and op not in self.binary and op not in (ca.OP_CONST, ca.OP_INPUT, ca.OP_OUTPUT):
                raise ExactEvaluationError(f"{f.name()}: CasADi operation {op} has no exact evaluation")

    def __call__(self, *args, track_largest: bool = False) -> list["Exact"]:
        """Evaluates at `args`, arrays of doubles (each taken exactly)."""
        with mpmath.workdps(DIGITS):
            return self.exact_at([self._input_nonzeros(i, a) for i, a in enumerate(args)], track_largest)

    def exact_at(self, inputs: list[list], track_largest: bool = False) -> list["Exact"]:
        """Evaluates at inputs given exactly: each input's non-zeros as mpmath numbers. With
        `track_largest`, also the largest intermediate's magnitude (`largest_intermediate`): a third
        of the evaluation's time in the derivation's profile, so only where a check needs it."""
        with mpmath.workdps(DIGITS):
            outputs = [mpmath.zeros(r, c) for r, c in self.out_shapes]
            w: list = [None] * max(self.work_size, 1)
            largest = mpmath.mpf(0)
            binary, unary, out_nz = self.binary, self.unary, self.out_nz
            for op, ins, outs, const in self.program:
                if op in binary:
                    v = binary[op](w[ins[0]], w[ins[1]])
                elif op == ca.OP_CONST:
                    v = mpmath.mpf(const)
                elif op == ca.OP_INPUT:
                    v = inputs[ins[0]][ins[1]]
                elif op == ca.OP_OUTPUT:
                    r, c = out_nz[outs[0]][outs[1]]
                    outputs[outs[0]][r, c] = w[ins[0]]
                    continue
                else:
                    v = unary[op](w[ins[0]])
                w[outs[0]] = v
                if track_largest:
                    largest = max(largest, abs(v))
            self.largest_intermediate = float(largest) if track_largest else float("nan")
            return [Exact(o) for o in outputs]

    def _input_nonzeros(self, i: int, a) -> list:
        a = np.asarray(a, dtype=float).reshape(self.f.size1_in(i), self.f.size2_in(i))
        return [mpmath.mpf(float(a[r, c])) for r, c in self.in_nz[i]]

    def checked(self, *args, cancelling: bool = False) -> list["Exact"]:
        """Evaluates exactly and checks the result against CasADi's own double evaluation
        (normwise relative per output): a check of this interpreter. CasADi's doubles are only
        compared, never returned. `cancelling`: the outputs may cancel to far below the graph's
        intermediates, so the bound also allows INTERMEDIATE_TOLERANCE times the largest of them."""
        exact = self(*args, track_largest=cancelling)
        floor = INTERMEDIATE_TOLERANCE * self.largest_intermediate if cancelling else 0.0
        doubles = self.f(*[np.asarray(a, dtype=float) for a in args])
        doubles = [doubles] if self.f.n_out() == 1 else doubles
        for k, (ours, theirs) in enumerate(zip(exact, doubles)):
            ours, theirs = ours.to_numpy(), np.array(theirs, dtype=float)
            scale = max(float(np.max(np.abs(theirs))), 1e-300)
            err = float(np.max(np.abs(ours - theirs)))
            if not (np.all(np.isfinite(ours)) and np.all(np.isfinite(theirs))):
                raise ExactEvaluationError(
                    f"{self.f.name()}: output {k}: not finite in double precision at these inputs (the "
                    "description's values overflow it)")
            if not err <= max(INTERPRETER_TOLERANCE * scale, 1e-14, floor):
                raise ExactEvaluationError(
                    f"{self.f.name()}: output {k}: the exact interpretation and CasADi differ by {err:.3e} "
                    f"(scale {scale:.3e})")
        return exact


class Exact:
    """A matrix in 50-digit arithmetic with the operators the task formulas use."""

    def __init__(self, m: mpmath.matrix):
        self.m = m

    @classmethod
    def of(cls, a) -> "Exact":
        """From exactly representable doubles (every element is taken exactly)."""
        with mpmath.workdps(DIGITS):
            return cls(mpmath.matrix([[mpmath.mpf(float(x)) for x in row] for row in np.atleast_2d(a)]))

    @staticmethod
    def inv(a: "Exact") -> "Exact":
        with mpmath.workdps(DIGITS):
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
        with mpmath.workdps(DIGITS):
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
        """Each element rounded to the nearest double (mpmath rounds correctly: the same bits on
        every machine)."""
        return np.array([[float(self.m[i, j]) for j in range(self.m.cols)] for i in range(self.m.rows)])
