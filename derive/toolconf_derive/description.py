"""Model and task descriptions: the TOML files under derive/ read into plain data.

Nothing here derives anything. The expressions are checked against the grammar of expression.py
as they are read (a description is data, never code) and stay strings, so that SymPy
(symbolic.py) and CasADi (numeric.py) each build them in their own arithmetic, which keeps the
cross-check independent.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from .errors import DescriptionError
from .expression import FORMULA_FUNCTIONS, Expression, ExpressionError, formula, parse, python_number
from .files import Table, read_toml
from .quantities import Constant, Named
from .urdf_description import URDF_KEYS, urdf_names


@dataclass(frozen=True)
class Model:
    path: Path
    name: str
    title: str
    source: str
    dof: int
    parameters: list[Named]
    constants: list[Constant]
    q: list[Named]
    q_dot: list[Named]
    u: list[Named]
    dynamics_kind: str
    equations: list[str]
    q_ddot: list[str]
    equilibrium_q: list[str]
    equilibrium_q_dot: list[str]
    equilibrium_u: list[str]
    links: list[dict] = field(default_factory=list)
    gravity: str = "g"
    # planar_chain: the parameter that is the mass of a point payload held at the tip, if any.
    payload: str | None = None
    goals: dict[str, dict[str, list[str]]] = field(default_factory=dict)
    printed_where: str = ""
    printed_a: list[list[str]] | None = None
    printed_b: list[list[str]] | None = None
    # urdf: the chain read from the URDF file (urdf.UrdfChain), its gravity vector, the joint
    # impedance (stiffness K, damping D per joint) and where the impedance values come from.
    chain: object = None
    urdf_gravity: list[float] = field(default_factory=list)
    impedance_stiffness: list[float] = field(default_factory=list)
    impedance_damping: list[float] = field(default_factory=list)
    impedance_source: str = ""
    # urdf: which tools are valid and the box random tools are drawn from (urdf_description.tool_rule:
    # per-parameter domains, linear constraints, sampling box), for the IR's model.tool_rule.
    # None for the other kinds: their parameters are masses, lengths, ... (> 0, drawn from the
    # paper's [0.1, 0.6]), the renderer's default (derive/render).
    tool_rule: dict | None = None
    # explicit: the tip's position (x, y, z) in the base frame as expressions ([tip] position), and
    # how many of x, y, z the tip terms use ([tip] components).
    tip: list[str] | None = None
    tip_components: int | None = None
    # [formulation]: per task name, the formulation the description chooses ("paper" or a name of
    # the task's [task.formulations]); a task it does not name takes its default (Task.formulation).
    formulation: dict[str, str] = field(default_factory=dict)

    @property
    def state(self) -> list[Named]:
        return self.q + self.q_dot

    @property
    def state_dim(self) -> int:
        return 2 * self.dof

    @property
    def tip_dim(self) -> int:
        """TIP_DIM, the components of the tip the tip terms use: x, y, z of a URDF arm's tool tip,
        x, y of a planar chain's free end in its plane, the first [tip] components of an explicit
        model's."""
        return TIP_DIMS.get(self.dynamics_kind, self.tip_components)


@dataclass(frozen=True)
class TermDef:
    """A free-energy term (eq. free_energy) as derive/tasks.toml's [[term]] gives it."""
    name: str
    symbol: str
    latex: str
    doc: str
    label: str
    unit: str
    # Where its value is read (READS): a block of n rows of the state X, of its rate X_dot, the
    # control U (a term read from the control has no sensitivity dU/dU to derive), or the tool's
    # tip (`tip`, block = the order of the time derivative: y, y_dot), whose TIP_DIM components
    # fill the first rows of the n.
    source: str
    block: int
    # The documented range (toolconf.ranges()) a goal of it lies in; None: it has no goal (the
    # control's prior mean eta^U is 0, as in the paper).
    goal_range: str | None

    @property
    def has_sensitivity(self) -> bool:
        return self.source != "control"

    @property
    def on_tip(self) -> bool:
        """Whether it is read at the tool's tip: its goal has TIP_DIM entries."""
        return self.source == "tip"


@dataclass(frozen=True)
class Remark:
    term: str
    alternative: str
    text: str


# The formulation a task's own sensitivity formulas are: the paper's.
PAPER = "paper"


@dataclass(frozen=True)
class Formulation:
    """A named alternative to some of a task's sensitivity formulas ([task.formulations.<name>]),
    the default of the models whose dynamics kind is in `default_for`."""
    name: str
    doc: str
    default_for: tuple[str, ...]
    sensitivity: dict[str, str]


@dataclass(frozen=True)
class Task:
    name: str
    index: int
    title: str
    doc: str
    terms: list[str]
    # The kinematic term whose distance to its goal is the task's error (eq. task_error).
    error: str
    sensitivity: dict[str, str]
    remarks: list[Remark] = field(default_factory=list)
    default_precision: dict[str, float] = field(default_factory=dict)
    # Every term tasks.toml defines, in its order (the runtime's `Term`), and the order J's
    # summands are added in (its cost_order).
    all_terms: tuple[TermDef, ...] = ()
    cost_order: tuple[str, ...] = ()
    # Where the task is defined, for messages: the file and its key (task[0]).
    path: Path | str = ""
    key: str = ""
    # Its named formulations, and which one `sensitivity` is for the model it was resolved for
    # (for_model): PAPER or a name of `formulations`, and why ("default", "default_for",
    # "description").
    formulations: dict[str, Formulation] = field(default_factory=dict)
    formulation: str = PAPER
    chosen_by: str = "default"

    @property
    def sensitivity_terms(self) -> list[str]:
        """The terms with a sensitivity d/dU (all but the control) this task's controller uses,
        in the order of the term list."""
        return [t.name for t in self.all_terms if t.has_sensitivity and t.name in self.terms]

    @property
    def control_term(self) -> str:
        """The name of the term read from the control U (its precision is P^U)."""
        return next(t.name for t in self.all_terms if not t.has_sensitivity)

    @property
    def precision_terms(self) -> list[str]:
        """The terms whose precisions the task's confidence takes: its sensitivity terms, then the
        control's."""
        return self.sensitivity_terms + [self.control_term]

    def term(self, name: str) -> TermDef:
        return next(t for t in self.all_terms if t.name == name)

    def argument_doc(self, name: str) -> str:
        """`the joint angles theta`: a term in a generated function's argument documentation."""
        return f"{self.term(name).doc} {name}"

    @property
    def sensitivity_function(self) -> str:
        """The generated function that returns this task's sensitivities."""
        return f"{self.name}_sensitivity"

    @property
    def confidence_function(self) -> str:
        """The generated function that returns this task's control confidence Pi^U."""
        return f"{self.name}_control_confidence"

    @property
    def gradient_function(self) -> str:
        """The generated function that returns d ln|Pi^U| / dp for this task."""
        return f"{self.name}_logdet_gradient"


# A model's module, src/<model>.rs of the generated crate, must not clash with the crate's own
# (templates/registry/src/: lib.rs, tasks.rs, trig.rs, powi.rs; `mod` is a Rust keyword).
RESERVED_MODEL_NAMES = ("lib", "mod", "powi", "rigid_body", "tasks", "trig", "validity")
# The constants templates/model.rs.tera declares in every model's module (a test keeps the list
# and the template in step); a description constant `g` becomes the Rust constant `G` beside them.
MODULE_CONSTANTS = ("NAME", "DOF", "STATE_DIM", "TIP_DIM", "PARAMETER_COUNT", "PARAMETER_NAMES",
                    "PARAMETER_UNITS", "STATE_NAMES", "CONTROL_NAMES", "EQUILIBRIUM_STATE", "EQUILIBRIUM_CONTROL")
RUST_NAME = re.compile(r"[a-z][a-z0-9_]*")
# The longest name a description gives: a model's name is part of its library's file name
# (`libtoolconf_model_<name>.so`) and of cargo's artefacts beside it, which a file system limits to
# 255 bytes (derive/render/src/escape.rs's MAX_NAME, which the renderer checks an IR against).
MAX_NAME = 64
# Every edition's strict and reserved keywords (the Rust Reference, "Keywords"), which no
# generated `let`, `fn` or `mod` may be named.
RUST_KEYWORDS = frozenset((
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for", "if",
    "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "self", "static",
    "struct", "super", "trait", "true", "type", "unsafe", "use", "where", "while", "async", "await", "dyn",
    "abstract", "become", "box", "do", "final", "macro", "override", "priv", "typeof", "unsized", "virtual",
    "yield", "try", "gen"))
# The columns a tools file has besides the parameters' (crates/model/src/inputs/tools_file.rs).
TOOL_FILE_COLUMNS = ("name", "model")

# The keys each table may have, as serde's deny_unknown_fields: a misspelt key is an error, not a
# silently ignored setting. (name, type, required); types are checked by _TYPES.
NAMED = (("name", "string", True), ("latex", "text", False), ("unit", "text", False), ("doc", "text", False))
MODEL_KEYS = {
    "model": (("name", "string", True), ("title", "text", False), ("source", "text", False),
              ("dof", "integer", True)),
    "constant": (("value", "number", True), ("latex", "text", False), ("unit", "text", False),
                 ("doc", "text", False)),
    "coordinates": (("q", "tables", True), ("q_dot", "tables", True), ("u", "tables", True)),
    "dynamics": (("kind", "string", True), ("equations", "texts", False), ("q_ddot", "strings", False),
                 ("links", "tables", False), ("gravity", "string", False), ("payload", "string", False)),
    "link": (("mass", "string", True), ("length", "string", True)),
    "equilibrium": (("q", "values", True), ("q_dot", "values", True), ("u", "values", True)),
    "printed": (("where", "text", False), ("A", "matrix", False), ("B", "matrix", False)),
    "tip": (("position", "strings", True), ("components", "integer", False), ("source", "text", False)),
    **URDF_KEYS,
}
# The dynamics kinds, and the tip dimension TIP_DIM of those whose tip is not described: a URDF
# tool's tip moves in space, a planar chain's in its plane (an explicit model's: [tip] components).
KINDS = ("explicit", "planar_chain", "urdf")
TIP_DIMS = {"urdf": 3, "planar_chain": 2}
# An explicit model's tip components when [tip] does not say: x, y and z.
TIP_COMPONENTS = 3
# parameters and coordinates are required except for kind "urdf", where the URDF and the tool
# define them (urdf_description.urdf_names).
TOP_KEYS = (("model", "table", True), ("parameters", "tables", False), ("constants", "table", False),
            ("coordinates", "table", False), ("dynamics", "table", True), ("equilibrium", "table", True),
            ("goals", "table", False), ("printed", "table", False), ("urdf", "table", False),
            ("impedance", "table", False), ("tool", "table", False), ("tip", "table", False),
            ("formulation", "table", False))
TASK_KEYS = (("name", "string", True), ("index", "integer", True), ("title", "text", False),
             ("doc", "paragraph", False), ("terms", "strings", True), ("error", "string", True),
             ("sensitivity", "table", True),
             ("defaults", "table", False), ("remarks", "tables", False), ("formulations", "table", False))
FORMULATION_KEYS = (("doc", "paragraph", True), ("default_for", "strings", False), ("sensitivity", "table", True))
DEFAULTS_KEYS = (("precision", "table", True),)
REMARK_KEYS = (("term", "string", True), ("alternative", "string", True), ("text", "paragraph", True))
TERM_KEYS = (("name", "string", True), ("symbol", "text", True), ("latex", "text", True),
             ("doc", "text", True), ("label", "text", True), ("unit", "text", True), ("read", "string", True),
             ("goal_range", "string", False))
# How a term's value is read, as tasks.toml writes it (white space aside): (source, block); for
# the tip, block is the order of the derivative (y, y_dot = J(q) q_dot, then
# y_ddot = J(q) q_ddot + Jdot(q, q_dot) q_dot, the generated tip_bias giving Jdot q_dot).
READS = {"IO @ X": ("state", 0), "OI @ X": ("state", 1), "IO @ X_dot": ("state_rate", 0),
         "OI @ X_dot": ("state_rate", 1), "U": ("control", 0), "tip(q)": ("tip", 0), "J(q) @ q_dot": ("tip", 1),
         "J(q) @ q_ddot + Jdot(q, q_dot) @ q_dot": ("tip", 2)}
# The documented ranges a goal may be checked against (crates/core/src/validate.rs).
GOAL_RANGES = ("joint_angle", "joint_rate", "joint_acceleration", "tip_position", "tip_velocity",
               "tip_acceleration")


def _named(t: Table) -> Named:
    return Named(name=t.get("name"), latex=t.get("latex", t.get("name")), unit=t.get("unit", ""), doc=t.get("doc", ""))


def _constants(top: Table) -> list[Constant]:
    table = top.table("constants", tuple((k, "table", True) for k in top.get("constants", {})))
    out = []
    for name in table.raw:
        c = table.table(name, MODEL_KEYS["constant"])
        out.append(Constant(name=name, latex=c.get("latex", name), unit=c.get("unit", ""), doc=c.get("doc", ""),
                            value=float(c.get("value"))))
    return out


def _goals(top: Table) -> dict[str, dict[str, list[str]]]:
    goals = top.table("goals", tuple((k, "table", True) for k in top.get("goals", {})))
    out = {}
    for task in goals.raw:
        # Which terms a goal may be given for is the task list's to say (symbolic.check_goals).
        terms = goals.table(task, tuple((t, "values", False) for t in goals.get(task, {})))
        out[task] = {term: [str(v) for v in values] for term, values in terms.raw.items()}
    return out


def load_model(path: Path) -> Model:
    top = Table(path, "", read_toml(path), TOP_KEYS)
    m = top.table("model", MODEL_KEYS["model"])
    dyn = top.table("dynamics", MODEL_KEYS["dynamics"])
    eq = top.table("equilibrium", MODEL_KEYS["equilibrium"])
    printed = top.table("printed", MODEL_KEYS["printed"])
    tip, components = _tip(path, top, dyn.get("kind"))
    if dyn.get("kind") == "urdf":
        parameters, q, q_dot, u, urdf = urdf_names(path, top)
    else:
        for key in ("parameters", "coordinates"):
            if key not in top.raw:
                raise DescriptionError(path, key, "missing (required)")
        for key in ("urdf", "impedance", "tool"):
            if key in top.raw:
                raise DescriptionError(path, key, "only for dynamics.kind = 'urdf'")
        coords = top.table("coordinates", MODEL_KEYS["coordinates"])
        parameters = [_named(p) for p in top.tables("parameters", NAMED)]
        q, q_dot, u = ([_named(c) for c in coords.tables(k, NAMED)] for k in ("q", "q_dot", "u"))
        urdf = {}
    model = Model(
        path=path,
        name=m.get("name"),
        title=m.get("title", ""),
        source=m.get("source", ""),
        dof=m.get("dof"),
        parameters=parameters,
        constants=_constants(top),
        q=q,
        q_dot=q_dot,
        u=u,
        dynamics_kind=dyn.get("kind"),
        equations=dyn.get("equations", []),
        q_ddot=list(dyn.get("q_ddot", [])),
        equilibrium_q=[str(v) for v in eq.get("q")],
        equilibrium_q_dot=[str(v) for v in eq.get("q_dot")],
        equilibrium_u=[str(v) for v in eq.get("u")],
        links=[link.raw for link in dyn.tables("links", MODEL_KEYS["link"])],
        gravity=dyn.get("gravity", "g"),
        payload=dyn.get("payload"),
        goals=_goals(top),
        printed_where=printed.get("where", ""),
        printed_a=printed.get("A"),
        printed_b=printed.get("B"),
        tip=tip,
        tip_components=components,
        formulation=_formulation(top),
        **urdf,
    )
    _validate_model(model)
    return model


def _tip(path: Path, top: Table, kind: str) -> tuple[list[str] | None, int | None]:
    """`[tip] position`: the tip's (x, y, z) in the base frame as expressions of q and the
    parameters, and `components`, how many of x, y, z the tip terms use, for kind `explicit`,
    which must have one: tasks.toml's tip terms read it. A `planar_chain`'s tip is its chain's free
    end and a `urdf` tool's its tool_tip_x/y/z, so neither takes the table."""
    if "tip" not in top.raw:
        if kind == "explicit":
            raise DescriptionError(path, "tip", "missing (required for dynamics.kind = 'explicit'): the tip terms of "
                                                "derive/tasks.toml (tip, tip_dot) read the tip's position; give "
                                                "[tip] position = [x, y, z] and components")
        return None, None
    if kind != "explicit":
        where = "the chain's free end" if kind == "planar_chain" else "the tool's tool_tip_x/y/z"
        raise DescriptionError(path, "tip", f"only for dynamics.kind = 'explicit': a {kind} model's tip is {where}")
    table = top.table("tip", MODEL_KEYS["tip"])
    position = [str(v) for v in table.get("position")]
    if len(position) != 3:
        raise DescriptionError(path, "tip.position", f"has {len(position)} entries, need 3: x, y, z in the base "
                                                     "frame (z = \"0\" for a planar arm)")
    components = table.get("components", TIP_COMPONENTS)
    if not 1 <= components <= 3:
        raise DescriptionError(path, "tip.components", f"is {components}, must be 1, 2 or 3: the first components "
                                                       "of the tip's x, y, z that the tip terms use")
    return position, components


def _formulation(top: Table) -> dict[str, str]:
    """`[formulation]`: task name = formulation name (checked against the tasks by check_tasks)."""
    table = top.table("formulation", tuple((k, "string", True) for k in top.get("formulation", {})))
    return dict(table.raw)


def _check_identifier(name: str, path: Path, key: str) -> None:
    # ASCII: Rust cannot name a module file `é.rs` (E0754), and Python's isidentifier() would let
    # NFKC-equal spellings through as different names.
    if not RUST_NAME.fullmatch(name):
        raise DescriptionError(path, key, f"'{name}' must be a lower-case ASCII name: a letter, then letters, "
                                          "digits or _ (it becomes a Rust name)")
    if len(name) > MAX_NAME:
        raise DescriptionError(path, key, f"is longer than {MAX_NAME} characters ({len(name)}, '{name[:20]}…'): it "
                                          "becomes a Rust name and part of file names")
    if name in RUST_KEYWORDS:
        raise DescriptionError(path, key, f"'{name}' is a Rust keyword (the name becomes a Rust name); rename it")


def rust_constant(name: str) -> str:
    """The Rust name of a description constant: `g` is `G` in the generated module."""
    return name.upper()


def name_keys(m: Model) -> dict[str, str]:
    """Each name the description gives a parameter, constant or coordinate, with its key."""
    groups = (("parameters", m.parameters), ("constants", m.constants), ("coordinates.q", m.q),
              ("coordinates.q_dot", m.q_dot), ("coordinates.u", m.u))
    keys: dict[str, str] = {}
    for label, entries in groups:
        for i, n in enumerate(entries):
            key = f"constants.{n.name}" if label == "constants" else f"{label}[{i}].name"
            _check_identifier(n.name, m.path, key)
            if n.name in keys:
                raise DescriptionError(m.path, key, f"'{n.name}' is already the name of {keys[n.name]}")
            keys[n.name] = key
    return keys


def _validate_names(m: Model) -> None:
    path = m.path
    _check_identifier(m.name, path, "model.name")
    if m.name in RESERVED_MODEL_NAMES:
        raise DescriptionError(path, "model.name", f"'{m.name}' is taken by the generated registry "
                                                   f"({', '.join(n + '.rs' for n in RESERVED_MODEL_NAMES)})")
    if m.dof < 1:
        raise DescriptionError(path, "model.dof", f"must be at least 1, got {m.dof}")
    name_keys(m)
    for i, p in enumerate(m.parameters):
        if p.name in TOOL_FILE_COLUMNS:
            raise DescriptionError(path, f"parameters[{i}].name", f"'{p.name}' is a column of every tools file "
                                                                  f"({', '.join(TOOL_FILE_COLUMNS)}); rename the parameter")
    for c in m.constants:
        if rust_constant(c.name) in MODULE_CONSTANTS:
            raise DescriptionError(path, f"constants.{c.name}", f"'{c.name}' becomes the Rust constant {rust_constant(c.name)}, "
                                                                "which every generated model already declares; rename it")


def _check_length(path: Path, key: str, seq: list, want: int, what: str) -> None:
    if len(seq) != want:
        raise DescriptionError(path, key, f"has {len(seq)} entries, {what} is {want}")


def _validate_shapes(m: Model) -> None:
    path, n, n2 = m.path, m.dof, 2 * m.dof
    for key, seq in (("coordinates.q", m.q), ("coordinates.q_dot", m.q_dot), ("coordinates.u", m.u),
                     ("equilibrium.q", m.equilibrium_q), ("equilibrium.q_dot", m.equilibrium_q_dot),
                     ("equilibrium.u", m.equilibrium_u)):
        _check_length(path, key, seq, n, "model.dof")
    for label, matrix, cols in (("A", m.printed_a, n2), ("B", m.printed_b, n)):
        if matrix is not None and (len(matrix) != n2 or any(len(r) != cols for r in matrix)):
            shape = f"{len(matrix)} rows of {sorted({len(r) for r in matrix})} entries"
            raise DescriptionError(path, f"printed.{label}", f"must be {n2}x{cols} for model.dof = {n}, got {shape}")


def _validate_tip(m: Model) -> None:
    """TIP_DIM <= n: a tip term's vectors and matrices are stored in the joints' n slots."""
    if m.dynamics_kind not in KINDS or m.tip_dim <= m.dof:
        return
    if m.dynamics_kind == "explicit":
        raise DescriptionError(m.path, "tip.components", f"is {m.tip_dim}, more than the model's {m.dof} "
                                                         "joint(s): a tip term's vectors are stored padded in the "
                                                         "joints' slots, so the tip may use at most model.dof "
                                                         "components")
    what = "x, y, z of the tool's tip" if m.dynamics_kind == "urdf" else "x, y of the chain's free end"
    raise DescriptionError(m.path, "model.dof", f"is {m.dof}: model '{m.name}' (dynamics.kind = "
                                                f"'{m.dynamics_kind}') has a tip of {m.tip_dim} components ({what}), "
                                                "more than its joints: a tip term's vectors are stored padded in "
                                                "the joints' slots")


def _validate_dynamics(m: Model) -> None:
    path = m.path
    if m.dynamics_kind == "explicit":
        _check_length(path, "dynamics.q_ddot", m.q_ddot, m.dof, "model.dof")
    elif m.dynamics_kind == "planar_chain":
        _check_length(path, "dynamics.links", m.links, m.dof, "model.dof")
        known = {p.name for p in m.parameters}
        for i, link in enumerate(m.links):
            for key in ("mass", "length"):
                if link[key] not in known:
                    raise DescriptionError(path, f"dynamics.links[{i}].{key}",
                                           f"must name a parameter, got {link[key]!r}")
        if m.payload is not None and m.payload not in known:
            raise DescriptionError(path, "dynamics.payload", f"must name a parameter, got {m.payload!r}")
        if m.gravity not in {c.name for c in m.constants}:
            raise DescriptionError(path, "dynamics.gravity", f"must name a constant, got {m.gravity!r}")
    elif m.dynamics_kind == "urdf":
        pass  # checked against the URDF when it was read (urdf_description)
    else:
        raise DescriptionError(path, "dynamics.kind",
                               f"'{m.dynamics_kind}' is not known (known: {', '.join(KINDS)})")


def _validate_model(m: Model) -> None:
    _validate_names(m)
    _validate_shapes(m)
    _validate_dynamics(m)
    _validate_tip(m)
    _validate_expressions(m)


def _term(path: Path, t: Table) -> TermDef:
    read = " ".join(t.get("read").split())
    if read not in READS:
        raise DescriptionError(path, t.sub("read"), f"'{t.get('read')}' is not a way to read a term "
                               f"(known: {', '.join(READS)})")
    goal_range = t.get("goal_range")
    if goal_range is not None and goal_range not in GOAL_RANGES:
        raise DescriptionError(path, t.sub("goal_range"), f"'{goal_range}' is not a goal range "
                               f"(known: {', '.join(GOAL_RANGES)})")
    source, block = READS[read]
    if (source == "control") != (goal_range is None):
        raise DescriptionError(path, t.sub("goal_range"), "the control's term has no goal (its prior mean is 0) "
                               "and every other term has one")
    _check_identifier(t.get("name"), path, t.sub("name"))
    return TermDef(name=t.get("name"), symbol=t.get("symbol"), latex=t.get("latex"), doc=t.get("doc"),
                   label=t.get("label"), unit=t.get("unit"), source=source, block=block, goal_range=goal_range)


def load_terms(path: Path, top: Table) -> tuple[TermDef, ...]:
    """tasks.toml's [[term]] list: names unique, read in distinct ways, exactly one the control."""
    terms = tuple(_term(path, t) for t in top.tables("term", TERM_KEYS))
    for i, t in enumerate(terms):
        if any(o.name == t.name or (o.source, o.block) == (t.source, t.block) for o in terms[:i]):
            raise DescriptionError(path, f"term[{i}]", f"'{t.name}' repeats an earlier term's name or reading")
    if sum(not t.has_sensitivity for t in terms) != 1:
        raise DescriptionError(path, "term", "exactly one term must be read from the control U")
    return terms


def _task(path: Path, t: Table, all_terms: tuple[TermDef, ...], cost_order: tuple[str, ...]) -> Task:
    known = [k.name for k in all_terms]
    terms = list(t.get("terms"))
    for i, term in enumerate(terms):
        if term not in known:
            raise DescriptionError(path, t.sub(f"terms[{i}]"), f"unknown term '{term}' (known: {', '.join(known)})")
    used = [k.name for k in all_terms if k.has_sensitivity and k.name in terms]
    if t.get("error") not in used:
        raise DescriptionError(path, t.sub("error"), f"'{t.get('error')}' is not one of the task's kinematic terms {used}")
    # Only the task's kinematic terms have a sensitivity; an extra one is an unknown key.
    sens = t.table("sensitivity", tuple((s, "string", True) for s in used))
    defaults = t.table("defaults", DEFAULTS_KEYS) if "defaults" in t.raw else None
    precision = defaults.table("precision", tuple((s, "number", True) for s in terms)) if defaults else None
    if precision is None:
        raise DescriptionError(path, t.sub("defaults.precision"), f"missing: a precision for each of {terms}")
    remarks = []
    for r in t.tables("remarks", REMARK_KEYS):
        if r.get("term") not in used:
            raise DescriptionError(path, r.sub("term"), f"'{r.get('term')}' is not a term with a sensitivity in this task")
        remarks.append(Remark(term=r.get("term"), alternative=r.get("alternative"), text=" ".join(r.get("text").split())))
    _check_identifier(t.get("name"), path, t.sub("name"))
    # A paragraph's lines are one line wherever it is shown (the IR's text is one line).
    return Task(name=t.get("name"), index=t.get("index"), title=t.get("title", ""), doc=" ".join(t.get("doc", "").split()),
                terms=terms, error=t.get("error"), sensitivity=dict(sens.raw), remarks=remarks,
                default_precision={k: float(v) for k, v in precision.raw.items()}, path=path, key=t.key,
                all_terms=all_terms, cost_order=cost_order, formulations=_formulations(path, t, used))


def _formulations(path: Path, t: Table, used: list[str]) -> dict[str, Formulation]:
    """[task.formulations.<name>]: each replaces some of the task's sensitivities (of its own
    kinematic terms) and is the default for the dynamics kinds of `default_for`, of which no kind
    may name two."""
    table = t.table("formulations", tuple((k, "table", True) for k in t.get("formulations", {})))
    out: dict[str, Formulation] = {}
    for name in table.raw:
        f = table.table(name, FORMULATION_KEYS)
        _check_identifier(name, path, f.key)
        if name == PAPER:
            raise DescriptionError(path, f.key, f"'{PAPER}' names the task's own sensitivity formulas; "
                                                "give the formulation another name")
        sens = f.table("sensitivity", tuple((s, "string", False) for s in used))
        if not sens.raw:
            raise DescriptionError(path, sens.key, f"empty: a formulation replaces some of {used}")
        kinds = tuple(f.get("default_for", []))
        for i, kind in enumerate(kinds):
            if kind not in KINDS:
                raise DescriptionError(path, f.sub(f"default_for[{i}]"), f"'{kind}' is not a dynamics kind "
                                                                          f"(known: {', '.join(KINDS)})")
            taken = next((o.name for o in out.values() if kind in o.default_for), None)
            if taken is not None:
                raise DescriptionError(path, f.sub(f"default_for[{i}]"), f"'{kind}' already has formulation "
                                                                          f"'{taken}' by default")
        out[name] = Formulation(name=name, doc=" ".join(f.get("doc").split()), default_for=kinds,
                                sensitivity=dict(sens.raw))
    return out


def load_tasks(path: Path) -> list[Task]:
    top = Table(path, "", read_toml(path, "a task file"),
                (("term", "tables", True), ("cost_order", "strings", True), ("task", "tables", True)))
    all_terms = load_terms(path, top)
    order = top.get("cost_order")
    if sorted(order) != sorted(t.name for t in all_terms):
        raise DescriptionError(path, "cost_order", f"{order} must name every term once "
                               f"({', '.join(t.name for t in all_terms)})")
    tasks = [_task(path, t, all_terms, tuple(order)) for t in top.tables("task", TASK_KEYS)]
    for t in tasks:
        _validate_task_expressions(path, t)
    names = [t.name for t in tasks]
    for t in tasks:
        if names.count(t.name) > 1:
            raise DescriptionError(path, f"{t.key}.name", f"'{t.name}' names two tasks")
    return tasks


# --- a model's tasks: its goals and the formulation of each task's sensitivities ------------------

def check_tasks(model: Model, tasks: list[Task]) -> None:
    """What of a description only the task list can check: its goals name a task and a term that
    task has a goal of, with model.dof entries (TIP_DIM for a term at the tip), and its
    [formulation] names a task and one of its formulations."""
    by_name = {t.name: t for t in tasks}
    for name, terms in model.goals.items():
        if name not in by_name:
            raise DescriptionError(model.path, f"goals.{name}", f"no task is named '{name}' (tasks: {', '.join(by_name)})")
        task = by_name[name]
        known = [t.name for t in task.all_terms if t.goal_range is not None]
        for term, values in terms.items():
            key = f"goals.{name}.{term}"
            if term not in known:
                raise DescriptionError(model.path, key, f"unknown key: a goal is given for a term of the task "
                                                        f"definitions ({', '.join(known)})")
            if term not in task.sensitivity_terms:
                raise DescriptionError(model.path, key, f"task '{name}' does not use {term}")
            if task.term(term).on_tip:
                _check_length(model.path, key, values, model.tip_dim, "the tip's components (TIP_DIM)")
            else:
                _check_length(model.path, key, values, model.dof, "model.dof")
    for name, chosen in model.formulation.items():
        if name not in by_name:
            raise DescriptionError(model.path, f"formulation.{name}",
                                   f"no task is named '{name}' (tasks: {', '.join(by_name)})")
        known = [PAPER, *by_name[name].formulations]
        if chosen not in known:
            raise DescriptionError(model.path, f"formulation.{name}", f"'{chosen}' is not a formulation of task "
                                                                      f"'{name}' (known: {', '.join(known)})")


def formulated(task: Task, model: Model) -> Task:
    """The task as `model` derives it: its sensitivities those of the formulation the
    description's [formulation] names, else of the one whose default_for has the model's dynamics
    kind, else the paper's (the task's own). A remark on a replaced formula no longer applies."""
    chosen, why = model.formulation.get(task.name), "description"
    if chosen is None:
        chosen = next((f.name for f in task.formulations.values() if model.dynamics_kind in f.default_for), None)
        why = "default_for"
    if chosen is None or chosen == PAPER:
        return replace(task, formulation=PAPER, chosen_by="default" if chosen is None else why)
    f = task.formulations[chosen]
    return replace(task, sensitivity={**task.sensitivity, **f.sensitivity}, formulation=chosen, chosen_by=why,
                   remarks=[r for r in task.remarks if r.term not in f.sensitivity])


def model_tasks(model: Model, tasks: list[Task]) -> list[Task]:
    """The tasks as `model` derives them (check_tasks, then formulated)."""
    check_tasks(model, tasks)
    return [formulated(t, model) for t in tasks]


# --- the expressions a description holds (the grammar of expression.py) ----------------------------

# The names tasks.toml's formulas may use besides inv (see that file's header).
FORMULA_NAMES = ("A", "B", "I", "O", "IO", "OI", "E", "dX_dU", "J")
# The largest magnitude of a description's value (a constant, an equilibrium, a goal) and of a
# precision: beyond it a number means nothing physical, and it would only overflow later.
MAX_VALUE = 1e6
MAX_PRECISION = 1e6


def expression(path: Path | str, key: str, text: str, names=(), **grammar) -> Expression:
    """`text` parsed by expression.py's grammar over `names`, or a DescriptionError naming the key."""
    try:
        return parse(text, names, **grammar)
    except ExpressionError as err:
        raise DescriptionError(path, key, f"{err} in '{text}'") from err


def value(path: Path | str, key: str, text: str) -> float:
    """A value that must be a number (pi/2, 1e-3, sqrt(2)/2) within +-MAX_VALUE: its double."""
    v = expression(path, key, text).value
    if v is None or abs(v) > MAX_VALUE:
        raise DescriptionError(path, key, f"'{text}' is not a number within [-{MAX_VALUE:g}, {MAX_VALUE:g}]")
    return v


def formula_expression(path: Path | str, key: str, text: str, names) -> Expression:
    """A task formula parsed (expression.formula's grammar), or a DescriptionError naming the key."""
    try:
        return formula(text, names)
    except ExpressionError as err:
        raise DescriptionError(path, key, f"{err} in '{text}'") from err


def task_formula(task: Task, key: str, text: str, namespace: dict):
    """A task formula (`key` under the task's table) built on `namespace`: the names of
    FORMULA_NAMES and inv, as matrices and a function of any matrix arithmetic."""
    names = {k: v for k, v in namespace.items() if k not in FORMULA_FUNCTIONS}
    full_key = f"{task.key}.{key}" if task.key else key
    tree = formula_expression(task.path, full_key, text, names)
    try:
        return tree.evaluate(names, {f: namespace[f] for f in FORMULA_FUNCTIONS}, python_number)
    except Exception as err:  # a shape or a singular inverse, in whichever arithmetic: the formula's error
        raise DescriptionError(task.path, full_key, f"cannot evaluate '{text}': {err}") from err


def sensitivity(task: Task, term: str, namespace: dict):
    """d term / dU by the task's formula (sensitivity.<term>) on `namespace`."""
    return task_formula(task, f"sensitivity.{term}", task.sensitivity[term], namespace)


def _validate_expressions(m: Model) -> None:
    """Every expression of the description in the grammar, each value a number in range; a URDF
    arm's equilibrium is at rest under its own gravity feed-forward (q_dot^e = 0, U^e = 0)."""
    names = [n.name for n in m.parameters + m.constants + m.q + m.q_dot + m.u]
    for c in m.constants:
        if not math.isfinite(c.value) or abs(c.value) > MAX_VALUE:
            raise DescriptionError(m.path, f"constants.{c.name}.value",
                                   f"{c.value!r} is not a number within [-{MAX_VALUE:g}, {MAX_VALUE:g}]")
    if m.dynamics_kind == "explicit":
        for i, text in enumerate(m.q_ddot):
            expression(m.path, f"dynamics.q_ddot[{i}]", text, names)
    # The tip depends on the joint positions, the parameters and the constants only.
    tip_names = {n.name for n in m.parameters + m.constants + m.q}
    for i, text in enumerate(m.tip or []):
        extra = sorted(_names_used(expression(m.path, f"tip.position[{i}]", text, names).tree) - tip_names)
        if extra:
            raise DescriptionError(m.path, f"tip.position[{i}]", f"'{text}' uses {', '.join(extra)}: the tip depends "
                                                                 "on the joint positions, the parameters and the "
                                                                 "constants only")
    for label, texts in (("q", m.equilibrium_q), ("q_dot", m.equilibrium_q_dot), ("u", m.equilibrium_u)):
        for i, text in enumerate(texts):
            v = value(m.path, f"equilibrium.{label}[{i}]", text)
            if m.dynamics_kind == "urdf" and label != "q" and v != 0:
                raise DescriptionError(m.path, f"equilibrium.{label}[{i}]",
                                       f"'{text}' is not 0: a URDF arm's equilibrium is at rest (q_dot = 0) with "
                                       "U = 0, the impedance and gravity feed-forward holding it")
            if m.dynamics_kind == "urdf" and label == "q":
                _within_limits(m, i, text, v)
    for task, terms in m.goals.items():
        for term, values in terms.items():
            for i, text in enumerate(values):
                value(m.path, f"goals.{task}.{term}[{i}]", text)
    printed_names = [n.name for n in m.parameters + m.constants]
    for label, matrix in (("A", m.printed_a), ("B", m.printed_b)):
        for i, row in enumerate(matrix or []):
            for j, text in enumerate(row):
                expression(m.path, f"printed.{label}[{i}][{j}]", text, printed_names)


def _names_used(node) -> set[str]:
    """The names an expression's tree reads (not its functions)."""
    out, pending = set(), [node]
    while pending:
        n = pending.pop()
        if n.kind == "name" and n.value is None:  # pi is a number
            out.add(n.text)
        pending.extend(n.args)
        pending.extend(operand for _, operand in n.rest)
    return out


def _within_limits(m: Model, i: int, text: str, v: float) -> None:
    """A URDF arm's q^e[i] (the double `v`) inside its joint's <limit lower upper> (urdf.py's
    rule: revolute and prismatic joints; an absent side is no bound), else refused."""
    chain = m.chain
    if chain is None or i >= len(chain.limits):
        return
    lower, upper = chain.limits[i]
    if (lower is not None and v < lower) or (upper is not None and v > upper):
        shown = lambda b, inf: inf if b is None else repr(b)  # noqa: E731
        raise DescriptionError(m.path, f"equilibrium.q[{i}]",
                               f"'{text}' = {v!r} is outside joint '{chain.joint_names[i]}''s limits "
                               f"[{shown(lower, '-inf')}, {shown(upper, 'inf')}] ({chain.path} <limit lower upper>)")


def _validate_task_expressions(path: Path, t: Task) -> None:
    for term, text in t.sensitivity.items():
        formula_expression(path, f"{t.key}.sensitivity.{term}", text, FORMULA_NAMES)
    for i, r in enumerate(t.remarks):
        formula_expression(path, f"{t.key}.remarks[{i}].alternative", r.alternative, FORMULA_NAMES)
    for name, f in t.formulations.items():
        for term, text in f.sensitivity.items():
            formula_expression(path, f"{t.key}.formulations.{name}.sensitivity.{term}", text, FORMULA_NAMES)
    for term, v in t.default_precision.items():
        if not (0 <= v <= MAX_PRECISION):
            raise DescriptionError(path, f"{t.key}.defaults.precision.{term}",
                                   f"{v!r} is not within [0, {MAX_PRECISION:g}]")
