"""Rigid-body dynamics of a serial chain (urdf.UrdfChain) on CasADi SX: inverse dynamics by the
recursive Newton-Euler algorithm (RNEA), the joint-space inertia M(q) by the composite-rigid-body
algorithm (CRBA), an LDL^T solve for the accelerations, and, independently, the articulated-body
algorithm (ABA, Featherstone 2008, ch. 7) in 6-D spatial algebra.

Why our own and not SymPy: expanding M(q) of a spatial chain symbolically takes 88 s for 5 joints
and does not finish for 6 (docs/explanation/derivation.md); the recursive algorithms on SX stay linear (RNEA, ABA)
or quadratic (CRBA) in the joints, and CasADi's expression graph is already single assignment.

Conventions. Body i's frame is joint i's frame (URDF: the joint's origin in the parent link, then
the joint's motion about/along its axis). Every vector of body i is in body i's coordinates.
Inertia in barycentric form about the body frame's origin: mass m, first moment h = m c and
rotational inertia I_o = I_c + m (|c|^2 1 - c c^T); it enters the equations linearly, which is
why the tool's seven parameters reach the dynamics only through the last body's ten numbers
(`last` below). The trigonometry of each revolute joint comes in as (sin q_i, cos q_i): SX
sin/cos nodes for symbolic joint angles, or exactly computed numbers at a fixed pose, so that no
libm result is ever folded into a constant.
"""

from __future__ import annotations

import casadi as ca

from .urdf import UrdfChain


def _zero(x) -> bool:
    return isinstance(x, float) and x == 0.0


def _dot(a, b):
    """a . b, skipping exact zero and unit float factors (SX would fold most of them, this
    keeps the graph free of them whatever CasADi does)."""
    total = 0.0
    for x, y in zip(a, b):
        term = _product(x, y)
        if _zero(term):
            continue
        total = term if _zero(total) else total + term
    return total


def _product(x, y):
    if _zero(x) or _zero(y):
        return 0.0
    if isinstance(x, float) and abs(x) == 1.0:
        return y if x > 0 else -y
    if isinstance(y, float) and abs(y) == 1.0:
        return x if y > 0 else -x
    return x * y


def _difference(x, y):
    """x - y without zero terms."""
    if _zero(y):
        return x
    if _zero(x):
        return -y
    return x - y


def _cross(a, b):
    return [_difference(_product(a[1], b[2]), _product(a[2], b[1])),
            _difference(_product(a[2], b[0]), _product(a[0], b[2])),
            _difference(_product(a[0], b[1]), _product(a[1], b[0]))]


def _add(*vs):
    out = []
    for parts in zip(*vs):
        live = [p for p in parts if not _zero(p)]
        total = 0.0
        for p in live:
            total = p if (isinstance(total, float) and total == 0.0) else total + p
        out.append(total)
    return out


def _scale(k, v):
    if _zero(k):
        return [0.0, 0.0, 0.0]
    return [0.0 if _zero(x) else k * x for x in v]


def _neg(v):
    return [0.0 if _zero(x) else -x for x in v]


def _matvec(m, v):
    return [_dot(row, v) for row in m]


def _mat_t_vec(m, v):
    return [_dot([m[0][j], m[1][j], m[2][j]], v) for j in range(3)]


class Joint:
    """The motion of one joint: parent-to-child coordinate changes for a given (sin, cos) or
    displacement."""

    def __init__(self, body, q, trig):
        self.body, self.q = body, q
        self.kind = body.kind
        self.axis = list(body.axis)
        self.r0 = [list(r) for r in body.rotation]
        self.s, self.c = trig if trig is not None else (None, None)
        self.p = list(body.translation)
        if self.kind == "prismatic":
            self.p = _add(self.p, _scale(q, _matvec(self.r0, self.axis)))
        self._coordinate = next((k for k in range(3) if abs(self.axis[k]) == 1.0), None)

    def _rot(self, v, transpose: bool):
        """Rot(axis, q) v (or its transpose), exact for coordinate axes, Rodrigues otherwise."""
        if self.kind == "prismatic":
            return v
        k = self._coordinate
        if k is not None:
            # About +-e_k by q: (v_i, v_j) turns by sigma q, sigma the axis' sign (negated for
            # the transpose); v_k stays.
            sigma = self.axis[k] * (-1.0 if transpose else 1.0)
            i, j = (k + 1) % 3, (k + 2) % 3
            cv_i, cv_j = _product(self.c, v[i]), _product(self.c, v[j])
            sv_i, sv_j = _product(self.s, v[i]), _product(self.s, v[j])
            out = [0.0, 0.0, 0.0]
            out[k] = v[k]
            if sigma > 0:
                out[i], out[j] = _difference(cv_i, sv_j), _add([sv_i], [cv_j])[0]
            else:
                out[i], out[j] = _add([cv_i], [sv_j])[0], _difference(cv_j, sv_i)
            return out
        a = self.axis
        s = -self.s if transpose else self.s
        along = _dot(a, v)
        return _add(_scale(self.c, v), _scale(s, _cross(a, v)), _scale((1 - self.c) * along, a))

    def to_child(self, v):
        """A parent-frame vector in the child's coordinates: Rot^T R0^T v."""
        return self._rot(_mat_t_vec(self.r0, v), transpose=True)

    def to_parent(self, v):
        """A child-frame vector in the parent's coordinates: R0 Rot v."""
        return _matvec(self.r0, self._rot(v, transpose=False))


def barycentric(m, h, inertia):
    """The 10 numbers [m, hx, hy, hz, Ixx, Iyy, Izz, Ixy, Ixz, Iyz] of one body."""
    return [m, *h, inertia[0][0], inertia[1][1], inertia[2][2], inertia[0][1], inertia[0][2], inertia[1][2]]


def _unpack(params):
    m, hx, hy, hz, ixx, iyy, izz, ixy, ixz, iyz = params
    return m, [hx, hy, hz], [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]


class ChainDynamics:
    """The chain's rigid-body algorithms; `last` (10 barycentric numbers, SX or float) replaces
    the last body's own inertia, so that a tool can be added to it."""

    def __init__(self, chain: UrdfChain, gravity: list[float]):
        self.chain = chain
        self.n = chain.dof
        self.gravity = [float(g) for g in gravity]

    def link_parameters(self, i: int) -> list[float]:
        b = self.chain.bodies[i]
        return barycentric(b.mass, list(b.first_moment), [list(r) for r in b.inertia])

    def tool_parameters(self, tool) -> list:
        """The last body's 10 numbers with a tool fixed at the flange: tool = [mass, com_x,
        com_y, com_z (flange frame), ixx, iyy, izz, ixy, ixz, iyz (the inertia tensor about the
        CoM in flange axes, URDF's convention: the products are its off-diagonal entries)]."""
        m, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz = tool
        rf = [list(r) for r in self.chain.flange_rotation]
        pf = list(self.chain.flange_translation)
        c = _add(_matvec(rf, [cx, cy, cz]), pf)
        # R I R^T about the CoM (a structural zero product adds nothing), then the parallel-axis
        # shift to the body origin.
        tensor = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]
        rotated = [[_dot(rf[i], [tensor[k][l] for k in range(3)]) for l in range(3)] for i in range(3)]
        about_com = [[_dot(rotated[i], rf[j]) for j in range(3)] for i in range(3)]
        cc = _dot(c, c)
        about_origin = [[_add([about_com[i][j]], [_product(m, _difference(cc if i == j else 0.0, _product(c[i], c[j])))])[0]
                         for j in range(3)] for i in range(3)]
        tool_bary = barycentric(m, _scale(m, c), about_origin)
        return [a + b for a, b in zip(self.link_parameters(self.n - 1), tool_bary)]

    def _inertia(self, i, last):
        return _unpack(last if i == self.n - 1 else self.link_parameters(i))

    def joints(self, q, trig):
        return [Joint(b, q[i], trig[i] if b.kind == "revolute" else None) for i, b in enumerate(self.chain.bodies)]

    def rnea(self, q, trig, qd, qdd, last, gravity: bool = True):
        """Inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q) (classical Newton-Euler; the base's
        acceleration is -gravity, which gives every body its weight)."""
        joints = self.joints(q, trig)
        w, dw = [0.0] * 3, [0.0] * 3
        dv = _neg(self.gravity) if gravity else [0.0] * 3
        forces = []
        for i, j in enumerate(joints):
            a = j.axis
            dv = j.to_child(_add(dv, _cross(dw, j.p), _cross(w, _cross(w, j.p))))
            w_in, dw_in = j.to_child(w), j.to_child(dw)
            if j.kind == "revolute":
                w = _add(w_in, _scale(qd[i], a))
                dw = _add(dw_in, _cross(w_in, _scale(qd[i], a)), _scale(qdd[i], a))
            else:
                w, dw = w_in, dw_in
                dv = _add(dv, _scale(2.0, _cross(w, _scale(qd[i], a))), _scale(qdd[i], a))
            m, h, inertia = self._inertia(i, last)
            f = _add(_scale(m, dv), _cross(dw, h), _cross(w, _cross(w, h)))
            n = _add(_matvec(inertia, dw), _cross(w, _matvec(inertia, w)), _cross(h, dv))
            forces.append((f, n))
        tau = [None] * self.n
        f_child, n_child = None, None
        for i in range(self.n - 1, -1, -1):
            f, n = forces[i]
            if f_child is not None:
                child = joints[i + 1]
                fc = child.to_parent(f_child)
                f = _add(f, fc)
                n = _add(n, child.to_parent(n_child), _cross(child.p, fc))
            tau[i] = _dot(joints[i].axis, n if joints[i].kind == "revolute" else f)
            f_child, n_child = f, n
        return tau

    def mass_matrix(self, q, trig, last):
        """M(q) by the composite-rigid-body algorithm: the composite inertia of each subtree, the
        force it needs for a unit acceleration of its joint, carried down to the base."""
        joints = self.joints(q, trig)
        comp = [self._inertia(i, last) for i in range(self.n)]
        for i in range(self.n - 1, 0, -1):
            m, h, inertia = comp[i]
            j = joints[i]
            hr = j.to_parent(h)
            rotated = _rotate_inertia(inertia, j.to_parent)
            p = j.p
            pm, ph, pi = comp[i - 1]
            shift = _sym_add(_sym_add(_neg_outer_cross(hr, p), _neg_outer_cross(p, hr)),
                             _scale_m(m, _neg_outer_cross(p, p)))
            comp[i - 1] = (pm + m, _add(ph, hr, _scale(m, p)), _sym_add(pi, _sym_add(rotated, shift)))
        mm = [[None] * self.n for _ in range(self.n)]
        for i in range(self.n):
            m, h, inertia = comp[i]
            a = joints[i].axis
            if joints[i].kind == "revolute":
                f, n = _cross(a, h), _matvec(inertia, a)
            else:
                f, n = _scale(m, a), _cross(h, a)
            mm[i][i] = _dot(a, n if joints[i].kind == "revolute" else f)
            for k in range(i - 1, -1, -1):
                child = joints[k + 1]
                f = child.to_parent(f)
                n = _add(child.to_parent(n), _cross(child.p, f))
                mm[k][i] = mm[i][k] = _dot(joints[k].axis, n if joints[k].kind == "revolute" else f)
        return mm


def _outer_cross(a, b):
    """[a]x [b]x as a 3x3 matrix."""
    def cx(v):
        return [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
    ca_, cb = cx(a), cx(b)
    return [[_dot(ca_[i], [cb[0][j], cb[1][j], cb[2][j]]) for j in range(3)] for i in range(3)]


def _neg_outer_cross(a, b):
    return [[0.0 if _zero(x) else -x for x in row] for row in _outer_cross(a, b)]


def _sym_add(a, b):
    return [_add(ra, rb) for ra, rb in zip(a, b)]


def _scale_m(k, m):
    return [_scale(k, row) for row in m]


def _rotate_inertia(inertia, to_parent):
    """R I R^T for symmetric I, with R applied as `to_parent`."""
    columns = [to_parent([inertia[0][j], inertia[1][j], inertia[2][j]]) for j in range(3)]
    ri = [[columns[j][i] for j in range(3)] for i in range(3)]      # R I
    rows = [to_parent(ri[i]) for i in range(3)]                      # R (R I)^T = (R I R^T)^T
    return [[rows[j][i] if j >= i else rows[i][j] for j in range(3)] for i in range(3)]


def ldl_factor(m):
    """M = L D L^T for symmetric positive definite M, unrolled (no pivoting: M's leading minors
    are positive): (L, 1/D), the reciprocals taken once for every right-hand side."""
    n = len(m)
    lower = [[0.0] * n for _ in range(n)]
    d, inv_d = [None] * n, [None] * n
    for j in range(n):
        ld = [_product(lower[j][k], d[k]) for k in range(j)]
        d[j] = _difference(m[j][j], _dot(ld, [lower[j][k] for k in range(j)]))
        inv_d[j] = 1.0 / d[j]
        for i in range(j + 1, n):
            lower[i][j] = _product(_difference(m[i][j], _dot([lower[i][k] for k in range(j)], ld)), inv_d[j])
    return lower, inv_d


def ldl_apply(factor, b):
    """M^-1 b from ldl_factor's (L, 1/D): forward substitution, scaling, back substitution."""
    lower, inv_d = factor
    n = len(inv_d)
    z = list(b)
    for i in range(1, n):
        z[i] = _difference(z[i], _dot(lower[i][:i], z[:i]))
    y = [_product(z[i], inv_d[i]) for i in range(n)]
    for i in range(n - 2, -1, -1):
        y[i] = _difference(y[i], _dot([lower[k][i] for k in range(i + 1, n)], y[i + 1:]))
    return y


def ldl_logdet(m):
    """ln det M = sum ln D_ii of M = L D L^T (M symmetric positive definite)."""
    n = len(m)
    lower = [[0.0] * n for _ in range(n)]
    d = [None] * n
    for j in range(n):
        ld = [lower[j][k] * d[k] for k in range(j)]
        d[j] = m[j][j] - _dot(ld, [lower[j][k] for k in range(j)]) if j else m[j][j]
        for i in range(j + 1, n):
            num = m[i][j] - _dot([lower[i][k] for k in range(j)], ld) if j else m[i][j]
            lower[i][j] = num / d[j]
    total = ca.log(d[0])
    for j in range(1, n):
        total = total + ca.log(d[j])
    return total


def aba(dyn: ChainDynamics, q, trig, qd, tau, last):
    """Forward dynamics qdd = M^-1 (tau - C qd - g) by the articulated-body algorithm, in 6-D
    spatial algebra ([angular; linear] motion vectors): an independent route to the accelerations
    that CRBA + LDL^T gives."""
    n = dyn.n
    joints = dyn.joints(q, trig)

    def sx(v):
        return ca.vertcat(*[ca.SX(x) if isinstance(x, float) else x for x in v])

    def rotation_t(j):
        # E = (R0 Rot)^T: rows are the child's axes in parent coordinates.
        cols = [j.to_child([1.0 if k == c else 0.0 for k in range(3)]) for c in range(3)]
        return ca.horzcat(*[sx(col) for col in cols])

    def plucker(j):
        e = rotation_t(j)
        px = ca.skew(sx(j.p))
        z = ca.SX.zeros(3, 3)
        return ca.vertcat(ca.horzcat(e, z), ca.horzcat(-e @ px, e))

    def crm(v):
        w, lin = v[:3], v[3:]
        return ca.vertcat(ca.horzcat(ca.skew(w), ca.SX.zeros(3, 3)), ca.horzcat(ca.skew(lin), ca.skew(w)))

    def crf(v):
        return -crm(v).T

    def spatial_inertia(params):
        m, h, inertia = _unpack(params)
        hx = ca.skew(sx(h))
        return ca.vertcat(ca.horzcat(ca.vertcat(*[ca.horzcat(*[ca.SX(x) if isinstance(x, float) else x for x in row])
                                                  for row in inertia]), hx),
                          ca.horzcat(hx.T, m * ca.SX.eye(3)))

    def motion_subspace(j):
        a = sx(j.axis)
        return ca.vertcat(a, ca.SX.zeros(3, 1)) if j.kind == "revolute" else ca.vertcat(ca.SX.zeros(3, 1), a)

    xs, vs, cs, ia, pa, ss = [], [], [], [], [], []
    for i, j in enumerate(joints):
        x = plucker(j)
        s = motion_subspace(j)
        vj = s * qd[i]
        v = (x @ vs[i - 1] + vj) if i else vj
        c = crm(v) @ vj
        inertia = spatial_inertia(last if i == n - 1 else dyn.link_parameters(i))
        xs.append(x), vs.append(v), cs.append(c), ss.append(s)
        ia.append(inertia)
        pa.append(crf(v) @ inertia @ v)
    us, ds, uu = [None] * n, [None] * n, [None] * n
    for i in range(n - 1, -1, -1):
        us[i] = ia[i] @ ss[i]
        ds[i] = (ss[i].T @ us[i])[0]
        uu[i] = tau[i] - (ss[i].T @ pa[i])[0]
        if i:
            ia_ = ia[i] - us[i] @ us[i].T / ds[i]
            pa_ = pa[i] + ia_ @ cs[i] + us[i] * uu[i] / ds[i]
            ia[i - 1] = ia[i - 1] + xs[i].T @ ia_ @ xs[i]
            pa[i - 1] = pa[i - 1] + xs[i].T @ pa_
    a_base = ca.vertcat(ca.SX.zeros(3, 1), sx(_neg(dyn.gravity)))
    qdd, acc = [None] * n, None
    for i in range(n):
        a_in = xs[i] @ (acc if i else a_base) + cs[i]
        qdd[i] = (uu[i] - (us[i].T @ a_in)[0]) / ds[i]
        acc = a_in + ss[i] * qdd[i]
    return qdd
