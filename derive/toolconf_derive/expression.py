"""The one reader of every expression a description, a task file or tasks.toml holds: equations
of motion, equilibria, goals, the printed matrices and the task formulas. They are data shared
between labs, so they are parsed by a grammar, never evaluated as Python (no eval, no sympify on
raw text, no attribute access, no strings):

    expression := term (("+" | "-") term)*
    term       := unary (("*" | "/" | "@") unary)*
    unary      := ("-" | "+") unary | power
    power      := atom ["**" unary]
    atom       := number | name | function "(" expression ("," expression)* ")" | "(" expression ")"

with Python's precedence (-x**2 is -(x**2), ** groups to the right), names and functions only
those the caller allows (a description's parameters and coordinates, sin, cos, sqrt, pi; a task
formula's A, B, inv, ...). The parsed tree is then built by the caller's arithmetic (SymPy,
CasADi, mpmath, NumPy, floats) with Python's operators in the order Python applies them, so
the result is the object `eval` of the same text gave.

Bounds keep a hostile text cheap: its length, its number of nodes, its nesting depth, the
exponent of ** (a number, |e| <= MAX_EXPONENT), its polynomial degree, the number of terms
its full expansion can have (the degree alone lets (x+y)*(x+y)*... expand to 2**32 terms), the
characters of a number; a number, or a part that is a number (pi*1e400, 1e308*1e308), must be finite, and a
division by what is a number must not divide by zero.
"""

from __future__ import annotations

import math
import re
from contextlib import contextmanager
from dataclasses import dataclass

MAX_CHARACTERS = 20_000
MAX_NODES = 5_000
MAX_DEPTH = 32
MAX_EXPONENT = 16
MAX_DEGREE = 32
# No expansion larger than the longest sum the node bound lets one write out: SymPy expands
# 5000 terms in about 3 s, so the derivation's own expansions stay bounded.
MAX_TERMS = MAX_NODES
MAX_NUMBER_CHARACTERS = 100

# What a description's scalar expressions may call (arity), and the named numbers.
SCALAR_FUNCTIONS = {"sin": 1, "cos": 1, "sqrt": 1}
SCALAR_CONSTANTS = {"pi": math.pi}

# ASCII only (re.ASCII): Python's \d also matches other scripts' digits (Arabic-Indic, mathematical
# bold), which float() then reads as numbers, and \s other spaces; a description's numbers and
# spaces are ASCII.
TOKEN = re.compile(r"(?P<space>\s+)|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
                   r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<op>\*\*|[-+*/@(),])", re.ASCII)


class ExpressionError(ValueError):
    """Why a text is not an expression of the grammar (one line; the caller adds file and key)."""


@dataclass(frozen=True)
class Node:
    """One node of the tree. kind: "number" (text), "name" (text), "neg"/"pos" (args[0]),
    "sum"/"product" (args[0], then (operator, operand) pairs in rest), "pow" (args), "call"
    (text = function, args). `value` is the node's double when it is a number (else None),
    `degree` its polynomial degree (a name 1, a number 0), `terms` an upper bound of the terms of
    its full expansion (a function call counts as one: its arguments are bounded as nodes)."""
    kind: str
    text: str = ""
    args: tuple = ()
    rest: tuple = ()
    value: float | None = None
    degree: int = 0
    terms: int = 1


def _constant(value: float, what: str) -> float:
    if not math.isfinite(value):
        raise ExpressionError(f"{what} is not finite")
    return value


def _fold(op: str, a: float, b: float) -> float:
    """The double of a binary operation on two numbers, refused where it is not a real number."""
    try:
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            return a / b
        if op == "**":
            result = a ** b
            if isinstance(result, complex):
                raise ExpressionError(f"{a!r}**{b!r} is not a real number")
            return result
    except ZeroDivisionError as err:
        raise ExpressionError("division by zero") from err
    except OverflowError as err:
        raise ExpressionError(f"{a!r} {op} {b!r} is not finite") from err
    raise ExpressionError(f"'{op}' of two numbers")  # '@' of numbers: not a matrix product


OPENING, CLOSING = "([{", ")]}"


def bracket_problem(text: str) -> str | None:
    """Why the brackets of `text` do not balance (positions count characters from 1), or None:
    said before the grammar's own errors, which would name only the first token it cannot use."""
    stack: list[tuple[str, int]] = []
    for i, ch in enumerate(text, 1):
        if ch in OPENING:
            stack.append((ch, i))
        elif ch in CLOSING:
            if not stack:
                return f"unbalanced brackets: '{ch}' at character {i} closes nothing"
            opened, at = stack.pop()
            if OPENING.index(opened) != CLOSING.index(ch):
                return f"unbalanced brackets: '{ch}' at character {i} closes '{opened}' from character {at}"
    if stack:
        opened, at = stack[-1]
        return f"unbalanced brackets: '{opened}' at character {at} is never closed"
    return None


class _Parser:
    def __init__(self, text: str, names, functions: dict[str, int], constants: dict[str, float],
                 max_degree: int, max_number: float, matrices: bool):
        if len(text) > MAX_CHARACTERS:
            raise ExpressionError(f"longer than {MAX_CHARACTERS} characters ({len(text)})")
        problem = bracket_problem(text)
        if problem:
            raise ExpressionError(problem)
        self.text, self.names, self.functions, self.constants = text, names, functions, constants
        self.max_degree, self.max_number, self.matrices = max_degree, max_number, matrices
        self.tokens = self._tokens(text)
        self.at, self.nodes, self.depth = 0, 0, 0

    @staticmethod
    def _tokens(text: str) -> list[tuple[str, str, int]]:
        tokens, i = [], 0
        while i < len(text):
            m = TOKEN.match(text, i)
            if m is None:
                raise ExpressionError(f"unexpected character {text[i]!r} at character {i + 1} (allowed: numbers, "
                                      "names, + - * / ** @ ( ) ,)")
            if m.lastgroup != "space":
                tokens.append((m.lastgroup, m.group(), i + 1))
            i = m.end()
        tokens.append(("end", "", len(text) + 1))
        return tokens

    # --- tokens ---------------------------------------------------------------------------------

    def peek(self) -> tuple[str, str, int]:
        return self.tokens[self.at]

    def take(self) -> tuple[str, str, int]:
        token = self.tokens[self.at]
        self.at += 1
        return token

    def expect(self, op: str, opened: tuple[str, str, int]) -> None:
        kind, text, where = self.take()
        if (kind, text) != ("op", op):
            if kind == "end":
                raise ExpressionError(f"'{opened[1]}' at character {opened[2]} was never closed")
            raise ExpressionError(f"expected '{op}' at character {where}, found '{text}'")

    def node(self, kind: str, **fields) -> Node:
        self.nodes += 1
        if self.nodes > MAX_NODES:
            raise ExpressionError(f"more than {MAX_NODES} numbers, names and operators")
        if fields.get("degree", 0) > self.max_degree:
            raise ExpressionError(f"of polynomial degree {fields['degree']}, more than {self.max_degree}")
        if fields.get("terms", 1) > MAX_TERMS:
            raise ExpressionError(f"expands to more than {MAX_TERMS} terms")
        return Node(kind, **fields)

    @contextmanager
    def nested(self):
        """One level deeper (a bracket, a unary sign, an exponent): Python's recursion stays short."""
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExpressionError(f"nested more than {MAX_DEPTH} deep")
        try:
            yield
        finally:
            self.depth -= 1

    # --- grammar --------------------------------------------------------------------------------

    def whole(self) -> Node:
        tree = self.expression()
        kind, text, where = self.peek()
        if kind != "end":
            if text == ")":
                raise ExpressionError(f"')' at character {where} closes nothing")
            raise ExpressionError(f"unexpected '{text}' at character {where}")
        return tree

    def expression(self) -> Node:
        with self.nested():
            return self.chain("sum", ("+", "-"), self.term)

    def term(self) -> Node:
        return self.chain("product", ("*", "/", "@"), self.unary)

    def chain(self, kind: str, operators: tuple, operand) -> Node:
        """A left-associative run of `operators`, kept flat (a 5000-term sum is no deep tree)."""
        first = operand()
        rest, places = [], []
        while self.peek()[0] == "op" and self.peek()[1] in operators:
            _, op, where = self.take()
            rest.append((op, operand()))
            places.append(where)
        if not rest:
            return first
        value = first.value
        for (op, x), where in zip(rest, places):
            if op == "/" and x.value == 0:
                raise ExpressionError("division by zero")
            self.check_operands(op, where, value, x)
            value = None if value is None or x.value is None else _fold(op, value, x.value)
        degrees = [first.degree] + [x.degree for _, x in rest]
        degree = max(degrees) if kind == "sum" else sum(degrees)
        terms = [first.terms] + [x.terms for _, x in rest]
        terms = sum(terms) if kind == "sum" else math.prod(min(t, MAX_TERMS + 1) for t in terms)
        return self.node(kind, args=(first,), rest=tuple(rest), degree=degree, terms=terms,
                         value=None if value is None else _constant(value, "the value"))

    def check_operands(self, op: str, where: int, left: float | None, right: Node) -> None:
        """One meaning in every arithmetic: `@` only between matrices (task formulas); there, `*`
        and `/` only with a number (NumPy's `*` of matrices is elementwise, SymPy's a product)
        and no number added to a matrix (NumPy would broadcast it)."""
        if not self.matrices:
            if op == "@":
                raise ExpressionError(f"'@' at character {where} is the matrix product, which only task formulas have")
            return
        numbers = (left is not None, right.value is not None)
        if op == "*" and not any(numbers):
            raise ExpressionError(f"'*' at character {where} multiplies two matrices: write '@'")
        if op == "/" and not numbers[1]:
            raise ExpressionError(f"'/' at character {where} divides by a matrix: write inv(...)")
        if op in "+-" and numbers[0] != numbers[1]:
            raise ExpressionError(f"'{op}' at character {where} adds a number and a matrix")

    def unary(self) -> Node:
        kind, text, _ = self.peek()
        if kind == "op" and text in ("-", "+"):
            self.take()
            with self.nested():
                x = self.unary()
            value = None if x.value is None else (-x.value if text == "-" else x.value)
            return self.node("neg" if text == "-" else "pos", args=(x,), value=value, degree=x.degree,
                             terms=x.terms)
        return self.power()

    def power(self) -> Node:
        base = self.atom()
        kind, text, where = self.peek()
        if (kind, text) != ("op", "**"):
            return base
        if self.matrices:
            raise ExpressionError(f"'**' at character {where}: a task formula has no powers (write A @ A)")
        self.take()
        with self.nested():
            exponent = self.unary()
        if exponent.value is None:
            raise ExpressionError(f"the exponent after '**' at character {where} must be a number")
        if abs(exponent.value) > MAX_EXPONENT:
            raise ExpressionError(f"the exponent {exponent.value:g} at character {where} is larger than "
                                  f"{MAX_EXPONENT} in magnitude")
        value = None if base.value is None else _constant(_fold("**", base.value, exponent.value), "the power")
        power = math.ceil(abs(exponent.value))
        degree = base.degree * max(1, power)
        # The multinomial expansion of a k-term base to the e-th power has C(k + e - 1, e) terms.
        terms = math.comb(base.terms + power - 1, power) if power >= 1 else base.terms
        return self.node("pow", args=(base, exponent), value=value, degree=degree, terms=terms)

    def atom(self) -> Node:
        kind, text, where = self.take()
        if kind == "number":
            if len(text) > MAX_NUMBER_CHARACTERS:
                raise ExpressionError(f"the number at character {where} has more than {MAX_NUMBER_CHARACTERS} "
                                      "characters")
            value = _constant(float(text), f"the number {text}")
            if abs(value) > self.max_number:
                raise ExpressionError(f"the number {text} at character {where} is larger than {self.max_number:g}")
            return self.node("number", text=text, value=value)
        if kind == "name":
            return self.name(text, where)
        if (kind, text) == ("op", "("):
            inner = self.expression()
            self.expect(")", (kind, text, where))
            return inner
        if kind == "end":
            raise ExpressionError("ends where a number, name or '(' is expected" if self.text.strip()
                                  else "is empty")
        raise ExpressionError(f"unexpected '{text}' at character {where}")

    def name(self, text: str, where: int) -> Node:
        is_call = self.peek()[:2] == ("op", "(")
        if text in self.functions:
            if not is_call:
                raise ExpressionError(f"'{text}' is a function: write {text}(...)")
            return self.call(text, self.take())
        if text not in self.names and text not in self.constants:
            known = ", ".join(list(self.names) + list(self.constants) + list(self.functions))
            raise ExpressionError(f"'{text}' is not defined (known here: {known})")
        if is_call:
            raise ExpressionError(f"'{text}' at character {where} is not a function")
        value = self.constants.get(text)
        return self.node("name", text=text, value=value, degree=0 if value is not None else 1)

    def call(self, function: str, opened: tuple[str, str, int]) -> Node:
        args = [self.expression()]
        while self.peek()[:2] == ("op", ","):
            self.take()
            args.append(self.expression())
        self.expect(")", opened)
        if len(args) != self.functions[function]:
            raise ExpressionError(f"{function}() takes {self.functions[function]} argument(s), got {len(args)}")
        value = None
        if all(a.value is not None for a in args) and function in MATH:
            try:
                value = _constant(MATH[function](*(a.value for a in args)), f"{function}(...)")
            except ValueError as err:
                raise ExpressionError(f"{function}({args[0].value!r}) is not a real number") from err
        return self.node("call", text=function, args=tuple(args), value=value,
                         degree=max([1] + [a.degree for a in args]))


MATH = {"sin": math.sin, "cos": math.cos, "sqrt": math.sqrt}


@dataclass(frozen=True)
class Expression:
    """A parsed text: build it with `evaluate`."""
    text: str
    tree: Node

    def evaluate(self, values: dict, functions: dict, number):
        """The tree built from `values` (name -> object), `functions` (name -> callable) and
        `number` (a number's text -> object), with Python's operators in Python's order."""
        return _evaluate(self.tree, values, functions, number)

    @property
    def value(self) -> float | None:
        """The double of a text that is a number (pi/2, 1e-3), else None."""
        return self.tree.value


_BINARY = {"+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b,
           "/": lambda a, b: a / b, "@": lambda a, b: a @ b}


def _evaluate(node: Node, values: dict, functions: dict, number):
    kind = node.kind
    if kind == "number":
        return number(node.text)
    if kind == "name":
        return values[node.text]
    if kind == "neg":
        return -_evaluate(node.args[0], values, functions, number)
    if kind == "pos":
        return +_evaluate(node.args[0], values, functions, number)
    if kind == "pow":
        return _evaluate(node.args[0], values, functions, number) ** _evaluate(node.args[1], values, functions, number)
    if kind == "call":
        return functions[node.text](*(_evaluate(a, values, functions, number) for a in node.args))
    result = _evaluate(node.args[0], values, functions, number)
    for op, operand in node.rest:
        result = _BINARY[op](result, _evaluate(operand, values, functions, number))
    return result


def parse(text: str, names, functions: dict[str, int] | None = None, constants: dict[str, float] | None = None,
          max_degree: int = MAX_DEGREE, max_number: float = math.inf, matrices: bool = False) -> Expression:
    """`text` as an Expression over `names` (any container of allowed names), `functions`
    (name -> number of arguments; default sin, cos, sqrt) and `constants` (named numbers; default
    pi), `max_degree` and `max_number` (the largest number written), and whether its names are
    `matrices` (task formulas: `@`, no `**`); anything else is an ExpressionError saying what and
    where (characters count from 1)."""
    if not isinstance(text, str):
        raise ExpressionError(f"must be a string, got {text!r}")
    parser = _Parser(text, names, SCALAR_FUNCTIONS if functions is None else functions,
                     SCALAR_CONSTANTS if constants is None else constants, max_degree, max_number, matrices)
    return Expression(text, parser.whole())


# --- the arithmetics the derivation builds expressions in ------------------------------------------

def python_number(text: str):
    """A number as Python's eval reads it: an int, or a float where it has a point or exponent."""
    return int(text) if text.isascii() and text.isdigit() else float(text)


def sympy_number(rational: bool):
    """A number as sympify reads it: Integer, or Float (Rational, exactly, with `rational`)."""
    import sympy as sp

    def number(text: str):
        if text.isascii() and text.isdigit():
            return sp.Integer(text)
        return sp.Rational(text) if rational else sp.Float(text)
    return number


def sympy_expression(text: str, symbols: dict, rational: bool = True):
    """`text` as the SymPy expression sympify(text, locals=symbols + sin, cos, sqrt, pi,
    rational=...) gives, built from the tree (no text reaches SymPy's parser)."""
    import sympy as sp
    tree = parse(text, symbols)
    values = dict(symbols, pi=sp.pi)
    return tree.evaluate(values, {"sin": sp.sin, "cos": sp.cos, "sqrt": sp.sqrt}, sympy_number(rational))


def number_value(text: str) -> float:
    """A text that must be a number (pi/2, -1e-3, sqrt(2)/2): its double."""
    value = parse(text, ()).value
    if value is None:  # unreachable with no names: every tree of numbers has a value
        raise ExpressionError("is not a number")
    return value


# Task formulas: products of a few matrices (tasks.toml's are of degree <= 5) and numbers. The
# bounds keep the symbolic inverse and simplification of a hostile formula short, and its values
# finite in double precision.
FORMULA_FUNCTIONS = {"inv": 1}
FORMULA_DEGREE = 8
FORMULA_NUMBER = 1e6


def formula(text: str, names) -> Expression:
    """A task formula over the matrix names of `names` and inv(...)."""
    return parse(text, names, FORMULA_FUNCTIONS, {}, FORMULA_DEGREE, FORMULA_NUMBER, matrices=True)
