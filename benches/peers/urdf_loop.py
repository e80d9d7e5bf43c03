"""toolconf's closed loop for a URDF arm, written as a Python user would write it: Pinocchio's
`aba` in the right-hand side, SciPy's `solve_ivp`, numpy for the rest. The same loop as
toolconf's (crates/model/src/model/closed_loop_n.rs, crates/core/src/controller.rs):

    plant       tau = U + dT + K (q^e - q) - D q_dot + g(q^e),   q_ddot = aba(q, q_dot, tau)
    controller  U_dot = -gamma [sum over the task's terms of K_term (term - goal) + P^U U]
                K_term = S_term^T P_term,  S from derive/tasks.toml's formulas on A, B (and J) at X^e

with A = [[O, I], [-M^-1 (dg/dq + K), -M^-1 D]], B = [[O], [M^-1]] from Pinocchio's `crba` and
`computeGeneralizedGravityDerivatives` at q^e. The terms are the joints' (theta = q,
theta_dot = q_dot, theta_ddot = the plant's q_ddot, u = U) and, on a task on the tool's tip, the
tip's, observed with Pinocchio at the frame "tool_tip" (pin_robot.model_with_tool): tip =
oMf.translation, tip_dot = getFrameVelocity(LOCAL_WORLD_ALIGNED).linear = J(q) q_dot, tip_ddot =
getFrameClassicalAcceleration(LOCAL_WORLD_ALIGNED).linear = J(q) q_ddot + Jdot q_dot after
forwardKinematics(q, q_dot, q_ddot), q_ddot the plant's. As toolconf binds a task, a tip term's
value, goal, precision and sensitivity fill the first 3 rows of the joint-sized vectors and
matrices, zero below (a scalar precision is that multiple of the 3 x 3 identity; goals absolute in
the base frame), and J in the formulas is the tip's Jacobian at q^e
(computeFrameJacobian(LOCAL_WORLD_ALIGNED), its 3 linear rows) padded to n x n. The formulas are
those of the task's formulation as toolconf derives it for the model (derive/toolconf_derive: the
description's [formulation], else the one whose default_for has the dynamics kind: the static gain
on position and tip_position for the URDF arms), parsed by toolconf_derive's expression grammar,
not eval. The metrics on the output grid as toolconf takes them (task error: the sum of the
task's weighted error over every grid point, t = 0 included; int F dt and int J dt by the
trapezoidal rule). The impedance can be scaled (`stiffness_scale`, `damping_scale`) for the study
in docs/explanation/static-gain.md; at 1 it is the description's.

Checked against toolconf (benches/timing/model_timing.rs) on the Panda, the first 5 tools of
urdf_peers.py's population (boxes with tips) per task, both integrated tightly (toolconf's
`explicit` DP5 and this loop in SciPy's DOP853, rtol 1e-10, atol 1e-12; `urdf_peers.py --check`
repeats it): the largest relative difference of ln|Pi^U| and of the task error, 2026-12-05:

    position (static gain)            1.8e-16   2.3e-15      tip_position (static gain)   8.4e-13   1.1e-14
    velocity                          3.7e-16   5.2e-11      tip_velocity                 1.9e-12   8.8e-12
    acceleration                      6.7e-14   1.0e-10      tip_acceleration             2.0e-14   1.4e-09
    panda_wrist_turn.toml             4.1e-16   8.8e-10      panda_touch_point.toml       1.4e-15   1.5e-12
    panda_draw_line.toml              1.4e-15   7.0e-11      panda_push_off.toml          3.3e-13   9.5e-09

(tip_position's ln|Pi^U| is 8e-4 to 1.2e-3 on these tools: its differences are 8e-16 absolute at most.)

Needs numpy, scipy and pin (benches/peers/requirements.txt), and derive/toolconf_derive (no
SymPy: the description and task readers and the expression grammar).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

from pin_robot import MODELS, ROOT, description, model_with_tool

sys.path.insert(0, str(ROOT / "derive"))
from toolconf_derive.description import FORMULA_NAMES, PAPER, formulated, load_model, load_tasks  # noqa: E402
from toolconf_derive.expression import formula, number_value, python_number  # noqa: E402

TIP_FRAME = "tool_tip"
# The tip's components of a URDF arm (x, y, z in the base frame): TIP_DIM of derive/tasks.toml.
TIP_DIM = 3


@lru_cache(maxsize=None)
def task_definitions() -> dict:
    """derive/tasks.toml's tasks by name, as toolconf_derive reads them (formulas unresolved)."""
    return {t.name: t for t in load_tasks(ROOT / "derive" / "tasks.toml")}


@lru_cache(maxsize=None)
def model_description(robot: str):
    """A model of derive/models by name, or a description of kind urdf by its path (*.toml)."""
    return load_model(Path(robot) if robot.endswith(".toml") else MODELS / f"{robot}.toml")


def terms() -> list:
    """Every free-energy term (name, read from the tip or not), in tasks.toml's order."""
    return [(t.name, t.on_tip) for t in next(iter(task_definitions().values())).all_terms]


def on_tip(term: str) -> bool:
    return dict(terms())[term]


def definition(robot: str, kind: str, formulation: str | None = None):
    """Task `kind` with the sensitivities of `formulation` ("paper" or a name of the task's
    [task.formulations]), by default those toolconf derives for `robot` (toolconf_derive's
    `formulated`: the description's choice, else the default for its dynamics kind)."""
    task = task_definitions()[kind]
    if formulation is None:
        return formulated(task, model_description(robot))
    if formulation == PAPER:
        return task
    f = task.formulations[formulation]
    return replace(task, sensitivity={**task.sensitivity, **f.sensitivity}, formulation=formulation)


def term_identity(term: str, n: int) -> np.ndarray:
    """I for a joint term; the tip's TIP_DIM x TIP_DIM identity padded with zeros for a tip term."""
    d = TIP_DIM if on_tip(term) else n
    return np.diag([1.0 if i < d else 0.0 for i in range(n)])


def pad(v, n: int) -> np.ndarray:
    out = np.zeros(n)
    out[:len(v)] = v
    return out


def pad_matrix(m, n: int) -> np.ndarray:
    m = np.asarray(m, dtype=float)
    out = np.zeros((n, n))
    out[:m.shape[0], :m.shape[1]] = m
    return out


def uniform_grid(t_end: float, dt: float) -> np.ndarray:
    """toolconf's uniform_grid(0, t_end, dt): t_i = i dt below t_end, then t_end itself."""
    n = int(np.ceil(t_end / dt - 1e-9 * t_end / dt))
    return np.array([i * dt for i in range(n)] + [t_end])


def _per_joint(value, n):
    return np.full(n, float(value)) if np.isscalar(value) else np.array(value, dtype=float)


@dataclass
class Task:
    """A task as toolconf binds it to a model: kind, goals and precisions (joint-sized, tip
    terms padded), its terms, error term and sensitivity formulas, episode options."""
    kind: str
    goal: dict
    precision: dict
    terms: list = field(default_factory=list)
    error: str = "theta"
    sensitivity: dict = field(default_factory=dict)
    cost_order: tuple = ()
    formulation: str = PAPER
    t_end: float = 5.0
    dt: float = 0.05
    u0: np.ndarray | None = None
    x0: np.ndarray | None = None
    gamma: float = 1.0
    perturbation: np.ndarray | None = None
    rtol: float = 1e-3
    atol: float = 1e-6

    @property
    def reads_tip(self) -> bool:
        return any(on_tip(t) for t in self.terms)

    @property
    def reads_tip_acceleration(self) -> bool:
        return "tip_ddot" in self.terms

    @classmethod
    def paper(cls, robot: str, kind: str, formulation: str | None = None) -> "Task":
        """The model's paper-style task: its description's goals, tasks.toml's precisions, the
        formulation toolconf derives for the model (or `formulation`)."""
        t = definition(robot, kind, formulation)
        goals = model_description(robot).goals.get(kind, {})
        n = len(description(robot).q_e)
        goal = {name: np.zeros(n) for name, _ in terms()}
        for term, values in goals.items():
            goal[term] = pad([number_value(str(v)) for v in values], n)
        precision = {name: float(t.default_precision.get(name, 0.0)) * term_identity(name, n) for name, _ in terms()}
        return cls(kind, goal, precision, terms=list(t.terms), error=t.error, sensitivity=dict(t.sensitivity),
                   cost_order=tuple(t.cost_order), formulation=t.formulation)

    @classmethod
    def from_file(cls, robot: str, path: Path, formulation: str | None = None) -> "Task":
        """A task file (the keys examples/tasks/*.toml use), over the paper-style defaults: a
        tip term's goal has the tip's 3 components, its scalar precision weighs them alone."""
        import tomllib
        with Path(path).open("rb") as f:
            raw = tomllib.load(f)
        task = cls.paper(robot, raw["kind"], formulation)
        n = len(description(robot).q_e)
        for term, values in raw.get("goal", {}).items():
            task.goal[term] = pad(np.array(values, dtype=float), n)
        for term, value in raw.get("precision", {}).items():
            task.precision[term] = (float(value) * term_identity(term, n) if np.isscalar(value)
                                    else pad_matrix(value, n))
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


def sensitivities(task: Task, a: np.ndarray, b: np.ndarray, j: np.ndarray, n: int) -> dict:
    """The task's formulas (derive/tasks.toml, its formulation) on numpy A, B and the padded tip
    Jacobian J, through toolconf_derive's expression grammar (a general inverse)."""
    eye, zero = np.eye(n), np.zeros((n, n))
    e = np.vstack([eye, eye])
    values = {"A": a, "B": b, "I": eye, "O": zero, "IO": np.hstack([eye, zero]), "OI": np.hstack([zero, eye]),
              "E": e, "dX_dU": np.linalg.inv(a) @ (e - b), "J": j}
    return {term: formula(text, FORMULA_NAMES).evaluate(values, {"inv": np.linalg.inv}, python_number)
            for term, text in task.sensitivity.items()}


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
        self.tip_frame = self.model.getFrameId(TIP_FRAME)
        self.g_e = pin.computeGeneralizedGravity(self.model, self.data, self.q_e).copy()
        m = pin.crba(self.model, self.data, self.q_e)
        m = np.triu(m) + np.triu(m, 1).T
        g_q = pin.computeGeneralizedGravityDerivatives(self.model, self.data, self.q_e)
        m_inv = np.linalg.inv(m)
        self.mass, self.gravity_stiffness = m, g_q
        self.a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ (g_q + np.diag(self.k)), -m_inv @ np.diag(self.d)]])
        self.b = np.vstack([np.zeros((n, n)), m_inv])
        # The tip's Jacobian at q^e, its linear rows in the base frame, padded to n x n.
        self.tip_jacobian = pad_matrix(pin.computeFrameJacobian(
            self.model, self.data, self.q_e, self.tip_frame, pin.LOCAL_WORLD_ALIGNED)[:TIP_DIM], n)
        s = sensitivities(task, self.a, self.b, self.tip_jacobian, n)
        self.sensitivity = s
        p = task.precision
        # K = S^T P for every term the task uses; P^U for the control's own term.
        self.gain = {term: s[term].T @ p[term] for term in task.terms if term in s}
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

    def observe(self, q, qd, u) -> dict:
        """Every term the task reads at state (q, q_dot) and control U: the joints' and, on a tip
        task, the tip's from Pinocchio's forward kinematics (padded to n)."""
        qdd = self.acceleration(q, qd, u)
        value = {"theta": q, "theta_dot": qd, "theta_ddot": qdd, "u": u}
        if self.task.reads_tip:
            model, data, frame, n = self.model, self.data, self.tip_frame, self.n
            if self.task.reads_tip_acceleration:
                pin.forwardKinematics(model, data, q, qd, qdd)
                value["tip_ddot"] = pad(pin.getFrameClassicalAcceleration(
                    model, data, frame, pin.LOCAL_WORLD_ALIGNED).linear, n)
            else:
                pin.forwardKinematics(model, data, q, qd)
            value["tip"] = pad(pin.updateFramePlacement(model, data, frame).translation, n)
            value["tip_dot"] = pad(pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED).linear, n)
        return value

    def rhs(self, _t, z):
        """Z_dot = [q_dot; q_ddot; U_dot]: Pinocchio's aba (and the tip's kinematics), then the
        controller."""
        self.evals += 1
        n, t = self.n, self.task
        q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
        value = self.observe(q, qd, u)
        grad = t.precision["u"] @ u
        for term, k in self.gain.items():
            grad = grad + k @ (value[term] - t.goal[term])
        return np.concatenate([qd, value["theta_ddot"], -t.gamma * grad])

    def jacobian(self, _t, z):
        """dZ_dot/dZ from Pinocchio's ABA derivatives (for the implicit methods of the study); on
        the joint tasks only (a tip task's implicit integration takes SciPy's finite differences)."""
        n, g, t = self.n, self.gain, self.task
        zero = np.zeros((n, n))
        q, qd, u = z[:n], z[n:2 * n], z[2 * n:]
        tau = u + self.dt_torque + self.k * (self.q_e - q) - self.d * qd + self.g_e
        dq, dv, minv = pin.computeABADerivatives(self.model, self.data, q, qd, tau)
        minv = np.triu(minv) + np.triu(minv, 1).T
        a_q, a_v = dq - minv * self.k, dv - minv * self.d
        k_th, k_thd, k_thdd = (g.get(term, zero) for term in ("theta", "theta_dot", "theta_ddot"))
        j = np.zeros((3 * n, 3 * n))
        j[:n, n:2 * n] = np.eye(n)
        j[n:2 * n, :n], j[n:2 * n, n:2 * n], j[n:2 * n, 2 * n:] = a_q, a_v, minv
        j[2 * n:, :n] = -t.gamma * (k_th + k_thdd @ a_q)
        j[2 * n:, n:2 * n] = -t.gamma * (k_thd + k_thdd @ a_v)
        j[2 * n:, 2 * n:] = -t.gamma * (k_thdd @ minv + t.precision["u"])
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
        implicit = method in ("Radau", "BDF", "LSODA")
        kw = {"jac": self.jacobian} if implicit and not t.reads_tip else {}

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
        """Task error, int F dt, int J dt on the grid, as toolconf computes them (J's summands in
        tasks.toml's cost_order)."""
        n, t = self.n, self.task
        task_error, f_values, j_values, distances = 0.0, [], [], []
        for z in states:
            value = self.observe(z[:n], z[n:2 * n], z[2 * n:])
            e = value[t.error] - t.goal[t.error]
            task_error += float(e @ t.precision[t.error] @ e)
            distances.append(float(np.linalg.norm(e)))
            j = 0.0
            for term in t.cost_order:
                if term in t.terms:
                    e = value[term] - t.goal[term]
                    j += float(e @ t.precision[term] @ e)
            j_values.append(0.5 * j)
            f_values.append(0.5 * j - 0.5 * self.logdet)
        trapz = lambda v: float(np.sum(0.5 * np.diff(grid) * (np.array(v[1:]) + np.array(v[:-1]))))  # noqa: E731
        # Progress 1 - e(T)/e(0) on a position task (joint or tip), as toolconf's Metrics::progress.
        position = t.error in ("theta", "tip") and distances[0] > 0.0
        return {"task_error": task_error, "free_energy": trapz(f_values), "cost_j": trapz(j_values),
                "logdet": float(self.logdet), "rhs_evals": self.evals,
                "progress": 1.0 - distances[-1] / distances[0] if position else None}
