"""Planar chains of uniform rods (n-link arms) by Lagrangian mechanics.

Conventions follow the paper's 2-DOF arm: each angle theta_i is the *absolute* angle of link i
from the horizontal, gravity points along -y, and joint torque U_i acts between link i-1 (or the
base) and link i, so the generalised force on theta_i is Q_i = U_i - U_{i+1}.

Only the geometry (where each rod's centre is) is written once, generic over the backend's sin
and cos. The calculus is done twice, independently: SymPy differentiates symbolically here
(`sympy_chain`), CasADi by algorithmic differentiation (`casadi_chain`), and the derivation
compares the two at random points like every other function.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Link:
    mass: str
    length: str


def centres(q, lengths, sin, cos):
    """Positions (x, y) of the rods' centres of mass for absolute angles q."""
    out, x, y = [], 0, 0
    for theta, l in zip(q, lengths):
        out.append((x + l / 2 * cos(theta), y + l / 2 * sin(theta)))
        x, y = x + l * cos(theta), y + l * sin(theta)
    return out


def tip(q, lengths, sin, cos):
    """Position (x, y) of the chain's free end, where a payload is held."""
    return sum(l * cos(theta) for theta, l in zip(q, lengths)), sum(l * sin(theta) for theta, l in zip(q, lengths))


def generalised_forces(u):
    """Q_i = U_i - U_{i+1}: joint torque i acts on link i and, in reaction, on link i-1."""
    n = len(u)
    return [u[i] - (u[i + 1] if i + 1 < n else 0) for i in range(n)]


def sympy_chain(q, q_dot, u, masses, lengths, g, payload=None):
    """Returns (q_ddot, T, V, M, Q) with q_ddot = M^-1 (Q - C(q, q_dot) q_dot - dV/dq), by SymPy.
    `payload`, if given, is the mass of a point load held at the tip."""
    import sympy as sp

    qv, qdv = sp.Matrix(q), sp.Matrix(q_dot)
    kinetic, potential = 0, 0
    for (xc, yc), m, l, qd in zip(centres(q, lengths, sp.sin, sp.cos), masses, lengths, q_dot):
        v = sp.Matrix([xc, yc]).jacobian(qv) * qdv
        kinetic += m * (v[0] ** 2 + v[1] ** 2) / 2 + (m * l**2 / 12) * qd**2 / 2
        potential += m * g * yc
    if payload is not None:
        xt, yt = tip(q, lengths, sp.sin, sp.cos)
        v = sp.Matrix([xt, yt]).jacobian(qv) * qdv
        kinetic += payload * (v[0] ** 2 + v[1] ** 2) / 2
        potential += payload * g * yt
    kinetic = sp.simplify(sp.expand(kinetic))
    mass = sp.hessian(kinetic, qdv).applyfunc(sp.simplify)
    momentum = mass * qdv
    bias = momentum.jacobian(qv) * qdv - sp.Matrix([kinetic]).jacobian(qv).T + sp.Matrix([potential]).jacobian(qv).T
    forces = sp.Matrix(generalised_forces(u))
    # Solve with the adjugate: one shared determinant, which CSE keeps once in the code.
    det = sp.factor(mass.det())
    q_ddot = (mass.adjugate() * (forces - bias.applyfunc(sp.simplify))) / det
    return q_ddot, kinetic, potential, mass, forces


def casadi_chain(q, q_dot, u, masses, lengths, g, payload=None):
    """Returns q_ddot as CasADi expressions, differentiating the same Lagrangian by AD."""
    import casadi as ca

    qv, qdv = ca.vertcat(*q), ca.vertcat(*q_dot)
    kinetic, potential = 0, 0
    for (xc, yc), m, l, qd in zip(centres(q, lengths, ca.sin, ca.cos), masses, lengths, q_dot):
        v = ca.jacobian(ca.vertcat(xc, yc), qv) @ qdv
        kinetic += m * ca.sumsqr(v) / 2 + (m * l**2 / 12) * qd**2 / 2
        potential += m * g * yc
    if payload is not None:
        xt, yt = tip(q, lengths, ca.sin, ca.cos)
        v = ca.jacobian(ca.vertcat(xt, yt), qv) @ qdv
        kinetic += payload * ca.sumsqr(v) / 2
        potential += payload * g * yt
    mass, _ = ca.hessian(kinetic, qdv)
    bias = ca.jacobian(mass @ qdv, qv) @ qdv - ca.gradient(kinetic, qv) + ca.gradient(potential, qv)
    forces = ca.vertcat(*generalised_forces(u))
    solution = ca.solve(mass, forces - bias)
    return [solution[i] for i in range(len(q))]
