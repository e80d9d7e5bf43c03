"""The functions a URDF model exports (the same names and signatures as every other model's), their
check (code graph against reference graph, both in 50-digit arithmetic), test vectors and IR.

The IR of each function is CasADi's instruction sequence of its code graph (sequence.py) in the
shape templates/model.rs.tera renders for every model; `dynamics` and `dynamics_jacobian` carry
per-tool coefficients (the last body's inertia with the tool, and K q^e + g(q^e; p)).
"""

from __future__ import annotations

import multiprocessing
import time

import casadi as ca
import mpmath
import numpy as np

from . import ir_types as irt
from . import progress
from .description import Model, model_tasks, sensitivity
from .errors import DescriptionError
from .exact import ExactFunction
from .functions import _sample_control, _sample_precision, _sample_state
from .ir import _rust_type, _struct_name, model_document
from .rigid_body import ldl_logdet
from .rust_printer import float_literal
from .sequence import as_lets, instruction_count, instructions
from .urdf import DIGITS, ORTHONORMAL, orthonormal_deviation
from .urdf_model import AGREEMENT, SeqArg, SeqFunction, SeqOutput, UrdfDerivation, UrdfMismatch, _sample_tool


def _state_doc(m: Model) -> str:
    return f"state X = [{' '.join(s.name for s in m.state)}]"


def build_functions(dv: UrdfDerivation) -> list[SeqFunction]:
    m, n = dv.model, dv.n
    x = SeqArg("x", _state_doc(m), 2 * n, 1, False, _sample_state(n))
    u = SeqArg("u", f"control U = [{' '.join(s.name for s in m.u)}]", n, 1, False, _sample_control(n))
    np_ = len(m.parameters)
    p = SeqArg("params", f"tool parameters [{' '.join(s.name for s in m.parameters)}]", np_, 1, False, _sample_tool)
    eqs = ", ".join(m.equations)
    xs, us, ps = dv.x, dv.u, dv.p
    k = dv.coefficients(ps)
    fns = [
        SeqFunction(
            "dynamics",
            "The plant X_dot = f(X, U; p): the arm under joint impedance about q^e with the gravity at "
            "q^e fed forward, M(q) q_ddot + C q_dot + g(q) = U + K (q^e - q) - D q_dot + g(q^e).",
            eqs, [x, u, p], [SeqOutput("x_dot", "X_dot", 2 * n, 1)],
            ca.Function("dynamics", [xs, us, ps], [dv.dynamics_with(xs, us, k)]),
            lambda v: dv.reference_dynamics.checked(v["x"], v["u"], v["params"]),
            coefficients=dv.coefficients, code_with=dv.dynamics_with, unhoisted=dv.dynamics_inline,
        ),
        SeqFunction(
            "dynamics_jacobian",
            "Jacobians (df/dX, df/dU) of the plant at any state and control: -M^-1 [K + dID/dq, "
            "D + dID/dq_dot] at q_ddot = f and M^-1, with ID the inverse dynamics.",
            eqs, [x, u, p], [SeqOutput("f_x", "df/dX", 2 * n, 2 * n), SeqOutput("f_u", "df/dU", 2 * n, n)],
            ca.Function("dynamics_jacobian", [xs, us, ps], dv.jacobian_with(xs, us, k)),
            lambda v: dv.reference_jacobian.checked(v["x"], v["u"], v["params"]),
            coefficients=dv.coefficients, code_with=dv.jacobian_with, unhoisted=dv.jacobian_inline,
        ),
        SeqFunction(
            "state_matrix",
            "A = df/dX at the equilibrium (X^e, U^e): [[O, I], [-M^-1 (dg/dq + K), -M^-1 D]].",
            "eq. (LTI) for the arm under joint impedance", [p], [SeqOutput("a", "A", 2 * n, 2 * n)],
            dv.state_matrix, lambda v: [dv.reference_ab.checked(v["params"])[0]],
        ),
        SeqFunction(
            "input_matrix",
            "B = df/dU at the equilibrium (X^e, U^e): [[O], [M^-1]].",
            "eq. (LTI) for the arm under joint impedance", [p], [SeqOutput("b", "B", 2 * n, n)],
            dv.input_matrix, lambda v: [dv.reference_ab.checked(v["params"])[1]],
        ),
    ]
    ns = dv.task_namespace_sx()
    for task in dv.tasks:
        fns += _task_functions(dv, task, ns, p)
    kr = dv.rigid_coefficients(ps)
    fns.append(SeqFunction(
        "rigid_body_dynamics",
        "The robot's own rigid-body dynamics X_dot = [q_dot; q_ddot], M(q) q_ddot + C(q, q_dot) q_dot + "
        "g(q) = U, with U the joint torques (no impedance, no gravity feed-forward): what Pinocchio's "
        "aba computes for the arm with the tool fixed at its flange.",
        "rigid-body dynamics of the URDF chain (RNEA, CRBA)", [x, u, p], [SeqOutput("x_dot", "X_dot", 2 * n, 1)],
        ca.Function("rigid_body_dynamics", [xs, us, ps], [dv.rigid_with(xs, us, kr)]),
        lambda v: dv.reference_rigid_body.checked(v["x"], v["u"], v["params"]),
        coefficients=dv.rigid_coefficients, code_with=dv.rigid_with, unhoisted=dv.rigid_inline,
    ))
    q = SeqArg("q", f"joint positions q = [{' '.join(s.name for s in m.state[:n])}]", n, 1, False,
               lambda rng: _sample_state(n)(rng)[:n])
    fns.append(SeqFunction(
        "tip",
        f"The tool's tip (tool-centre point) y(q; p) in the base frame '{dv.chain.base}', and its "
        "Jacobian J = dy/dq (geometric: z_i x (y - o_i) per revolute joint, z_i per prismatic one), "
        "what Pinocchio's frame placement and computeFrameJacobian (LOCAL_WORLD_ALIGNED, linear "
        "rows) give for a frame at the tip.",
        "forward kinematics of the URDF chain to the flange, then the tip offset (tool_tip_x/y/z)",
        [q, p], [SeqOutput("position", "y (m, base frame)", 3, 1), SeqOutput("jacobian", "J = dy/dq", 3, n)],
        dv.tip, lambda v: dv.reference_tip.checked(v["q"], v["params"]),
    ))
    q_dot = SeqArg("q_dot", f"joint velocities q_dot = [{' '.join(s.name for s in m.state[n:])}]", n, 1, False,
                   lambda rng: _sample_state(n)(rng)[n:])
    fns.append(SeqFunction(
        "tip_bias",
        "The tip's acceleration at zero joint acceleration, Jdot(q, q_dot) q_dot = d(J q_dot)/dq q_dot "
        "(base frame), so that y_ddot = J(q) q_ddot + tip_bias(q, q_dot): the linear part of Pinocchio's "
        "frame classical acceleration (LOCAL_WORLD_ALIGNED) at q_ddot = 0 for a frame at the tip.",
        "forward kinematics of the URDF chain, differentiated twice in time", [q, q_dot, p],
        [SeqOutput("bias", "Jdot q_dot (m/s^2, base frame)", 3, 1)],
        dv.tip_bias, lambda v: dv.reference_tip_bias.checked(v["q"], v["q_dot"], v["params"]),
    ))
    return fns


def _task_functions(dv: UrdfDerivation, task, ns, p_arg) -> list[SeqFunction]:
    n, ps = dv.n, dv.p
    terms = task.sensitivity_terms
    sens = {t: sensitivity(task, t, ns).sx() for t in terms}
    out = [SeqFunction(
        task.sensitivity_function,
        f"{task.title}: the sensitivities d(task variable)/dU the controller uses, "
        f"in the order ({', '.join('d_' + t + '_du' for t in terms)}).",
        "appendix \"Task specific controllers\"", [p_arg],
        [SeqOutput(f"d_{t}_du", f"d{t}/dU = {task.sensitivity[t]}", n, n) for t in terms],
        ca.Function(task.sensitivity_function, [ps], [ca.cse(ca.sparsify(sens[t])) for t in terms]),
        lambda v, task=task: [dv.reference_sensitivity(task, v["params"])[t] for t in task.sensitivity_terms],
    )]
    inputs = {t: ca.SX.sym(f"p_{t}", n, n) for t in task.precision_terms}
    full = {t: ca.triu(s) + ca.triu(s, False).T for t, s in inputs.items()}
    pi = full[task.control_term]
    for t in terms:
        pi = pi + sens[t].T @ full[t] @ sens[t]
    prec_args = [SeqArg(f"p_{t}", f"precision P of {task.argument_doc(t)} (symmetric; the upper triangle is read)",
                        n, n, True, _sample_precision(n)) for t in task.precision_terms]
    symbols = [inputs[t] for t in task.precision_terms]

    def precisions(v):
        return {t: v[f"p_{t}"] for t in task.precision_terms}

    out.append(SeqFunction(
        task.confidence_function,
        f"{task.title}: the control confidence Pi^U = d2F/dU2 = "
        + " + ".join(f"S_{t}^T P_{t} S_{t}" for t in terms) + " + P_u.",
        "eq. (control_conf) and the closed forms after it", [p_arg] + prec_args,
        [SeqOutput("pi_u", "Pi^U (symmetric)", n, n, symmetric=True)],
        ca.Function(task.confidence_function, [ps] + symbols, [ca.cse(ca.triu(pi))]),
        lambda v, task=task: [dv.reference_confidence(task, v["params"], precisions(v))],
    ))
    entries = [[pi[i, j] for j in range(n)] for i in range(n)]
    gradient = ca.gradient(ldl_logdet(entries), ps)
    out.append(SeqFunction(
        task.gradient_function,
        f"{task.title}: the gradient of the confidence term, d ln|Pi^U| / dp = "
        "tr((Pi^U)^-1 dPi^U/dp_i) for every tool parameter p_i (by reverse-mode AD of "
        "sum ln D_ii, Pi^U = L D L^T), what a tool design search climbs.",
        "eq. (control_conf) differentiated in the tool parameters", [p_arg] + prec_args,
        [SeqOutput("gradient", "d ln|Pi^U| / dp, one entry per tool parameter", len(dv.model.parameters), 1)],
        ca.Function(task.gradient_function, [ps] + symbols, [ca.cse(gradient)]),
        lambda v, task=task: [dv.reference_gradient(task, v["params"], precisions(v))],
    ))
    return out


def _code_values(fn: SeqFunction, v: dict) -> list[np.ndarray]:
    """The code graph's values at `v`, exactly, symmetric outputs mirrored."""
    exact = ExactFunction(fn.code) if "exact" not in fn.stats else fn.stats["exact"]
    fn.stats["exact"] = exact
    values = [o.to_numpy() for o in exact(*[v[a.name] for a in fn.args])]
    for out, value in zip(fn.outputs, values):
        if out.symmetric:
            value[:] = np.triu(value) + np.triu(value, 1).T
    return values


def test_vectors(fn: SeqFunction, count: int) -> list[dict]:
    """`count` random valid inputs and the reference outputs, after checking that the code graph
    gives the same values (both exactly; normwise relative AGREEMENT per output, the gradient
    relative to max(scale, 1) as the Rust test does). A disagreement stops the derivation."""
    rng = fn.rng()
    samples = [{a.name: a.sample(rng) for a in fn.args} for _ in range(count)]
    started = time.perf_counter()
    vectors, worst = [], 0.0
    for k, v in enumerate(samples):
        reference = [r.to_numpy() for r in fn.reference(v)]
        code = _code_values(fn, v)
        for out, got, ref in zip(fn.outputs, code, reference):
            ref = ref.reshape(out.rows, out.cols)
            floor = 1.0 if fn.name.endswith("_logdet_gradient") else 1e-300
            scale = max(float(np.max(np.abs(ref))), floor)
            err = float(np.max(np.abs(got - ref)))
            worst = max(worst, err / scale)
            if not (np.all(np.isfinite(got)) and err <= AGREEMENT * scale):
                raise UrdfMismatch(f"{fn.name}: output {out.name} at sample {k}: the code graph and the reference "
                                   f"disagree (max abs difference {err:.3e}, scale {scale:.3e})")
        vectors.append({
            "inputs": {name: [float(x) for x in np.asarray(val).reshape(-1)] for name, val in v.items()},
            "outputs": {o.name: [float(x) for x in ref.reshape(-1)] for o, ref in zip(fn.outputs, reference)},
        })
    fn.stats["agreement"] = worst
    fn.stats["check_seconds"] = time.perf_counter() - started
    return vectors


def _arg_ir(a: SeqArg, used: bool) -> irt.Arg:
    return irt.Arg(name=a.name, doc=a.doc, rows=a.rows, cols=a.cols, rust_type=_rust_type((a.rows, a.cols)),
                   symmetric=a.symmetric, used=used)


def _body_ir(body: dict) -> dict:
    """sequence.instructions' bindings, trig and sequence as the IR's types."""
    return {"bindings": [irt.Binding(**b) for b in body["bindings"]], "trig": [irt.Trig(**t) for t in body["trig"]],
            "sequence": irt.Sequence(slots=[irt.Slot(**w) for w in body["sequence"]["slots"]],
                                     steps=[irt.Step(**w) for w in body["sequence"]["steps"]])}


def function_ir(fn: SeqFunction) -> irt.Function:
    coefficients, unhoisted = None, None
    if fn.coefficients is not None:
        k_count = fn.coefficients.size1_out(0)
        k_arg = {"name": "coefficients", "rows": k_count, "cols": 1}
        call = [a for a in fn.args if a.name != "params"]
        body = instructions(fn.code_with, [{"name": a.name, "rows": a.rows, "cols": a.cols} for a in call] + [k_arg],
                            [o.name for o in fn.outputs])
        made = instructions(fn.coefficients, [{"name": "params", "rows": fn.coefficients.size1_in(0), "cols": 1}],
                            ["k"], prefix="s")
        # A few hundred operations: one `let` each, the coefficient struct's form.
        temporaries, writes = as_lets(made, prefix="s")
        values = ["0.0"] * k_count
        for w in writes:
            values[int(w["target"][2:-1])] = w["rust"]
        made["temporaries"] = temporaries
        bound = {b["arg"] for b in body["bindings"]}
        struct = _struct_name(fn.name)
        coefficients = irt.Coefficients(
            struct=struct, count=k_count, constants=[], bindings=[irt.Binding(**b) for b in made["bindings"]],
            temporaries=[irt.Let(**t) for t in made["temporaries"]], values=values, cost=irt.Cost(**made["cost"]),
            args=[irt.CoefficientArg(name=a.name, rust_type="&" + _rust_type((a.rows, a.cols)), used=a.name in bound)
                  for a in call] + [irt.CoefficientArg(name="coefficients", rust_type="&" + struct,
                                                       used="coefficients" in bound)],
        )
        unhoisted = instruction_count(fn.unhoisted)
        args = [_arg_ir(a, a.name in bound or a.name == "params") for a in fn.args]
    else:
        body = instructions(fn.code, [{"name": a.name, "rows": a.rows, "cols": a.cols} for a in fn.args],
                            [o.name for o in fn.outputs])
        bound = {b["arg"] for b in body["bindings"]}
        args = [_arg_ir(a, a.name in bound) for a in fn.args]
    outputs = []
    for out, entries in zip(fn.outputs, body["outputs"]):
        outputs.append(irt.Output(name=out.name, doc=out.doc, rows=out.rows, cols=out.cols,
                                  rust_type=_rust_type((out.rows, out.cols)), symmetric=out.symmetric,
                                  entries=[irt.Entry(**e) for e in sorted(entries, key=lambda e: (e["row"], e["col"]))]))
    fn.stats["cost"] = body["cost"]
    if coefficients:
        fn.stats["coefficient_cost"] = made["cost"]
        fn.stats["unhoisted_cost"] = unhoisted
    code = _body_ir(body)
    return irt.Function(
        name=fn.name, doc=fn.doc, equation=fn.equation, args=args, coefficients=coefficients,
        cost=irt.Cost(**body["cost"]), unhoisted_cost=None if unhoisted is None else irt.Cost(**unhoisted),
        outputs=outputs, constants=[], bindings=code["bindings"], trig=code["trig"], compounds=[], temporaries=[],
        sequence=code["sequence"],
    )


def vectors_document(model: Model, functions: list[SeqFunction], generator: irt.Generator, count: int,
                     schema: int, jobs: int = 1) -> dict:
    return {
        "schema": schema,
        "generator": generator,
        "model": model.name,
        "tolerance": "max|rust - casadi| <= 1e-12 max|casadi| per output (the generated crate's tests/vectors.rs)",
        "functions": [{"name": fn.name, "vectors": v} for fn, v in zip(functions, all_vectors(functions, count, jobs))],
    }


# The functions the forked workers of all_vectors check (inherited from the parent at the fork:
# their graphs and reference closures are not picklable, and need not be).
_FORKED: list[SeqFunction] = []


def _forked_vectors(job: tuple[int, int]) -> tuple[list[dict], float, float]:
    fn = _FORKED[job[0]]
    vectors = test_vectors(fn, job[1])
    return vectors, fn.stats["agreement"], fn.stats["check_seconds"]


def all_vectors(functions: list[SeqFunction], count: int, jobs: int) -> list[list[dict]]:
    """test_vectors of every function, on `jobs` forked processes where more than one is asked
    for (make model, one model on every core; make derive runs models side by side instead). Each
    function draws its samples from its own seeded generator and its check is the same whichever
    process runs it, so the vectors and the IR are the same bytes; results come back in order."""
    jobs = min(jobs, len(functions))
    out = []
    for fn, vectors in zip(functions, _vectors_in_order(functions, count, jobs)):
        progress.step("checking", f"{fn.name}: code graph = reference graph (50 digits) at {count} points")
        out.append(vectors)
    return out


def _vectors_in_order(functions: list[SeqFunction], count: int, jobs: int):
    """Each function's test vectors as it is checked: here, or on `jobs` forked processes, their
    stats copied back."""
    if jobs <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        yield from (test_vectors(fn, count) for fn in functions)
        return
    global _FORKED
    _FORKED = functions
    try:
        with multiprocessing.get_context("fork").Pool(jobs) as pool:
            results = pool.imap(_forked_vectors, [(i, count) for i in range(len(functions))])
            for fn, (vectors, worst, seconds) in zip(functions, results):
                fn.stats["agreement"], fn.stats["check_seconds"] = worst, seconds
                yield vectors
    finally:
        _FORKED = []


# |f(X^e, U^e)| (rad/s^2) accepted as zero: the reference graph's rounding of its folded constants.
EQUILIBRIUM_RESIDUAL = 1e-12
# Tools at which the report states the linearisation and the confidence: a light probe, a
# hammer-like tool, a heavy drill off the flange axis (mass, centre of mass, box sides in m).
REPORT_TOOLS = [
    ("probe", 0.1, (0.0, 0.0, 0.08), (0.02, 0.02, 0.16)),
    ("hammer", 0.8, (0.0, 0.0, 0.12), (0.04, 0.10, 0.30)),
    ("drill", 2.0, (0.04, 0.0, 0.10), (0.08, 0.20, 0.22)),
]


def report_tool(mass: float, com, sides) -> np.ndarray:
    from fractions import Fraction
    m = Fraction(mass)
    a, b, c = (Fraction(s) for s in sides)
    moments = [m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12]
    # A box in flange axes (no products), its tip at the far end of its z side.
    return np.array([mass, *com, *(float(x) for x in moments), 0.0, 0.0, 0.0, 0.0, 0.0, float(c)])


def singular_joints(dv: UrdfDerivation, p: np.ndarray, name: str) -> None:
    """A is singular exactly when dg/dq + K is: refuse naming the joints of its null space."""
    import mpmath
    a, b = dv.reference_ab(p)
    n = dv.n
    with mpmath.workdps(50):
        m_inv = mpmath.matrix([[b.m[n + i, j] for j in range(n)] for i in range(n)])
        a21 = mpmath.matrix([[a.m[n + i, j] for j in range(n)] for i in range(n)])
        stiff = -(mpmath.inverse(m_inv) * a21)
        values, vectors = mpmath.eigsy((stiff + stiff.T) / 2)
        smallest = min(range(n), key=lambda i: abs(values[i]))
        largest = max(abs(v) for v in values)
        if abs(values[smallest]) <= mpmath.mpf("1e-9") * largest:
            joints = [dv.chain.joint_names[i] for i in range(n) if abs(vectors[i, smallest]) > 0.1]
            raise DescriptionError(dv.model.path, "impedance.stiffness",
                                   f"A is singular at the equilibrium for the {name} tool: dg/dq + K has a zero "
                                   f"eigenvalue along joints {', '.join(joints)}; give them stiffness")


def report_data(dv: UrdfDerivation, functions: list[SeqFunction]) -> irt.UrdfReport:
    import mpmath
    n, m = dv.n, dv.model
    fmt = lambda v: mpmath.nstr(mpmath.mpf(v), 6)  # noqa: E731
    tools = []
    for name, mass, com, sides in REPORT_TOOLS:
        p = report_tool(mass, com, sides)
        a, b = dv.reference_ab(p)
        with mpmath.workdps(50):
            m_inv = mpmath.matrix([[b.m[n + i, j] for j in range(n)] for i in range(n)])
            mass_e = mpmath.inverse(m_inv)
            a21 = mpmath.matrix([[a.m[n + i, j] for j in range(n)] for i in range(n)])
            stiff = -(mass_e * a21)
            g_q = stiff - mpmath.diag(dv.stiffness)
            sv_g = sorted(mpmath.svd_r(g_q, compute_uv=False), reverse=True)
            sv_s = sorted(mpmath.svd_r(stiff, compute_uv=False), reverse=True)
            logdets = []
            for task in dv.tasks:
                eye = np.eye(n)
                precision = {t: task.default_precision[t] * eye for t in task.terms}
                pi = dv.reference_confidence(task, p, precision)
                logdets.append(irt.Logdet(task=task.name, value=fmt(mpmath.log(mpmath.det(pi.m)))))
        tools.append(irt.ReportTool(
            name=name, parameters=", ".join(f"{q.name} = {fmt(v)}" for q, v in zip(m.parameters, p)),
            gravity_sv=", ".join(fmt(v) for v in sv_g), stiffness_sv=", ".join(fmt(v) for v in sv_s),
            logdets=logdets))
    bodies = [irt.Body(joint=b.joint, kind=b.kind, axis=" ".join(f"{v:g}" for v in b.axis),
                       mass=f"{b.mass:g}", stiffness=f"{k:g}", damping=f"{d:g}")
              for b, k, d in zip(dv.chain.bodies, dv.stiffness, dv.damping)]
    costs = []
    for fn in functions:
        c = fn.stats["cost"]
        hoisted = "coefficient_cost" in fn.stats
        costs.append(irt.CostRow(
            name=fn.name, ops=c["ops"], weighted=c["weighted"], sin_cos=c["sin_cos"],
            agreement=f"{fn.stats['agreement']:.1e}",
            coefficients=fn.stats["coefficient_cost"]["ops"] if hoisted else None,
            unhoisted=fn.stats["unhoisted_cost"]["ops"] if hoisted else None))
    return irt.UrdfReport(
        urdf=str(dv.chain.path), robot=dv.chain.robot, base=dv.chain.base, flange=dv.chain.flange,
        gravity=", ".join(f"{g:g}" for g in dv.dyn.gravity), impedance_source=m.impedance_source,
        equilibrium=", ".join(m.equilibrium_q), bodies=bodies, tools=tools, costs=costs,
        equation_refs=m.equations,
    )


def not_an_equilibrium(chain, residual) -> str:
    """Why f(X^e, U^e) is not zero, in one line: the joints with the largest residual q_ddot, and
    the likely cause. The plant feeds the gravity at q^e forward (tau = ... + g(q^e)) and q_dot^e
    = U^e = 0 are checked, so a residual means the code's g(q^e) (RNEA) and the reference's (the
    gradient of the potential) disagree: a rotation of the chain that is not orthonormal makes
    them differ (urdf.py refuses one, this names it should one get through), otherwise numbers
    so far apart that their rounding shows."""
    n = chain.dof
    acc = [abs(float(v)) for v in residual[n:2 * n]]
    top = max(acc)
    worst = sorted((i for i in range(n) if acc[i] >= top / 10), key=lambda i: -acc[i])[:3]
    unit = ["rad/s^2" if b.kind == "revolute" else "m/s^2" for b in chain.bodies]
    joints = ", ".join(f"'{chain.joint_names[i]}' {acc[i]:.2e} {unit[i]}" for i in worst)
    with mpmath.workdps(DIGITS):
        rotations = [(f"joint '{b.joint}' origin", b.rotation) for b in chain.bodies]
        rotations.append((f"flange '{chain.flange}'", chain.flange_rotation))
        where, deviation = max(((w, orthonormal_deviation(mpmath.matrix([list(r) for r in rot])))
                                for w, rot in rotations), key=lambda t: t[1])
        shown = mpmath.nstr(deviation, 3)
    if deviation > ORTHONORMAL:
        cause = (f"likely cause: the rotation of {where} is not orthonormal (|R^T R - I| = {shown}) in "
                 f"{chain.path.name}")
    else:
        cause = (f"rotations orthonormal (|R^T R - I| <= {shown}), gravity fed forward: the code's g(q^e) (RNEA) "
                 f"and the reference's disagree; look for numbers far off an arm's scale in {chain.path.name}")
    return (f"not an equilibrium: |f(X^e, U^e)| = {top:.2e} > {EQUILIBRIUM_RESIDUAL:g}, largest at joint {joints}; "
            f"{cause}")


def urdf_documents(model: Model, tasks, generator: irt.Generator, vectors: int, schema: int,
                   jobs: int = 1) -> tuple[irt.Ir, dict]:
    """The IR and the test vectors of a URDF model, its functions checked on `jobs` processes."""
    tasks = model_tasks(model, tasks)
    dv = UrdfDerivation(model, model.chain, tasks)
    residual = dv.reference_dynamics(dv.x_e, dv.u_e, report_tool(*REPORT_TOOLS[1][1:]))[0].to_numpy()
    # Not exactly zero: the graphs' constants were folded in double while they were built.
    if not float(np.max(np.abs(residual))) <= EQUILIBRIUM_RESIDUAL:
        raise DescriptionError(model.path, "equilibrium", not_an_equilibrium(model.chain, residual.ravel()))
    progress.step("deriving", f"chain of {model.dof} joints: RNEA, CRBA and ABA graphs, equilibrium")
    for name, mass, com, sides in REPORT_TOOLS:
        singular_joints(dv, report_tool(mass, com, sides), name)
    functions = build_functions(dv)
    progress.step("deriving", f"{len(functions)} function graphs")
    document = vectors_document(model, functions, generator, vectors, schema, jobs)
    irs = [function_ir(fn) for fn in functions]
    # Each is an instruction sequence of its graph already: milliseconds, one line for all.
    progress.step("deriving", f"code of the {len(irs)} functions (instruction sequences of their graphs)")
    x_e = [float_literal(v) for v in dv.x_e]
    u_e = [float_literal(v) for v in dv.u_e]
    ir = model_document(model, x_e, u_e, tasks, irs, generator, report_data(dv, functions), vectors,
                        templates=["urdf/report.md.tera"])
    return ir, document
