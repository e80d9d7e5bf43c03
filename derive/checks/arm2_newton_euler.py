#!/usr/bin/env python3
"""Re-derives the paper's eq. (DE_theta_2) from its own force and moment balances (appendix
"Tool Dynamics": eqs. link1_moment, link2_force, acc_ang_lin) and prints what differs from the
printed equation. See docs/explanation/paper-notes.md, section 4.

    derive/.venv/bin/python derive/checks/arm2_newton_euler.py
"""

import sympy as sp

t = sp.symbols("t")
m1, m2, l1, l2, g, T1, T2 = sp.symbols("m1 m2 l1 l2 g T1 T2", positive=True)
th1, th2 = sp.Function("theta1")(t), sp.Function("theta2")(t)

# Centre of link 2 and, from eq. (link2_force), the joint-B reaction forces.
x2 = l1 * sp.cos(th1) + l2 / 2 * sp.cos(th2)
y2 = l1 * sp.sin(th1) + l2 / 2 * sp.sin(th2)
H_B = m2 * sp.diff(x2, t, 2)
V_B = m2 * (sp.diff(y2, t, 2) + g)

# Eq. (link1_moment), moved to one side.
balance = sp.Rational(1, 3) * m1 * l1**2 * sp.diff(th1, t, 2) - (
    T1 - T2 + H_B * l1 * sp.sin(th1) - V_B * l1 * sp.cos(th1) - m1 * g * l1 * sp.cos(th1) / 2
)
# Eq. (DE_theta_2) as printed.
printed = (
    (m1 / 3 + m2) * l1**2 * sp.diff(th1, t, 2)
    + m2 * l1 * l2 / 2 * sp.diff(th2, t, 2) * sp.cos(th1 - th2)
    + m2 * l1**2 * sp.diff(th1, t) ** 2 * sp.sin(th1 - th2)
    + m2 * l1 * l2 / 2 * sp.diff(th2, t) ** 2 * sp.sin(th1 - th2)
    + T2 - T1 + (m1 / 2 + m2) * g * l1 * sp.cos(th1)
)
difference = sp.simplify(sp.expand_trig(balance - printed))
print("balances - printed eq. (DE_theta_2) =", difference)
