"""Report data: the derived closed forms in LaTeX (SymPy's printer) and the entry-by-entry
comparison with what the paper prints. The report template renders this into generated/<model>.md."""

from __future__ import annotations

import mpmath
import sympy as sp

from . import ir_types as irt
from .symbolic import Derivation, cofactor_determinant, parse, tidy

# The tool at which the report states d ln|Pi^U|/dp: the middle of the paper's box [0.1, 0.6].
REFERENCE_PARAMETER = sp.Rational(7, 20)


def _latex(d: Derivation, e) -> str:
    return sp.latex(e, symbol_names=d.symbol_latex, mat_str="bmatrix", mat_delim="")


def _compare(d: Derivation, label: str, derived: sp.Matrix, printed_rows: list[list[str]]) -> list[irt.Comparison]:
    symbols = {str(s): s for s in d.params + list(d.constants)}
    rows = []
    for i, row in enumerate(printed_rows):
        for j, text in enumerate(row):
            printed = parse(d.model, text, symbols, f"printed.{label}[{i}][{j}]")
            difference = tidy(derived[i, j] - printed)
            rows.append(irt.Comparison(
                entry=f"{label}[{i + 1},{j + 1}]",
                derived=_latex(d, derived[i, j]),
                printed=_latex(d, printed),
                equal=difference == 0,
                difference=_latex(d, difference),
            ))
    return rows


def _equations(d: Derivation) -> list[irt.Equation]:
    m = d.model
    if d.lagrangian is None:
        return [irt.Equation(rf"\ddot{{{c.latex}}}", _latex(d, e)) for c, e in zip(m.q, d.q_ddot)]
    lag = d.lagrangian
    return [
        irt.Equation("T", _latex(d, lag["T"])),
        irt.Equation("V", _latex(d, lag["V"])),
        irt.Equation("M(q) = \\partial^2 T / \\partial \\dot q^2", _latex(d, lag["M"])),
        irt.Equation("Q", _latex(d, lag["Q"])),
        irt.Equation("\\ddot q", "M(q)^{-1}\\left(Q - \\frac{\\partial (M \\dot q)}{\\partial q}\\dot q"
                     " + \\frac{\\partial T}{\\partial q} - \\frac{\\partial V}{\\partial q}\\right)"),
    ]


def _gradient(d: Derivation, t, substitute: dict) -> irt.GradientReport:
    """d ln|Pi^U|/dp with the default precisions: its values at the reference tool (50-digit
    mpmath, printed to 6 digits, so the same text on every machine) and, for one joint, the
    closed form (for more joints it runs to pages; the generated code has it, CSE'd)."""
    gradient = t.logdet_gradient.subs(substitute).subs(d.constants)
    evaluate = sp.lambdify(d.params, list(gradient), modules="mpmath")
    with mpmath.workdps(50):
        values = evaluate(*[mpmath.mpf(REFERENCE_PARAMETER.p) / REFERENCE_PARAMETER.q] * len(d.params))
        shown = [mpmath.nstr(mpmath.mpf(v), 6) for v in values]
    closed = None
    if d.model.dof == 1:
        pi = t.confidence.subs(substitute)
        closed = [irt.GradientClosedForm(p.name, _latex(d, tidy(sp.diff(sp.log(cofactor_determinant(pi)), p))))
                  for p in d.params]
    return irt.GradientReport(
        reference=f"{float(REFERENCE_PARAMETER)}",
        values=[irt.GradientValue(p.name, v) for p, v in zip(d.params, shown)],
        closed=closed,
    )


def report_data(d: Derivation) -> irt.ClosedFormReport:
    m = d.model
    n = m.dof
    comparisons = []
    if m.printed_a is not None:
        comparisons += _compare(d, "A", d.a, m.printed_a)
    if m.printed_b is not None:
        comparisons += _compare(d, "B", d.b, m.printed_b)

    tasks = []
    for t in d.tasks:
        task = t.task
        defaults = {term: sp.nsimplify(task.default_precision[term]) * sp.eye(n) for term in task.terms}
        confidence_default = t.confidence.subs(
            {s: defaults[term][i, j] for term, reads in t.precision_reads.items() for s, i, j in reads}
        ).applyfunc(tidy)
        formula = " + ".join(
            rf"\left(\frac{{\partial {task.term(term).latex}}}{{\partial U}}\right)^{{T}} P^{{{task.term(term).latex}}}"
            rf" \frac{{\partial {task.term(term).latex}}}{{\partial U}}"
            for term in task.sensitivity_terms
        ) + r" + P^{U}"
        tasks.append(irt.TaskReport(
            name=task.name,
            index=task.index,
            title=task.title,
            doc=task.doc,
            sensitivities=[
                irt.SensitivityReport(term=term, what=rf"\frac{{\partial {task.term(term).latex}}}{{\partial U}}",
                                      formula=task.sensitivity[term], latex=_latex(d, t.sensitivity[term]))
                for term in task.sensitivity_terms
            ],
            confidence_formula=formula,
            default_precisions=", ".join(
                f"P^{{{task.term(term).latex}}} = {sp.latex(sp.nsimplify(task.default_precision[term]))} I"
                for term in task.terms
            ),
            confidence_default=_latex(d, confidence_default),
            gradient=_gradient(d, t, {s: defaults[term][i, j] for term, reads in t.precision_reads.items()
                                      for s, i, j in reads}),
            remarks=[
                irt.Remark(
                    what=rf"\frac{{\partial {task.term(r['remark'].term).latex}}}{{\partial U}}",
                    text=" ".join(r["remark"].text.split()),
                    alternative_formula=r["remark"].alternative,
                    alternative=_latex(d, r["alternative"]),
                    used=_latex(d, r["used"]),
                    equal=(r["alternative"] - r["used"]).applyfunc(tidy) == sp.zeros(n, n),
                )
                for r in t.remarks
            ],
        ))

    return irt.ClosedFormReport(
        printed_where=m.printed_where,
        equations=_equations(d),
        equation_refs=m.equations,
        equilibrium_x=_latex(d, d.x_e.T),
        equilibrium_u=_latex(d, d.u_e.T),
        a=_latex(d, d.a),
        b=_latex(d, d.b),
        comparisons=comparisons,
        differences=[c for c in comparisons if not c.equal],
        tasks=tasks,
    )
