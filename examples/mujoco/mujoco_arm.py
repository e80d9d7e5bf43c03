"""A toolconf URDF arm in MuJoCo: the same URDF the model was derived from, the same plant.

toolconf's plant (docs/explanation/real-arms.md, "The task formulation for real arms") is the rigid-body chain
from the description's base to its flange with the tool fixed to the flange, under joint
impedance about the equilibrium with the gravity there fed forward:

    M(q) q̈ + C(q, q̇) q̇ + g(q) = U + K (q^e − q) − D q̇ + g(q^e).

`arm_model` builds exactly that in MuJoCo, in three steps, each a function here:

1. `strip_urdf`: the URDF as MuJoCo can load it and as toolconf reads it. Removed: every
   <visual> and <collision> (their meshes are `package://` paths MuJoCo cannot resolve, the
   Panda's visuals are COLLADA, which MuJoCo does not read, and toolconf's dynamics never use
   them: with no geometry there is nothing to collide either); every link and joint beyond the
   flange (the Panda's hand and its two finger joints: the tool replaces them, as toolconf drops
   them) and above the base; every joint's <dynamics> (toolconf does not read its damping and
   friction, `derive/toolconf_derive/urdf.py`; MuJoCo would add the Panda's 0.003 N m s/rad);
   and <transmission>/<gazebo> elements, which MuJoCo does not know.
2. `arm_spec`: MuJoCo's model of it (mujoco.MjSpec), with the joints' limits off (toolconf's
   plant has none), contacts off, no armature and no friction loss, the description's gravity;
   the joint impedance as MuJoCo's own joint spring and damper (stiffness K_i about springref
   q^e_i, damping D_i: passive forces evaluated at every integrator stage, continuous in time as
   in toolconf's plant, not held by the controller's tick); the flange kept as its own body
   (static bodies not fused) so the tool hangs from its frame.
3. `attach_tool`: the tool from a tools-file row: a body at the flange's origin and axes with
   the row's mass, centre of mass and full inertia tensor about it, and a site at its tip.

MuJoCo keeps a body's inertia as principal moments and a frame. Given a full tensor
(`fullinertia`, which its URDF reader sets for every <inertia>), it diagonalises it with a
Jacobi iteration (mju_eig3) that stops short of double precision: the tensor it keeps differs
from the file's by up to 4.6e-7 relative (the Panda's links and the catalogue's tools), which
moved q̈ by up to 1.6e-6 relative to toolconf's, 10⁸ times the two derivations' rounding.
So `principal_inertia` diagonalises each tensor with LAPACK (numpy's eigh) and hands MuJoCo the
moments and the frame instead: the tensor MuJoCo keeps (`body_inertia`, recomposed by
`inertia_tensor`) is then the file's to 9e-16, and q̈ toolconf's to rounding (test_mujoco.py).

The gravity feed-forward g(q^e) is a constant torque, computed once by MuJoCo from its own model
of arm and tool (`gravity_torque`), as a robot computes it from its own.
"""

from __future__ import annotations

import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import defusedxml.ElementTree as SafeET
import mujoco
import numpy as np

TOOL_BODY, TIP_SITE = "toolconf_tool", "toolconf_tip"


@dataclass(frozen=True)
class Description:
    """What MuJoCo needs of a toolconf model description of kind `urdf`."""
    name: str
    urdf: Path
    base: str
    flange: str
    gravity: tuple
    stiffness: tuple
    damping: tuple


def read_description(path: str | Path) -> Description:
    """The [urdf] and [impedance] tables of a model description (derive/models/*.toml); the
    URDF is relative to the description's folder, as for toolconf."""
    path = Path(path)
    try:
        d = tomllib.loads(path.read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise ValueError(f"{path}: not a TOML model description: {e}") from None
    kind = d.get("dynamics", {}).get("kind") if isinstance(d.get("dynamics"), dict) else None
    if kind != "urdf":
        raise ValueError(f"{path}: dynamics.kind = {kind!r}: not a URDF arm's description")
    try:
        urdf, impedance = d["urdf"], d["impedance"]
        gravity = tuple(float(g) for g in urdf["gravity"])
        if len(gravity) != 3:
            raise ValueError(f"urdf.gravity: {len(gravity)} components, not 3")
        return Description(name=str(d["model"]["name"]), urdf=path.parent / urdf["file"],
                           base=str(urdf["base"]), flange=str(urdf["flange"]), gravity=gravity,
                           stiffness=tuple(float(k) for k in impedance["stiffness"]),
                           damping=tuple(float(c) for c in impedance["damping"]))
    except KeyError as e:
        raise ValueError(f"{path}: no key {e.args[0]!r}: not a URDF arm's description") from None
    except (TypeError, ValueError) as e:
        raise ValueError(f"{path}: [model], [urdf] or [impedance]: {e}") from None


def _ends(joint) -> tuple[str, str]:
    """A joint's (parent, child) links."""
    parent, child = joint.find("parent"), joint.find("child")
    if parent is None or child is None:
        raise ValueError(f"joint {joint.get('name')!r}: no <parent> or <child>")
    return parent.get("link"), child.get("link")


def _chain(root, base: str, flange: str) -> set[str]:
    """The links from `base` down to `flange` (the flange's path up to the base)."""
    parent_of = {child: parent for parent, child in map(_ends, root.findall("joint"))}
    chain, link = [flange], flange
    while link != base:
        if link not in parent_of:
            raise ValueError(f"the flange {flange!r} is not below the base {base!r}")
        link = parent_of[link]
        chain.append(link)
    return set(chain)


def strip_urdf(text: str, base: str, flange: str) -> str:
    """Step 1: the URDF with only the base-to-flange chain's kinematics and inertia (above)."""
    root = SafeET.fromstring(text)
    keep = _chain(root, base, flange)
    for link in root.findall("link"):
        if link.get("name") not in keep:
            root.remove(link)
            continue
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
        origin = link.find("inertial/origin")
        if origin is not None and any(float(a) != 0.0 for a in origin.get("rpy", "0 0 0").split()):
            raise ValueError(f"link {link.get('name')!r}: its <inertial> frame is rotated "
                             f"(rpy {origin.get('rpy')}): not handled by this example")
    for joint in root.findall("joint"):
        if not set(_ends(joint)) <= keep:
            root.remove(joint)
            continue
        for element in joint.findall("dynamics") + joint.findall("safety_controller"):
            joint.remove(element)
    for element in root.findall("transmission") + root.findall("gazebo"):
        root.remove(element)
    return ET.tostring(root, encoding="unicode")


def arm_spec(description: Description, q_e, integrator: str, timestep: float) -> mujoco.MjSpec:
    """Step 2: the stripped URDF as a MuJoCo spec with toolconf's plant's options (above)."""
    try:
        text = strip_urdf(description.urdf.read_bytes().decode("utf-8"), description.base,
                          description.flange)
        spec = mujoco.MjSpec.from_string(text)
    except (UnicodeDecodeError, ET.ParseError, ValueError) as e:
        raise ValueError(f"{description.urdf}: {e}") from None
    spec.compiler.fusestatic = False
    spec.option.gravity = description.gravity
    spec.option.timestep = timestep
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    joints = [j for j in spec.joints if j.type != mujoco.mjtJoint.mjJNT_FREE]
    if len(joints) != len(description.stiffness):
        raise ValueError(f"{len(joints)} joints in MuJoCo's model, "
                         f"{len(description.stiffness)} in the description's impedance")
    for body in spec.bodies:
        if not np.isnan(body.fullinertia[0]):
            principal_inertia(body, _tensor(body.fullinertia))
    for joint, k, d, q in zip(joints, description.stiffness, description.damping, q_e):
        joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
        joint.armature, joint.frictionloss = 0.0, 0.0
        joint.stiffness, joint.damping, joint.springref = k, d, q
    return spec


def attach_tool(spec: mujoco.MjSpec, flange: str, tool: dict) -> None:
    """Step 3: the tool of a tools-file row (toolconf's parameter names) at the flange."""
    body = spec.body(flange).add_body(name=TOOL_BODY)
    body.mass = tool["tool_mass"]
    body.ipos = [tool["tool_com_x"], tool["tool_com_y"], tool["tool_com_z"]]
    principal_inertia(body, _tensor([tool[f"tool_i{a}"] for a in ("xx", "yy", "zz", "xy", "xz", "yz")]))
    body.add_site(name=TIP_SITE, pos=[tool["tool_tip_x"], tool["tool_tip_y"], tool["tool_tip_z"]])


def arm_model(description: Description, q_e, tool: dict, integrator: str = "RK4",
              timestep: float = 1e-3) -> mujoco.MjModel:
    """MuJoCo's model of the arm with `tool` at its flange (steps 1-3)."""
    spec = arm_spec(description, q_e, integrator, timestep)
    attach_tool(spec, description.flange, tool)
    return spec.compile()


def _tensor(entries) -> np.ndarray:
    """The 3 × 3 tensor of (Ixx, Iyy, Izz, Ixy, Ixz, Iyz): URDF's <inertia> and MuJoCo's
    `fullinertia` order, the products being the tensor's off-diagonal entries."""
    xx, yy, zz, xy, xz, yz = entries
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], dtype=np.float64)


def principal_inertia(body, tensor: np.ndarray) -> None:
    """The body's inertia as MuJoCo keeps it, principal moments and their frame, from the full
    tensor about the centre of mass in the body's axes (LAPACK's symmetric eigensolver)."""
    moments, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] = -axes[:, 2]
    quaternion = np.empty(4)
    mujoco.mju_mat2Quat(quaternion, axes.reshape(-1))
    body.fullinertia = [np.nan, 0.0, 0.0, 0.0, 0.0, 0.0]
    body.inertia, body.iquat = moments, quaternion
    body.explicitinertial = True


def inertia_tensor(model: mujoco.MjModel, body: str) -> np.ndarray:
    """A body's inertia tensor about its centre of mass in the body's axes, as MuJoCo holds
    it: R diag(I) Rᵀ from its principal moments and frame."""
    body = model.body(body)
    rotation = np.empty(9)
    mujoco.mju_quat2Mat(rotation, body.iquat)
    r = rotation.reshape(3, 3)
    return r @ np.diag(body.inertia) @ r.T


def gravity_torque(model: mujoco.MjModel, q: np.ndarray) -> np.ndarray:
    """g(q): the joint torques that hold arm and tool still at q (MuJoCo's bias at q̇ = 0)."""
    data = mujoco.MjData(model)
    data.qpos[:] = q
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)
    return data.qfrc_bias.copy()
