"""docs/reference/description.md, the reference of the model description file, written from the key tables
the reader enforces (description.py's TOP_KEYS and MODEL_KEYS, urdf_description.py's URDF_KEYS):
which keys each table has, their type and whether they are required come from the same tuples that
refuse a misspelt key, so the reference cannot list a key the reader does not know, or miss one.
What a key means and its default are written here, once; `undocumented` names a key the tables
have and MEANING lacks, and the test (derive/tests/test_reference.py) fails on it and on a stale
docs/reference/description.md. `make derive` rewrites the file.
"""

from __future__ import annotations

from .description import MODEL_KEYS, NAMED, TOP_KEYS
from .urdf_description import COM_BOUND, SAMPLE, URDF_KEYS

_NAMED = {
    "name": (None, "name (a lower-case ASCII letter, then letters, digits, `_`; at most 64; not a Rust or Python "
                   "keyword): the tools-file column, "
                   "the Python dict key, the name in every message"),
    "latex": ("the name", "how the report typesets it"),
    "unit": ('""', "SI unit, shown in reports and docs"),
    "doc": ('""', "one line, in the generated docs"),
}

# (table as the reader names it, its keys, where it applies, what it is).
SECTIONS = (
    ("(top level)", TOP_KEYS, "every model", "The tables of a description file."),
    ("model", MODEL_KEYS["model"], "every model", "The model's identity."),
    ("parameters", NAMED, "kinds `explicit`, `planar_chain`",
     "`[[parameters]]`, one table per tool parameter, in the order the runtime passes them (a tools "
     "file's columns). Every parameter's domain is > 0. A `urdf` model has none: its tool's parameters "
     "are fixed (`tool_mass`, `tool_com_x`, `tool_com_y`, `tool_com_z`, `tool_ixx`, `tool_iyy`, "
     "`tool_izz`, `tool_ixy`, `tool_ixz`, `tool_iyz`, `tool_tip_x`, `tool_tip_y`, `tool_tip_z`)."),
    ("constants.NAME", MODEL_KEYS["constant"], "kinds `explicit`, `planar_chain`",
     "`[constants]` holds one table per constant, e.g. `g = { value = 9.81, unit = \"m/s^2\" }`; the "
     "expressions may use its name."),
    ("coordinates", MODEL_KEYS["coordinates"], "kinds `explicit`, `planar_chain`",
     "The generalised coordinates q, their rates and the controls, each a list of `model.dof` tables "
     "with the keys of `coordinates.q[i]`. A `urdf` model takes them from the URDF's joint names "
     "(`<joint>`, `<joint>_dot`, `<joint>_torque`)."),
    ("coordinates.q[i]", NAMED, "each entry of `q`, `q_dot` and `u`", "One coordinate."),
    ("dynamics", MODEL_KEYS["dynamics"], "every model", "The equations of motion."),
    ("dynamics.links[i]", MODEL_KEYS["link"], "kind `planar_chain`", "One uniform rod of the chain."),
    ("equilibrium", MODEL_KEYS["equilibrium"], "every model",
     "The equilibrium (X^e, U^e) the model is linearised about (eq. LTI), checked before anything is "
     "derived: f(X^e, U^e) = 0 (exactly for the symbolic kinds, to the rounding of the graphs' constants "
     "for `urdf`). Each entry is an expression (`pi`, `sqrt`, numbers)."),
    ("printed", MODEL_KEYS["printed"], "optional",
     "A paper's printed A and B (expressions over the parameters), compared entry by entry with the "
     "derived ones in the model's report."),
    ("tip", MODEL_KEYS["tip"], "kind `explicit` (required)",
     "Where the tip (the point a tip task moves) is: required for kind `explicit`, since the tip terms "
     "of derive/tasks.toml (`tip`, `tip_dot`) read it; a `planar_chain`'s is its chain's free end "
     "(TIP_DIM 2: x, y in its plane), a `urdf` model's the tool's `tool_tip_x/y/z` in the flange frame "
     "(TIP_DIM 3), so neither takes the table. Every model has a generated `tip` (its position and "
     "Jacobian dy/dq, `toolconf.tip`) and `TIP_DIM`, the components its tip terms use, which must not "
     "exceed `model.dof`: a tip term's goal, precision and sensitivity are stored in the first TIP_DIM "
     "of the joints' slots (derive/tasks.toml, J)."),
    ("urdf", URDF_KEYS["urdf"], "kind `urdf` (required)", "The robot and its chain."),
    ("impedance", URDF_KEYS["impedance"], "kind `urdf` (required)",
     "The joint impedance of the plant tau = U + K (q^e - q) - D q_dot + g(q^e) (docs/explanation/real-arms.md): K and "
     "D per joint, each in [0, 1e6]. Every confidence depends on them; docs/how-to/choose-impedance-gains.md says how to choose "
     "them."),
    ("tool", URDF_KEYS["tool"], "kind `urdf`", "Which tools are valid, and where random tools come from."),
)

_SAMPLE = ", ".join(f"`{k}` [{lo:g}, {hi:g}]" for k, (lo, hi) in SAMPLE.items())

# (table, key) -> (default or None for required, meaning). Types and requiredness are the tables'.
MEANING = {
    ("(top level)", "model"): (None, "`[model]`"),
    ("(top level)", "parameters"): ("none", "`[[parameters]]`: required for kinds `explicit`, `planar_chain`; "
                                            "refused for `urdf`"),
    ("(top level)", "constants"): ("none", "`[constants]`"),
    ("(top level)", "coordinates"): ("none", "`[coordinates]`: required for kinds `explicit`, `planar_chain`; "
                                             "refused for `urdf`"),
    ("(top level)", "dynamics"): (None, "`[dynamics]`"),
    ("(top level)", "equilibrium"): (None, "`[equilibrium]`"),
    ("(top level)", "goals"): ("zero goals", "`[goals.<task>]`, one table per task of derive/tasks.toml "
                                             "(`position`, `velocity`, `acceleration`, `tip_position`, "
                                             "`tip_velocity`, `tip_acceleration`), each key a term the task "
                                             "uses (`theta`, `theta_dot`, `theta_ddot` with `model.dof` "
                                             "expressions; `tip` in m, `tip_dot` in m/s and `tip_ddot` in "
                                             "m/s² with TIP_DIM, absolute in the base frame): the default "
                                             "goal of that task; a term it omits has goal 0"),
    ("(top level)", "formulation"): ("each task's default", "`[formulation]`: `<task> = \"<name>\"`, the "
                                                           "formulation of the task's sensitivities the model "
                                                           "uses: `\"paper\"` (derive/tasks.toml's formulas) or "
                                                           "a name of the task's `[task.formulations]`; a task "
                                                           "not named takes the formulation whose `default_for` "
                                                           "lists the model's dynamics kind, else the paper's "
                                                           "(docs/explanation/static-gain.md)"),
    ("(top level)", "printed"): ("none", "`[printed]`"),
    ("(top level)", "urdf"): ("none", "`[urdf]`: required for kind `urdf`, refused otherwise"),
    ("(top level)", "impedance"): ("none", "`[impedance]`: required for kind `urdf`, refused otherwise"),
    ("(top level)", "tool"): ("the defaults below", "`[tool]`: kind `urdf` only"),
    ("(top level)", "tip"): ("none", "`[tip]`: required for kind `explicit`, refused for the other kinds "
                                     "(they have their tip)"),
    ("model", "name"): (None, "name of the model (as a parameter's `name`): `--model NAME`, the generated module "
                              "and file names"),
    ("model", "title"): ('""', "one line for reports and `toolconf models`"),
    ("model", "source"): ('""', "where the equations come from"),
    ("model", "dof"): (None, "number of joints n (for `urdf`, checked against the chain)"),
    **{("parameters", k): v for k, v in _NAMED.items()},
    **{("coordinates.q[i]", k): v for k, v in _NAMED.items()},
    ("constants.NAME", "value"): (None, "the number"),
    **{("constants.NAME", k): _NAMED[k] for k in ("latex", "unit", "doc")},
    ("coordinates", "q"): (None, "the joint coordinates"),
    ("coordinates", "q_dot"): (None, "their rates, in the same order"),
    ("coordinates", "u"): (None, "the joint torques (or forces)"),
    ("dynamics", "kind"): (None, "`explicit` (q_ddot written out), `planar_chain` (derived by Lagrange from "
                                 "`links`) or `urdf` (derived from `[urdf]` by RNEA/CRBA)"),
    ("dynamics", "equations"): ("[]", "the equations' names in their source, for the docs"),
    ("dynamics", "q_ddot"): ("none", "kind `explicit`: `model.dof` expressions of q, q_dot, u, the parameters "
                                     "and constants (`sin`, `cos`, `sqrt`, `pi`); parsed, never evaluated"),
    ("dynamics", "links"): ("none", "kind `planar_chain`: `model.dof` tables `{ mass, length }`"),
    ("dynamics", "gravity"): ('"g"', "kind `planar_chain`: the constant that is the gravitational acceleration"),
    ("dynamics", "payload"): ("none", "kind `planar_chain`: a parameter that is a point mass held at the tip"),
    ("dynamics.links[i]", "mass"): (None, "the parameter that is the rod's mass"),
    ("dynamics.links[i]", "length"): (None, "the parameter that is the rod's length"),
    ("equilibrium", "q"): (None, "q^e, `model.dof` expressions; for `urdf`, within each joint's URDF limits"),
    ("equilibrium", "q_dot"): (None, "q_dot^e, `model.dof` expressions (zero at a rest equilibrium)"),
    ("equilibrium", "u"): (None, "U^e, `model.dof` expressions (zero for `urdf`: gravity is fed forward)"),
    ("tip", "position"): (None, "3 expressions, the tip's x, y, z in the base frame (m), of the joint positions, "
                                "the parameters and the constants (`\"0\"` for z of a planar arm)"),
    ("tip", "components"): ("3", "TIP_DIM, how many of the tip's x, y, z (the first ones) the tip terms use: 1, "
                                 "2 or 3, at most `model.dof` (2 for a planar arm: x, y)"),
    ("tip", "source"): ('""', "where the geometry comes from"),
    ("printed", "where"): ('""', "where in the paper they are printed"),
    ("printed", "A"): ("none", "2n x 2n expressions"),
    ("printed", "B"): ("none", "2n x n expressions"),
    ("urdf", "file"): (None, "the URDF, **relative to the folder of this description file** (the one rule: "
                             "`make derive`, `make crate` and derive/derive.py resolve it the same way); read "
                             "as docs/reference/urdf-arms.md, \"How a URDF is read\", says"),
    ("urdf", "base"): (None, "the link the chain starts from (fixed to the world)"),
    ("urdf", "flange"): (None, "the link the tool is fixed to; links beyond it are not read"),
    ("urdf", "gravity"): (None, "3 numbers, m/s^2 in the base frame, each within +-1e3"),
    ("urdf", "source"): ('""', "where the URDF comes from"),
    ("impedance", "stiffness"): (None, "K, one per joint, N m/rad (N/m for a prismatic joint)"),
    ("impedance", "damping"): (None, "D, one per joint, N m s/rad"),
    ("impedance", "source"): ('""', "where the gains come from"),
    ("tool", "com_bound"): (f"{COM_BOUND:g}", "m: a valid tool's centre of mass and tip lie within it of the "
                                              "flange along each flange axis; in (0, 1e6]"),
    ("tool", "sample"): (_SAMPLE, "`[tool.sample]`: per tool parameter, the box `[lo, hi]` random tools are drawn "
                                  "from (`select --models`, design's random baseline); within the parameter's "
                                  "domain, its centre a valid tool"),
    ("tool", "source"): ('""', "where the tool rule comes from (a datasheet's payload)"),
}


def undocumented() -> list[str]:
    """Keys the reader knows that MEANING lacks, and MEANING's keys the reader does not know."""
    known = {(table, key) for table, keys, _, _ in SECTIONS for key, _, _ in keys}
    return ([f"{t}.{k}: not documented" for t, k in sorted(known - MEANING.keys())]
            + [f"{t}.{k}: documented, but not a key" for t, k in sorted(MEANING.keys() - known)])


def description_reference() -> str:
    lines = ["# The model description file: reference",
             "",
             "<!-- Written by derive/toolconf_derive/reference.py from the tables the reader enforces; "
             "`make derive` rewrites it, derive/tests/test_reference.py fails when it is stale. -->",
             "",
             "A model is one TOML file (`derive/models/*.toml`; `make crate MODELS=<folder>` for your own). "
             "Every table refuses a key it does not list here, naming the file and the key; every "
             "expression is parsed (numbers, names, `+ - * / **`, `sin`, `cos`, `sqrt`, `pi`), never "
             "evaluated. \"required\" means the file is refused without it.",
             "",
             "A `text` (`texts`: an array of them) is free text of one line: any character but the control "
             "characters (tab and newline among them), the Unicode line and paragraph separators, the "
             "bidirectional controls and the byte-order mark, each refused naming the file and the key (a "
             "task file's `paragraph`, a task's `doc`, a remark's `text`, a formulation's `doc`, may have "
             "newlines, and is shown as one line). Text is data: it reaches the generated code only escaped "
             "for where it goes (derive/render/src/escape.rs), as a Rust string literal, one line of a "
             "comment (runs of spaces made one and a run of three backticks or tildes escaped, so that no "
             "Markdown code block forms for rustdoc to run), a C comment of `toolconf_model.h` (`*/` broken "
             "up) or a TOML string. Numbers are ASCII decimals (no other script's digits).",
             ""]
    for table, keys, applies, what in SECTIONS:
        lines += [f"## `{table}`" if table != "(top level)" else "## Top level", "",
                  f"{what} Applies to: {applies}.", "",
                  "| key | type | required / default | meaning |", "|---|---|---|---|"]
        for key, kind, required in keys:
            default, meaning = MEANING[(table, key)]
            need = "required" if required else f"default: {default}"
            lines.append(f"| `{key}` | {kind} | {need} | {meaning} |")
        lines.append("")
    return "\n".join(lines)
