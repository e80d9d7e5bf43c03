"""The operation counts stated in generated/<model>.rs (derive/toolconf_derive/cost.py), checked on
expressions counted by hand, and on the committed IR: hoisting must pay where it is used.

    derive/.venv/bin/python -m unittest discover -s derive/tests      (part of make test)
"""

from __future__ import annotations

import json
import sys
import unittest
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.cost import cost, cse_cost, total  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
x, y, z = sp.symbols("x y z", real=True)


def kinds(c: dict) -> dict[str, int]:
    return c["kinds"]


class Counting(unittest.TestCase):
    def test_counts_and_weights_by_hand(self):
        # x*y + x/y: one MUL, one DIV, one ADD; sin(x)**2: one SIN, one POW.
        c = cost([x * y + x / y, sp.sin(x)**2])
        self.assertEqual(kinds(c), {"ADD": 1, "DIV": 1, "MUL": 1, "POW": 1, "SIN": 1})
        self.assertEqual(c["ops"], 5)
        self.assertEqual(c["weighted"], 1 + 8 + 1 + 2 + 20)

    def test_a_shared_subexpression_counts_once(self):
        # CSE computes sin(x) once: SIN + 2 MUL, not 2 SIN + 2 MUL.
        c = cse_cost([sp.sin(x) * y, sp.sin(x) * z])
        self.assertEqual(kinds(c), {"MUL": 2, "SIN": 1})

    def test_a_constant_costs_nothing(self):
        self.assertEqual(cost([sp.Integer(1), x]), {"ops": 0, "weighted": 0, "kinds": {}})

    def test_total_adds_kind_by_kind(self):
        t = total(cost([x * y]), cost([x * y - z]))
        self.assertEqual(kinds(t), {"MUL": 2, "SUB": 1})
        self.assertEqual((t["ops"], t["weighted"]), (3, 3))


class CommittedCosts(unittest.TestCase):
    def test_every_generated_function_states_its_cost(self):
        for ir_path in sorted(p for p in (ROOT / "generated").glob("*.json") if not p.name.endswith(".vectors.json")):
            ir = json.loads(ir_path.read_text())
            for f in ir["functions"]:
                with self.subTest(model=ir["model"]["name"], function=f["name"]):
                    self.assertEqual(f["cost"]["ops"], sum(kinds(f["cost"]).values()))
                    if f["coefficients"] is not None:
                        # hoist.py keeps coefficients only when the per-call code is cheaper.
                        self.assertLessEqual(f["cost"]["weighted"], f["unhoisted_cost"]["weighted"])

    def test_hoisting_pays_for_arm2s_dynamics(self):
        ir = json.loads((ROOT / "generated" / "arm2.json").read_text())
        dynamics = next(f for f in ir["functions"] if f["name"] == "dynamics")
        # The paper's accelerations divide by parameter expressions; per call, none is left.
        self.assertLess(dynamics["cost"]["weighted"], dynamics["unhoisted_cost"]["weighted"])
        self.assertNotIn("DIV", kinds(dynamics["cost"]))


if __name__ == "__main__":
    unittest.main()
