"""The tip of a tool: where a hammer held by the Panda puts its tip, and how the tip moves with
the joints.

    python examples/python/tip.py

``toolconf.tip(model, params, q)`` gives the tip's position y(q) in the robot's base frame and
its Jacobian J = dy/dq (3 x 7 for the Panda); with the joint velocities, also J̇ q̇, so that the
tip's velocity is J q̇ and its acceleration J q̈ + J̇ q̇.
"""

import numpy as np

import toolconf

# A hammer at the flange, in the order of toolconf.models()["panda"]["parameters"]: mass [kg],
# centre of mass [m], moments and products of inertia [kg m²], and its tip [m], in the flange
# frame (toolconf.tool_from_urdf reads these from a tool's own URDF).
HAMMER = [1.384, -0.0037, 0.0037, 0.1675, 0.0357, 0.0361, 0.0022,
          7.7e-4, -7.1e-4, 7.1e-4, 0.055, 0.0, 0.3684]


def main():
    q = np.array(toolconf.models()["panda"]["equilibrium"]["q"])
    here = toolconf.tip("panda", HAMMER, q)
    print("q [rad]:      ", " ".join(f"{v:+.4f}" for v in q))
    print("tip y(q) [m]: ", " ".join(f"{v:+.6f}" for v in here["position"]))
    print("J = dy/dq [m/rad]:")
    for row in here["jacobian"]:
        print("  ", " ".join(f"{v:+.4f}" for v in row))

    # Turn every joint by 1 mrad: the tip moves by J dq, to first order.
    dq = np.full(7, 1e-3)
    moved = toolconf.tip("panda", HAMMER, q + dq)["position"] - here["position"]
    print("moved [mm]:   ", " ".join(f"{v:+.4f}" for v in 1e3 * moved))
    print("J dq [mm]:    ", " ".join(f"{v:+.4f}" for v in 1e3 * here["jacobian"] @ dq))

    # Many configurations in one call (one row each): the first joint swept over a half turn.
    sweep = np.tile(q, (5, 1))
    sweep[:, 0] = np.linspace(-np.pi / 2, np.pi / 2, 5)
    for q0, y in zip(sweep[:, 0], toolconf.tip("panda", HAMMER, sweep)["position"]):
        print(f"q1 = {q0:+.3f} rad: tip at", " ".join(f"{v:+.4f}" for v in y))


if __name__ == "__main__":
    main()
