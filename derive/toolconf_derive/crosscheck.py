"""SymPy against CasADi: every closed form the derivation emits is evaluated at the test-vector
inputs and compared with CasADi's algorithmic-differentiation / numeric result. A disagreement
stops the derivation: generated code is never written from a closed form that failed this."""

from __future__ import annotations

import numpy as np
import sympy as sp

# Normwise relative tolerance per output (max |sympy - casadi| / max |casadi|). Both sides are
# double precision; the closed forms and CasADi's LU solves differ only by rounding.
TOLERANCE = 1e-9


class DerivationMismatch(AssertionError):
    pass


def check_against_casadi(fn, d, samples: list[dict], reference: list[list[np.ndarray]]) -> None:
    symbols, slots = [], []
    for arg in fn.args:
        for s, i, j in arg.reads:
            symbols.append(s)
            slots.append((arg.name, i, j))
    constants = {c: v for c, v in d.constants.items()}
    exprs = [out.value.subs(constants) for out in fn.outputs]
    evaluate = sp.lambdify(symbols, exprs, modules="numpy")
    for k, (v, refs) in enumerate(zip(samples, reference)):
        values = [float(np.asarray(v[name])[i, j]) for name, i, j in slots]
        got = evaluate(*values)
        for out, g, ref in zip(fn.outputs, got, refs):
            g = np.asarray(g, dtype=float).reshape(out.value.shape)
            ref = ref.reshape(out.value.shape)
            scale = np.max(np.abs(ref))
            err = np.max(np.abs(g - ref))
            if not np.all(np.isfinite(g)) or err > TOLERANCE * max(scale, 1e-300) and err > 1e-14:
                raise DerivationMismatch(
                    f"{fn.name}: output {out.name} at sample {k}: SymPy and CasADi disagree "
                    f"(max abs difference {err:.3e}, scale {scale:.3e})\n"
                    f"inputs: { {n: np.asarray(x).tolist() for n, x in v.items()} }\n"
                    f"sympy: {g.tolist()}\ncasadi: {ref.tolist()}"
                )
