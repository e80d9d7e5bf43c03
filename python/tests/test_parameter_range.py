"""The valid ranges keep the generated arithmetic finite: derived from the expressions themselves.

The IR of every model (``generated/<model>.json``) holds each temporary and output of every
generated function as the Rust expression the runtime evaluates. Every intermediate value is
bounded here by interval arithmetic on log10|value|, with every tool parameter in
``toolconf.ranges()["tool_parameter"]`` = [10^-k, 10^k], precision entries |P| <= 10^kp, states and
torques within the divergence bound and sin, cos within [-1, 1]:

* a product adds the bounds, a quotient subtracts them, an integer power multiplies them (so a
  term's bound moves by its degree in the parameters, factor by factor, per decade of k: m·l²
  by 3, 1/(m·l²)² by 6);
* a sum of terms of one sign is at least its largest term and at most twice it; a sum of
  mixed signs may vanish, so it has no lower bound;
* a division by a quantity that may vanish has no upper bound: the exact models' mass-matrix
  determinant in the dynamics, det Π^U in ∂ln|Π^U|/∂p. Those are checked at run time instead (an
  episode's state must stay finite, design treats a non-finite gradient as undefined), and what
  is computed from them is left out of the bound.

The test asserts that everything bounded stays within 10^±300 (f64 overflows past 1.8·10^308,
and turns subnormal, losing digits, below 2.2·10^-308), and that Π^U's entries stay below
10^150, so that ln|Π^U|'s 2×2 determinant Π₀₀Π₁₁ − Π₀₁² cannot overflow either. It also shows the
range is not much narrower than it could be: at k = 9 some bound passes 10^300.
"""

import ast
import json
import math
from pathlib import Path

import toolconf

GENERATED = Path(__file__).resolve().parents[2] / "generated"
INF = math.inf
LOG2 = math.log10(2)
LIMIT = 300.0


class Bound:
    """log10 bounds of |v| (lo = -inf: v may be 0) and its sign (+1, -1, or 0: either)."""

    __slots__ = ("hi", "lo", "sign")

    def __init__(self, hi, lo, sign):
        self.hi, self.lo, self.sign = hi, lo, sign


def constant(c):
    if c == 0:
        return Bound(-INF, -INF, 0)
    return Bound(math.log10(abs(c)), math.log10(abs(c)), 1 if c > 0 else -1)


def add(a, b):
    if a.hi == -INF:
        return b
    if b.hi == -INF:
        return a
    hi = max(a.hi, b.hi) + LOG2
    if a.sign == b.sign != 0:
        return Bound(hi, max(a.lo, b.lo), a.sign)
    return Bound(hi, -INF, 0)


def negate(a):
    return Bound(a.hi, a.lo, -a.sign)


def multiply(a, b):
    return Bound(a.hi + b.hi, a.lo + b.lo, a.sign * b.sign)


def divide(a, b):
    if b.lo == -INF:
        return Bound(INF, -INF, 0)
    return Bound(a.hi - b.lo, a.lo - b.hi, a.sign * b.sign)


def power(a, n):
    if n == 0:
        return constant(1.0)
    sign = a.sign if n % 2 else (1 if a.lo > -INF else 0)
    if n > 0:
        return Bound(n * a.hi, n * a.lo, sign)
    if a.lo == -INF:
        return Bound(INF, -INF, 0)
    return Bound(n * a.lo, n * a.hi, sign)


class Evaluator:
    """Bounds every node of the expressions it is given, in the order the code evaluates them."""

    def __init__(self, names):
        self.names = names
        self.nodes = []

    def expression(self, rust):
        # The IR's Rust is Python's syntax but for `x.powi(n)`.
        return self.node(ast.parse(rust, mode="eval").body)

    def node(self, n):
        if isinstance(n, ast.Constant):
            return constant(float(n.value))
        if isinstance(n, ast.Name):
            return self.names[n.id]
        if isinstance(n, ast.UnaryOp) and isinstance(n.op, ast.USub):
            return negate(self.node(n.operand))
        if isinstance(n, ast.BinOp):
            a, b = self.node(n.left), self.node(n.right)
            op = {ast.Add: add, ast.Sub: lambda x, y: add(x, negate(y)), ast.Mult: multiply,
                  ast.Div: divide}[type(n.op)]
            result = op(a, b)
        elif isinstance(n, ast.Call) and n.func.attr == "powi":
            exponent = ast.literal_eval(n.args[0])
            result = power(self.node(n.func.value), exponent)
        else:
            raise AssertionError(f"unexpected expression {ast.dump(n)}")
        self.nodes.append(result)
        return result


def analyse(model, k, kp, state):
    """(function name, largest hi, smallest finite lo, largest hi of its outputs) of every
    generated function of `model`, over the nodes with a bound."""
    ir = json.loads((GENERATED / f"{model}.json").read_text())
    values = {c["name"]: c["value"] for c in ir["model"]["constants"]}
    out = []
    for f in ir["functions"]:
        e = Evaluator({})
        parameter = Bound(k, -k, 1)

        def bind(binding, coefficient_values):
            arg = binding["arg"]
            if arg == "params":
                return parameter
            if arg.startswith("p_"):
                return Bound(kp, -INF, 0)
            if arg == "coefficients":
                return coefficient_values[int(binding["access"].split("[")[1].rstrip("]"))]
            return Bound(state, -INF, 0)

        coefficients = f.get("coefficients") or {}
        for c in coefficients.get("constants", []) + f["constants"]:
            e.names[c["name"]] = constant(values[c["name"]])
        for b in coefficients.get("bindings", []):
            e.names[b["name"]] = bind(b, [])
        for t in coefficients.get("temporaries", []):
            e.names[t["name"]] = e.expression(t["rust"])
        kv = [e.expression(v) for v in coefficients.get("values", [])]
        for b in f["bindings"]:
            e.names[b["name"]] = bind(b, kv)
        for t in f["trig"]:
            e.names[t["sin"]] = e.names[t["cos"]] = Bound(0.0, -INF, 0)
        for t in f["compounds"] + f["temporaries"]:
            e.names[t["name"]] = e.expression(t["rust"])
        outputs = [e.expression(entry["rust"]) for o in f["outputs"] for entry in o["entries"]]
        bounded = [v for v in e.nodes + outputs + kv if v.hi < INF]
        out.append((
            f["name"],
            max((v.hi for v in bounded), default=-INF),
            min((v.lo for v in bounded if v.lo > -INF), default=INF),
            max((v.hi for v in outputs if v.hi < INF), default=-INF),
        ))
    return out


def stated():
    ranges = toolconf.ranges()
    low, high = ranges["tool_parameter"]["low"], ranges["tool_parameter"]["high"]
    assert low * high == 1.0, "the analysis takes the parameter box symmetric in log10"
    return (math.log10(high), math.log10(ranges["precision_entry"]["high"]),
            math.log10(ranges["state"]["high"]))


def closed_form_models():
    """The models whose generated functions are closed forms, one expression per entry (the
    planar arms, msd). A URDF arm's are CasADi work-slot sequences (RNEA, CRBA, LDLᵀ) with no
    degree in the parameters to bound: tests/parameter_range.rs evaluates them at the corners
    of the model's own tool domain instead."""
    models = []
    for model in toolconf.models():
        ir = json.loads((GENERATED / f"{model}.json").read_text())
        if not any(f.get("sequence") for f in ir["functions"]):
            models.append(model)
    return models


def test_every_generated_value_stays_finite_over_the_stated_ranges():
    k, kp, state = stated()
    assert {p.stem for p in GENERATED.glob("*.json") if not p.stem.endswith(".vectors")} \
        == set(toolconf.models())
    models = closed_form_models()
    assert {"arm2", "arm3", "msd"} <= set(models)
    for model in models:
        for name, hi, lo, outputs_hi in analyse(model, k, kp, state):
            assert hi <= LIMIT, f"{model} {name}: a value may reach 10^{hi:.0f}"
            assert lo >= -LIMIT, f"{model} {name}: a value may fall to 10^{lo:.0f}"
            if name.endswith("_control_confidence"):
                assert 2 * outputs_hi <= LIMIT, f"{model} {name}: Π^U up to 10^{outputs_hi:.0f}"


def test_the_range_could_not_be_much_wider():
    _, kp, state = stated()
    widest = max(hi for model in closed_form_models()
                 for _, hi, _, _ in analyse(model, 9.0, kp, state))
    assert widest > LIMIT, widest


def test_the_bound_follows_a_terms_degree():
    # B of the paper's arm has 3/(m2·l2²) and (3/2)·(3l1 + 2l2)/l2 · 1/(l1²(m1 + 3m2)): factor by
    # factor, degrees 3 and 1 + 1 + 3 = 5 (an upper bound: l1/l1² counts 3, not 1), so its
    # bound moves by 5 decades per decade of k; A's g·m2/(l1(m1 + 3m2)) by 3.
    narrow = {name: hi for name, hi, _, _ in analyse("arm2", 2.0, 0.0, 6.0)}
    wide = {name: hi for name, hi, _, _ in analyse("arm2", 3.0, 0.0, 6.0)}
    assert round(wide["input_matrix"] - narrow["input_matrix"], 6) == 5.0
    assert round(wide["state_matrix"] - narrow["state_matrix"], 6) == 3.0
