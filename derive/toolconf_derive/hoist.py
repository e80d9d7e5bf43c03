"""Per-tool coefficients: split a function of (X, U; p) into parameter-only factors, computed once
per tool, and a per-call part that only combines them with the state and control.

Integrating one episode evaluates the dynamics ~10^3 times with the same tool parameters. In the
printed closed forms the parameters sit inside the expressions (e.g. the divisions by
l1^2 (m1/3 + m2) and l2^2 m2 in the paper's accelerations), so every call would recompute them.
Writing each output entry as sum_i c_i(p) r_i(X, U) moves every c_i into a struct built once per
tool; what is left per call has no division by a parameter expression at all (arm2).

An entry with a state-dependent denominator (the Lagrangian planar chains' mass-matrix inverse) is
not expanded, which would multiply its terms: its maximal parameter-only subexpressions are
replaced in place. The whole rewrite is kept only when the per-call code gets cheaper (weighted
operation count after CSE, cost.py); otherwise the coefficients are the parameters themselves, so
every model has the same `<name>_with` API. The counts before and after are stated in each
generated function's documentation.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .cost import cse_cost


@dataclass
class Hoisted:
    """`entries` rewritten over the coefficient symbols `symbols[i]` = `values[i]`(p);
    `unhoisted` is the cost (cost.py) of the entries as given, with the parameters inline."""
    symbols: list[sp.Symbol]
    values: list[sp.Expr]
    entries: list[sp.Expr]
    unhoisted: dict


def hoist(entries: list[sp.Expr], per_call: list[sp.Symbol], params: list[sp.Symbol],
          constants: set[sp.Symbol], prefix: str = "k") -> Hoisted:
    """Writes each entry as sum_i c_i(p) r_i(per_call). Numbers and the model's `constants` stay
    inline; anything else without a per-call symbol is a coefficient. If that is not cheaper per
    call, the coefficients are the `params` themselves."""
    per_call_set = set(per_call)
    values: list[sp.Expr] = []
    index: dict[sp.Expr, sp.Symbol] = {}
    symbols: list[sp.Symbol] = []

    def coefficient(c: sp.Expr, tidy: bool = True) -> sp.Expr:
        if tidy:
            c = sp.factor(sp.cancel(c))
        if c.is_Number or c in constants:
            return c
        # A coefficient and its negation share one field.
        for sign, key in ((1, c), (-1, sp.factor(-c))):
            if key in index:
                return sign * index[key]
        s = sp.Symbol(f"{prefix}{len(values)}", real=True)
        index[c] = s
        values.append(c)
        symbols.append(s)
        return s

    def structural(e: sp.Expr) -> sp.Expr:
        # Replaces every maximal parameter-only subexpression by a coefficient, keeping the
        # expression's shape: never more work per call, and cheap for large expressions.
        if not (e.free_symbols & per_call_set):
            return coefficient(e, tidy=False)
        if e.is_Atom:
            return e
        if e.is_Add or e.is_Mul:
            constant = [a for a in e.args if not (a.free_symbols & per_call_set)]
            varying = [structural(a) for a in e.args if a.free_symbols & per_call_set]
            if constant:
                varying.insert(0, coefficient(e.func(*constant), tidy=False))
            return e.func(*varying)
        return e.func(*[structural(a) for a in e.args])

    def state_dependent_denominator(e: sp.Expr) -> bool:
        return any(p.exp.is_negative and (p.base.free_symbols & per_call_set) for p in e.atoms(sp.Pow))

    rewritten = []
    for e in entries:
        if not (e.free_symbols & per_call_set):
            rewritten.append(coefficient(e))
            continue
        if state_dependent_denominator(e):
            # Expanding over a state-dependent denominator multiplies the terms (and the
            # derivation time) for nothing: hoist in place.
            rewritten.append(structural(e))
            continue
        groups: dict[sp.Expr, sp.Expr] = {}
        order: list[sp.Expr] = []
        for term in sp.Add.make_args(sp.expand(e, power_exp=False, log=False)):
            c, r = term.as_independent(*per_call, as_Add=False)
            if r not in groups:
                groups[r] = sp.Integer(0)
                order.append(r)
            groups[r] += c
        rewritten.append(sp.Add(*[coefficient(groups[r]) * r for r in order if groups[r] != 0]))

    before = cse_cost(entries)
    if cse_cost(rewritten)["weighted"] >= before["weighted"]:
        identity = [sp.Symbol(f"{prefix}{i}", real=True) for i in range(len(params))]
        rename = dict(zip(params, identity))
        return Hoisted(identity, list(params), [e.xreplace(rename) for e in entries], before)
    return Hoisted(symbols, values, rewritten, before)
