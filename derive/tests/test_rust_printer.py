"""The Rust expression printer (derive/toolconf_derive/rust_printer.py), checked by running what it
prints: every expression of a coverage set is compiled by rustc into one small program, evaluated
at fixed symbol values, and compared with SymPy's own 50-digit value of the same expression.

    derive/.venv/bin/python -m unittest derive.tests.test_rust_printer   (part of make test)
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from toolconf_derive.rust_printer import RustPrinter, float_literal  # noqa: E402

x, y, a, b, n = sp.symbols("x y a b n", real=True)
# Exactly representable values, so Rust and SymPy start from the same numbers. `n` is an integer
# value for powers of negative bases, which are real only there.
VALUES = {x: sp.Rational(3, 4), y: sp.Rational(-5, 4), a: sp.Rational(5, 16), b: sp.Rational(5, 2), n: 2}
R = sp.Rational
U = dict(evaluate=False)

# Each entry is one construct the derivation can emit (or a model description can contain).
COVERAGE = {
    # negative rationals, alone and as coefficients
    "negative rational": R(-3, 4),
    "negative rational coefficient": R(-3, 4) * x,
    "negative unit fraction coefficient": -x / 7,
    "rational minus symbol": R(1, 3) - x,
    # negative and fractional powers
    "inverse": 1 / x,
    "negative integer power": x**-2,
    "negative half power": (x + a)**R(-1, 2),
    "negative rational power": a**R(-3, 2),
    "fractional power": a**R(1, 3),
    "fractional powers in a quotient": a**R(2, 3) * b**R(-1, 3),
    "float exponent": a**sp.Float(-0.5),
    "symbolic exponent": a**x,
    "negative symbolic exponent": a**(-x),
    "power of a sum": (x + y)**3,
    "fractional power of a difference": (x - y)**R(5, 2),
    "integer base": 2**x,
    "negative integer base": (-2)**n,
    "negative float base": sp.Float(-1.5)**n,
    "rational base": R(1, 3)**x,
    # nested minus signs
    "minus a difference": -(x - (y - a)),
    "minus a product with a difference": -x * (y - a),
    "unevaluated minus one times a sum": sp.Mul(-1, x + a, **U),
    "difference of products": x * y - a * b,
    "minus a quotient": -(x / (y - a)),
    "minus a negative power": -(x - a)**-3,
    "leading negative square": -x**2 + y,
    "difference minus a constant": x - 3,
    "double negation in a function": sp.exp(-(y - x)),
    # integer and float literals
    "integer coefficient and offset": 3 * x + 2,
    "float coefficient": sp.Float(2.5) * x,
    "negative float coefficient": sp.Float(-0.1) * x + 1,
    "tiny float": sp.Float(1e-20) * x + sp.Float(3e-21),
    "huge float": sp.Float(1e20) * x,
    "float exponent that is an integer": x**sp.Float(2.0),
    "large integer": 12345678901 * x,
    # functions of sums
    "sine of a sum": sp.sin(x + y),
    "cosine of a difference": sp.cos(x - y),
    "tangent of a half": sp.tan(x / 2),
    "exponential of a sum": sp.exp(x + a),
    "log of a sum": sp.log(a + b),
    "absolute value of a difference": sp.Abs(y - x),
    "square of a sine of a sum": sp.sin(x + y)**2,
    "sine of a number": sp.sin(2),
    "cosine of a rational": sp.cos(R(1, 3)),
    "log of a number": sp.log(2),
    "exponential of a negative number": sp.exp(-3),
    "function of a function": sp.sin(sp.cos(x) * a),
    # products with divisions
    "product over product": x * y / (a * b),
    "over a sum": x / (a + b),
    "rational coefficient over a symbol": 3 * x / (4 * y),
    "sum over difference over two": (x + y) / (a - b) / 2,
    "one over a product with a sum": 1 / (x * (y + a)),
    "mixed powers in a quotient": x * y**-2 / (a + b)**3,
    "quotient of functions": sp.sin(x) / sp.cos(y),
    "quotient of quotients": (x / a) / (y / b),
    # sqrt
    "square root": sp.sqrt(a),
    "square root of a number": sp.sqrt(2),
    "square root of a rational": sp.sqrt(R(3, 7)),
    "one over a square root of a sum": 1 / sp.sqrt(x + a),
    "symbol over a square root": x / sp.sqrt(a),
    "product of square roots": sp.sqrt(a) * sp.sqrt(b + x),
    "half of root three": sp.sqrt(3) / 2,
    # pi, e and the model's named constants (symbols)
    "pi": sp.pi,
    "pi times a symbol": sp.pi * x,
    "pi over two minus a symbol": sp.pi / 2 - x,
    "sine of pi over three plus a symbol": sp.sin(sp.pi / 3 + x),
    "square root of pi": sp.sqrt(sp.pi),
    "power of pi": sp.pi**x,
    "e": sp.E,
    "e times a symbol": sp.E * x,
    "power of e": sp.E**(x + y),
    "pendulum acceleration": 3 / (a * b**2) * (x - a * sp.Float(9.81) * b * sp.cos(y) / 2),
}


def rust_program(printed: dict[str, str]) -> str:
    lets = "".join(f"    let {s.name}: f64 = {float_literal(float(v))};\n" for s, v in VALUES.items())
    prints = "".join(f'    println!("{{:e}}", {code});\n' for code in printed.values())
    return ("#![allow(warnings)]\nuse std::f64::consts::PI;\n"
            f"fn main() {{\n{lets}{prints}}}\n")


def run_rust(source: str) -> list[float]:
    with tempfile.TemporaryDirectory() as tmp:
        src, exe = Path(tmp) / "printed.rs", Path(tmp) / "printed"
        src.write_text(source)
        build = subprocess.run(["rustc", "--edition", "2021", "-o", str(exe), str(src)],
                               capture_output=True, text=True)
        if build.returncode != 0:
            raise AssertionError(f"the printed Rust does not compile:\n{build.stderr}")
        out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    return [float(line) for line in out.splitlines()]


@unittest.skipIf(shutil.which("rustc") is None, "rustc is not installed")
class PrintedRustMatchesSymPy(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        printer = RustPrinter()
        cls.printed = {name: printer(e) for name, e in COVERAGE.items()}
        # One program for the whole set: one rustc run (a second or two) instead of one per case.
        values = run_rust(rust_program(cls.printed))
        cls.rust = dict(zip(COVERAGE, values, strict=True))

    def test_every_expression_evaluates_to_sympys_value(self):
        for name, e in COVERAGE.items():
            with self.subTest(name, rust=self.printed[name]):
                want = sp.N(sp.sympify(e).xreplace(VALUES), 50)
                self.assertTrue(want.is_real, f"{e} is not real at the test point")
                got = self.rust[name]
                # ~1e-14 relative: a few roundings of the printed operations, not a wrong formula.
                self.assertLessEqual(abs(got - float(want)), 1e-14 * abs(float(want)) + 1e-300,
                                     f"{e}: Rust {got!r}, SymPy {want}")


class PrinterForm(unittest.TestCase):
    """Properties of the text itself that the numbers cannot show."""

    def test_every_literal_is_a_float(self):
        # An integer literal next to an f64 is a type error in Rust.
        self.assertEqual(RustPrinter()(3 * x + 2), "3.0 * x + 2.0")

    def test_float_literals_round_trip(self):
        for v in (0.1, 1e-20, 1e20, 9.81, 5e-324, 123456789.0):
            self.assertEqual(float(float_literal(v)), v)
            self.assertRegex(float_literal(v), r"[.e]")

    def test_a_non_finite_literal_is_refused(self):
        with self.assertRaises(ValueError):
            float_literal(float("inf"))

    def test_an_unknown_function_is_refused(self):
        with self.assertRaises(NotImplementedError):
            RustPrinter()(sp.Function("f")(x))

    def test_symbols_take_their_rust_names(self):
        self.assertEqual(RustPrinter({x: "state[0]"})(sp.sin(x)), "state[0].sin()")


if __name__ == "__main__":
    unittest.main()
