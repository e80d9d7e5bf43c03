"""The intermediate representation: one JSON document per model that the Tera renderer turns into
Rust and a report. It carries the CSE'd expressions (printed as Rust f64 code), the shapes, the
docs, and the CasADi test vectors; the renderer needs nothing else. The document is built of
ir_types' dataclasses, made from the types the renderer reads it into (derive/render/src/ir.rs)."""

from __future__ import annotations

import numpy as np
import sympy as sp

from . import ir_types as irt
from . import progress
from .cost import cost, total
from .crosscheck import check_against_casadi
from .description import name_keys, rust_constant
from .errors import DescriptionError
from .expression import sympy_expression
from .functions import Arg, Function
from .hoist import hoist
from .rust_printer import RustPrinter, float_literal
from .symbolic import Derivation

# The renderer's, as derive/ir_schema.json gives it.
IR_SCHEMA = irt.IR_SCHEMA


def _rust_type(shape: tuple[int, int]) -> str:
    r, c = shape
    return f"SVector<f64, {r}>" if c == 1 else f"SMatrix<f64, {r}, {c}>"


def _scopes(f: irt.Function) -> list[tuple[str, list[str]]]:
    """The names each Rust scope of one function's IR declares (arguments and lets), as
    templates/model.rs.tera renders them."""
    body = [e.name for e in f.constants + f.bindings + f.compounds + f.temporaries]
    body += [side for t in f.trig for side in (t.sin, t.cos) if side != "_"]
    body += [slot.name for slot in (f.sequence.slots if f.sequence else [])]
    body += [o.name for o in f.outputs]
    c = f.coefficients
    if c is None:
        return [(f.name, [a.name for a in f.args] + body)]
    return [(f.name + "_with", [a.name for a in c.args] + body),
            (f"{c.struct}::new", ["params"] + [e.name for e in c.constants + c.bindings + c.temporaries])]


def check_rust_names(m, functions: list[irt.Function]) -> None:
    """Every name in a generated scope is declared once: a description name equal to one the
    generated code uses (an argument such as `x`, an output such as `a`, a temporary `t3`, the
    `sin_q` of a joint angle) would shadow it and silently change the arithmetic."""
    keys = name_keys(m)
    for scope, names in (s for f in functions for s in _scopes(f)):
        seen: set[str] = set()
        for name in names:
            if name in seen:
                if name in keys:
                    raise DescriptionError(m.path, keys[name], f"'{name}' is also a name the generated {scope} uses "
                                                               "for its own values; rename it")
                raise ValueError(f"{m.name}: the generated {scope} declares '{name}' twice")
            seen.add(name)


def _temporaries(prefix: str, taken: set[str]):
    """t0, t1, ... without the model's own names: a control named `t0` keeps its name, and the
    temporaries skip it (check_rust_names then finds every scope's names distinct)."""
    return (sp.Symbol(f"{prefix}{i}", real=True) for i in range(10**6) if f"{prefix}{i}" not in taken)


def _trig_symbols(angle: sp.Symbol) -> tuple[sp.Symbol, sp.Symbol]:
    return sp.Symbol(f"sin_{angle.name}", real=True), sp.Symbol(f"cos_{angle.name}", real=True)


def joint_trigonometry(entries: list[sp.Expr], angles: list[sp.Symbol]):
    """Replaces every sine and cosine in `entries` by a symbol: sin_q, cos_q for a joint angle q,
    and for an angle sum or difference (sin(q1 - q2), ...) a `trig<i>` defined from those by the
    addition theorems. One `sin_cos` per joint then covers all trigonometry (generated/src/trig.rs), and
    the entries keep their shape (each compound is one atom for hoisting and CSE).
    Returns the rewritten entries and the compound definitions [(symbol, expression)]."""
    single = {}
    for q in angles:
        s, c = _trig_symbols(q)
        single[sp.sin(q)] = s
        single[sp.cos(q)] = c
    atoms = set()
    for e in entries:
        atoms |= e.atoms(sp.sin, sp.cos)
    replace, compounds = dict(single), []
    for a in sorted(atoms - set(single), key=sp.default_sort_key):
        if not (a.args[0].free_symbols <= set(angles)):
            continue
        symbol = sp.Symbol(f"trig{len(compounds)}", real=True)
        compounds.append((symbol, sp.expand_trig(a).xreplace(single)))
        replace[a] = symbol
    return [e.xreplace(replace) for e in entries], compounds


def _code(entries: list[sp.Expr], d: Derivation, args: list, declared: set[str], prefix: str,
          angles: list[sp.Symbol] = (), compounds: list[tuple[sp.Symbol, sp.Expr]] = ()) -> dict:
    """CSE'd Rust for `entries`: the constants and argument elements it reads, the joint angles'
    sin_cos it needs, its temporaries, the reduced entries and what they cost per call."""
    replacements, reduced = sp.cse(entries, symbols=_temporaries(prefix, declared), order="canonical")
    used = set()
    for _, e in replacements:
        used |= e.free_symbols
    for e in reduced:
        used |= e.free_symbols
    printer = RustPrinter()
    compound_code, compound_definitions = [], []
    for symbol, definition in compounds:
        if symbol in used:
            used |= definition.free_symbols
            compound_code.append(irt.Let(symbol.name, printer(definition)))
            compound_definitions.append(definition)
    trig = []
    for q in angles:
        s, c = _trig_symbols(q)
        if s in used or c in used:
            used.add(q)
            trig.append(irt.Trig(q.name, s.name if s in used else "_", c.name if c in used else "_"))
    bindings = []
    for arg in args:
        for s, i, j in arg.reads:
            if s in used:
                if arg.name == "coefficients":
                    access = f"coefficients.k[{i}]"
                else:
                    access = f"{arg.name}[{i}]" if arg.shape[1] == 1 else f"{arg.name}[({i}, {j})]"
                bindings.append(irt.Binding(s.name, arg.name, access))
    return {
        "constants": [irt.Let(c.name, rust_constant(c.name)) for c in d.constants if c in used],
        "bindings": bindings,
        "trig": trig,
        "compounds": compound_code,
        "temporaries": [irt.Let(str(t), printer(e)) for t, e in replacements],
        "reduced": [printer(e) for e in reduced],
        "cost": cost(compound_definitions + [e for _, e in replacements] + list(reduced)) | {"sin_cos": len(trig)},
        "compound_cost": cost(compound_definitions),
    }


def _struct_name(function: str) -> str:
    return "".join(w.capitalize() for w in function.split("_")) + "Coefficients"


def function_ir(fn: Function, d: Derivation) -> irt.Function:
    declared = {s.name for s in d.params + list(d.constants) + d.x + d.u}
    for arg in fn.args:
        declared |= {s.name for s, _, _ in arg.reads}
    entries, where = [], []
    for oi, out in enumerate(fn.outputs):
        for r in range(out.value.rows):
            for c in range(r if out.symmetric else 0, out.value.cols):
                if out.value[r, c] != 0:
                    entries.append(out.value[r, c])
                    where.append((oi, r, c))

    coefficients = None
    call_args = fn.args
    angles: list[sp.Symbol] = []
    compounds: list[tuple[sp.Symbol, sp.Expr]] = []
    if fn.per_tool_coefficients:
        angles = d.x[:d.model.dof]
        entries, compounds = joint_trigonometry(entries, angles)
        per_call = [s for a in fn.args if a.name != "params" for s, _, _ in a.reads]
        per_call += [t for q in angles for t in _trig_symbols(q)] + [c for c, _ in compounds]
        params = [a for a in fn.args if a.name == "params"]
        hoisted = hoist(entries, per_call, d.params, set(d.constants))
        k = Arg("coefficients", "", (len(hoisted.symbols), 1), [(s, i, 0) for i, s in enumerate(hoisted.symbols)],
                False, None)
        coefficient_code = _code(hoisted.values, d, params, declared, "s")
        coefficients = irt.Coefficients(
            struct=_struct_name(fn.name),
            count=len(hoisted.symbols),
            constants=coefficient_code["constants"],
            bindings=coefficient_code["bindings"],
            temporaries=coefficient_code["temporaries"],
            values=coefficient_code["reduced"],
            cost=irt.Cost(**coefficient_code["cost"]),
            args=[],
        )
        entries = hoisted.entries
        call_args = [a for a in fn.args if a.name != "params"] + [k]
    elif any(a.name == "q" for a in fn.args):
        # A function of the joint positions alone (the tip): the same one sin_cos per joint.
        angles = d.q
        entries, compounds = joint_trigonometry(entries, angles)
    code = _code(entries, d, call_args, declared, "t", angles, compounds)
    unhoisted = None
    if coefficients is not None:
        # What one call of `name(x, u, params)` would take with the parameters inline (the same
        # sin_cos and angle sums), to set against the coefficients' once-per-tool cost.
        unhoisted = irt.Cost(**(total(hoisted.unhoisted, code["compound_cost"]) | {"sin_cos": code["cost"]["sin_cos"]}))

    outputs = [irt.Output(name=out.name, doc=out.doc, rows=out.value.rows, cols=out.value.cols,
                          rust_type=_rust_type(out.value.shape), symmetric=out.symmetric, entries=[])
               for out in fn.outputs]
    for (oi, r, c), e in zip(where, code["reduced"]):
        outputs[oi].entries.append(irt.Entry(row=r, col=c, rust=e))

    bound_args = {b.arg for b in code["bindings"]}
    if coefficients is not None:
        coefficients.args = [
            irt.CoefficientArg(name=a.name, rust_type="&" + (coefficients.struct if a.name == "coefficients"
                                                             else _rust_type(a.shape)),
                               used=a.name in bound_args)
            for a in call_args
        ]
    return irt.Function(
        name=fn.name,
        doc=fn.doc,
        equation=fn.equation,
        args=[
            irt.Arg(name=a.name, doc=a.doc, rows=a.shape[0], cols=a.shape[1], rust_type=_rust_type(a.shape),
                    symmetric=a.symmetric,
                    used=a.name in bound_args or (coefficients is not None and a.name == "params"))
            for a in fn.args
        ],
        coefficients=coefficients,
        cost=irt.Cost(**code["cost"]),
        unhoisted_cost=unhoisted,
        outputs=outputs,
        constants=code["constants"],
        bindings=code["bindings"],
        trig=code["trig"],
        compounds=code["compounds"],
        temporaries=code["temporaries"],
    )


def test_vectors(fn: Function, d: Derivation, count: int) -> list[dict]:
    """`count` random valid inputs and CasADi's outputs for them (row-major), after checking
    that SymPy's closed forms give the same numbers: the derivation stops if they do not.
    Inputs are exact dyadics and outputs CasADi's exact values rounded once to double, so the
    numbers are the same on every machine (exact.py)."""
    rng = fn.rng()
    samples = [{a.name: a.sample(rng) for a in fn.args} for _ in range(count)]
    reference = [[o.to_numpy() for o in fn.casadi(v)] for v in samples]
    check_against_casadi(fn, d, samples, reference)
    progress.step("checking", f"{fn.name}: SymPy = CasADi at {count} points")
    return [
        {
            "inputs": {name: [float(x) for x in np.asarray(val).reshape(-1)] for name, val in v.items()},
            "outputs": {o.name: [float(x) for x in ref.reshape(o.value.shape).reshape(-1)]
                        for o, ref in zip(fn.outputs, refs)},
        }
        for v, refs in zip(samples, reference)
    ]


def vectors_document(d: Derivation, functions: list[Function], generator: irt.Generator, count: int) -> dict:
    """The test vectors file (generated/<model>.vectors.json), kept out of the IR so that a change
    to a derivation reads as an IR and code diff, not as thousands of changed numbers. The
    renderer does not read it (the generated crate's tests/vectors.rs does)."""
    return {
        "schema": IR_SCHEMA,
        "generator": generator,
        "model": d.model.name,
        "tolerance": "max|rust - casadi| <= 1e-12 max|casadi| per output (the generated crate's tests/vectors.rs)",
        "functions": [{"name": fn.name, "vectors": test_vectors(fn, d, count)} for fn in functions],
    }


def _goal(m, task, term: str) -> list[str]:
    """The description's goal of `term` in `task` (zero where it gives none), one entry per joint:
    a goal at the tip (TIP_DIM entries) padded with zeros, as tasks.toml's J pads its rows."""
    values = m.goals.get(task.name, {}).get(term, [])
    return list(values) + ["0"] * (m.dof - len(values))


def _formulation(task) -> irt.Formulation:
    doc = task.formulations[task.formulation].doc if task.formulation in task.formulations else ""
    return irt.Formulation(name=task.formulation, doc=doc, chosen_by=task.chosen_by)


def _reported(f: irt.Function) -> irt.Function:
    progress.step("deriving", f"{f.name}: code")
    return f


def model_ir(d: Derivation, functions: list[Function], generator: irt.Generator, report: irt.ClosedFormReport,
             vectors: int) -> irt.Ir:
    """The IR; `vectors` is the number of test vectors per function, which live in their own file."""
    printer = RustPrinter()
    return model_document(d.model, [printer(v) for v in d.x_e], [printer(v) for v in d.u_e],
                          [t.task for t in d.tasks], [_reported(function_ir(fn, d)) for fn in functions], generator,
                          report, vectors)


def _tool_rule(rule: dict) -> irt.ToolRule:
    """The rule urdf_description.tool_rule gives as a dict, as the IR's."""
    inertia = rule.get("inertia")
    return irt.ToolRule(domains=[irt.Domain(**d) for d in rule["domains"]],
                        constraints=[irt.Constraint(**c) for c in rule["constraints"]],
                        sample=rule["sample"], defaults=rule["defaults"],
                        inertia=None if inertia is None else irt.Inertia(**inertia), source=rule["source"])


def model_document(m, x_e: list[str], u_e: list[str], tasks: list, functions: list[irt.Function],
                   generator: irt.Generator, report: irt.ClosedFormReport | irt.UrdfReport, vectors: int,
                   templates: list[str] | None = None) -> irt.Ir:
    """The IR of model `m` around its functions' IR, with the equilibrium as Rust literals and the
    tasks of tasks.toml; `templates` names the template variants it renders through."""
    check_rust_names(m, functions)
    printer = RustPrinter()
    return irt.Ir(
        schema=IR_SCHEMA,
        generator=generator,
        model=irt.Model(
            name=m.name,
            title=m.title,
            source=m.source,
            dof=m.dof,
            state_dim=m.state_dim,
            tip_dim=m.tip_dim,
            parameters=[irt.Parameter(p.name, p.latex, p.unit, p.doc) for p in m.parameters],
            constants=[irt.Constant(c.name, rust_constant(c.name), c.value, c.unit, c.doc) for c in m.constants],
            state=[irt.Variable(s.name, s.latex) for s in m.state],
            control=[irt.Variable(s.name, s.latex) for s in m.u],
            equilibrium=irt.Equilibrium(x=x_e, u=u_e),
            # Only where the description states one (a URDF tool): without it the renderer gives
            # every parameter the planar arms' rule (> 0, drawn from [0.1, 0.6]).
            tool_rule=None if m.tool_rule is None else _tool_rule(m.tool_rule),
        ),
        terms=[irt.Term(t.name, t.symbol, t.latex, t.doc, t.label, t.unit, irt.TermRead(t.source, t.block), t.goal_range)
               for t in (tasks[0].all_terms if tasks else ())],
        cost_order=list(tasks[0].cost_order if tasks else ()),
        tasks=[
            irt.Task(
                name=t.name, index=t.index, title=t.title, doc=t.doc,
                terms=t.terms, sensitivity_terms=t.sensitivity_terms, error=t.error,
                sensitivity_function=t.sensitivity_function,
                confidence_function=t.confidence_function,
                gradient_function=t.gradient_function,
                goals=[irt.Goal(term, [printer(sympy_expression(v, {}, rational=False)) for v in _goal(m, t, term)])
                       for term in t.sensitivity_terms],
                precisions=[irt.Precision(term, float_literal(t.default_precision[term]), t.default_precision[term])
                            for term in t.terms],
                formulation=_formulation(t),
            )
            for t in tasks
        ],
        functions=functions,
        test_vectors=irt.TestVectors(file=generator.vectors, per_function=vectors),
        report=report,
        templates=templates,
    )
