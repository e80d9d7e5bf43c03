"""toolconf's closed loop for a URDF arm, written as a Python user would write it: Pinocchio's
`aba` in the right-hand side, SciPy's `solve_ivp`, numpy for the rest. The same loop as
toolconf's (crates/runtime/src/model/closed_loop_n.rs, crates/core/src/controller.rs):

    plant       tau = U + dT + K (q^e - q) - D q_dot + g(q^e),   q_ddot = aba(q, q_dot, tau)
    controller  U_dot = -gamma [K_th (q - q^g) + K_thd (q_dot - q_dot^g) + K_thdd (q_ddot - q_ddot^g) + P^U U]
                K_term = S_term^T P_term,  S from derive/tasks.toml's formulas on A, B at X^e

with A = [[O, I], [-M^-1 (dg/dq + K), -M^-1 D]], B = [[O], [M^-1]] from Pinocchio's `crba` and
`computeGeneralizedGravityDerivatives` at q^e; the metrics on the output grid as toolconf takes
them (task error: the sum of the task's weighted error over every grid point, t = 0 included;
int F dt and int J dt by the trapezoidal rule). The impedance can be scaled (`stiffness_scale`,
`damping_scale`) for the study in docs/urdf.md; at 1 it is the description's.

Needs numpy, scipy and pin (bench/peers/requirements.txt).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from pin_robot import ROOT, description, model_with_tool

TERMS = ("theta", "theta_dot", "theta_ddot")
ERROR_TERM = {"position": "theta", "velocity": "theta_dot", "acceleration": "theta_ddot"}


def tasks_toml() -> dict:
    with (ROOT / "derive" / "tasks.toml").open("rb") as f:
        return {t["name"]: t for t in tomllib.load(f)["task"]}


def uniform_grid(t_end: float, dt: float) -> np.ndarray:
    """toolconf's uniform_grid(0, t_end, dt): t_i = i dt below t_end, then t_end itself."""
    n = math.ceil(t_end / dt - 1e-9 * t_end / dt)
    return np.array([i * dt for i in range(n)] + [t_end])


def _per_joint(value, n):
    return np.full(n, float(value)) if np.isscalar(value) else np.array(value, dtype=float)


def _precision(value, n):
    return float(value) * np.eye(n) if np.isscalar(value) else np.array(value, dtype=float)


@dataclass
class Task:
    """A task as toolconf binds it to a model: kind, goals, precisions, episode options."""
    kind: str
    goal: dict
    precision: dict
    t_end: float = 5.0
    dt: float = 0.05
    u0: np.ndarray | None = None
    x0: np.ndarray | None = None
    gamma: float = 1.0
    perturbation: np.ndarray | None = None
    rtol: float = 1e-3
    atol: float = 1e-6
    terms: list = field(default_factory=list)

    @classmethod
    def paper(cls, robot: str, kind: str) -> "Task":
        """The model's paper-style task: its description's goals, tasks.toml's precisions."""
        with (ROOT / "derive" / "models" / f"{robot}.toml").open("rb") as f:
            goals = tomllib.load(f).get("goals", {}).get(kind, {})
        n = len(description(robot).q_e)
        env = {"__builtins__": {}, "pi": math.pi}
        t = tasks_toml()[kind]
        goal = {term: np.array([float(eval(str(v), env)) for v in goals.get(term, ["0"] * n)])  # noqa: S307
                for term in TERMS}
        precision = {term: float(t["defaults"]["precision"].get(term, 0.0)) * np.eye(n)
                     for term in (*TERMS, "u")}
        return cls(kind, goal, precision, terms=list(t["terms"]))

    @classmethod
    def from_file(cls, robot: str, path: Path) -> "Task":
        """A task file (the keys examples/tasks/*.toml use), over the paper-style defaults."""
        with Path(path).open("rb") as f:
            raw = tomllib.load(f)
        task = cls.paper(robot, raw["kind"])
        n = len(description(robot).q_e)
        for term, values in raw.get("goal", {}).items():
            task.goal[term] = np.array(values, dtype=float)
        for term, value in raw.get("precision", {}).items():
            task.precision[term] = _precision(value, n)
        e = raw.get("episode", {})
        task.t_end, task.dt = e.get("t_end", task.t_end), e.get("dt", task.dt)
        task.gamma, task.rtol, task.atol = e.get("learning_rate", 1.0), e.get("rtol", 1e-3), e.get("atol", 1e-6)
        if "initial_torque" in e:
            task.u0 = _per_joint(e["initial_torque"], n)
        if "perturbation" in e:
            task.perturbation = _per_joint(e["perturbation"], n)
        if "initial_theta" in e or "initial_theta_dot" in e:
            q0 = np.array(e.get("initial_theta", description(robot).q_e), dtype=float)
            task.x0 = np.concatenate([q0, np.array(e.get("initial_theta_dot", np.zeros(n)), dtype=float)])
        return task


def sensitivities(kind: str, a: np.ndarray, b: np.ndarray, n: int) -> dict:
    """derive/tasks.toml's formulas for `kind` on numpy A and B (a general inverse)."""
    eye, zero = np.eye(n), np.zeros((n, n))
    e = np.vstack([eye, eye])
    ns = {"A": a, "B": b, "inv": np.linalg.inv, "I": eye, "O": zero, "IO": np.hstack([eye, zero]),
          "OI": np.hstack([zero, eye]), "E": e, "dX_dU": np.linalg.inv(a) @ (e - b)}
    t = tasks_toml()[kind]
    return {term: eval(t["sensitivity"][term], {"__builtins__": {}}, dict(ns))  # noqa: S307 - the repo's formulas
            for term in TERMS if term in t["sensitivity"]}


class ClosedLoop:
    """One tool of a URDF robot on one task, with its controller's gains and ln|Pi^U|."""

    def __init__(self, robot: str, tool, task: Task, stiffness_scale: float = 1.0, damping_scale: float = 1.0):
        d = description(robot)
        self.model, self.data = model_with_tool(robot, tool)
        n = self.n = self.model.nq
        self.task = task
        self.q_e = d.q_e
        self.k = d.stiffness * stiffness_scale
        self.d = d.damping * damping_scale
        self.g_e = pin.computeGeneralizedGravity(self.model, self.data, self.q_e).copy()
        m = pin.crba(self.model, self.data, self.q_e)
        m = np.triu(m) + np.triu(m, 1).T
        g_q = pin.computeGeneralizedGravityDerivatives(self.model, self.data, self.q_e)
        m_inv = np.linalg.inv(m)
        self.mass, self.gravity_stiffness = m, g_q
        self.a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ (g_q + np.diag(self.k)), -m_inv @ np.diag(self.d)]])
        self.b = np.vstack([np.zeros((n, n)), m_inv])
        s = sensitivities(task.kind, self.a, self.b, n)
        self.sensitivity = s
        p = task.precision
        self.gain = {term: (s[term].T @ p[term] if term in s else np.zeros((n, n))) for term in TERMS}
        pi_u = p["u"] + sum(s[t].T @ p[t] @ s[t] for t in s)
        sign, self.logdet = np.linalg.slogdet(pi_u)
        if sign <= 0:
            raise ValueError("Pi^U is not positive definite")
        self.pi_u = pi_u
        self.dt_torque = task.perturbation if task.perturbation is not None else np.zeros(n)
        self.evals = 0

    def acceleration(self, q, qd, u):
        tau = u + self.dt_torque + self.k * (self.q_e - q) - self.d * qd + self.g_e
        return pin.aba(self.model, self.data, q, qd, tau)

    def rhs(self, _t, z):
        """Z_dot = [q_dot; q_ddot; U_dot]: Pinocchio's aba, then the controller."""
        self.evals += 1
        n, t, g = self.n, self.task, self.gain
        q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
        qdd = self.acceleration(q, qd, u)
        grad = (g["theta"] @ (q - t.goal["theta"]) + g["theta_dot"] @ (qd - t.goal["theta_dot"])
                + g["theta_ddot"] @ (qdd - t.goal["theta_ddot"]) + t.precision["u"] @ u)
        return np.concatenate([qd, qdd, -t.gamma * grad])

    def jacobian(self, _t, z):
        """dZ_dot/dZ from Pinocchio's ABA derivatives (for the implicit methods of the study)."""
        n, g, t = self.n, self.gain, self.task
        q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
        tau = u + self.dt_torque + self.k * (self.q_e - q) - self.d * qd + self.g_e
        dq, dv, minv = pin.computeABADerivatives(self.model, self.data, q, qd, tau)
        minv = np.triu(minv) + np.triu(minv, 1).T
        a_q, a_v = dq - minv * self.k, dv - minv * self.d
        j = np.zeros((3 * n, 3 * n))
        j[:n, n:2 * n] = np.eye(n)
        j[n:2 * n, :n], j[n:2 * n, n:2 * n], j[n:2 * n, 2 * n:] = a_q, a_v, minv
        j[2 * n:, :n] = -t.gamma * (g["theta"] + g["theta_ddot"] @ a_q)
        j[2 * n:, n:2 * n] = -t.gamma * (g["theta_dot"] + g["theta_ddot"] @ a_v)
        j[2 * n:, 2 * n:] = -t.gamma * (g["theta_ddot"] @ minv + t.precision["u"])
        return j

    def initial_state(self):
        n, t = self.n, self.task
        x0 = t.x0 if t.x0 is not None else np.concatenate([self.q_e, np.zeros(n)])
        u0 = t.u0 if t.u0 is not None else np.full(n, 0.1)
        return np.concatenate([x0, u0])

    def integrate(self, method: str = "RK45", rtol: float | None = None, atol: float | None = None,
                  max_evals: int | None = None):
        """solve_ivp on the output grid; returns (grid, states) or raises on failure: a state
        beyond 1e6 (toolconf's divergence bound, a terminal event) or, with `max_evals`, more
        right-hand sides than that (toolconf gives up after 10^6 step attempts)."""
        t = self.task
        grid = uniform_grid(t.t_end, t.dt)
        kw = {"jac": self.jacobian} if method in ("Radau", "BDF", "LSODA") else {}

        def diverged(_t, z):
            return 1e6 - float(np.max(np.abs(z)))
        diverged.terminal = True
        rhs = self.rhs
        if max_evals is not None:
            def rhs(t_, z):
                if self.evals >= max_evals:
                    raise RuntimeError(f"more than {max_evals} right-hand sides")
                return self.rhs(t_, z)
        sol = solve_ivp(rhs, (0.0, t.t_end), self.initial_state(), method=method, t_eval=grid, events=diverged,
                        rtol=rtol if rtol is not None else t.rtol, atol=atol if atol is not None else t.atol, **kw)
        if not sol.success:
            raise RuntimeError(sol.message)
        if sol.status == 1:
            raise RuntimeError(f"diverged at t = {sol.t_events[0][0]:.3g} s")
        return grid, sol.y.T

    def metrics(self, grid, states) -> dict:
        """Task error, int F dt, int J dt on the grid, as toolconf computes them."""
        n, t = self.n, self.task
        err_term = ERROR_TERM[t.kind]
        task_error, f_values, j_values = 0.0, [], []
        for z in states:
            q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
            qdd = self.acceleration(q, qd, u)
            value = {"theta": q, "theta_dot": qd, "theta_ddot": qdd}
            e = value[err_term] - t.goal[err_term]
            task_error += float(e @ t.precision[err_term] @ e)
            j = float(u @ t.precision["u"] @ u)
            for term in TERMS:
                if term in t.terms:
                    e = value[term] - t.goal[term]
                    j += float(e @ t.precision[term] @ e)
            j_values.append(0.5 * j)
            f_values.append(0.5 * j - 0.5 * self.logdet)
        trapz = lambda v: float(np.sum(0.5 * np.diff(grid) * (np.array(v[1:]) + np.array(v[:-1]))))  # noqa: E731
        return {"task_error": task_error, "free_energy": trapz(f_values), "cost_j": trapz(j_values),
                "logdet": float(self.logdet), "rhs_evals": self.evals}
