"""Prints SymPy expressions as Rust f64 expressions.

SymPy's own RustCodePrinter prints integer literals as integers (`3*m2`), which is a type error
next to an f64 in Rust, so this small printer covers exactly the operations the derivation emits
and prints every literal as an f64.
"""

from __future__ import annotations

import sympy as sp

ATOM, POSTFIX, MUL, UNARY, ADD = 5, 4, 3, 2, 1

FUNCTIONS = {sp.sin: "sin", sp.cos: "cos", sp.tan: "tan", sp.exp: "exp", sp.log: "ln", sp.Abs: "abs"}


def float_literal(value: float) -> str:
    text = repr(float(value))
    if "inf" in text or "nan" in text:
        raise ValueError(f"non-finite literal {text} in generated code")
    return text if ("." in text or "e" in text) else text + ".0"


class RustPrinter:
    def __init__(self, names: dict[sp.Symbol, str] | None = None):
        self.names = names or {}

    def __call__(self, expr: sp.Expr) -> str:
        # strict: a number or SymPy object, never text (text is read by expression.py).
        return self.print(sp.sympify(expr, strict=True))[0]

    def wrap(self, printed: tuple[str, int], at_least: int) -> str:
        code, prec = printed
        return code if prec >= at_least else f"({code})"

    def print(self, e: sp.Expr) -> tuple[str, int]:
        if isinstance(e, sp.Symbol):
            return self.names.get(e, e.name), ATOM
        if e is sp.pi:
            return "PI", ATOM
        if e is sp.E:
            return "std::f64::consts::E", ATOM
        if isinstance(e, sp.Integer):
            v = int(e)
            return (f"{v}.0", ATOM) if v >= 0 else (f"-{-v}.0", UNARY)
        if isinstance(e, sp.Rational):
            text = f"{abs(int(e.p))}.0 / {int(e.q)}.0"
            return (f"({text})", ATOM) if e.p > 0 else (f"-({text})", UNARY)
        if isinstance(e, sp.Float):
            v = float(e)
            return (float_literal(v), ATOM) if v >= 0 else (float_literal(v), UNARY)
        if isinstance(e, sp.Add):
            return self.print_add(e)
        if isinstance(e, sp.Mul):
            return self.print_mul(e)
        if isinstance(e, sp.Pow):
            return self.print_pow(e)
        if isinstance(e, sp.Function) and e.func in FUNCTIONS and len(e.args) == 1:
            return f"{self.receiver(e.args[0])}.{FUNCTIONS[e.func]}()", POSTFIX
        raise NotImplementedError(f"the Rust printer does not know {type(e).__name__}: {e}")

    def receiver(self, e: sp.Expr) -> str:
        """`e` as the receiver of a method call (`e.sin()`, `e.powf(..)`). A bare number needs the
        `_f64` suffix (`2.0.sin()` is an ambiguous numeric type), and a negative one brackets,
        as the method call binds tighter than the minus (`-2.0_f64.powf(n)` is -(2^n))."""
        if e.is_Number:
            literal = f"{float_literal(e)}_f64"
            return f"({literal})" if e.is_negative else literal
        return self.wrap(self.print(e), POSTFIX)

    def print_add(self, e: sp.Add) -> tuple[str, int]:
        out = ""
        for i, term in enumerate(e.as_ordered_terms()):
            coeff, rest = term.as_coeff_Mul()
            negative = coeff.is_negative
            body = -term if negative else term
            code = self.wrap(self.print(body), MUL)
            if i == 0:
                out = f"-{self.wrap(self.print(body), MUL)}" if negative else code
            else:
                out += f" - {code}" if negative else f" + {code}"
        return out, ADD

    def print_mul(self, e: sp.Mul) -> tuple[str, int]:
        coeff, rest = e.as_coeff_Mul()
        if coeff.is_negative:
            inner = self.wrap(self.print(-e), MUL)
            return f"-{inner}", UNARY
        num, den = [], []
        for f in e.as_ordered_factors():
            if isinstance(f, sp.Pow) and f.exp.is_Rational and f.exp.is_negative:
                den.append(sp.Pow(f.base, -f.exp))
            elif isinstance(f, sp.Rational) and not isinstance(f, sp.Integer) and f.p == 1:
                den.append(sp.Integer(f.q))
            else:
                num.append(f)
        num_code = " * ".join(self.wrap(self.print(f), MUL) for f in num) if num else "1.0"
        if not den:
            return num_code, MUL
        # Every factor of the denominator is wrapped to bind tighter than the division.
        den_code = " * ".join(self.wrap(self.print(f), MUL) for f in den)
        if len(den) > 1:
            den_code = f"({den_code})"
        elif self.print(den[0])[1] < POSTFIX:
            den_code = f"({self.print(den[0])[0]})"
        return f"{num_code} / {den_code}", MUL

    def print_pow(self, e: sp.Pow) -> tuple[str, int]:
        base, exp = e.base, e.exp
        b = self.receiver(base)
        if exp == sp.Rational(1, 2):
            return f"{b}.sqrt()", POSTFIX
        if exp == -sp.Rational(1, 2):
            return f"1.0 / {b}.sqrt()", MUL
        if exp.is_Integer:
            v = int(exp)
            if v == -1:
                return f"1.0 / {b}", MUL
            return f"{b}.powi({v})", POSTFIX
        return f"{b}.powf({self.wrap(self.print(exp), ATOM)})", POSTFIX
