#!/usr/bin/env python3
"""Where each model's tool tip rests, y(q^e), by the derivation's own forward kinematics: what the
default goals of the tip tasks in derive/models/*.toml ([goals.tip_position], [goals.tip_velocity])
are chosen from (the descriptions' comments say how).

- panda, ur5: a nominal tool whose tip is 0.10 m out along the flange z (tool_tip = (0, 0, 0.1)),
  the reference graph of urdf_model.UrdfDerivation (the inward composition) in 50 digits;
- the planar arms (kind planar_chain, and arm2): the mid-box tool, every parameter 0.35 (the
  middle of the paper's [0.1, 0.6]), by numeric.CasadiModel's tip from the description;
- msd: its tip is its displacement, 0 at rest.

    derive/.venv/bin/python derive/checks/tip_goals.py [derive/models/panda.toml ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(HERE))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.urdf_model import INERTIAL, UrdfDerivation  # noqa: E402

# The nominal URDF tool: 1 kg at 5 cm out, a 10 cm box's moments, its tip 0.10 m along flange z
# (only the tip moves y; the inertia is there to make it a tool).
NOMINAL_TIP = (0.0, 0.0, 0.1)
# The mid-box tool of the paper's box [0.1, 0.6].
MID_BOX = 0.35


def rest_tip(path: Path) -> tuple[list[float], int]:
    """y(q^e) of the model's nominal tool (its first TIP_DIM components) and TIP_DIM."""
    model = load_model(path)
    if model.dynamics_kind == "urdf":
        dv = UrdfDerivation(model, model.chain, load_tasks(HERE / "tasks.toml"))
        tool = np.array([1.0, 0.0, 0.0, 0.05] + [1e-3] * 3 + [0.0] * 3 + list(NOMINAL_TIP))
        assert len(tool) == INERTIAL + 3
        y = dv.reference_tip.checked(dv.q_e, tool)[0]
    else:
        cm = CasadiModel(model)
        y = cm.tip.checked(cm.x_e[:model.dof], np.full(len(model.parameters), MID_BOX))[0]
    values = [float(v) for v in y.to_numpy().ravel()[:model.tip_dim]]
    return [0.0 if abs(v) < 1e-12 else v for v in values], model.tip_dim


def main() -> int:
    paths = [Path(a) for a in sys.argv[1:]] or sorted((HERE / "models").glob("*.toml"))
    for path in paths:
        y, k = rest_tip(path)
        print(f"{path.stem}: TIP_DIM {k}, y(q^e) = [{', '.join(repr(v) for v in y)}] m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
