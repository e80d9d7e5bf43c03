#!/usr/bin/env python3
"""Writes examples/tools/panda_tools.csv and examples/tools/ur5_tools.csv: tools a Franka Emika
Panda and a Universal Robots UR5 carry at their flange, each built from parts whose mass and
centre of mass come from the vendor's documentation where it gives them, and from a stated shape
where it gives only a mass (or nothing: then the value is a nominal one of the tool class, marked
"assumed"). Every part and every hand-held tool is defined once, here, and placed on each robot's
flange or in each robot's gripper: the two catalogues share their Robotiq devices, their touch
probe and their hand-held tools.

    python3 examples/tools/panda_tools.py            # rewrites both CSVs (standard library only)
    python3 examples/tools/panda_tools.py --check    # exit 1 if either CSV differs from what it writes

Frames. Every part is placed in the robot's flange frame, z out of the flange: panda_link8 on the
Panda, tool0 on the UR5 (ur5_robot.urdf's frame "coincident with the all-zeros TCP on the UR
controller": z along wrist 3's axis out of the ISO 9409-1-50-4-M6 tool flange, x along
wrist_3_link's x; at the UR5's equilibrium, wrist down, tool0's x, y, z are the base's -y, -x, -z).
The Franka Hand is mounted turned by -45 degrees about z (panda.urdf's panda_hand_joint, rpy
0 0 -pi/4), and Franka gives its numbers in the hand's own frame: they are turned into the
flange frame here (which is what `toolconf tool --urdf` gives for the hand of panda.urdf, within
the manual's rounding). The Franka Hand's fingertip centre, its TCP, where a grasped tool is held,
is 0.1034 m out along z (Franka's flange-to-hand transform). The Robotiq devices are given in the
FT 300's frame (manual 5.2.1), taken as the flange's: the sensor's axes aligned with the flange's
(its dowel pin in the flange's). On the UR5 a hand-held tool is held between the 2F-85's fingertips
on the FT 300, the far end of the gripper's stated box. A tool's parameters are its mass, its
centre of mass, its full inertia tensor about the centre of mass in flange axes (toolconf's
tool_ixx, tool_iyy, tool_izz, tool_ixy, tool_ixz, tool_iyz, URDF's convention) and its tip
(tool_tip_x/y/z, the point that does the work: the vendor's TCP where it publishes one,
otherwise the end of the stated geometry; each row's comment says which). A sum of rigid bodies'
tensors is a rigid body's, so every row is valid for toolconf.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
FINGERTIPS = 0.1034  # m along the flange z axis (Franka: flange to hand, the fingertips' centre)


@dataclass(frozen=True)
class Part:
    """A rigid part: mass (kg), centre of mass (m, flange frame), inertia tensor about its own
    centre of mass in flange axes (kg m^2, 3 x 3)."""
    name: str
    mass: float
    com: tuple[float, float, float]
    inertia: tuple


def diagonal(moments):
    return tuple(tuple(moments[i] if i == j else 0.0 for j in range(3)) for i in range(3))


def turned_about_z(part: Part, angle: float) -> Part:
    """The part turned by `angle` about the flange's z axis: R c and R I R^T."""
    c, s = math.cos(angle), math.sin(angle)
    r = ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))
    com = tuple(sum(r[i][k] * part.com[k] for k in range(3)) for i in range(3))
    tensor = tuple(tuple(sum(r[i][k] * part.inertia[k][l] * r[j][l] for k in range(3) for l in range(3))
                         for j in range(3)) for i in range(3))
    return Part(part.name, part.mass, com, tensor)


def box(name, mass, com, sides):
    """A solid box with sides (a, b, c) along the flange's x, y, z."""
    a, b, c = sides
    return Part(name, mass, com, diagonal((mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12,
                                           mass * (a * a + b * b) / 12)))


def cylinder(name, mass, com, diameter, length, axis="z"):
    """A solid cylinder along a flange axis."""
    r2 = (diameter / 2) ** 2
    along = mass * r2 / 2
    across = mass * (3 * r2 + length * length) / 12
    moments = tuple(along if a == axis else across for a in "xyz")
    return Part(name, mass, com, diagonal(moments))


def combine(parts):
    """Mass, centre of mass and the full inertia tensor about it in flange axes (parallel-axis
    theorem)."""
    mass = sum(p.mass for p in parts)
    com = tuple(sum(p.mass * p.com[k] for p in parts) / mass for k in range(3))
    tensor = [[0.0] * 3 for _ in range(3)]
    for p in parts:
        d = [p.com[k] - com[k] for k in range(3)]
        dd = sum(x * x for x in d)
        for i in range(3):
            for j in range(3):
                tensor[i][j] += p.inertia[i][j] + p.mass * ((dd if i == j else 0.0) - d[i] * d[j])
    return mass, com, tensor


# The Franka Hand, as Franka Emika's Panda manual gives it ("Mechanical data of Hand", the values
# to enter in Desk): 0.73 kg, centre of mass (-0.01, 0, 0.03) m from the flange, inertia
# diag(0.001, 0.0025, 0.0017) kg m^2.
# The numbers are in the hand's frame; FRANKA_HAND is turned into the flange's.
FRANKA_HAND = turned_about_z(Part("Franka Hand", 0.73, (-0.01, 0.0, 0.03), diagonal((0.001, 0.0025, 0.0017))),
                             -math.pi / 4)
HAND_SOURCE = ("Franka Hand: mass, CoM and inertia from Franka Emika's Panda manual (Mechanical data of Hand), "
               "turned by -45 deg about z into the flange frame")
HAND_TCP = (0.0, 0.0, FINGERTIPS)
TCP_SOURCE = "tip: the hand's TCP, 0.1034 m out (Franka's flange-to-TCP transform)"

# Robotiq FT 300 manual, section 5.2.1 (moment of inertia and centre of mass of sensor
# combinations): FT 300 alone 300 g at z = 17 mm; with the 2F-85 gripper 1205 g at z = 76 mm;
# with the 2F-140 1275 g at 83 mm; with the Wrist Camera 530 g at (0, 2, 30) mm; with the Wrist
# Camera and the 2F-85 1275 g at (0, 1, 77) mm. The manual's inertia matrix is a figure, not
# text, so the moments come from stated shapes that reproduce its masses and centres of mass.
FT300 = cylinder("FT 300", 0.300, (0.0, 0.0, 0.017), 0.075, 0.034)
FT300_SOURCE = "Robotiq FT 300 manual 5.2.1"


def ft300_tip(total, com_z, length, com_xy=(0.0, 0.0)):
    """The far end along z of the device box `on_ft300` places (its centre plus half its length)."""
    box_part = on_ft300("device", total, com_z, (0.01, 0.01, length), com_xy)[1]
    return (box_part.com[0], box_part.com[1], box_part.com[2] + length / 2)


def on_ft300(name, total, com_z, sides, com_xy=(0.0, 0.0)):
    """A Robotiq device on the FT 300: the part beyond the sensor (mass total - 0.3 kg) is a box of
    `sides` centred where the manual's combined centre of mass puts it."""
    extra = total - FT300.mass
    z = (total * com_z - FT300.mass * FT300.com[2]) / extra
    xy = tuple(total * c / extra for c in com_xy)
    return [FT300, box(name, extra, (*xy, z), sides)]


@dataclass(frozen=True)
class Tool:
    name: str
    parts: list
    source: str
    tip: tuple
    tip_source: str


@dataclass(frozen=True)
class Holder:
    """What holds a hand-held tool: its parts, where it holds the tool (m along the flange's z
    axis), the prefix of the tools' names and the source of its own numbers."""
    name: str
    parts: list
    grasp: float
    source: str


@dataclass(frozen=True)
class HandHeld:
    """A hand-held tool, held at `grasp` (m along z): `shape(grasp)` gives its parts and its tip in
    the flange frame, so the same tool is placed in any holder."""
    name: str
    shape: object
    description: str
    tip_source: str

    def held_by(self, holder: Holder) -> Tool:
        parts, tip = self.shape(holder.grasp)
        return Tool(f"{holder.name} + {self.name}", [*holder.parts, *parts],
                    f"{holder.source}; {self.description}", tip, self.tip_source)


def screwdriver_6x125(g):
    return ([cylinder("handle", 0.045, (0.0, 0.0, g), 0.028, 0.100),
             cylinder("blade", 0.028, (0.0, 0.0, g + 0.050 + 0.0625), 0.006, 0.125)],
            (0.0, 0.0, g + 0.050 + 0.125))


def screwdriver_ph2x250(g):
    return ([cylinder("handle", 0.060, (0.0, 0.0, g), 0.032, 0.110),
             cylinder("blade", 0.065, (0.0, 0.0, g + 0.055 + 0.125), 0.008, 0.250)],
            (0.0, 0.0, g + 0.055 + 0.250))


def claw_hammer(g):
    return ([cylinder("handle", 0.200, (0.0, 0.0, g + 0.110), 0.030, 0.280),
             box("head", 0.454, (0.0, 0.0, g + 0.265), (0.110, 0.025, 0.030))],
            (0.055, 0.0, g + 0.265))


def cordless_drill(g):
    return [box("drill", 1.1, (0.0, 0.0, g + 0.04), (0.060, 0.180, 0.200))], (0.0, 0.0, g + 0.04 + 0.100)


def whiteboard_marker(g):
    return [cylinder("marker", 0.020, (0.0, 0.0, g + 0.070 - 0.040), 0.018, 0.140)], (0.0, 0.0, g + 0.140 - 0.040)


SCREWDRIVER_6X125 = HandHeld(
    "screwdriver 6x125", screwdriver_6x125,
    "grasped at its handle's middle, pointing out along z: a slotted 6 x 125 mm "
    "screwdriver (blade size by its designation; handle 28 x 100 mm, 45 g, and blade 28 g assumed), "
    "solid cylinders", "tip: the blade's end")
SCREWDRIVER_PH2X250 = HandHeld(
    "screwdriver ph2x250", screwdriver_ph2x250,
    "a Phillips PH2 x 250 mm screwdriver grasped at its handle (handle 32 x 110 mm, "
    "60 g, and blade 65 g assumed), solid cylinders", "tip: the blade's end")
CLAW_HAMMER = HandHeld(
    "claw hammer 16 oz", claw_hammer,
    "grasped 30 mm from the end of its 280 mm handle: a 16 oz claw hammer (the head's "
    "0.454 kg is its designation; handle 0.2 kg assumed), head a solid box 110 x 25 x 30 mm across the "
    "handle, handle a solid cylinder", "tip: the centre of the striking face, the head's end along x")
CORDLESS_DRILL = HandHeld(
    "cordless drill", cordless_drill,
    "grasped at its grip: a 12 V class cordless drill with battery, 1.1 kg and "
    "200 x 180 x 60 mm (assumed, the class's typical size), its CoM 40 mm beyond the fingertips, a solid box",
    "tip: the chuck, the box's far end along z")
WHITEBOARD_MARKER = HandHeld(
    "whiteboard marker", whiteboard_marker,
    "grasped 40 mm from its back end, pointing out along z: a whiteboard marker 18 x 140 mm, 20 g "
    "(assumed, the class's typical size and mass), a solid cylinder", "tip: the felt tip, the marker's far end")

FRANKA_HAND_HOLDER = Holder("hand", [FRANKA_HAND], FINGERTIPS, HAND_SOURCE)
FT300_2F85 = on_ft300("2F-85", 1.205, 0.076, (0.075, 0.085, 0.123))
FT300_2F85_SOURCE = (f"{FT300_SOURCE}: FT 300 + 2F-85 1.205 kg, CoM z = 76 mm; inertia: the sensor's cylinder and "
                     "a solid box 75 x 85 x 123 mm for the gripper")
FT300_2F85_TIP = ft300_tip(1.205, 0.076, 0.123)
GRIPPER_2F85_HOLDER = Holder(
    "2f-85 on ft300", FT300_2F85, FT300_2F85_TIP[2],
    f"{FT300_2F85_SOURCE}, holding the tool between its fingertips (the box's far end, "
    f"{FT300_2F85_TIP[2] * 1000:.0f} mm out)")

# The Robotiq FT 300 and what stacks on it, on either robot's flange.
ROBOTIQ = [
    Tool("ft300 sensor", [FT300],
         f"{FT300_SOURCE}: 0.300 kg, CoM z = 17 mm; inertia of a solid cylinder 75 mm across, 34 mm long "
         "(twice the CoM height)", (0.0, 0.0, 0.034), "tip: the sensor's tool face, the cylinder's far end"),
    Tool("2f-85 gripper on ft300", FT300_2F85, FT300_2F85_SOURCE, FT300_2F85_TIP,
         "tip: between the fingertips, the far end of the gripper's box"),
    Tool("2f-140 gripper on ft300", on_ft300("2F-140", 1.275, 0.083, (0.075, 0.140, 0.137)),
         f"{FT300_SOURCE}: FT 300 + 2F-140 1.275 kg, CoM z = 83 mm; inertia: the sensor's cylinder and a "
         "solid box 75 x 140 x 137 mm for the gripper", ft300_tip(1.275, 0.083, 0.137),
         "tip: between the fingertips, the far end of the gripper's box"),
    Tool("wrist camera on ft300", on_ft300("Wrist Camera", 0.530, 0.030, (0.075, 0.075, 0.020), (0.0, 0.002)),
         f"{FT300_SOURCE}: FT 300 + Wrist Camera 0.530 kg, CoM (0, 2, 30) mm; inertia: the sensor's "
         "cylinder and a solid box 75 x 75 x 20 mm for the camera", ft300_tip(0.530, 0.030, 0.020, (0.0, 0.002)),
         "tip: the camera's face, the far end of its box"),
    Tool("2f-85 + wrist camera on ft300", on_ft300("Wrist Camera + 2F-85", 1.275, 0.077,
                                                   (0.075, 0.085, 0.140), (0.0, 0.001)),
         f"{FT300_SOURCE}: FT 300 + Wrist Camera + 2F-85 1.275 kg, CoM (0, 1, 77) mm; inertia: the sensor's "
         "cylinder and a solid box 75 x 85 x 140 mm", ft300_tip(1.275, 0.077, 0.140, (0.0, 0.001)),
         "tip: between the fingertips, the far end of the box"),
]

TOUCH_PROBE = Tool(
    "touch probe on 100 mm extension", [cylinder("adapter", 0.060, (0.0, 0.0, 0.005), 0.063, 0.010),
                                        cylinder("extension", 0.085, (0.0, 0.0, 0.060), 0.020, 0.100),
                                        cylinder("probe", 0.035, (0.0, 0.0, 0.125), 0.025, 0.030)],
    "a touch probe on an aluminium extension bar on the flange, no hand: adapter plate 63 x 10 mm "
    "(60 g), bar 20 x 100 mm (85 g, aluminium's density), probe body 25 x 30 mm (35 g); masses assumed, "
    "solid cylinders", (0.0, 0.0, 0.140), "tip: the probe's end (its body's far face)")

PANDA_TOOLS = [
    Tool("franka hand", [FRANKA_HAND], HAND_SOURCE + "; the hand as it ships, nothing grasped",
         HAND_TCP, TCP_SOURCE),
    *ROBOTIQ,
    *(t.held_by(FRANKA_HAND_HOLDER) for t in (SCREWDRIVER_6X125, SCREWDRIVER_PH2X250, CLAW_HAMMER, CORDLESS_DRILL)),
    TOUCH_PROBE,
]

# The Franka Hand is Panda-only; on the UR5 the hand-held tools are held by the 2F-85 on the FT 300. Not the
# PH2 x 250 screwdriver nor the hammer: their tips would rest 0.46 and 0.42 m out, at or below the UR5's
# mounting plane (the flange is 0.43 m above it at the equilibrium).
UR5_TOOLS = [
    *ROBOTIQ,
    TOUCH_PROBE,
    *(t.held_by(GRIPPER_2F85_HOLDER) for t in (SCREWDRIVER_6X125, WHITEBOARD_MARKER, CORDLESS_DRILL)),
]


@dataclass(frozen=True)
class Catalogue:
    model: str
    out: Path
    header: list
    tools: list


CATALOGUES = [
    Catalogue("panda", HERE / "panda_tools.csv", [
        "# Tools for the Franka Emika Panda (model panda), made by examples/tools/panda_tools.py: edit that,",
        "# not this file. Each row is a rigid body fixed to the flange panda_link8: mass (kg), centre of mass",
        "# (m, flange frame, z out of the flange), its inertia tensor about the centre of mass in flange axes",
        "# (kg m^2; URDF's ixy, ixz, iyz) and its tip (m, flange frame). Each comment names where the numbers",
        "# come from, and which are assumed.",
    ], PANDA_TOOLS),
    Catalogue("ur5", HERE / "ur5_tools.csv", [
        "# Tools for the Universal Robots UR5 (model ur5), made by examples/tools/panda_tools.py: edit that,",
        "# not this file. Each row is a rigid body fixed to the ISO 9409-1-50-4-M6 tool flange, frame tool0 of",
        "# ur5_robot.urdf (the UR controller's all-zeros TCP: z out of the flange along wrist 3's axis, x along",
        "# wrist_3_link's x; at the equilibrium, wrist down, tool0's x, y, z are the base's -y, -x, -z): mass (kg),",
        "# centre of mass (m, flange frame), its inertia tensor about the centre of mass in flange axes (kg m^2;",
        "# URDF's ixy, ixz, iyz) and its tip (m, flange frame). The Robotiq devices' axes are the flange's; the",
        "# hand-held tools are held between the fingertips of the 2F-85 on the FT 300. Each comment names where",
        "# the numbers come from, and which are assumed.",
    ], UR5_TOOLS),
]


def number(x: float) -> str:
    """Six significant digits, the way a catalogue prints them (a rounding error from 0 is 0)."""
    return "0" if abs(x) < 1e-15 else f"{x:.6g}"


def render(catalogue: Catalogue) -> str:
    lines = [
        *catalogue.header,
        "name,model,tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz,tool_ixy,tool_ixz,"
        "tool_iyz,tool_tip_x,tool_tip_y,tool_tip_z",
    ]
    for t in catalogue.tools:
        mass, com, tensor = combine(t.parts)
        lines.append(f"# {t.name}: {t.source}; {t.tip_source}.")
        values = [mass, *com, tensor[0][0], tensor[1][1], tensor[2][2], tensor[0][1], tensor[0][2], tensor[1][2],
                  *t.tip]
        lines.append(",".join([t.name, catalogue.model, *(number(v) for v in values)]))
    return "\n".join(lines) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="compare with the committed CSVs instead of writing them")
    args = ap.parse_args()
    stale = 0
    for catalogue in CATALOGUES:
        text = render(catalogue)
        if args.check:
            if not catalogue.out.exists() or catalogue.out.read_text() != text:
                print(f"{catalogue.out} is not what {Path(__file__).name} writes: run it and commit the CSV",
                      file=sys.stderr)
                stale = 1
            continue
        catalogue.out.write_text(text)
        print(f"wrote {catalogue.out} ({len(catalogue.tools)} tools)")
    return stale


if __name__ == "__main__":
    sys.exit(main())
