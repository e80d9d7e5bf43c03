"""``toolconf.tool_from_urdf`` and ``toolconf tool --urdf`` on the Franka Hand of the Panda's URDF,
against Pinocchio (``pin``, in derive/requirements.txt), which reads the same file itself.

How the reference is built (Pinocchio 4): ``buildModelFromUrdf`` merges a link on a fixed joint
into the body of the moving joint above it (``panda_hand`` and ``panda_hand_tcp`` into
``panda_joint7``'s body, with ``panda_link7``), but keeps each such link's own inertia on the
frame of its fixed joint (``model.frames[f].inertia``, expressed in that frame, which is the
link's frame); a link on a moving joint is that joint's body (``model.inertias[j]``, in the
joint's frame). So the hand is the sum of the ``panda_hand_joint`` and ``panda_hand_tcp_joint``
frames' inertias and of the two finger joints' bodies, each moved to the world by its placement
(``oMf[f].act``, ``oMi[j].act``) after ``forwardKinematics`` and ``updateFramePlacements`` at
the fingers' opening (both finger joints set: Pinocchio builds the ``<mimic>`` joint as an
independent one), then into the flange frame by ``oMf[flange].actInv``. ``crba``'s ``Ycrb``
would not do: the hand shares its body with ``panda_link7``.
"""

import csv
import io
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import toolconf
from test_fuzz_arguments import FUZZ, call, mostly

import pinocchio as pin  # in derive/requirements.txt: make test installs it

REPO = Path(__file__).resolve().parents[2]
PANDA = REPO / "derive" / "robots" / "panda_description" / "urdf" / "panda.urdf"
FINGERS = ("panda_finger_joint1", "panda_finger_joint2")
COLUMNS = [
    "name", "model", "tool_mass", "tool_com_x", "tool_com_y", "tool_com_z",
    "tool_ixx", "tool_iyy", "tool_izz", "tool_ixy", "tool_ixz", "tool_iyz",
    "tool_tip_x", "tool_tip_y", "tool_tip_z",
]
# Relative to each quantity's largest entry: round-off of the frame changes, far below what a
# misread origin or inertia moves.
TOLERANCE = 1e-10


def pinocchio_hand(opening, flange):
    """The Franka Hand's composite inertia (a ``pin.Inertia`` about its centre of mass, in the
    flange frame) and the tip ``panda_hand_tcp``'s position in that frame, by Pinocchio."""
    model = pin.buildModelFromUrdf(str(PANDA))
    data = model.createData()
    # The arm anywhere (the hand's placement relative to the flange does not depend on it).
    q = pin.neutral(model)
    q[:7] = [0.3, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7]
    fingers = [model.getJointId(j) for j in FINGERS]
    for j in fingers:
        q[model.joints[j].idx_q] = opening
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    total = pin.Inertia.Zero()
    for name in ("panda_hand_joint", "panda_hand_tcp_joint"):
        f = model.getFrameId(name, pin.FIXED_JOINT)
        total += data.oMf[f].act(model.frames[f].inertia)
    for j in fingers:
        total += data.oMi[j].act(model.inertias[j])
    placement = data.oMf[model.getFrameId(flange, pin.BODY)]
    tip = placement.actInv(data.oMf[model.getFrameId("panda_hand_tcp", pin.BODY)]).translation
    return placement.actInv(total), np.array(tip)


def as_arrays(row):
    com = np.array([row["tool_com_x"], row["tool_com_y"], row["tool_com_z"]])
    i = np.array([
        [row["tool_ixx"], row["tool_ixy"], row["tool_ixz"]],
        [row["tool_ixy"], row["tool_iyy"], row["tool_iyz"]],
        [row["tool_ixz"], row["tool_iyz"], row["tool_izz"]],
    ])
    tip = np.array([row["tool_tip_x"], row["tool_tip_y"], row["tool_tip_z"]])
    return row["tool_mass"], com, i, tip


def relative(got, want):
    got, want = np.asarray(got, float), np.asarray(want, float)
    return float(np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-300))


@pytest.mark.parametrize("flange", [None, "panda_link8"])
@pytest.mark.parametrize("opening", [0.0, 0.02, 0.04])
def test_the_franka_hand_equals_pinocchios_composite_inertia(opening, flange):
    row = toolconf.tool_from_urdf(
        PANDA, "panda_hand", "panda_hand_tcp", opening=opening, flange=flange
    )
    assert list(row) == COLUMNS
    mass, com, inertia, tip = as_arrays(row)
    want, want_tip = pinocchio_hand(opening, flange or "panda_hand")
    assert want.mass == pytest.approx(0.76, abs=1e-15)
    assert relative(mass, want.mass) <= TOLERANCE
    assert relative(com, want.lever) <= TOLERANCE, (com, want.lever)
    assert relative(inertia, want.inertia) <= TOLERANCE, (inertia, want.inertia)
    assert relative(tip, want_tip) <= TOLERANCE, (tip, want_tip)
    # The hand's 0.1034 m to its tool-centre point along its z axis, as the flange's.
    assert tip == pytest.approx([0.0, 0.0, 0.1034], abs=1e-15)


def test_the_flange_frame_turns_the_hand_by_its_fixed_joint():
    """In panda_link8's frame the hand is turned by panda_hand_joint's rpy 0 0 -pi/4: the same
    body, its tensor R I Rᵀ, its centre of mass R c."""
    hand = as_arrays(toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", opening=0.04))
    flange = as_arrays(toolconf.tool_from_urdf(
        PANDA, "panda_hand", "panda_hand_tcp", opening=0.04, flange="panda_link8"))
    c, s = math.cos(-math.pi / 4), math.sin(-math.pi / 4)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert flange[0] == hand[0]
    assert relative(flange[1], r @ hand[1]) <= 1e-14
    assert relative(flange[2], r @ hand[2] @ r.T) <= 1e-14
    assert np.linalg.eigvalsh(flange[2]) == pytest.approx(np.linalg.eigvalsh(hand[2]), rel=1e-13)


def test_a_named_joint_position_is_the_opening_for_that_joint():
    by_opening = toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", opening=0.03)
    by_name = toolconf.tool_from_urdf(
        PANDA, "panda_hand", "panda_hand_tcp", joints={"panda_finger_joint1": 0.03}
    )
    assert by_name == by_opening
    row = toolconf.tool_from_urdf(
        PANDA, "panda_hand", "panda_hand_tcp", opening=0.01, name="Franka Hand", model="Panda"
    )
    assert row["name"] == "Franka Hand" and row["model"] == "panda"
    assert toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", opening=0.01)["model"] is None


def test_the_command_line_prints_the_same_row(cli):
    status, stdout, stderr = cli(
        "tool", "--urdf", PANDA, "--root", "panda_hand", "--tip", "panda_hand_tcp",
        "--opening", "0.04", "--flange", "panda_link8", "--model", "panda", "--name", "Franka Hand",
    )
    assert status == 0, stderr
    lines = stdout.splitlines()
    assert lines[0].startswith("# from ") and "panda_finger_joint2 = 0.04 (mimics" in lines[0]
    rows = list(csv.DictReader(io.StringIO("\n".join(lines[1:]) + "\n")))
    assert len(rows) == 1 and list(rows[0]) == COLUMNS
    want = toolconf.tool_from_urdf(
        PANDA, "panda_hand", "panda_hand_tcp", opening=0.04, flange="panda_link8",
        name="Franka Hand", model="panda",
    )
    # Printed to round-trip: the same floats, bit for bit.
    assert {k: (v if k in ("name", "model") else float(v)) for k, v in rows[0].items()} == want


@pytest.mark.parametrize("kwargs, says", [
    ({}, "panda.urdf, line 334: joint 'panda_finger_joint1' is prismatic and has no position"),
    ({"opening": 0.05}, "position 0.05 m is outside its limits [0, 0.04]"),
    ({"opening": -0.01}, "position -0.01 m is outside its limits [0, 0.04]"),
    ({"opening": 0.02, "flange": "panda_link6"}, "joint 'panda_joint7' between --flange 'panda_link6' and --root 'panda_hand' is revolute, not fixed"),
    ({"opening": 0.02, "flange": "panda_leftfinger"}, "is not an ancestor of --root 'panda_hand'"),
    ({"opening": 0.02, "joints": {"panda_finger_joint2": 0.01}}, "give the position of 'panda_finger_joint1'"),
    ({"opening": 0.02, "joints": {"panda_joint1": 0.01}}, "is not below --root 'panda_hand'"),
    ({"opening": 0.02, "model": "arm2"}, "model: 'arm2' is not a model with a tool at a URDF flange"),
    ({"opening": float("nan")}, "opening: NaN is not finite"),
])
def test_bad_input_is_a_value_error_naming_the_file_and_joint(kwargs, says):
    with pytest.raises(ValueError) as e:
        toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", **kwargs)
    assert says in str(e.value)
    assert "\n" not in str(e.value)


def test_a_tip_outside_the_tool_and_an_unknown_link_are_refused():
    with pytest.raises(ValueError, match="--tip 'panda_link7' is not --root 'panda_hand' or a link below it"):
        toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_link7", opening=0.0)
    with pytest.raises(ValueError, match="--root 'gripper' is no link of the file"):
        toolconf.tool_from_urdf(PANDA, "gripper", "panda_hand_tcp", opening=0.0)
    with pytest.raises(ValueError, match="cannot read the URDF file"):
        toolconf.tool_from_urdf(REPO / "missing.urdf", "a", "b")


def test_a_position_of_the_wrong_type_is_a_type_error():
    with pytest.raises(TypeError, match="opening: a bool is not a position"):
        toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", opening=True)
    with pytest.raises(TypeError, match="a position must be a real number"):
        toolconf.tool_from_urdf(PANDA, "panda_hand", "panda_hand_tcp", joints={"panda_finger_joint1": "wide"})


LINKS = ["panda_hand", "panda_hand_tcp", "panda_link8", "panda_leftfinger", "panda_link0", "", "é\n"]
JOINTS = ["panda_finger_joint1", "panda_finger_joint2", "panda_hand_joint", "nope"]


@FUZZ
@given(mostly(st.sampled_from([PANDA, str(PANDA), str(REPO)])), mostly(st.sampled_from(LINKS)),
       mostly(st.sampled_from(LINKS)), mostly(st.one_of(st.none(), st.sampled_from(LINKS))),
       mostly(st.one_of(st.none(), st.floats(-0.01, 0.05))),
       mostly(st.one_of(st.none(), st.dictionaries(st.sampled_from(JOINTS), st.floats(-0.01, 0.05),
                                                   max_size=2))),
       mostly(st.one_of(st.none(), st.text(max_size=8))),
       mostly(st.one_of(st.none(), st.sampled_from(["panda", "UR5", "arm2"]))))
def test_arguments_of_any_type_give_a_row_or_one_line(urdf, root, tip, flange, opening, joints,
                                                        name, model):
    """As test_fuzz_arguments.py does for the other functions: finite numbers, or ValueError,
    TypeError or MemoryError with a one-line message."""
    call(toolconf.tool_from_urdf, urdf, root, tip, flange=flange, opening=opening, joints=joints,
         name=name, model=model)
