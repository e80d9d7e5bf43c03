#!/usr/bin/env python3
"""Does a joint position task reach its goal on a real arm? The paper's task-1 sensitivity against
the stabilised plant's static gain, measured.

For random physical tools (urdf_model._sample_tool, seeded) on a URDF model, or tools from the
paper's box [0.1, 0.6]^k on the paper's arms (kinds explicit, planar_chain), the position task
of derive/tasks.toml (its four terms, default precisions, the description's [goals.position])
is run from rest at X^e under the nonlinear plant the generated code integrates (`dynamics`),
with the controller of crates/core/src/controller.rs written out:
U_dot = -gamma (sum_t S_t^T P_t (obs_t - goal_t) + P^U U), obs_theta_ddot = f(X, U)'s lower half,
gamma = 1, 5 s, CasADi's CVODES at rtol 1e-10. Two sensitivity sets:

- paper:  dtheta/dU = [I O] A^-1 (E - B),  dtheta_dot/dU = [O I] A^-1 (E - B),  dtheta_ddot/dU = I
- static: dtheta/dU = -[I O] A^-1 B (= (dg/dq + K)^-1 under impedance: the response of the
          rest position to a constant torque), dtheta_dot/dU = -[O I] A^-1 B (= O), dtheta_ddot/dU = I

Reported per set: progress 1 - |theta(T) - theta^g| / |theta(0) - theta^g| (min, median, max),
how many tools moved away (progress < 0), and the task error integral of |theta - theta^g|^2.

    derive/.venv/bin/python derive/checks/position_sensitivity.py derive/models/panda.toml [tools] [P^U] [P^theta]

P^U (a number, times I) replaces the task's default precision of the control, 1 (sigma_U = 1 N m):
the prior that holds U near 0 against the position evidence, which on a stiff arm decides how
far either sensitivity can move it. P^theta likewise replaces the joints' precision, 100
(sigma_theta = 0.1 rad): with the static gain S = (dg/dq + K)^-1 the loop's rate is about
gamma S^T P^theta S, so a stiff joint (K = 600 N m/rad) needs P^theta near K^2 to move within
seconds.
"""

from __future__ import annotations

import sys
from pathlib import Path

import casadi as ca
import numpy as np

HERE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(HERE))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.numeric import CasadiModel  # noqa: E402
from toolconf_derive.symbolic import parse  # noqa: E402
from toolconf_derive.urdf_model import UrdfDerivation, _sample_tool  # noqa: E402

T_END = 5.0


def sensitivities(a: np.ndarray, b: np.ndarray, n: int, which: str) -> dict[str, np.ndarray]:
    eye = np.eye(n)
    a_inv = np.linalg.inv(a)
    if which == "paper":
        dx = a_inv @ (np.vstack([eye, eye]) - b)
    else:
        dx = -a_inv @ b
    return {"theta": dx[:n], "theta_dot": dx[n:], "theta_ddot": eye}


def episode(dv: UrdfDerivation, p: np.ndarray, prec: dict, goal: np.ndarray, which: str) -> tuple[float, float]:
    n = dv.n
    a, b = np.array(dv.state_matrix(p)), np.array(dv.input_matrix(p))
    s = sensitivities(a, b, n, which)
    x, u, e = ca.SX.sym("x", 2 * n), ca.SX.sym("u", n), ca.SX.sym("e")
    f = dv.dynamics_inline(x, u, p)
    gradient = prec["u"] * u
    goals = {"theta": goal, "theta_dot": np.zeros(n), "theta_ddot": np.zeros(n)}
    observed = {"theta": x[:n], "theta_dot": x[n:], "theta_ddot": f[n:]}
    for t in ("theta", "theta_dot", "theta_ddot"):
        gradient = gradient + ca.DM(s[t].T * prec[t]) @ (observed[t] - goals[t])
    error = x[:n] - goal
    z = ca.vertcat(x, u, e)
    ode = ca.vertcat(f, -gradient, ca.dot(error, error))
    sim = ca.integrator("sim", "cvodes", {"x": z, "ode": ode}, 0.0, T_END,
                        {"reltol": 1e-10, "abstol": 1e-12, "max_num_steps": 200000})
    z0 = np.concatenate([dv.x_e, np.zeros(n), [0.0]])
    try:
        out = np.array(sim(x0=z0)["xf"]).ravel()
    except RuntimeError:
        return float("nan"), float("nan")  # the closed loop diverged (CVODES gave up)
    start = np.linalg.norm(dv.x_e[:n] - goal)
    progress = 1.0 - np.linalg.norm(out[:n] - goal) / start
    return progress, out[-1]


class SymbolicPlant:
    """What `episode` asks of a URDF derivation, for a model of kind `explicit` or `planar_chain`
    (the paper's arms): its CasADi graph (numeric.CasadiModel, built from the description's strings),
    A and B by AD at the equilibrium, and tools drawn from the paper's box [0.1, 0.6]^k."""

    def __init__(self, model):
        self.cm = CasadiModel(model)
        self.n = model.dof
        self.x_e = self.cm.x_e
        self.k = len(model.parameters)
        x, u, p = self.cm.x, self.cm.u, self.cm.p
        f = self.cm.dynamics.f(x, u, p)
        self.dynamics_inline = ca.Function("f", [x, u, p], [f])

    def state_matrix(self, p):
        return self.cm.jacobian.f(self.cm.x_e, self.cm.u_e, p)[0]

    def input_matrix(self, p):
        return self.cm.jacobian.f(self.cm.x_e, self.cm.u_e, p)[1]

    def tools(self, rng, count):
        return [rng.uniform(0.1, 0.6, self.k) for _ in range(count)]


def main() -> int:
    model = load_model(Path(sys.argv[1]))
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 20
    task = next(t for t in load_tasks(HERE / "tasks.toml") if t.name == "position")
    prec = dict(task.default_precision)
    if len(sys.argv) > 3:
        prec["u"] = float(sys.argv[3])
    if len(sys.argv) > 4:
        prec["theta"] = float(sys.argv[4])
    rng = np.random.default_rng(2026)
    if model.dynamics_kind == "urdf":
        dv = UrdfDerivation(model, model.chain, load_tasks(HERE / "tasks.toml"))
        tools = [_sample_tool(rng).ravel() for _ in range(count)]
    else:
        dv = SymbolicPlant(model)
        tools = dv.tools(rng, count)
    goal = np.array([float(parse(model, v, {}, f"goals.position.theta[{i}]").evalf(30))
                     for i, v in enumerate(model.goals["position"]["theta"])])
    print(f"{model.name}: {count} tools, goal |theta^g - q^e| = {np.linalg.norm(goal - dv.x_e[:dv.n]):.3f} rad, "
          f"{T_END:g} s, precisions {prec}")
    for which in ("paper", "static"):
        rows = np.array([episode(dv, p, prec, goal, which) for p in tools])
        failed = int(np.sum(np.isnan(rows[:, 0])))
        if failed == count:
            print(f"  {which:6s} every episode diverged")
            continue
        rows = rows[~np.isnan(rows[:, 0])]
        progress, integral = rows[:, 0], rows[:, 1]
        print(f"  {which:6s} progress min {progress.min():+.3f} median {np.median(progress):+.3f} "
              f"max {progress.max():+.3f}; moved away {int(np.sum(progress < 0))}/{count}; "
              f"int |e|^2 dt median {np.median(integral):.4g} rad^2 s; diverged {failed}/{count}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
