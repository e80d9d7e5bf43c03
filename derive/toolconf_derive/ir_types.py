"""The IR's types: one dataclass per struct of the renderer's derive/render/src/ir.rs, with the same
name and the same fields in the same order, which is the order of the keys in the JSON. The
renderer refuses a key it does not know and a missing one, so a field added here and not there
(or the other way round) stops `make derive` at the render; derive/tests/test_ir_types.py holds
the two lists equal without rendering.

A field made with `omitted()` is left out of the JSON when it is None (the renderer's
`#[serde(default, skip_serializing_if = "Option::is_none")]`); every other field is written, as
`null` when it is None. `as_json` turns a document of these into what json.dumps writes.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any


def omitted():
    """A field left out of the JSON when it is None."""
    return field(default=None, metadata={"omit_none": True})


def as_json(value: Any) -> Any:
    """`value` as JSON data: a dataclass as an object of its fields in order (an `omitted()` one
    left out when None), lists and dicts item by item, anything else as it is."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: as_json(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not (f.metadata.get("omit_none") and getattr(value, f.name) is None)}
    if isinstance(value, (list, tuple)):
        return [as_json(v) for v in value]
    if isinstance(value, dict):
        return {k: as_json(v) for k, v in value.items()}
    return value


@dataclass
class Generator:
    """What made the IR, as the generated files name it."""
    command: str
    model: str
    tasks: str
    ir: str
    vectors: str
    derive: str
    render: str


@dataclass
class Parameter:
    name: str
    latex: str
    unit: str
    doc: str


@dataclass
class Constant:
    name: str
    rust: str
    value: float
    unit: str
    doc: str


@dataclass
class Variable:
    """A state or control variable."""
    name: str
    latex: str


@dataclass
class Equilibrium:
    """X^e and U^e as Rust literals."""
    x: list[str]
    u: list[str]


@dataclass
class Domain:
    """One tool parameter's domain; None for no bound."""
    lo: float | None
    hi: float | None
    lo_open: bool
    hi_open: bool


@dataclass
class Constraint:
    """c . p <= 0, and the rule in words."""
    coefficients: list[float]
    text: str


@dataclass
class Inertia:
    """The parameters that are a rigid body's inertia tensor about its centre of mass (their
    indices: the moments xx, yy, zz and the products xy, xz, yz), which must be positive definite
    with eigenvalues obeying the triangle inequality, to a relative `slack`."""
    moments: list[int]
    products: list[int]
    slack: float


@dataclass
class ToolRule:
    domains: list[Domain]
    constraints: list[Constraint]
    sample: list[list[float]]
    # Per parameter, what a tools file that leaves its column out means (None: required).
    defaults: list[float | None]
    inertia: Inertia | None
    source: str

    @classmethod
    def of(cls, rule: dict) -> "ToolRule":
        """The rule urdf_description.tool_rule gives as a dict."""
        inertia = rule.get("inertia")
        return cls(domains=[Domain(**d) for d in rule["domains"]],
                   constraints=[Constraint(**c) for c in rule["constraints"]],
                   sample=rule["sample"], defaults=rule["defaults"],
                   inertia=None if inertia is None else Inertia(**inertia), source=rule["source"])


@dataclass
class Model:
    name: str
    title: str
    source: str
    dof: int
    state_dim: int
    # TIP_DIM: the components of the tip the tip terms use (their first rows of the n).
    tip_dim: int
    parameters: list[Parameter]
    constants: list[Constant]
    state: list[Variable]
    control: list[Variable]
    equilibrium: Equilibrium
    tool_rule: ToolRule | None = omitted()


@dataclass
class TermRead:
    """Where a term's value is read: `block` (n rows) of the state X (`state`), of its rate
    (`state_rate`), the control (`control`, block 0), or the tool's tip (`tip`, block = the order
    of the derivative: 0 the position y(q), 1 the velocity J(q) q_dot)."""
    source: str
    block: int


@dataclass
class Term:
    """A free-energy term of tasks.toml's [[term]] list."""
    name: str
    symbol: str
    latex: str
    doc: str
    label: str
    unit: str
    read: TermRead
    goal_range: str | None = omitted()


@dataclass
class Goal:
    term: str
    rust: list[str]


@dataclass
class Precision:
    term: str
    rust: str
    value: float


@dataclass
class Formulation:
    """Which formulation of its sensitivities a task has in this model: `paper` (tasks.toml's
    formulas) or a name of its [task.formulations] (with that table's doc), and why: `default`
    (nothing chose another), `default_for` (the formulation's default_for names the model's
    dynamics kind) or `description` (the model's [formulation] names it)."""
    name: str
    doc: str
    chosen_by: str


@dataclass
class Task:
    name: str
    index: int
    title: str
    doc: str
    terms: list[str]
    sensitivity_terms: list[str]
    error: str
    sensitivity_function: str
    confidence_function: str
    gradient_function: str
    goals: list[Goal]
    precisions: list[Precision]
    formulation: Formulation


@dataclass
class Arg:
    name: str
    doc: str
    rows: int
    cols: int
    rust_type: str
    symmetric: bool
    used: bool


@dataclass
class Cost:
    """Operation counts (cost.py), `kinds` in name order."""
    ops: int
    weighted: int
    kinds: dict[str, int]
    sin_cos: int


@dataclass
class Let:
    name: str
    rust: str


@dataclass
class Binding:
    name: str
    arg: str
    access: str


@dataclass
class Trig:
    angle: str
    sin: str
    cos: str


@dataclass
class CoefficientArg:
    name: str
    rust_type: str
    used: bool


@dataclass
class Coefficients:
    struct: str
    count: int
    constants: list[Let]
    bindings: list[Binding]
    temporaries: list[Let]
    values: list[str]
    cost: Cost
    args: list[CoefficientArg]


@dataclass
class Entry:
    """A nonzero output entry; `rust` is its closed form (None where an instruction sequence
    writes it)."""
    row: int
    col: int
    rust: str | None = omitted()


@dataclass
class Output:
    name: str
    doc: str
    rows: int
    cols: int
    rust_type: str
    symmetric: bool
    entries: list[Entry]


@dataclass
class Slot:
    name: str
    mutable: bool


@dataclass
class Step:
    target: str
    rust: str


@dataclass
class Sequence:
    """CasADi's instructions on its work slots (sequence.py)."""
    slots: list[Slot]
    steps: list[Step]


@dataclass
class Function:
    name: str
    doc: str
    equation: str
    args: list[Arg]
    coefficients: Coefficients | None
    cost: Cost
    unhoisted_cost: Cost | None
    outputs: list[Output]
    constants: list[Let]
    bindings: list[Binding]
    trig: list[Trig]
    compounds: list[Let]
    temporaries: list[Let]
    sequence: Sequence | None = omitted()


@dataclass
class TestVectors:
    file: str
    per_function: int


@dataclass
class Equation:
    lhs: str
    rhs: str


@dataclass
class Comparison:
    entry: str
    derived: str
    printed: str
    equal: bool
    difference: str


@dataclass
class SensitivityReport:
    term: str
    what: str
    formula: str
    latex: str


@dataclass
class GradientValue:
    name: str
    value: str


@dataclass
class GradientClosedForm:
    name: str
    latex: str


@dataclass
class GradientReport:
    reference: str
    values: list[GradientValue]
    closed: list[GradientClosedForm] | None


@dataclass
class Remark:
    what: str
    text: str
    alternative_formula: str
    alternative: str
    used: str
    equal: bool


@dataclass
class TaskReport:
    name: str
    index: int
    title: str
    doc: str
    sensitivities: list[SensitivityReport]
    confidence_formula: str
    default_precisions: str
    confidence_default: str
    gradient: GradientReport
    remarks: list[Remark]


@dataclass
class ClosedFormReport:
    """The report of a model derived in closed form (report.py)."""
    printed_where: str
    equations: list[Equation]
    equation_refs: list[str]
    equilibrium_x: str
    equilibrium_u: str
    a: str
    b: str
    comparisons: list[Comparison]
    differences: list[Comparison]
    tasks: list[TaskReport]


@dataclass
class Body:
    joint: str
    kind: str
    axis: str
    mass: str
    stiffness: str
    damping: str


@dataclass
class Logdet:
    task: str
    value: str


@dataclass
class ReportTool:
    name: str
    parameters: str
    gravity_sv: str
    stiffness_sv: str
    logdets: list[Logdet]


@dataclass
class CostRow:
    name: str
    ops: int
    weighted: int
    sin_cos: int
    agreement: str
    coefficients: int | None = omitted()
    unhoisted: int | None = omitted()


@dataclass
class UrdfReport:
    """The report of a URDF arm (urdf_functions.report_data)."""
    urdf: str
    robot: str
    base: str
    flange: str
    gravity: str
    impedance_source: str
    equilibrium: str
    bodies: list[Body]
    tools: list[ReportTool]
    costs: list[CostRow]
    equation_refs: list[str]


@dataclass
class Ir:
    """One model's IR (generated/<model>.json)."""
    schema: int
    generator: Generator
    model: Model
    terms: list[Term]
    # The order J's summands are added in (tasks.toml's cost_order).
    cost_order: list[str]
    tasks: list[Task]
    functions: list[Function]
    test_vectors: TestVectors
    report: ClosedFormReport | UrdfReport
    templates: list[str] | None = omitted()
