"""The on-robot controller on MuJoCo against `toolconf simulate` (`make mujoco-test`).

First MuJoCo's plant is checked to be toolconf's, open loop: the model it builds from the URDF
(limits, contacts, armature, friction, impedance, gravity), the tool's inertia as MuJoCo keeps it,
and q̈, the tip and its Jacobian at random states against the model library's exports. Then the
Panda's catalogue on its touch task, closed loop: each tool's task error, ∫F and tip path agree
within the bound compare.py derives (the tick's first-order error by halving h, MuJoCo's RK4 by
halving its step, toolconf's tolerances), the tick's error is first order as that bound assumes,
and the eleven tools rank alike by ∫F, each gap wider than the two bounds beside it.

The model library is TOOLCONF_MUJOCO_LIBRARY (a folder `make model` wrote) or built here from
generated/panda.json; the command line is TOOLCONF_BIN or `cargo build --bin toolconf`'s.
"""

from __future__ import annotations

import json
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco  # make mujoco-test installs it (examples/mujoco/requirements.txt)
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import compare  # noqa: E402
from compare import REPO, ROUNDING, RATE_HZ, SUBSTEPS  # noqa: E402
from model_library import ModelLibrary  # noqa: E402
from mujoco_arm import (TIP_SITE, TOOL_BODY, arm_model, gravity_torque, inertia_tensor,  # noqa: E402
                        read_description, strip_urdf)

DESCRIPTION = REPO / "derive" / "models" / "panda.toml"
TOOLS = REPO / "examples" / "tools" / "panda_tools.csv"
TASK = REPO / "examples" / "tasks" / "panda_touch_point.toml"


@pytest.fixture(scope="module")
def library_folder(tmp_path_factory) -> Path:
    given = os.environ.get("TOOLCONF_MUJOCO_LIBRARY")
    return Path(given) if given else compare.build_library(REPO / "generated" / "panda.json",
                                                           tmp_path_factory.mktemp("library"))


@pytest.fixture(scope="module")
def library(library_folder) -> ModelLibrary:
    return ModelLibrary(library_folder)


@pytest.fixture(scope="module")
def toolconf() -> Path:
    given = os.environ.get("TOOLCONF_BIN")
    return Path(given) if given else compare.build_toolconf()


@pytest.fixture(scope="module")
def description():
    return read_description(DESCRIPTION)


@pytest.fixture(scope="module")
def tools(toolconf, library):
    found = compare.catalogue(toolconf, TOOLS, TASK, library)
    assert len(found) == 11
    return found


@pytest.fixture(scope="module")
def comparison(library_folder, toolconf, tmp_path_factory):
    """The example's own command (docs/tutorials/mujoco.md) on the catalogue and touch task, its
    comparison.json read back."""
    out = tmp_path_factory.mktemp("comparison")
    status = compare.main(["--out", str(out), "--library", str(library_folder),
                           "--toolconf", str(toolconf)])
    assert status == 0
    assert (out / "comparison.png").stat().st_size > 0
    assert (out / "comparison.csv").read_text().count("\n") == 12
    return json.loads((out / "comparison.json").read_text())


def test_the_stripped_urdf_is_the_chain_toolconf_derives(description):
    root = ET.fromstring(strip_urdf(description.urdf.read_text(), description.base,
                                    description.flange))
    links = [link.get("name") for link in root.findall("link")]
    assert links == [f"panda_link{i}" for i in range(9)]
    joints = {j.get("name"): j.get("type") for j in root.findall("joint")}
    assert joints == {**{f"panda_joint{i}": "revolute" for i in range(1, 8)},
                      "panda_joint8": "fixed"}
    for tag in ("visual", "collision", "mesh", "dynamics"):
        assert root.find(f".//{tag}") is None, tag
    with pytest.raises(ValueError, match="not below the base"):
        strip_urdf(description.urdf.read_text(), "panda_link3", "panda_link1")


def test_mujoco_plant_is_toolconf_plant(library, description, tools):
    """Limits and contacts off, no armature or friction loss, the impedance as joint spring and
    damper about q^e, the description's gravity, RK4, and the tool at the flange."""
    q_e = library.equilibrium_state[:library.dof]
    for tool in tools:
        model = arm_model(description, q_e, tool.params)
        assert model.nv == library.dof and not model.jnt_limited.any()
        assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
        assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
        assert not model.dof_armature.any() and not model.dof_frictionloss.any()
        np.testing.assert_array_equal(model.dof_damping, description.damping)
        np.testing.assert_array_equal(model.jnt_stiffness, description.stiffness)
        np.testing.assert_array_equal(model.qpos_spring, q_e)
        np.testing.assert_array_equal(model.opt.gravity, description.gravity)
        body, p = model.body(TOOL_BODY), tool.params
        assert model.body(body.parentid[0]).name == description.flange
        assert body.mass[0] == p["tool_mass"]
        np.testing.assert_array_equal(body.ipos, [p["tool_com_x"], p["tool_com_y"], p["tool_com_z"]])
        np.testing.assert_array_equal(model.site(TIP_SITE).pos,
                                      [p["tool_tip_x"], p["tool_tip_y"], p["tool_tip_z"]])


def test_the_tools_full_inertia_is_attached(library, description, tools):
    """MuJoCo keeps principal moments and a frame: recomposed, they are the row's tensor."""
    q_e = library.equilibrium_state[:library.dof]
    for tool in tools:
        p = tool.params
        row = np.array([[p["tool_ixx"], p["tool_ixy"], p["tool_ixz"]],
                        [p["tool_ixy"], p["tool_iyy"], p["tool_iyz"]],
                        [p["tool_ixz"], p["tool_iyz"], p["tool_izz"]]])
        kept = inertia_tensor(arm_model(description, q_e, p), TOOL_BODY)
        assert np.linalg.norm(kept - row) <= ROUNDING * np.linalg.norm(row), tool.name


def test_open_loop_dynamics_and_tip_agree(library, description, tools):
    """q̈ of the rigid body (passive forces off) and of the plant (impedance and g(q^e) from
    MuJoCo's own model) against the library's exports, at 20 random states per tool: both
    are one double-precision evaluation by different routes, so they differ by rounding, which
    solving M q̈ = τ amplifies by at most κ(M): ‖Δq̈‖ ≤ 100 ε κ(M) ‖q̈‖. The tip and its
    Jacobian within 100 ε."""
    rng = np.random.default_rng(45)
    n, q_e = library.dof, library.equilibrium_state[:library.dof]
    passive = mujoco.mjtDisableBit.mjDSBL_SPRING | mujoco.mjtDisableBit.mjDSBL_DAMPER
    for tool in tools:
        model = arm_model(description, q_e, tool.params)
        data, site = mujoco.MjData(model), model.site(TIP_SITE).id
        feed_forward = gravity_torque(model, q_e)
        mass, jacobian = np.empty((n, n)), np.empty((3, n))
        for _ in range(20):
            q, q_dot, u = q_e + rng.uniform(-0.5, 0.5, n), rng.uniform(-1, 1, n), rng.uniform(-5, 5, n)
            x = np.concatenate([q, q_dot])
            for flags, applied, expected in (
                    (passive, u, library.rigid_body_dynamics(x, u, tool.vector)[n:]),
                    (0, u + feed_forward, library.dynamics(x, u, tool.vector)[n:])):
                model.opt.disableflags = mujoco.mjtDisableBit.mjDSBL_CONTACT | flags
                data.qpos[:], data.qvel[:], data.qfrc_applied[:] = q, q_dot, applied
                mujoco.mj_forward(model, data)
                mujoco.mj_fullM(model, mass, data.qM)
                bound = ROUNDING * np.linalg.cond(mass) * np.linalg.norm(expected)
                assert np.linalg.norm(data.qacc - expected) <= bound, (tool.name, q, q_dot, u)
            y, j = library.tip(q, tool.vector)
            mujoco.mj_jacSite(model, data, jacobian, None, site)
            assert np.linalg.norm(data.site_xpos[site] - y) <= ROUNDING * np.linalg.norm(y)
            assert np.linalg.norm(jacobian - j) <= ROUNDING * np.linalg.norm(j)


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """|R(z)| of classical RK4 on ẋ = λx, z = λΔt: a mode is integrated stably where < 1."""
    return np.abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24)


def test_mujoco_step_is_stable_for_every_mode(library, tools):
    """The plant's fastest modes (the light wrist under its damping, |λ| up to 3.2e3 /s) need
    RK4's step below 1 ms: at h/SUBSTEPS every mode of A at the equilibrium is damped."""
    step = 1.0 / (RATE_HZ * SUBSTEPS)
    for tool in tools:
        modes = np.linalg.eigvals(library.state_matrix(tool.vector))
        assert np.all(modes.real < 0)
        assert rk4_amplification(modes * step).max() < 1.0, tool.name


def test_each_tools_episode_agrees_within_the_derived_bound(comparison):
    assert len(comparison["tools"]) == 11
    lo, hi = comparison["ratio_range"]
    for row in comparison["tools"]:
        # Both controllers read the tool and task alike: the same ln|Π^U| (the last bit may
        # differ: libm's ln in the library, glibc's in the command line).
        logdet = row["logdet"]
        assert abs(logdet["mujoco"] - logdet["toolconf"]) <= ROUNDING * abs(logdet["toolconf"])
        for metric in compare.METRICS:
            m = row[metric]
            # The tick's error is first order, as the bound assumes: D₁/D₂ near 2.
            assert lo <= m["tick_ratio"] <= hi, (row["name"], metric, m)
            assert abs(m["difference"]) <= m["bound"], (row["name"], metric, m)
        # At every grid time; at t = 0 the bound is the rounding alone (the same start).
        tip = row["tip"]
        assert all(d <= b for d, b in zip(tip["difference"], tip["bound"])), (row["name"], tip)
        assert len(tip["difference"]) == 101


def test_the_ranking_by_free_energy_is_the_same(comparison):
    assert comparison["ranking_mujoco"] == comparison["ranking_toolconf"]
    rows = comparison["tools"]
    assert [r["name"] for r in rows] == comparison["ranking_toolconf"]
    # Each neighbour is further apart than both bounds allow either engine to move it.
    for better, worse in zip(rows, rows[1:]):
        gap = worse["free_energy"]["toolconf"] - better["free_energy"]["toolconf"]
        assert gap > better["free_energy"]["bound"] + worse["free_energy"]["bound"], (better, worse)
