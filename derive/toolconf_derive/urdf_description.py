"""The rules of a URDF arm's description (`dynamics.kind = "urdf"`): its `[urdf]`, `[impedance]`
and `[tool]` tables, checked against the chain the URDF reader (urdf.py) finds, and the tool's
parameters and rule that follow. description.py calls `urdf_names` for such a model; nothing here
imports description.py.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from .errors import DescriptionError
from .files import Table
from .quantities import Named
from .urdf import read_chain

# The keys of a URDF arm's own tables (description.py's MODEL_KEYS for the rest).
URDF_KEYS = {
    "urdf": (("file", "text", True), ("base", "text", True), ("flange", "text", True),
             ("gravity", "numbers", True), ("source", "text", False)),
    "impedance": (("stiffness", "numbers", True), ("damping", "numbers", True), ("source", "text", False)),
    "tool": (("com_bound", "number", False), ("sample", "table", False), ("source", "text", False)),
}
# A URDF arm's gravity (m/s^2) and joint impedance gains (N m/rad, N m s/rad): physical ranges.
MAX_GRAVITY = 1e3
MAX_GAIN = 1e6


def urdf_names(path: Path, top: Table):
    """Kind "urdf": the chain from the URDF file, the tool's parameters (TOOL_PARAMETERS) and the
    coordinates named after the URDF's joints: q = the joint positions, U = their torques; with
    the model's URDF fields (its chain, gravity, impedance and tool rule)."""
    for key in ("parameters", "coordinates"):
        if key in top.raw:
            raise DescriptionError(path, key, "not allowed for dynamics.kind = 'urdf': the tool's parameters and the "
                                              "URDF's joints define them")
    for key in ("urdf", "impedance"):
        if key not in top.raw:
            raise DescriptionError(path, key, "missing (required for dynamics.kind = 'urdf')")
    urdf = top.table("urdf", URDF_KEYS["urdf"])
    imp = top.table("impedance", URDF_KEYS["impedance"])
    if len(urdf.get("gravity")) != 3:
        raise DescriptionError(path, "urdf.gravity", f"must be 3 numbers (m/s^2, in the base frame), got {urdf.get('gravity')!r}")
    for i, g in enumerate(urdf.get("gravity")):
        if abs(g) > MAX_GRAVITY:
            raise DescriptionError(path, f"urdf.gravity[{i}]", f"{g!r} is outside [-{MAX_GRAVITY:g}, {MAX_GRAVITY:g}] m/s^2")
    file = Path(os.path.normpath(path.parent / urdf.get("file")))
    if not os.path.lexists(file):
        # The reader would name only the URDF; the user needs the key and the rule for its path.
        raise DescriptionError(path, "urdf.file", f"{urdf.get('file')!r}: no such file {str(file)!r} (urdf.file is "
                                                  "relative to the folder of the description)")
    chain = read_chain(file, urdf.get("base"), urdf.get("flange"))
    dof = top.raw["model"]["dof"]
    if dof != chain.dof:
        raise DescriptionError(path, "model.dof", f"is {dof}, the chain from '{chain.base}' to '{chain.flange}' "
                                                  f"has {chain.dof} moving joints")
    for key in ("stiffness", "damping"):
        values = imp.get(key)
        if len(values) != chain.dof:
            raise DescriptionError(path, f"impedance.{key}", f"has {len(values)} entries, the chain from "
                                                             f"'{chain.base}' to '{chain.flange}' has {chain.dof} joints")
        for i, v in enumerate(values):
            if not 0 <= v <= MAX_GAIN:
                raise DescriptionError(path, f"impedance.{key}[{i}]",
                                       f"{v!r} is not within [0, {MAX_GAIN:g}] ({chain.joint_names[i]})")
    q = [Named(j, rf"q_{{{i + 1}}}", "rad" if b.kind == "revolute" else "m", f"position of joint {j}")
         for i, (j, b) in enumerate(zip(chain.joint_names, chain.bodies))]
    q_dot = [Named(f"{j}_dot", rf"\dot{{q}}_{{{i + 1}}}") for i, j in enumerate(chain.joint_names)]
    u = [Named(f"{j}_torque", rf"U_{{{i + 1}}}") for i, j in enumerate(chain.joint_names)]
    extra = {"chain": chain, "urdf_gravity": [float(g) for g in urdf.get("gravity")],
             "impedance_stiffness": [float(v) for v in imp.get("stiffness")],
             "impedance_damping": [float(v) for v in imp.get("damping")],
             "impedance_source": imp.get("source", ""),
             "tool_rule": tool_rule(path, top.table("tool", URDF_KEYS["tool"]))}
    return list(TOOL_PARAMETERS), q, q_dot, u, extra


TOOL_PARAMETERS = [
    Named("tool_mass", "m_t", "kg", "mass of the tool"),
    *(Named(f"tool_com_{a}", f"c_{a}", "m", f"tool's centre of mass, {a} in the flange frame") for a in "xyz"),
    *(Named(f"tool_i{a}{a}", f"I_{{{a}{a}}}", "kg m^2",
            f"tool's principal moment about its centre of mass, flange {a} axis") for a in "xyz"),
    *(Named(f"tool_i{ab}", f"I_{{{ab}}}", "kg m^2",
            f"tool's product of inertia about its centre of mass, flange axes (URDF's i{ab})")
      for ab in ("xy", "xz", "yz")),
    *(Named(f"tool_tip_{a}", f"t_{a}", "m", f"tool's tip (tool-centre point), {a} in the flange frame") for a in "xyz"),
]
# What a tools file that leaves a column out means: a tool whose inertia tensor is diagonal in
# flange axes (files written before the products were parameters), and a tip at the flange.
PARAMETER_DEFAULTS = {"tool_ixy": 0.0, "tool_ixz": 0.0, "tool_iyz": 0.0,
                      "tool_tip_x": 0.0, "tool_tip_y": 0.0, "tool_tip_z": 0.0}
# Which tools are valid (generated/src/validity.rs; toolconf-core's ToolN::new refuses the rest)
# and the box random tools are drawn from (the mixed sampler, the design tests). A rigid body:
# mass > 0; an inertia tensor I (moments and products) that is positive definite with eigenvalues
# obeying the triangle inequality, i.e. 1/2 tr(I) 1 - I (the body's second moment of mass) positive
# semi-definite (the linear rule on the diagonal moments is the part of it a design can use, the
# `inertia` rule the whole); its centre of mass and its tip within `com_bound` of the flange along
# each axis (a description's `[tool] com_bound`). Slack: urdf.py's relative 1e-9 for printed decimals.
COM_BOUND = 1.0
TRIANGLE_SLACK = 1e-9
# A tool of 0.05-3 kg with its centre of mass within 5 cm of the flange axis and up to 25 cm out,
# moments of a body a few centimetres to 30 cm across (a description's `[tool.sample]`).
# Products within 1e-4 kg m^2 (a body a little off its flange axes), tips 5-35 cm out along the
# flange's z axis and within 5 cm of it.
SAMPLE = {"tool_mass": (0.05, 3.0), "tool_com_x": (-0.05, 0.05), "tool_com_y": (-0.05, 0.05),
          "tool_com_z": (0.0, 0.25), "tool_ixx": (1e-4, 0.02), "tool_iyy": (1e-4, 0.02), "tool_izz": (1e-4, 0.02),
          "tool_ixy": (-1e-4, 1e-4), "tool_ixz": (-1e-4, 1e-4), "tool_iyz": (-1e-4, 1e-4),
          "tool_tip_x": (-0.05, 0.05), "tool_tip_y": (-0.05, 0.05), "tool_tip_z": (0.05, 0.35)}
_MOMENTS = ("tool_ixx", "tool_iyy", "tool_izz")
_PRODUCTS = ("tool_ixy", "tool_ixz", "tool_iyz")


def tool_rule(path, table) -> dict:
    """The IR's `model.tool_rule` of a URDF tool: per parameter its domain (lo, hi, open ends;
    None for no bound) and sampling box, and the linear constraints c . p <= 0 with their text.
    `table` is the description's `[tool]` (COM_BOUND and SAMPLE where it is silent)."""
    bound = table.get("com_bound", COM_BOUND)
    # At most the runtime's tool-parameter range (toolconf::validate::TOOL_PARAMETER's 1e6), the
    # magnitude over which the generated arithmetic is checked finite (tests/parameter_range.rs).
    if not (isinstance(bound, (int, float)) and math.isfinite(bound) and 0 < bound <= 1e6):
        raise DescriptionError(path, "tool.com_bound", f"{bound!r} must be a number in (0, 1e6] (m)")
    names = [p.name for p in TOOL_PARAMETERS]
    domains = [_domain(n, float(bound)) for n in names]
    raw = table.get("sample", {})
    for key in raw:
        if key not in names:
            raise DescriptionError(path, f"tool.sample.{key}", f"unknown parameter (known: {', '.join(names)})")
    sample = []
    for name, domain in zip(names, domains):
        box = raw.get(name, SAMPLE[name])
        key = f"tool.sample.{name}"
        if not (isinstance(box, (list, tuple)) and len(box) == 2
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in box)):
            raise DescriptionError(path, key, f"must be [lo, hi], two finite numbers, got {box!r}")
        lo, hi = float(box[0]), float(box[1])
        if not lo < hi:
            raise DescriptionError(path, key, f"[{lo}, {hi}] is empty or a point (need lo < hi)")
        if not (_inside(lo, domain) and _inside(hi, domain)):
            raise DescriptionError(path, key, f"[{lo}, {hi}] leaves the parameter's domain")
        sample.append([lo, hi])
    constraints = []
    for k, moment in enumerate(_MOMENTS):
        others = [m for m in _MOMENTS if m != moment]
        coefficients = [0.0] * len(names)
        coefficients[names.index(moment)] = 1.0
        for m in others:
            coefficients[names.index(m)] = -(1.0 + TRIANGLE_SLACK)
        constraints.append({"coefficients": coefficients,
                            "text": f"{moment} <= {others[0]} + {others[1]} (triangle inequality of the "
                                    "principal moments)"})
    centre = [(lo + hi) / 2 for lo, hi in sample]
    for c in constraints:
        if sum(a * x for a, x in zip(c["coefficients"], centre)) > 0:
            raise DescriptionError(path, "tool.sample", f"the sampling box's centre violates {c['text']}: random "
                                                        "tools could not be drawn from it")
    return {"domains": domains, "constraints": constraints, "sample": sample,
            "inertia": {"moments": [names.index(m) for m in _MOMENTS],
                        "products": [names.index(m) for m in _PRODUCTS], "slack": TRIANGLE_SLACK},
            "defaults": [PARAMETER_DEFAULTS.get(n) for n in names],
            "source": table.get("source", "")}


def _domain(name: str, bound: float) -> dict:
    if name.startswith(("tool_com_", "tool_tip_")):
        return {"lo": -bound, "hi": bound, "lo_open": False, "hi_open": False}
    if name in _PRODUCTS:
        return {"lo": None, "hi": None, "lo_open": True, "hi_open": True}
    return {"lo": 0.0, "hi": None, "lo_open": True, "hi_open": True}


def _inside(value: float, domain: dict) -> bool:
    lo, hi = domain["lo"], domain["hi"]
    above = lo is None or (value > lo if domain["lo_open"] else value >= lo)
    below = hi is None or (value < hi if domain["hi_open"] else value <= hi)
    return above and below
