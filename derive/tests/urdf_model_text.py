"""The head of a URDF model file as the derivation tests write it: the `[model]`, `[dynamics]`
and `[urdf]` tables (up to the gravity), to which each test adds its own impedance, equilibrium
and whatever it checks."""


def urdf_model_head(file: str, name: str = "three", dof: int = 3, base: str = "base",
                    flange: str = "flange") -> str:
    """The model `name` with `dof` joints from the URDF `file`, its chain from link `base` to link
    `flange`, under Earth's gravity along −z."""
    return f"""
[model]
name = "{name}"
dof = {dof}
[dynamics]
kind = "urdf"
[urdf]
file = "{file}"
base = "{base}"
flange = "{flange}"
gravity = [0.0, 0.0, -9.81]
"""
