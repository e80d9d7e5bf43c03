#!/usr/bin/env python3
"""Which plant should the controller of a real arm see? The numbers behind docs/explanation/real-arms.md's choice.

For 1000 random physical tools (urdf_model._sample_tool, seeded) on a URDF model, the three tasks'
ln|Pi^U| with the default precisions under three formulations of the linearised plant at q^e:

- raw torque control, the paper's form: A21 = -M^-1 dg/dq, A22 = O (how many tools have an A
  that can be inverted at all);
- joint impedance with the gravity at q^e fed forward (what make derive generates):
  A21 = -M^-1 (dg/dq + K), A22 = -M^-1 D;
- joint impedance with full gravity compensation: A21 = -M^-1 K, A22 = -M^-1 D.

    derive/.venv/bin/python derive/checks/urdf_formulation.py derive/models/panda.toml
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(HERE))

from toolconf_derive.description import load_model, load_tasks, sensitivity  # noqa: E402
from toolconf_derive.urdf_model import UrdfDerivation, _sample_tool  # noqa: E402


def logdets(task, a, b, n):
    eye, zero = np.eye(n), np.zeros((n, n))
    e = np.vstack([eye, eye])
    ns = {"A": a, "B": b, "inv": np.linalg.inv, "I": eye, "O": zero, "IO": np.hstack([eye, zero]),
          "OI": np.hstack([zero, eye]), "E": e, "dX_dU": np.linalg.inv(a) @ (e - b)}
    pi = task.default_precision["u"] * eye
    for t in task.sensitivity_terms:
        s = sensitivity(task, t, ns)
        pi = pi + task.default_precision[t] * s.T @ s
    return np.linalg.slogdet(pi)[1]


def main() -> int:
    model = load_model(Path(sys.argv[1]))
    # The joint tasks, on the paper's formulas: the formulations of the plant are compared on them
    # (the tip tasks' J is the same for both plants).
    tasks = [t for t in load_tasks(HERE / "tasks.toml") if not any(t.term(x).on_tip for x in t.terms)]
    dv = UrdfDerivation(model, model.chain, tasks)
    n = dv.n
    k, d = np.diag(dv.stiffness), np.diag(dv.damping)
    rng = np.random.default_rng(2023)
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 1000
    results = {"set point": [], "full compensation": []}
    invertible = 0
    for _ in range(count):
        p = _sample_tool(rng).ravel()
        m = np.array(dv.mass_at_equilibrium(p))
        g = np.array(dv.gravity_stiffness_at_equilibrium(p))
        m_inv = np.linalg.inv(m)
        b = np.vstack([np.zeros((n, n)), m_inv])
        top = np.hstack([np.zeros((n, n)), np.eye(n)])
        raw = np.vstack([top, np.hstack([-m_inv @ g, np.zeros((n, n))])])
        invertible += np.linalg.matrix_rank(raw) == 2 * n
        for name, stiff in (("set point", g + k), ("full compensation", k)):
            a = np.vstack([top, np.hstack([-m_inv @ stiff, -m_inv @ d])])
            results[name].append([logdets(t, a, b, n) for t in tasks])
    print(f"{model.name}: {count} tools; raw torque control: A invertible for {invertible} of them")
    print("formulation, task: mean, std, min, max of ln|Pi^U|; Spearman rank correlation with the tool mass")
    masses = []
    rng = np.random.default_rng(2023)
    for _ in range(count):
        masses.append(_sample_tool(rng).ravel()[0])
    ranks = lambda v: np.argsort(np.argsort(v))  # noqa: E731
    for name, rows in results.items():
        rows = np.array(rows)
        for j, t in enumerate(tasks):
            col = rows[:, j]
            rho = np.corrcoef(ranks(col), ranks(masses))[0, 1] if np.std(col) > 0 else float("nan")
            print(f"  {name:18s} {t.name:12s} {col.mean():.6f} {col.std():.3e} {col.min():.6f} {col.max():.6f} "
                  f"rho(mass) {rho:+.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
