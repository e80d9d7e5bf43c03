"""Operation counts of the generated code: the header of every function in generated/<model>.rs
states its cost per call, taken from here and carried in the IR (so the drift check reviews it).

An operation is one node of SymPy's `count_ops` (ADD, SUB, MUL, DIV, NEG, POW, SIN, ...) over the
code as it is generated: the CSE temporaries and the output entries, each shared subexpression
counted once. The joints' `sin_cos` calls are counted apart (ir.joint_trigonometry). The weighted
count multiplies each kind by WEIGHTS, a rough relative latency on x86-64 (anything not listed
costs 1); hoist.py uses it to decide whether per-tool coefficients pay. count_ops reads a square
root as x**(1/2), one POW and one DIV, and a rational coefficient 3/4 as a DIV the compiler folds:
the counts compare derivations, they do not time them (docs/explanation/performance.md does).
"""

from __future__ import annotations

from collections import Counter

import sympy as sp

WEIGHTS = {"DIV": 8, "POW": 2, "SIN": 20, "COS": 20, "SQRT": 8, "EXP": 20, "LOG": 20}


def op_counts(exprs: list[sp.Expr]) -> Counter:
    """How many operations of each kind (count_ops' names) the expressions take."""
    counts: Counter = Counter()
    for e in exprs:
        visual = sp.count_ops(e, visual=True)
        if visual == 0:
            continue
        for kind, n in visual.as_coefficients_dict().items():
            counts[kind.name] += int(n)
    return counts


def cost(exprs: list[sp.Expr]) -> dict:
    """{"ops": total, "weighted": weighted total, "kinds": {kind: count} in name order}."""
    counts = op_counts(exprs)
    return {
        "ops": sum(counts.values()),
        "weighted": sum(n * WEIGHTS.get(kind, 1) for kind, n in counts.items()),
        "kinds": {kind: counts[kind] for kind in sorted(counts)},
    }


def total(*costs: dict) -> dict:
    """The cost of running code of each of `costs` one after the other."""
    counts: Counter = Counter()
    for c in costs:
        counts.update(c["kinds"])
    return {
        "ops": sum(c["ops"] for c in costs),
        "weighted": sum(c["weighted"] for c in costs),
        "kinds": {kind: counts[kind] for kind in sorted(counts)},
    }


def cse_cost(entries: list[sp.Expr]) -> dict:
    """The cost of `entries` after common-subexpression elimination, as the generator emits them."""
    replacements, reduced = sp.cse(entries, order="canonical")
    return cost([e for _, e in replacements] + list(reduced))
