"""The runtime's predicted episode cost (crates/model/src/prediction) recomputed with SciPy on the
same linear systems: tests/fixtures/prediction_scipy.json holds each system (M, c, z0, the terms'
C, offset, goal and precision, the grid, ln|Pi^U|) and the runtime's prediction, and a Rust test
(`the_scipy_fixture_is_what_the_code_gives`) keeps it the code's. Here scipy.linalg.expm steps the
affine system on the grid and the sums are formed independently: they must agree within 1e-8
relative.

    make python-test (SciPy is among python/requirements-dev.txt)
"""

from __future__ import annotations

import json
import unittest
from pathlib import Path

import numpy as np
from scipy.linalg import expm

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "tests" / "fixtures" / "prediction_scipy.json"


def grid(t_end: float, dt: float) -> np.ndarray:
    """0, dt, 2dt, ... and t_end itself (the runtime's uniform grid)."""
    n = int(np.ceil(t_end / dt - 1e-9 * max(t_end / dt, 1.0)))
    return np.append(np.arange(n) * dt, t_end)


def step(m: np.ndarray, c: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """z(t + h) = Phi z(t) + g for z' = M z + c, from expm of the augmented matrix."""
    nz = m.shape[0]
    aug = np.zeros((nz + 1, nz + 1))
    aug[:nz, :nz], aug[:nz, nz] = m * h, c * h
    e = expm(aug)
    return e[:nz, :nz], e[:nz, nz]


def predict(s: dict) -> dict[str, float]:
    m, c, z = np.array(s["m"]), np.array(s["c"]), np.array(s["z0"])
    t = grid(s["t_end"], s["dt"])
    steps = {}
    values = []
    for k, tk in enumerate(t):
        if k > 0:
            h = round(tk - t[k - 1], 12)
            if h not in steps:
                steps[h] = step(m, c, tk - t[k - 1])
            phi, g = steps[h]
            z = phi @ z + g
        te, j = 0.0, 0.0
        for term in s["terms"]:
            e = np.array(term["c"]) @ z + np.array(term["offset"]) - np.array(term["goal"])
            v = e @ np.array(term["precision"]) @ e
            te += v if term["name"] == s["error_term"] else 0.0
            j += v if term["in_cost"] else 0.0
        values.append((te, 0.5 * j))
    te = np.array([v[0] for v in values])
    j = np.array([v[1] for v in values])
    f = j - 0.5 * s["logdet"]
    trapezoid = lambda y: float(np.sum(0.5 * np.diff(t) * (y[1:] + y[:-1])))
    return {"task_error": float(te.sum()), "cost_j": trapezoid(j), "free_energy": trapezoid(f)}


class PredictionAgainstScipy(unittest.TestCase):
    def test_the_runtimes_prediction_is_scipys(self):
        cases = json.loads(FIXTURE.read_text())
        self.assertGreaterEqual(len(cases), 3)
        for case in cases:
            got = predict(case["system"])
            for key in ("task_error", "free_energy", "cost_j"):
                with self.subTest(case=case["name"], key=key):
                    self.assertLessEqual(
                        abs(got[key] - case[key]), 1e-8 * abs(case[key]), (got[key], case[key])
                    )


if __name__ == "__main__":
    unittest.main()
