"""The expression grammar (derive/toolconf_derive/expression.py), the one reader of every
expression in a description, a task file or tasks.toml.

- What it reads, it reads as Python's arithmetic does: precedence and grouping against values
  worked out by hand, and every expression of the shipped descriptions against SymPy's own
  parser on the same (trusted) text, object for object.
- What it refuses, it refuses with one line (an ExpressionError; DescriptionError naming the
  file and key through the description), in bounded time, running nothing: code payloads,
  attribute access, strings, huge numbers and exponents, long sums, deep nesting.

    derive/.venv/bin/python -m unittest discover -s derive/tests -p 'test_expression.py'
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
import unittest
from pathlib import Path

import numpy as np
import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.description import (  # noqa: E402
    FORMULA_NAMES,
    Task,
    load_model,
    load_tasks,
    task_formula,
)
from toolconf_derive.errors import DescriptionError  # noqa: E402
from toolconf_derive.expression import (  # noqa: E402
    MAX_CHARACTERS,
    MAX_DEPTH,
    MAX_EXPONENT,
    MAX_NODES,
    MAX_TERMS,
    ExpressionError,
    number_value,
    parse,
    python_number,
    sympy_expression,
)

ROOT = Path(__file__).resolve().parents[2]
# Each refusal takes far less; the bound catches a grammar that evaluates before it refuses.
SECONDS = 2.0
CANARY = Path(tempfile.gettempdir()) / "toolconf-expression-canary"
PAYLOADS = {
    # The reported attack: attribute access and escaped string literals reaching __import__.
    "globals": '(1).__add__.__globals__["\\137\\137builtins\\137\\137"]["\\137\\137import\\137\\137"]'
               f'("\\157\\163").system("touch {CANARY}")',
    "class": "().__class__",
    "subclasses": "().__class__.__base__.__subclasses__()",
    "import": f'__import__("os").system("touch {CANARY}")',
    "string": "'abc'",
    "escaped": '"\\x5f\\x5f"',
    "lambda": "lambda: 1",
    "comprehension": "[x for x in (1,)]",
    "subscript": "x[0]",
    "attribute": "x.real",
    "keyword": "x if x else 1",
    "walrus": "(y := 1)",
}


def numbers(text: str) -> float:
    """A text of numbers and pi built as doubles."""
    return parse(text, ()).evaluate({"pi": math.pi}, {"sin": math.sin, "cos": math.cos, "sqrt": math.sqrt},
                                    python_number)


class Reads(unittest.TestCase):
    def test_precedence_and_grouping_as_python(self):
        # Values by hand: ** binds tighter than unary minus and groups to the right; - and /
        # group to the left; a unary minus may follow **.
        for text, want in (("-2**2", -4), ("2**3**2", 512), ("2**-1", 0.5), ("1-2-3", -4), ("8/2/2", 2),
                           ("2*3+4*5", 26), ("(2+3)*4", 20), ("--3", 3), ("+-+3", -3), ("-2**-2", -0.25),
                           ("1e-3*1000", 1.0), (".5+1.", 1.5), ("sqrt(16)/cos(0)", 4.0)):
            with self.subTest(text=text):
                self.assertEqual(numbers(text), want)
                self.assertEqual(parse(text, ()).value, want)

    def test_value_of_a_number_is_the_double(self):
        self.assertEqual(number_value("-pi/2"), -math.pi / 2)
        self.assertEqual(number_value("pi/3"), math.pi / 3)
        self.assertEqual(number_value("0.1"), 0.1)

    def test_sympy_objects(self):
        x, y = sp.symbols("x y", real=True)
        symbols = {"x": x, "y": y}
        self.assertEqual(sympy_expression("-x**2", symbols), -(x ** 2))
        self.assertEqual(sympy_expression("x - y - 1", symbols), x - y - 1)
        self.assertEqual(sympy_expression("0.1*x", symbols), sp.Rational(1, 10) * x)
        self.assertEqual(sympy_expression("sqrt(x)*sin(pi/6)", symbols), sp.sqrt(x) / 2)
        self.assertEqual(sympy_expression("1/3", {}), sp.Rational(1, 3))
        self.assertEqual(sympy_expression("0.5", {}, rational=False), sp.Float("0.5"))

    def test_every_shipped_expression_is_what_sympys_parser_made_of_it(self):
        """The descriptions in derive/models and tests/fixtures: the tree built in SymPy equals
        sympify of the same trusted text (the reader the derivation used before), srepr for srepr,
        which keeps generated/ byte for byte what it was."""
        builtins = {"sin": sp.sin, "cos": sp.cos, "sqrt": sp.sqrt, "pi": sp.pi}
        paths = sorted((ROOT / "derive" / "models").glob("*.toml")) + [ROOT / "tests" / "fixtures" / "pendulum.toml"]
        checked = 0
        for path in paths:
            m = load_model(path)
            symbols = {p.name: sp.Symbol(p.name, positive=True) for p in m.parameters}
            symbols |= {c.name: sp.Symbol(c.name, real=True) for c in m.constants + m.q + m.q_dot + m.u}
            texts = [(t, symbols) for t in m.q_ddot] + [(t, {}) for t in
                                                        m.equilibrium_q + m.equilibrium_q_dot + m.equilibrium_u]
            texts += [(t, {}) for goals in m.goals.values() for values in goals.values() for t in values]
            texts += [(t, symbols) for row in (m.printed_a or []) + (m.printed_b or []) for t in row]
            for text, names in texts:
                with self.subTest(path=path.name, text=text):
                    want = sp.sympify(text, locals={**names, **builtins}, rational=True)
                    self.assertEqual(sp.srepr(sympy_expression(text, names)), sp.srepr(want))
                    checked += 1
        self.assertGreater(checked, 100)

    def test_task_formulas_on_numpy_matrices(self):
        """tasks.toml's formulas against the same algebra written out in NumPy."""
        rng = np.random.default_rng(7)
        n = 2
        a, b = rng.normal(size=(2 * n, 2 * n)), rng.normal(size=(2 * n, n))
        eye, zero = np.eye(n), np.zeros((n, n))
        io, oi, e = np.hstack([eye, zero]), np.hstack([zero, eye]), np.vstack([eye, eye])
        j = np.vstack([rng.normal(size=(1, n)), np.zeros((1, n))])   # a tip of one component, padded
        ns = {"A": a, "B": b, "inv": np.linalg.inv, "I": eye, "O": zero, "IO": io, "OI": oi, "E": e,
              "dX_dU": np.linalg.inv(a) @ (e - b), "J": j}
        self.assertEqual(sorted(k for k in ns if k != "inv"), sorted(FORMULA_NAMES))
        tasks = {t.name: t for t in load_tasks(ROOT / "derive" / "tasks.toml")}
        inv = np.linalg.inv
        want = {
            ("position", "theta"): io @ inv(a) @ (e - b),
            ("position", "theta_dot"): oi @ inv(a) @ (e - b),
            ("position", "theta_ddot"): eye,
            ("velocity", "theta_dot"): -(io @ inv(a) @ b),
            ("acceleration", "theta_ddot"): io @ (a @ a @ (inv(a) @ (e - b)) + a @ b),
            ("tip_position", "tip"): j @ io @ inv(a) @ (e - b),
            ("tip_position", "tip_dot"): j @ oi @ inv(a) @ (e - b),
            ("tip_velocity", "tip_dot"): -(j @ io @ inv(a) @ b),
        }
        for (task, term), value in want.items():
            with self.subTest(task=task, term=term):
                got = task_formula(tasks[task], f"sensitivity.{term}", tasks[task].sensitivity[term], ns)
                np.testing.assert_allclose(got, value, rtol=1e-12, atol=1e-12)
        # The static gain (the URDF arms' default formulation of both position tasks).
        static = {
            ("position", "theta"): -(io @ inv(a) @ b),
            ("position", "theta_dot"): -(oi @ inv(a) @ b),
            ("position", "theta_ddot"): eye,
            ("tip_position", "tip"): -(j @ io @ inv(a) @ b),
            ("tip_position", "tip_dot"): -(j @ oi @ inv(a) @ b),
        }
        for (task, term), value in static.items():
            with self.subTest(task=task, term=term, formulation="static_gain"):
                text = tasks[task].formulations["static_gain"].sensitivity[term]
                got = task_formula(tasks[task], f"formulations.static_gain.sensitivity.{term}", text, ns)
                np.testing.assert_allclose(got, value, rtol=1e-12, atol=1e-12)


class Refuses(unittest.TestCase):
    def refused(self, text: str, problem: str, names=("x", "y"), **grammar) -> str:
        start = time.monotonic()
        with self.assertRaises(ExpressionError) as caught:
            parse(text, names, **grammar)
        self.assertLess(time.monotonic() - start, SECONDS, text[:80])
        message = str(caught.exception)
        self.assertNotIn("\n", message)
        self.assertIn(problem, message)
        self.assertLess(len(message), 400, message[:200])
        return message

    def setUp(self):
        CANARY.unlink(missing_ok=True)

    def tearDown(self):
        self.assertFalse(CANARY.exists(), "a payload ran")

    def test_code_is_not_an_expression(self):
        for label, text in PAYLOADS.items():
            with self.subTest(label):
                start = time.monotonic()
                with self.assertRaises(ExpressionError) as caught:
                    parse(text, ("x",))
                self.assertLess(time.monotonic() - start, SECONDS)
                self.assertNotIn("\n", str(caught.exception))

    def test_the_first_problem_is_named_with_its_place(self):
        self.refused("().__class__", "unexpected character '.' at character 3")
        self.refused("()", "unexpected ')' at character 2")
        self.refused("x.real", "unexpected character '.' at character 2")
        self.refused("'a'", "unexpected character \"'\" at character 1")
        self.refused("__import__(os)", "'__import__' is not defined (known here: x, y, pi, sin, cos, sqrt)")
        self.refused("x[0]", "unexpected character '[' at character 2")
        self.refused("x[0)", "unbalanced brackets: ')' at character 4 closes '[' from character 2")
        self.refused("(x", "'(' at character 1 is never closed")
        self.refused("x)", "')' at character 2 closes nothing")
        self.refused("sin", "'sin' is a function: write sin(...)")
        self.refused("x(1)", "'x' at character 1 is not a function")
        self.refused("sin(x, y)", "sin() takes 1 argument(s), got 2")
        self.refused("", "is empty")
        self.refused("x +", "ends where a number, name or '(' is expected")
        self.refused("x y", "unexpected 'y' at character 3")

    def test_the_matrix_product_is_only_for_task_formulas(self):
        self.refused("x @ y", "'@' at character 3 is the matrix product, which only task formulas have")

    def test_division_by_a_number_zero(self):
        for text in ("1/0", "x/0", "x/(2-2)", "x/0.0", "0**-1"):
            with self.subTest(text):
                self.refused(text, "division by zero")

    def test_numbers_and_powers_that_are_not_finite_or_too_large(self):
        self.refused("pi*1e400", "the number 1e400 is not finite")
        self.refused("1e308*1e308", "not finite")
        self.refused("1" * 101, "more than 100 characters")
        self.refused("9**9**9", f"larger than {MAX_EXPONENT} in magnitude")
        self.refused("x**17", "larger than 16")
        self.refused("x**y", "the exponent after '**' at character 2 must be a number")
        self.refused("(1e300)**2", "not finite")
        self.refused("sqrt(-1)", "is not a real number")
        self.refused("(-8)**(1/3)", "is not a real number")
        self.refused("*".join(["(x+y)**16"] * 5), "polynomial degree 80, more than 32")
        # Within the degree bound, a product of sums still expands in bounded work: 2**13 terms.
        self.refused("*".join(["(x+y)"] * 13), f"expands to more than {MAX_TERMS} terms")
        self.refused("(a+b+c+d+e+f)**16", f"expands to more than {MAX_TERMS} terms", names=tuple("abcdef"))
        self.assertIsNone(parse("*".join(["(x+y)"] * 12), ("x", "y")).value)

    def test_size_and_depth(self):
        self.refused("+".join(["x"] * 200_000), f"longer than {MAX_CHARACTERS} characters")
        self.refused("+".join(["x"] * 6_000), f"more than {MAX_NODES}")
        self.refused("(" * 40 + "x" + ")" * 40, f"nested more than {MAX_DEPTH} deep")
        self.refused("-" * 5_000 + "x", f"nested more than {MAX_DEPTH} deep")
        self.refused("x" + "**1" * 5_000, f"nested more than {MAX_DEPTH} deep")
        # The bounds still leave room: a 2000-term sum reads, flat (no deep recursion).
        self.assertIsNone(parse("+".join(["x"] * 2_000), ("x",)).value)

    def test_task_formulas_have_only_their_names_and_inv(self):
        names = FORMULA_NAMES
        grammar = {"functions": {"inv": 1}, "constants": {}, "max_degree": 8, "max_number": 1e6, "matrices": True}
        self.refused("A.T", "unexpected character '.'", names, **grammar)
        self.refused("sin(A)", "'sin' is not defined", names, **grammar)
        self.refused("A @ pi", "'pi' is not defined", names, **grammar)
        self.refused(" @ ".join(["A"] * 9), "polynomial degree 9, more than 8", names, **grammar)
        self.refused("inv(A, B)", "inv() takes 1 argument(s), got 2", names, **grammar)
        self.refused("A @ 9**9**9", "a task formula has no powers", names, **grammar)
        # One meaning in NumPy, SymPy, CasADi and mpmath alike.
        self.refused("A * B", "'*' at character 3 multiplies two matrices: write '@'", names, **grammar)
        self.refused("A / B", "'/' at character 3 divides by a matrix", names, **grammar)
        self.refused("A + 1", "'+' at character 3 adds a number and a matrix", names, **grammar)
        self.assertIsNone(parse("2 * A / 4 - (1 + 1) * B", names, **grammar).value)
        self.refused("1e308 * A", "the number 1e308 at character 1 is larger than 1e+06", names, **grammar)

    def test_a_task_formula_that_fails_in_its_arithmetic_names_the_key(self):
        task = Task(name="t", index=1, title="", doc="", terms=["theta"], error="theta",
                    sensitivity={"theta": "A @ IO"}, path="tasks.toml", key="task[0]")
        ns = {k: np.eye(2) for k in FORMULA_NAMES} | {"IO": np.ones((3, 3)), "inv": np.linalg.inv}
        with self.assertRaises(DescriptionError) as caught:
            task_formula(task, "sensitivity.theta", "A @ IO", ns)
        self.assertTrue(str(caught.exception).startswith("tasks.toml: task[0].sensitivity.theta: cannot evaluate"))
        with self.assertRaises(DescriptionError) as caught:
            task_formula(task, "sensitivity.theta", "1/0 + A", ns)
        self.assertEqual(str(caught.exception), "tasks.toml: task[0].sensitivity.theta: division by zero in '1/0 + A'")


if __name__ == "__main__":
    unittest.main()
