"""The derivation's numbers do not depend on the CPU: test points are exact dyadics built from
integers, and CasADi's graphs are evaluated exactly (derive/toolconf_derive/exact.py).

    derive/.venv/bin/python -m unittest discover -s derive/tests      (part of make test)
"""

from __future__ import annotations

import sys
import unittest
from fractions import Fraction
from pathlib import Path

import casadi as ca
import mpmath
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.exact import Exact, ExactEvaluationError, ExactFunction  # noqa: E402
from toolconf_derive.functions import (  # noqa: E402
    _log_uniform, _sample_control, _sample_parameters, _sample_precision, _sample_state)


def is_dyadic_double(x: float, max_denominator_bits: int = 1074) -> bool:
    return Fraction(x).denominator <= 2 ** max_denominator_bits


class ExactEvaluation(unittest.TestCase):
    def test_matches_an_independent_50_digit_evaluation(self):
        x, p = ca.SX.sym("x", 2), ca.SX.sym("p")
        expr = ca.vertcat(ca.sin(x[0]) * p + x[1] ** 2 / 4, ca.sqrt(p) / x[0] - ca.cos(x[1]) ** 3,
                          ca.exp(-x[0]) * ca.log(p) + ca.tan(x[1]) - 1 / p)
        f = ExactFunction(ca.Function("f", [x, p], [expr, ca.jacobian(expr, x)]))
        x0, x1, pv = 0.75, -1.25, 0.3125
        value, jac = f.checked(np.array([x0, x1]), np.array([pv]))
        with mpmath.workdps(60):
            a, b, c = mpmath.mpf(x0), mpmath.mpf(x1), mpmath.mpf(pv)
            want = [mpmath.sin(a) * c + b ** 2 / 4, mpmath.sqrt(c) / a - mpmath.cos(b) ** 3,
                    mpmath.exp(-a) * mpmath.log(c) + mpmath.tan(b) - 1 / c]
            want_jac = [[mpmath.cos(a) * c, b / 2], [-mpmath.sqrt(c) / a ** 2, 3 * mpmath.cos(b) ** 2 * mpmath.sin(b)],
                        [-mpmath.exp(-a) * mpmath.log(c), 1 / mpmath.cos(b) ** 2]]
        for i in range(3):
            self.assertEqual(value.to_numpy()[i, 0], float(want[i]))
            for j in range(2):
                self.assertEqual(jac.to_numpy()[i, j], float(want_jac[i][j]))

    def test_structural_zeros_of_a_sparse_output_are_zero(self):
        x = ca.SX.sym("x", 3)
        f = ExactFunction(ca.Function("f", [x], [ca.jacobian(ca.vertcat(x[0] * x[1], ca.sin(x[2])), x)]))
        (jac,) = f(np.array([0.5, 2.0, 0.0]))
        np.testing.assert_array_equal(jac.to_numpy(), [[2.0, 0.5, 0.0], [0.0, 0.0, 1.0]])

    def test_an_unknown_operation_is_refused(self):
        x = ca.SX.sym("x")
        with self.assertRaises(ExactEvaluationError):
            ExactFunction(ca.Function("f", [x], [ca.erf(x)]))

    def test_exact_matrix_algebra(self):
        a = Exact.of(np.array([[2.0, 1.0], [1.0, 3.0]]))
        eye = (a @ Exact.inv(a)).to_numpy()
        np.testing.assert_allclose(eye, np.eye(2), rtol=0, atol=1e-45)


class PortableSamples(unittest.TestCase):
    def setUp(self):
        self.rng = np.random.default_rng(7)

    def test_states_and_controls_are_on_the_2_to_the_minus_16_grid(self):
        for _ in range(200):
            x = _sample_state(3)(self.rng)
            u = _sample_control(3)(self.rng)
            self.assertTrue(all(Fraction(v).denominator <= 2 ** 16 for v in np.concatenate([x, u]).ravel()))
            self.assertTrue(np.all(np.abs(x[:3]) <= np.pi) and np.all(np.abs(x[3:]) <= 3.0))
            self.assertTrue(np.all(np.abs(u) <= 2.0))

    def test_parameters_are_positive_and_cover_both_ranges(self):
        values = np.concatenate([_sample_parameters(4)(self.rng).ravel() for _ in range(400)])
        self.assertTrue(np.all((values >= 0.02) & (values <= 5.0)))
        self.assertGreater(np.mean(values > 0.6), 0.15)  # the log-uniform half leaves the paper's box (expected 0.19)
        self.assertGreater(np.mean(values < 0.1), 0.1)

    def test_log_uniform_is_log_uniform_and_24_bit(self):
        v = _log_uniform(self.rng, 0.02, 5.0, 4000)
        logs = np.log(v / 0.02) / np.log(5.0 / 0.02)
        counts = np.histogram(logs, bins=4, range=(0, 1))[0]
        self.assertTrue(np.all(np.abs(counts - 1000) < 150), counts)
        for x in v[:200]:
            man, _ = Fraction(x).numerator, Fraction(x).denominator
            self.assertLessEqual(abs(man).bit_length(), 24)

    def test_precisions_are_exactly_symmetric_positive_definite(self):
        for n in (1, 2, 3):
            for _ in range(100):
                p = _sample_precision(n)(self.rng)
                np.testing.assert_array_equal(p, p.T)
                with mpmath.workdps(50):
                    eig = mpmath.eigsy(mpmath.matrix(p.tolist()))[0]
                self.assertGreater(min(eig), 0)

    def test_the_same_seed_gives_the_same_bits(self):
        a = [_sample_parameters(4)(np.random.default_rng(3)).tobytes() for _ in range(2)]
        self.assertEqual(a[0], a[1])


if __name__ == "__main__":
    unittest.main()
