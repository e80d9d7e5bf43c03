"""CasADi SX functions as the IR's straight-line code: CasADi's own instruction list, one step per
instruction on CasADi's work slots, beside the same bindings and trig as the SymPy closed forms;
templates/model.rs.tera renders it (derive/render/src/functions.rs).

For models too large for closed forms (URDF arms, urdf_model.py). Every instruction becomes one
binary or unary f64 operation on named values or literals: +, -, *, /, negation. The sine and
cosine of a joint angle (CasADi's SIN and COS of an input) become one `crate::trig::sin_cos`
call per angle, as for the closed forms; any other operation (sqrt, exp, log, ...) is refused, so
the generated code needs no f64 method and stays `core`-only. Constants are printed with Python's
shortest round-trip repr: the same bits on every machine.
"""

from __future__ import annotations

import re
from collections import Counter

import casadi as ca

from .cost import WEIGHTS
from .rust_printer import float_literal

BINARY = {ca.OP_ADD: ("ADD", "{a} + {b}"), ca.OP_SUB: ("SUB", "{a} - {b}"), ca.OP_MUL: ("MUL", "{a} * {b}"),
          ca.OP_DIV: ("DIV", "{a} / {b}")}
UNARY = {ca.OP_NEG: ("NEG", "-{a}"), ca.OP_SQ: ("MUL", "{a} * {a}"), ca.OP_TWICE: ("MUL", "2.0 * {a}"),
         ca.OP_INV: ("DIV", "1.0 / {a}")}
TRIG = {ca.OP_SIN: "sin", ca.OP_COS: "cos"}


class SequenceError(ValueError):
    pass


def _literal(value: float) -> str:
    text = float_literal(value)
    return f"({text})" if text.startswith("-") else text


def _access(arg: dict, row: int, col: int) -> str:
    if arg["name"] == "coefficients":
        return f"coefficients.k[{row}]"
    return f"{arg['name']}[{row}]" if arg["cols"] == 1 else f"{arg['name']}[({row}, {col})]"


def instructions(f: ca.Function, args: list[dict], outputs: list[str] | None = None, prefix: str = "w") -> dict:
    """The IR body of `f` (inputs in the order of `args`, each {name, rows, cols}; outputs named
    `outputs`): bindings of the input elements it reads, the joint angles' sin_cos, and the
    steps, one per instruction, on CasADi's work slots (declared once each, `sequence.slots`)
    or writing an output entry, with the operation count.

    Work slots rather than one `let` per instruction: rustc nests a debug-info scope per `let`,
    and LLVM's DWARF writer recurses once per scope, which overflowed its stack at ~16 000 `let`s
    (the Panda's gradients); CasADi's register-allocated slots are a few hundred per function,
    and LLVM turns them back into single assignment (mem2reg)."""
    outputs = outputs or [f"out{i}" for i in range(f.n_out())]
    alias: dict[int, str] = {}
    bindings, trig, steps = [], {}, []
    entries = [[] for _ in range(f.n_out())]
    in_nz = [list(zip(*f.sparsity_in(i).get_triplet())) for i in range(f.n_in())]
    out_nz = [list(zip(*f.sparsity_out(i).get_triplet())) for i in range(f.n_out())]
    shapes = [(f.size1_out(i), f.size2_out(i)) for i in range(f.n_out())]
    bound: dict[tuple[int, int], str] = {}
    writes: Counter = Counter()
    counts: Counter = Counter()

    def assign(slot: int, rust: str) -> None:
        name = f"{prefix}{slot}"
        steps.append({"target": name, "rust": rust})
        writes[name] += 1
        alias[slot] = name

    for k in range(f.n_instructions()):
        op, ins, outs = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_CONST:
            alias[outs[0]] = _literal(f.instruction_constant(k))
        elif op == ca.OP_INPUT:
            key = (ins[0], ins[1])
            if key not in bound:
                arg = args[ins[0]]
                r, c = in_nz[ins[0]][ins[1]]
                name = f"{arg['name']}_{r}" if arg["cols"] == 1 else f"{arg['name']}_{r}_{c}"
                bound[key] = name
                bindings.append({"name": name, "arg": arg["name"], "access": _access(arg, r, c)})
            alias[outs[0]] = bound[key]
        elif op == ca.OP_OUTPUT:
            r, c = out_nz[outs[0]][outs[1]]
            entries[outs[0]].append({"row": r, "col": c})
            target = f"{outputs[outs[0]]}[{r}]" if shapes[outs[0]][1] == 1 else f"{outputs[outs[0]]}[({r}, {c})]"
            steps.append({"target": target, "rust": alias[ins[0]]})
        elif op == ca.OP_ASSIGN:
            assign(outs[0], alias[ins[0]])
        elif op in TRIG:
            angle = alias[ins[0]]
            if angle not in {b["name"] for b in bindings}:
                raise SequenceError(f"{f.name()}: {TRIG[op]} of a computed value; only joint angles have sin_cos")
            entry = trig.setdefault(angle, {"angle": angle, "sin": "_", "cos": "_"})
            entry[TRIG[op]] = f"{TRIG[op]}_{angle}"
            alias[outs[0]] = entry[TRIG[op]]
        elif op in BINARY or op in UNARY:
            kind, pattern = BINARY[op] if op in BINARY else UNARY[op]
            a = alias[ins[0]]
            b = alias[ins[1]] if op in BINARY else None
            counts[kind] += 1
            assign(outs[0], pattern.format(a=a, b=b))
        else:
            raise SequenceError(f"{f.name()}: CasADi operation {op} has no straight-line f64 form here")
    slots = [{"name": name, "mutable": writes[name] > 1} for name in sorted(writes, key=lambda w: int(w[len(prefix):]))]
    cost = {"ops": sum(counts.values()), "weighted": sum(n * WEIGHTS.get(k, 1) for k, n in counts.items()),
            "kinds": {k: counts[k] for k in sorted(counts)}, "sin_cos": len(trig)}
    return {"constants": [], "bindings": bindings, "trig": list(trig.values()), "compounds": [],
            "sequence": {"slots": slots, "steps": steps}, "outputs": entries, "cost": cost}


def as_lets(body: dict, prefix: str = "w") -> tuple[list[dict], list[dict]]:
    """A body's steps in single assignment, for short sequences (a per-tool coefficient struct):
    one `let` per slot write, named `<slot>_<n>`, and the output writes [{target, rust}]."""
    slot = re.compile(rf"\b{prefix}\d+\b")
    current: dict[str, str] = {}
    lets, writes = [], []
    for step in body["sequence"]["steps"]:
        rust = slot.sub(lambda m: current[m.group(0)], step["rust"])
        if slot.fullmatch(step["target"]):
            name = f"{step['target']}_{len(lets)}"
            lets.append({"name": name, "rust": rust})
            current[step["target"]] = name
        else:
            writes.append({"target": step["target"], "rust": rust})
    return lets, writes


def instruction_count(f: ca.Function) -> dict:
    """The operation count of `f` as `instructions` would emit it, without building the code."""
    return instructions(f, [{"name": f"in{i}", "rows": f.size1_in(i), "cols": f.size2_in(i)}
                            for i in range(f.n_in())])["cost"]
