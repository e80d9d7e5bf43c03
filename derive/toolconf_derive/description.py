"""Model and task descriptions: the TOML files under derive/ read into plain data.

Nothing here derives anything; the expressions stay strings so that SymPy (symbolic.py) and
CasADi (numeric.py) each parse them on their own, which keeps the cross-check independent.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path


class DescriptionError(ValueError):
    """A model or task description that cannot be used, with the offending key named."""


@dataclass(frozen=True)
class Named:
    name: str
    latex: str
    unit: str = ""
    doc: str = ""


@dataclass(frozen=True)
class Constant(Named):
    value: float = 0.0


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

    @property
    def state(self) -> list[Named]:
        return self.q + self.q_dot

    @property
    def state_dim(self) -> int:
        return 2 * self.dof


@dataclass(frozen=True)
class Remark:
    term: str
    alternative: str
    text: str


@dataclass(frozen=True)
class Task:
    name: str
    index: int
    title: str
    doc: str
    terms: list[str]
    sensitivity: dict[str, str]
    remarks: list[Remark] = field(default_factory=list)
    default_precision: dict[str, float] = field(default_factory=dict)

    @property
    def sensitivity_terms(self) -> list[str]:
        """The kinematic terms (theta, theta_dot, theta_ddot) this task's controller uses, in order."""
        return [t for t in ("theta", "theta_dot", "theta_ddot") if t in self.terms]


KNOWN_TERMS = ("theta", "theta_dot", "theta_ddot", "u")


def _require(table: dict, key: str, where: str):
    if key not in table:
        raise DescriptionError(f"{where}: missing key '{key}'")
    return table[key]


def _named(entry: dict, where: str) -> Named:
    return Named(
        name=_require(entry, "name", where),
        latex=entry.get("latex", entry["name"]),
        unit=entry.get("unit", ""),
        doc=entry.get("doc", ""),
    )


def _check_identifier(name: str, where: str) -> None:
    if not name.isidentifier() or name != name.lower():
        raise DescriptionError(f"{where}: '{name}' must be a lower-case identifier (it becomes a Rust name)")


def load_model(path: Path) -> Model:
    raw = tomllib.loads(path.read_text())
    m = _require(raw, "model", str(path))
    dof = int(_require(m, "dof", f"{path}: [model]"))
    coords = _require(raw, "coordinates", str(path))
    dyn = _require(raw, "dynamics", str(path))
    eq = _require(raw, "equilibrium", str(path))
    printed = raw.get("printed", {})

    params = [_named(p, f"{path}: [[parameters]]") for p in _require(raw, "parameters", str(path))]
    constants = [
        Constant(name=k, latex=v.get("latex", k), unit=v.get("unit", ""), doc=v.get("doc", ""), value=float(v["value"]))
        for k, v in raw.get("constants", {}).items()
    ]
    q = [_named(c, f"{path}: coordinates.q") for c in _require(coords, "q", f"{path}: [coordinates]")]
    q_dot = [_named(c, f"{path}: coordinates.q_dot") for c in _require(coords, "q_dot", f"{path}: [coordinates]")]
    u = [_named(c, f"{path}: coordinates.u") for c in _require(coords, "u", f"{path}: [coordinates]")]

    model = Model(
        path=path,
        name=_require(m, "name", f"{path}: [model]"),
        title=m.get("title", ""),
        source=m.get("source", ""),
        dof=dof,
        parameters=params,
        constants=constants,
        q=q,
        q_dot=q_dot,
        u=u,
        dynamics_kind=_require(dyn, "kind", f"{path}: [dynamics]"),
        equations=dyn.get("equations", []),
        q_ddot=list(dyn.get("q_ddot", [])),
        equilibrium_q=[str(v) for v in _require(eq, "q", f"{path}: [equilibrium]")],
        equilibrium_q_dot=[str(v) for v in _require(eq, "q_dot", f"{path}: [equilibrium]")],
        equilibrium_u=[str(v) for v in _require(eq, "u", f"{path}: [equilibrium]")],
        links=list(dyn.get("links", [])),
        gravity=str(dyn.get("gravity", "g")),
        payload=dyn.get("payload"),
        goals={task: {term: [str(v) for v in vs] for term, vs in terms.items()}
               for task, terms in raw.get("goals", {}).items()},
        printed_where=printed.get("where", ""),
        printed_a=printed.get("A"),
        printed_b=printed.get("B"),
    )
    _validate_model(model)
    return model


def _validate_model(m: Model) -> None:
    where = str(m.path)
    _check_identifier(m.name, f"{where}: model.name")
    names = [n.name for n in m.parameters + m.constants + m.q + m.q_dot + m.u]
    for n in names:
        _check_identifier(n, where)
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise DescriptionError(f"{where}: names used twice: {', '.join(dupes)}")
    for label, seq in (("coordinates.q", m.q), ("coordinates.q_dot", m.q_dot), ("coordinates.u", m.u),
                       ("equilibrium.q", m.equilibrium_q), ("equilibrium.q_dot", m.equilibrium_q_dot),
                       ("equilibrium.u", m.equilibrium_u)):
        if len(seq) != m.dof:
            raise DescriptionError(f"{where}: {label} has {len(seq)} entries, model.dof is {m.dof}")
    for task, terms in m.goals.items():
        for term, values in terms.items():
            if term not in ("theta", "theta_dot", "theta_ddot") or len(values) != m.dof:
                raise DescriptionError(f"{where}: goals.{task}.{term} must be a known term with {m.dof} entries")
    if m.dynamics_kind == "explicit":
        if len(m.q_ddot) != m.dof:
            raise DescriptionError(f"{where}: dynamics.q_ddot has {len(m.q_ddot)} entries, model.dof is {m.dof}")
    elif m.dynamics_kind == "planar_chain":
        if len(m.links) != m.dof:
            raise DescriptionError(f"{where}: dynamics.links has {len(m.links)} links, model.dof is {m.dof}")
        known = {p.name for p in m.parameters}
        for i, link in enumerate(m.links):
            for key in ("mass", "length"):
                if link.get(key) not in known:
                    raise DescriptionError(f"{where}: dynamics.links[{i}].{key} must name a parameter, got {link.get(key)!r}")
        if m.payload is not None and m.payload not in known:
            raise DescriptionError(f"{where}: dynamics.payload must name a parameter, got {m.payload!r}")
        if m.gravity not in {c.name for c in m.constants}:
            raise DescriptionError(f"{where}: dynamics.gravity must name a constant, got {m.gravity!r}")
    else:
        raise DescriptionError(f"{where}: dynamics.kind '{m.dynamics_kind}' is not known (known: explicit, planar_chain)")
    n2 = 2 * m.dof
    if m.printed_a is not None and (len(m.printed_a) != n2 or any(len(r) != n2 for r in m.printed_a)):
        raise DescriptionError(f"{where}: printed.A must be {n2}x{n2}")
    if m.printed_b is not None and (len(m.printed_b) != n2 or any(len(r) != m.dof for r in m.printed_b)):
        raise DescriptionError(f"{where}: printed.B must be {n2}x{m.dof}")


def load_tasks(path: Path) -> list[Task]:
    raw = tomllib.loads(path.read_text())
    tasks = []
    for i, t in enumerate(_require(raw, "task", str(path))):
        where = f"{path}: task[{i}]"
        terms = list(_require(t, "terms", where))
        for term in terms:
            if term not in KNOWN_TERMS:
                raise DescriptionError(f"{where}: unknown term '{term}' (known: {', '.join(KNOWN_TERMS)})")
        sens = dict(_require(t, "sensitivity", where))
        task = Task(
            name=_require(t, "name", where),
            index=int(_require(t, "index", where)),
            title=t.get("title", ""),
            doc=t.get("doc", ""),
            terms=terms,
            sensitivity=sens,
            remarks=[Remark(**r) for r in t.get("remarks", [])],
            default_precision={k: float(v) for k, v in t.get("defaults", {}).get("precision", {}).items()},
        )
        if set(task.default_precision) != set(task.terms):
            raise DescriptionError(f"{where}: defaults.precision must give a precision for each of {task.terms}")
        for r in task.remarks:
            if r.term not in task.sensitivity_terms:
                raise DescriptionError(f"{where}: a remark is about '{r.term}', which the task does not use")
        missing = [s for s in task.sensitivity_terms if s not in sens]
        extra = [s for s in sens if s not in task.sensitivity_terms]
        if missing or extra:
            raise DescriptionError(f"{where}: sensitivity must define exactly the task's kinematic terms "
                                   f"(missing: {missing}, not used: {extra})")
        _check_identifier(task.name, where)
        tasks.append(task)
    return tasks
