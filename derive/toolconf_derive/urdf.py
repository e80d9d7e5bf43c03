"""A URDF robot read into the serial chain the derivation needs: the moving joints from the base
link to the flange link, each with the rigid body it carries (its link and every link fixed to it
merged in), and the flange's pose in the last body's frame.

Only the kinematic and inertial data are read (xml.etree through defusedxml: URDF is small and
plain XML, and entity declarations, which no URDF needs, are refused).
Refused, each with one line naming the file, the joint or link and the reason (a
DescriptionError, status 2 from derive.py): floating, planar and mimic joints (and any unknown
type) between the base and the flange; a moving side branch (below); a link with two parents, a
loop or a second root anywhere in the file; a revolute or prismatic joint without <limit>; a body carried by a moving joint without an <inertial>, or with mass <= 0; an inertia that
is not positive definite or whose principal moments violate the triangle inequality; a rotation
that is not orthonormal (below); a number outside its physical range (MAX_MASS, MAX_INERTIA,
MAX_LENGTH, MAX_ANGLE) or more than MAX_LINKS links.

How a URDF is read (one rule; docs/reference/urdf-arms.md, "How a URDF is read"):

- Angles, as Pinocchio reads them. Each rpy angle within SNAP (1e-9 rad) of a multiple k pi/2 is
  taken as exactly k pi/2, so its sine and cosine are exactly 0 or +-1; any other angle is used
  literally, as Pinocchio uses it. URDFs write pi/2 rounded: UR5 and Kinova 1.57079632679
  (5e-12 off, snapped: the exact zeros keep the generated code from multiplying by 1e-12 residues
  and move a link by under 1e-9 of its offset), UFactory's xArm7 1.5708 (3.7e-6 off: a different
  angle, used as written). Angles are snapped, never the matrix entries: snapping each entry on
  its own (as this reader once did) took sin(1.5708) as 1 but kept cos(1.5708) = -3.7e-6, a
  matrix that is no rotation, and the derivation then failed far from the cause (an equilibrium
  residual of 1e-9). Every rotation built from the file is checked orthonormal to
  ORTHONORMAL (1e-12) and refused otherwise, naming the joint or link and the deviation.
- Joint limits: every revolute or prismatic joint of the file has a <limit> (the URDF
  specification's rule, urdfdom's and the tool reader's), whose absent lower or upper is 0; those
  of the chain are kept (`UrdfChain.limits`; continuous joints have none), and an equilibrium q^e
  outside them is refused by description.py, naming equilibrium.q[i], the joint, the value and
  the limits. Effort and velocity limits are not read.
- The file's shape, as the tool reader (crates/tool-urdf/) reads every URDF: each
  joint of a URDF type naming two defined links, no link with two parents, the links one tree
  (one root, no loop anywhere, on the chain or off it); numbers ASCII decimals between XML's
  blanks (no other script's digits). The two readers are tested on one corpus of files
  (tests/fixtures/urdf/).
- <dynamics damping friction>: not read into the plant, whose joint damping is the description's
  [impedance]; the chain's joints with a non-zero value are listed (`UrdfChain.ignored_dynamics`)
  and derive.py says on stderr, once per derivation, that they are ignored.
- Branches: a fixed side branch (a fixed joint whose subtree does not hold the flange: a camera,
  UR5's ee_link) is merged into the body it hangs from, fixed links in it included; a moving side
  branch (a moving joint anywhere off the base-to-flange chain, e.g. fingers hanging beside the
  flange) is refused, naming the joint: the chain the derivation builds cannot move it.
  Everything below the flange is dropped (the tool replaces the hand), moving or not, and so is
  everything above the base.

Numbers: the file's decimals are read as doubles (correctly rounded, the same on every machine);
rotations (URDF rpy) and the merging of fixed links are done in 50-digit mpmath and rounded once,
never in libm.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import defusedxml.ElementTree as SafeET
from defusedxml import DefusedXmlException
from dataclasses import dataclass
from pathlib import Path

import mpmath

from .errors import DescriptionError
from .files import read_text, text_problem

DIGITS = 50
# An rpy angle within SNAP (rad) of a multiple of pi/2 is that multiple (the module docs).
SNAP = mpmath.mpf("1e-9")
# A rotation built from the file whose R^T R is further than this from I is refused.
ORTHONORMAL = mpmath.mpf("1e-12")
SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")
# Every joint type of the URDF specification (the others are refused on the chain).
URDF_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
# A number of the file: ASCII decimal as the tool reader (crates/tool-urdf/) and
# Rust's f64 parser read it, between XML's blanks (space, tab, CR, LF); no other script's
# digits, no `_`.
NUMBER = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|inf|infinity|nan)",
                    re.ASCII | re.IGNORECASE)
BLANKS = re.compile(r"[ \t\r\n]+")
# Bounds on what is read: the Panda's URDF is 15 KB; the derivation's graphs grow as n^2 (M) to
# n^3 (the Jacobian's solves) and a 7-joint arm already emits 2 MB of Rust.
MAX_BYTES = 4 * 1024 * 1024
MAX_JOINTS = 12
MAX_LINKS = 256
# Physical ranges of what is read (a robot arm, SI units): beyond them a number is a typo or an
# attack, and 1e300 would only overflow in the derivation's products.
MAX_MASS = 1e4          # kg
MAX_INERTIA = 1e5       # kg m^2, each entry
MAX_LENGTH = 100.0      # m, each coordinate of an origin
MAX_ANGLE = 100.0       # rad, each rpy angle
MAX_AXIS = 1e6          # each entry of an axis before it is normalised
MOVING = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class Body:
    """One moving joint and the rigid body it carries, in the joint's frame.

    `rotation`, `translation`: the joint frame (at q = 0) in the parent body's frame (the base
    link's for the first joint), fixed links in between composed in. `axis`: unit vector in the
    joint frame. Inertia in barycentric form about the joint frame's origin: mass m, first
    moment h = m c, and the rotational inertia about the origin (3x3, symmetric)."""
    joint: str
    kind: str          # "revolute" (continuous too) or "prismatic"
    rotation: tuple
    translation: tuple
    axis: tuple
    mass: float
    first_moment: tuple
    inertia: tuple


@dataclass(frozen=True)
class UrdfChain:
    path: Path
    robot: str
    base: str
    flange: str
    bodies: list[Body]
    # The flange frame in the last body's frame.
    flange_rotation: tuple
    flange_translation: tuple
    # Per body, its joint's <limit> (lower, upper) as doubles, None for a side without a bound.
    limits: tuple = ()
    # The chain's joints whose <dynamics> give a non-zero damping or friction (not read).
    ignored_dynamics: tuple = ()

    @property
    def dof(self) -> int:
        return len(self.bodies)

    @property
    def joint_names(self) -> list[str]:
        return [b.joint for b in self.bodies]


@dataclass
class _Inertial:
    """Mass, centre of mass and inertia about it, in some frame (mpmath)."""
    mass: mpmath.mpf
    com: mpmath.matrix
    inertia: mpmath.matrix


def _floats(path: Path, where: str, text: str | None, n: int, default: str, bound: float,
            unit: str = "") -> list[mpmath.mpf]:
    """`n` numbers, each within +-`bound` (its physical range, in `unit`)."""
    words = [w for w in BLANKS.split(text if text is not None else default) if w]
    values = [float(w) for w in words] if all(NUMBER.fullmatch(w) for w in words) else []
    if len(values) != n or not all(mpmath.isfinite(v) for v in values):
        what = "a finite number" if n == 1 else f"{n} finite numbers"
        raise DescriptionError(path, where, f"'{text}' is not {what} (ASCII decimals)")
    if any(abs(v) > bound for v in values):
        raise DescriptionError(path, where, f"'{text}' is outside [-{bound:g}, {bound:g}]{' ' + unit if unit else ''}")
    return [mpmath.mpf(v) for v in values]


def _number(path: Path, where: str, element, attribute: str, bound: float, unit: str) -> mpmath.mpf:
    text = element.get(attribute) if element is not None else None
    if text is None:
        raise DescriptionError(path, where, f"missing {attribute}")
    return _floats(path, f"{where} {attribute}", text, 1, "", bound, unit)[0]


def _sin_cos(angle: mpmath.mpf) -> tuple[mpmath.mpf, mpmath.mpf]:
    """(sin, cos) of an rpy angle: exactly 0 and +-1 for an angle within SNAP of k pi/2 (taken as
    k pi/2), the literal angle's otherwise."""
    k = int(mpmath.nint(angle / (mpmath.pi / 2)))
    if abs(angle - k * mpmath.pi / 2) < SNAP:
        return [(mpmath.mpf(0), mpmath.mpf(1)), (mpmath.mpf(1), mpmath.mpf(0)),
                (mpmath.mpf(0), mpmath.mpf(-1)), (mpmath.mpf(-1), mpmath.mpf(0))][k % 4]
    return mpmath.sin(angle), mpmath.cos(angle)


def rpy_rotation(rpy: list[mpmath.mpf]) -> mpmath.matrix:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll), each angle snapped to a
    quarter turn within SNAP (never the entries: R stays a rotation)."""
    (sr, cr), (sp, cp), (sy, cy) = (_sin_cos(a) for a in rpy)
    return mpmath.matrix([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def orthonormal_deviation(rotation: mpmath.matrix) -> mpmath.mpf:
    """max |R^T R - I|: 0 for a rotation (to the working precision)."""
    gram = rotation.T * rotation - mpmath.eye(3)
    return max(abs(gram[i, j]) for i in range(3) for j in range(3))


def check_rotation(path: Path, where: str, rotation: mpmath.matrix) -> mpmath.matrix:
    """`rotation` if it is orthonormal to ORTHONORMAL, else refused naming `where`."""
    deviation = orthonormal_deviation(rotation)
    if not deviation <= ORTHONORMAL:
        raise DescriptionError(path, where, f"rotation is not orthonormal: max |R^T R - I| = "
                                            f"{mpmath.nstr(deviation, 3)} > {mpmath.nstr(ORTHONORMAL, 1)}")
    return rotation


def _origin(path: Path, where: str, element) -> tuple[mpmath.matrix, mpmath.matrix]:
    origin = element.find("origin") if element is not None else None
    xyz = _floats(path, f"{where} origin xyz", origin.get("xyz") if origin is not None else None, 3, "0 0 0",
                  MAX_LENGTH, "m")
    rpy = _floats(path, f"{where} origin rpy", origin.get("rpy") if origin is not None else None, 3, "0 0 0",
                  MAX_ANGLE, "rad")
    return check_rotation(path, f"{where} origin rpy", rpy_rotation(rpy)), mpmath.matrix(xyz)


def _check_inertia(path: Path, where: str, inertia: mpmath.matrix, massless: bool) -> None:
    """Positive definite, principal moments obeying the triangle inequality (zero for a frame)."""
    if massless:
        if any(inertia[i, j] != 0 for i in range(3) for j in range(3)):
            raise DescriptionError(path, where, "has mass 0 but a non-zero inertia")
        return
    moments = sorted(mpmath.eigsy(inertia)[0])
    shown = ", ".join(mpmath.nstr(m, 6) for m in moments)
    if moments[0] <= 0:
        raise DescriptionError(path, where, f"inertia is not positive definite (principal moments {shown})")
    # Relative slack for the decimals URDFs print (a thin rod's Izz = Ixx + Iyy to 9 digits).
    if moments[2] > (moments[0] + moments[1]) * (1 + mpmath.mpf("1e-9")):
        raise DescriptionError(path, where, f"principal moments {shown} violate the triangle inequality "
                                            "(the largest exceeds the sum of the other two)")


def _inertial(path: Path, link, carried: bool) -> _Inertial:
    """The link's <inertial> in its own frame. `carried`: the link is the child of a moving joint,
    so it is a body and must have mass; a fixed link may be a massless frame."""
    name = link.get("name")
    where = f"link '{name}'"
    element = link.find("inertial")
    zero = _Inertial(mpmath.mpf(0), mpmath.matrix(3, 1), mpmath.matrix(3, 3))
    if element is None:
        if carried:
            raise DescriptionError(path, where, "has no <inertial>, but a moving joint carries it")
        return zero
    mass = _number(path, f"{where} mass", element.find("mass"), "value", MAX_MASS, "kg")
    if mass < 0 or (carried and mass == 0):
        raise DescriptionError(path, where, f"mass {mpmath.nstr(mass, 17)} must be > 0")
    tensor = element.find("inertia")
    if tensor is None:
        raise DescriptionError(path, where, "<inertial> has no <inertia>")
    i = {k: _number(path, f"{where} inertia", tensor, k, MAX_INERTIA, "kg m^2") for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    local = mpmath.matrix([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
                           [i["ixz"], i["iyz"], i["izz"]]])
    _check_inertia(path, where, local, mass == 0)
    rotation, com = _origin(path, f"{where} inertial", element)
    return _Inertial(mass, com, rotation * local * rotation.T)


def _moved(inertial: _Inertial, rotation: mpmath.matrix, translation: mpmath.matrix) -> _Inertial:
    return _Inertial(inertial.mass, rotation * inertial.com + translation,
                     rotation * inertial.inertia * rotation.T)


def _merged(a: _Inertial, b: _Inertial) -> _Inertial:
    """Two rigidly joined bodies in one frame (parallel-axis theorem)."""
    mass = a.mass + b.mass
    if mass == 0:
        return a
    com = (a.com * a.mass + b.com * b.mass) / mass
    total = mpmath.matrix(3, 3)
    for part in (a, b):
        d = part.com - com
        shift = (d.T * d)[0] * mpmath.eye(3) - d * d.T
        total += part.inertia + part.mass * shift
    return _Inertial(mass, com, total)


def _barycentric(x: _Inertial) -> tuple[float, tuple, tuple]:
    """(m, h = m c, inertia about the frame's origin) rounded once to doubles."""
    c = x.com
    about_origin = x.inertia + x.mass * ((c.T * c)[0] * mpmath.eye(3) - c * c.T)
    return (float(x.mass), tuple(float(x.mass * c[i]) for i in range(3)),
            tuple(tuple(float(about_origin[i, j]) for j in range(3)) for i in range(3)))


class _Tree:
    """The URDF's links and joints, with parent and child maps."""

    def __init__(self, path: Path, text: str):
        self.path = path
        try:
            # defusedxml: no entities, no external references (a "billion laughs" is refused).
            root = SafeET.fromstring(text)
        except ET.ParseError as err:
            raise DescriptionError(path, "", f"not valid XML: {err}") from err
        except DefusedXmlException as err:
            raise DescriptionError(path, "", f"refused XML: {err}") from err
        if root.tag != "robot":
            raise DescriptionError(path, "", f"the root element is <{root.tag}>, not <robot>")
        self.robot = root.get("name", "")
        problem = text_problem(self.robot)
        if problem:
            raise DescriptionError(path, "robot name", problem)
        if len(root.findall("link")) > MAX_LINKS:
            raise DescriptionError(path, "", f"{len(root.findall('link'))} links; a URDF the derivation reads has at "
                                             f"most {MAX_LINKS}")
        self.links = dict(_each_named(path, root, "link"))
        self.joints = {}
        self.parent_joint = {}
        self.child_joints: dict[str, list] = {name: [] for name in self.links}
        for name, joint in _each_named(path, root, "joint"):
            parent, child = joint.find("parent"), joint.find("child")
            parent = parent.get("link") if parent is not None else None
            child = child.get("link") if child is not None else None
            for role, link in (("parent", parent), ("child", child)):
                if link not in self.links:
                    raise DescriptionError(path, f"joint '{name}'", f"its {role} link '{link}' is not defined")
            if child in self.parent_joint:
                raise DescriptionError(path, f"link '{child}'",
                                       f"has two parents (joints '{self.parent_joint[child].get('name')}' and "
                                       f"'{name}'): a loop, which a serial chain cannot have")
            self.joints[name] = joint
            self.parent_joint[child] = joint
            self.child_joints[parent].append(joint)
            _check_joint(path, joint)
        self._check_tree()

    def _check_tree(self) -> None:
        """The links form one tree (URDF's rule, as urdfdom and the tool reader have it): no loop
        anywhere, one root link, every link below it."""
        done: set[str] = set()
        for start in self.links:
            walked, link = [], start
            while link not in done and link in self.parent_joint:
                if link in walked:
                    joint = self.parent_joint[walked[-1]]
                    raise DescriptionError(self.path, f"joint '{joint.get('name')}'",
                                           f"leads back to link '{link}': the links form a loop")
                walked.append(link)
                link = self.parent_joint[link].find("parent").get("link")
            done.update(walked)
        roots = [name for name in self.links if name not in self.parent_joint]
        if len(roots) != 1:
            shown = ", ".join(f"'{r}'" for r in roots[:4]) + (", ..." if len(roots) > 4 else "")
            raise DescriptionError(self.path, "", f"{len(roots)} root links ({shown}): a URDF's links form one "
                                                  "tree with one root")

    def path_to(self, base: str, flange: str) -> list:
        """The joints from `base` down to `flange`, in order."""
        for role, link in (("base", base), ("flange", flange)):
            if link not in self.links:
                raise DescriptionError(self.path, f"link '{link}'", f"(the {role}) is not defined in the file")
        joints, link, seen = [], flange, set()
        while link != base:
            if link in seen or link not in self.parent_joint:
                raise DescriptionError(self.path, f"link '{flange}'", f"(the flange) is not below the base '{base}'")
            seen.add(link)
            joint = self.parent_joint[link]
            joints.append(joint)
            link = joint.find("parent").get("link")
        return joints[::-1]


def _joint_kind(path: Path, joint) -> str:
    name, kind = joint.get("name"), joint.get("type")
    if joint.find("mimic") is not None:
        raise DescriptionError(path, f"joint '{name}'", "is a mimic joint, which is not supported "
                                                       "(each joint of the chain must be driven on its own)")
    if kind not in SUPPORTED:
        raise DescriptionError(path, f"joint '{name}'", f"type '{kind}' is not supported "
                                                       f"(supported: {', '.join(SUPPORTED)})")
    return kind


def _side_joint(tree: _Tree, joint, link: str, flange: str) -> None:
    """A joint off the chain at `link`: a fixed one is merged by the caller; a moving one is a
    moving side branch, refused; any other type as _joint_kind refuses it."""
    kind = joint.get("type")
    if kind in MOVING or kind in ("floating", "planar"):
        raise DescriptionError(tree.path, f"joint '{joint.get('name')}'",
                               f"({kind}) is a moving side branch at link '{link}': the branch moves and does "
                               f"not hold the flange '{flange}'; only fixed side branches are merged into the chain")
    _joint_kind(tree.path, joint)


def _fixed_subtree(tree: _Tree, link: str, on_path: set[str], flange: str) -> _Inertial:
    """The inertia of `link` and of every link fixed below it off the chain, in `link`'s frame;
    a moving joint off the chain is a moving side branch, refused. Nothing below the flange is
    read."""
    total = _inertial(tree.path, tree.links[link], link in on_path and tree.parent_joint.get(link) is not None
                      and tree.parent_joint[link].get("type") in MOVING)
    if link == flange:
        return total
    for joint in tree.child_joints[link]:
        child = joint.find("child").get("link")
        if child in on_path:
            continue
        _side_joint(tree, joint, link, flange)
        rotation, translation = _origin(tree.path, f"joint '{joint.get('name')}'", joint)
        total = _merged(total, _moved(_fixed_subtree(tree, child, on_path, flange), rotation, translation))
    return total


def _base_side_branches(tree: _Tree, link: str, on_path: set[str], flange: str) -> None:
    """Off the chain at the base: fixed links do not move with the arm and are not read, but a
    moving joint among them is a moving side branch like any other, refused."""
    for joint in tree.child_joints[link]:
        child = joint.find("child").get("link")
        if child in on_path:
            continue
        _side_joint(tree, joint, link, flange)
        _base_side_branches(tree, child, on_path, flange)


def _each_named(path: Path, root, tag: str):
    """Each <tag> element of `root`, in order, with its name: one without a name, or with the
    name of one before it, is refused."""
    seen: set[str] = set()
    for element in root.findall(tag):
        name = element.get("name")
        if not name:
            raise DescriptionError(path, tag, f"a <{tag}> has no name")
        if name in seen:
            raise DescriptionError(path, f"{tag} '{name}'", "is defined twice")
        seen.add(name)
        yield name, element


def _check_joint(path: Path, joint) -> None:
    """What the URDF specification requires of every joint of the file, as the tool reader
    requires it: a known type, and a <limit> on a revolute or prismatic joint whose bounds
    (absent: 0) are numbers."""
    name, kind = joint.get("name"), joint.get("type")
    if kind not in URDF_TYPES:
        raise DescriptionError(path, f"joint '{name}'", f"type '{kind}' is not a URDF joint type "
                                                       f"({', '.join(URDF_TYPES)})")
    element = joint.find("limit")
    if element is None and kind in ("revolute", "prismatic"):
        raise DescriptionError(path, f"joint '{name}'", f"is {kind} and has no <limit> (the URDF specification "
                                                       "requires one)")
    if element is not None:
        _limits(path, joint)


def _limits(path: Path, joint) -> tuple:
    """A revolute or prismatic joint's <limit> (lower, upper) as doubles, an absent side 0 (the
    URDF specification's default); (None, None) for a continuous joint."""
    element = joint.find("limit")
    if joint.get("type") not in ("revolute", "prismatic") or element is None:
        return (None, None)
    return tuple(float(_floats(path, f"joint '{joint.get('name')}' limit {side}", element.get(side), 1, "0",
                               math.inf)[0]) for side in ("lower", "upper"))


def _dynamics_given(joint) -> bool:
    """The joint's <dynamics> gives a non-zero damping or friction (which the plant ignores)."""
    element = joint.find("dynamics")
    if element is None:
        return False
    for attribute in ("damping", "friction"):
        text = element.get(attribute, "0").strip(" \t\r\n")
        if not NUMBER.fullmatch(text) or float(text) != 0:
            return True
    return False


def read_chain(path: Path, base: str, flange: str) -> UrdfChain:
    text = read_text(path, MAX_BYTES, "a URDF file")
    with mpmath.workdps(DIGITS):
        return _chain(_Tree(path, text), base, flange)


def _axis(path: Path, joint) -> mpmath.matrix:
    element = joint.find("axis")
    a = mpmath.matrix(_floats(path, f"joint '{joint.get('name')}' axis", element.get("xyz") if element is not None
                              else None, 3, "1 0 0", MAX_AXIS))
    norm = mpmath.sqrt((a.T * a)[0])
    if norm == 0:
        raise DescriptionError(path, f"joint '{joint.get('name')}'", "axis is zero")
    return a / norm


def _chain(tree: _Tree, base: str, flange: str) -> UrdfChain:
    path = tree.path
    joints = tree.path_to(base, flange)
    on_path = {j.find("child").get("link") for j in joints} | {base}
    for j in joints:
        _joint_kind(path, j)
    _base_side_branches(tree, base, on_path, flange)
    moving = [j for j in joints if j.get("type") in MOVING]
    if not moving:
        raise DescriptionError(path, f"link '{flange}'", f"no moving joint between the base '{base}' and the flange")
    if len(moving) > MAX_JOINTS:
        raise DescriptionError(path, f"link '{flange}'", f"{len(moving)} moving joints between the base '{base}' and "
                                                         f"the flange; at most {MAX_JOINTS} are derived")
    # Accumulate: the pose of the current link's frame in the last body's frame (or the base's),
    # and the current body's inertia (in its joint frame).
    bodies, pending_r, pending_t = [], mpmath.eye(3), mpmath.matrix(3, 1)
    current: _Inertial | None = None
    joint_of_body = None
    for j in joints:
        rotation, translation = _origin(path, f"joint '{j.get('name')}'", j)
        rotation, translation = pending_r * rotation, pending_r * translation + pending_t
        child = j.find("child").get("link")
        subtree = _fixed_subtree(tree, child, on_path, flange)
        if j.get("type") in MOVING:
            if current is not None:
                bodies.append(_body(joint_of_body, current))
            joint_of_body = (j, rotation, translation, _axis(path, j))
            current = subtree
            pending_r, pending_t = mpmath.eye(3), mpmath.matrix(3, 1)
        else:
            if current is not None:
                current = _merged(current, _moved(subtree, rotation, translation))
            pending_r, pending_t = rotation, translation
    bodies.append(_body(joint_of_body, current))
    return UrdfChain(path, tree.robot, base, flange, bodies,
                     tuple(tuple(float(pending_r[i, k]) for k in range(3)) for i in range(3)),
                     tuple(float(pending_t[i]) for i in range(3)),
                     limits=tuple(_limits(path, j) for j in moving),
                     ignored_dynamics=tuple(j.get("name") for j in moving if _dynamics_given(j)))


def _body(joint_data, inertial: _Inertial) -> Body:
    joint, rotation, translation, axis = joint_data
    mass, h, about_origin = _barycentric(inertial)
    kind = "prismatic" if joint.get("type") == "prismatic" else "revolute"
    return Body(joint.get("name"), kind,
                tuple(tuple(float(rotation[i, k]) for k in range(3)) for i in range(3)),
                tuple(float(translation[i]) for i in range(3)),
                tuple(float(axis[i]) for i in range(3)), mass, h, about_origin)
