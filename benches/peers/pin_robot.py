"""A URDF arm with a tool at its flange as Pinocchio sees it, built from the model description
(derive/models/<name>.toml) and the URDF file alone, without toolconf: what a Python user would
write, and the independent reference of python/tests/test_dynamics.py.

The URDF is cut at the description's flange (every link below it dropped, as toolconf's reader
drops the hand) and the tool added as a fixed link: mass, centre of mass in the flange frame,
its inertia tensor about it in flange axes, and its tip as a frame "tool_tip". Rotations within 1e-9 of a multiple of pi/2 are given
as that multiple, as toolconf's reader takes them (UR5 prints pi/2 as 1.57079632679).

Needs numpy and pin (Pinocchio) only.
"""

from __future__ import annotations

import math
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "derive" / "models"


@dataclass(frozen=True)
class Description:
    """What a URDF model description says: the URDF, its flange, the equilibrium pose and the
    joint impedance (K, D per joint)."""
    urdf: Path
    flange: str
    q_e: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray


def description(name: str) -> Description:
    """A model of derive/models by name, or a description of kind urdf by its path (*.toml)."""
    path = Path(name) if name.endswith(".toml") else MODELS / f"{name}.toml"
    with path.open("rb") as f:
        d = tomllib.load(f)
    env = {"__builtins__": {}, "pi": math.pi}
    q_e = np.array([float(eval(str(v), env)) for v in d["equilibrium"]["q"]])  # noqa: S307 - our description
    return Description((path.parent / d["urdf"]["file"]).resolve(), d["urdf"]["flange"], q_e,
                       np.array(d["impedance"]["stiffness"], dtype=float),
                       np.array(d["impedance"]["damping"], dtype=float))


def quarter_turn(angle: float) -> float:
    k = round(angle / (math.pi / 2))
    return k * (math.pi / 2) if abs(angle - k * (math.pi / 2)) < 1e-9 else angle


def model_with_tool(name: str, tool) -> tuple[pin.Model, pin.Data]:
    """Pinocchio's model of robot `name` with `tool` = (mass, com_x, com_y, com_z, ixx, iyy, izz,
    [ixy, ixz, iyz, [tip_x, tip_y, tip_z]]) fixed at its flange (the products and the tip zero
    where not given), its tip the frame "tool_tip"."""
    d = description(name)
    root = ET.parse(d.urdf).getroot()
    children: dict[str, list[str]] = {}
    for j in root.findall("joint"):
        children.setdefault(j.find("parent").get("link"), []).append(j.find("child").get("link"))
    below, stack = set(), list(children.get(d.flange, []))
    while stack:
        link = stack.pop()
        below.add(link)
        stack += children.get(link, [])
    for e in list(root.findall("link")):
        if e.get("name") in below:
            root.remove(e)
    for e in list(root.findall("joint")):
        if e.find("child").get("link") in below:
            root.remove(e)
    for origin in root.iter("origin"):
        if origin.get("rpy"):
            origin.set("rpy", " ".join(repr(quarter_turn(float(v))) for v in origin.get("rpy").split()))
    values = [float(v) for v in tool] + [0.0] * (13 - len(tool))
    m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz, tx, ty, tz = values
    root.append(ET.fromstring(
        f'<link name="tool"><inertial><origin xyz="{cx!r} {cy!r} {cz!r}" rpy="0 0 0"/><mass value="{m!r}"/>'
        f'<inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyy="{iyy!r}" iyz="{iyz!r}" izz="{izz!r}"/>'
        '</inertial></link>'))
    # The tip: a massless link (Pinocchio makes it a frame, "tool_tip") at the tool's tip offset.
    root.append(ET.fromstring('<link name="tool_tip"/>'))
    root.append(ET.fromstring(
        f'<joint name="tool_tip_joint" type="fixed"><parent link="tool"/><child link="tool_tip"/>'
        f'<origin xyz="{tx!r} {ty!r} {tz!r}" rpy="0 0 0"/></joint>'))
    root.append(ET.fromstring(
        f'<joint name="tool_joint" type="fixed"><parent link="{d.flange}"/><child link="tool"/>'
        '<origin xyz="0 0 0" rpy="0 0 0"/></joint>'))
    model = pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))
    return model, model.createData()
