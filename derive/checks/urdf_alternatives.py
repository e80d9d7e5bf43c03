#!/usr/bin/env python3
"""How the generated right-hand side of a URDF arm is formulated: the measurement behind
docs/explanation/derivation.md's choice. Emits four straight-line versions of the Panda's plant f(X, U; k) into a
scratch crate and times them over a population of 1000 random states and tools (one thread):

- crba_ldl: M(q) by CRBA, the bias by RNEA, an unrolled LDL^T solve (what make derive generates);
- aba:      the articulated-body algorithm (6-D spatial algebra) on the same coefficients;
- crba_nalgebra: M(q) and the bias straight-line, nalgebra's fixed-size Cholesky at run time;
- inline:   crba_ldl with the tool's parameters inline (no per-tool coefficients).

    derive/.venv/bin/python derive/checks/urdf_alternatives.py derive/models/panda.toml /tmp/urdf_alternatives
    cd /tmp/urdf_alternatives && CARGO_TARGET_DIR=<repo>/target cargo run --release

The scratch crate is not part of the project (nothing here is committed output).
"""

from __future__ import annotations

import sys
from pathlib import Path

import casadi as ca

HERE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(HERE))

from toolconf_derive.description import load_model, load_tasks  # noqa: E402
from toolconf_derive.rigid_body import aba  # noqa: E402
from toolconf_derive.sequence import instructions  # noqa: E402
from toolconf_derive.urdf_model import UrdfDerivation, _sample_tool  # noqa: E402


def rust_function(name: str, f: ca.Function, args: list[tuple[str, int]], outputs: list[tuple[str, int, int]]) -> str:
    body = instructions(f, [{"name": a, "rows": r, "cols": 1} for a, r in args], [o for o, _, _ in outputs])
    lines = [f"#[inline(never)]\npub fn {name}(x: &[f64; NX], u: &[f64; N], coefficients: &K) -> "
             + ("(" + ", ".join(f"[f64; {r * c}]" for _, r, c in outputs) + ")" if len(outputs) > 1 else
                f"[f64; {outputs[0][1] * outputs[0][2]}]") + " {"]
    for b in body["bindings"]:
        lines.append(f"    let {b['name']} = {b['access']};")
    for t in body["trig"]:
        lines.append(f"    let ({t['sin']}, {t['cos']}) = crate::trig::sin_cos({t['angle']});")
    for o, r, c in outputs:
        lines.append(f"    let mut {o} = [0.0f64; {r * c}];")
    for w in body["sequence"]["slots"]:
        lines.append(f"    let {'mut ' if w['mutable'] else ''}{w['name']}: f64;")
    for s in body["sequence"]["steps"]:
        target = s["target"]
        for o, r, c in outputs:
            if target.startswith(f"{o}[(") and c > 1:
                i, j = target[len(o) + 2:-2].split(", ")
                target = f"{o}[{int(i) * c + int(j)}]"
        lines.append(f"    {target} = {s['rust']};")
    lines.append("    " + (outputs[0][0] if len(outputs) == 1 else "(" + ", ".join(o for o, _, _ in outputs) + ")"))
    lines.append("}")
    return "\n".join(lines), body["cost"]["ops"]


def main() -> int:
    model = load_model(Path(sys.argv[1]))
    out = Path(sys.argv[2])
    dv = UrdfDerivation(model, model.chain, load_tasks(HERE / "tasks.toml"))
    n, x, u, k, p = dv.n, dv.x, dv.u, dv.k, dv.p
    last, offset = [k[i] for i in range(10)], [k[10 + i] for i in range(n)]
    q, qd = [x[i] for i in range(n)], [x[n + i] for i in range(n)]
    trig = dv._symbolic_trig(q)
    tau = [u[i] - dv.stiffness[i] * q[i] - dv.damping[i] * qd[i] + offset[i] for i in range(n)]
    graphs = {"crba_ldl": dv.dynamics_with,
              "aba": ca.Function("aba", [x, u, k], [ca.cse(ca.vertcat(*qd, *aba(dv.dyn, q, trig, qd, tau, last)))])}
    mass = dv.dyn.mass_matrix(q, trig, last)
    bias = dv.dyn.rnea(q, trig, qd, [0.0] * n, last)
    m_sx = ca.vertcat(*[ca.horzcat(*[ca.SX(v) if isinstance(v, float) else v for v in row]) for row in mass])
    rhs = ca.vertcat(*[tau[i] - bias[i] for i in range(n)])
    parts = ca.Function("parts", [x, u, k], [ca.cse(ca.triu(m_sx)), ca.cse(rhs)])
    inline = ca.Function("inline", [x, u, p], [dv.dynamics_with(x, u, dv.coefficients(p))])
    code, counts = [], {}
    for name, g in graphs.items():
        text, counts[name] = rust_function(name, g, [("x", 2 * n), ("u", n), ("coefficients", 10 + n)],
                                           [("x_dot", 2 * n, 1)])
        code.append(text)
    text, counts["crba_nalgebra"] = rust_function("parts", parts, [("x", 2 * n), ("u", n), ("coefficients", 10 + n)],
                                                  [("m", n, n), ("rhs", n, 1)])
    code.append(text)
    text, counts["inline"] = rust_function("inline", inline, [("x", 2 * n), ("u", n), ("coefficients", 7)],
                                           [("x_dot", 2 * n, 1)])
    code.append(text.replace("coefficients: &K", "coefficients: &P"))
    coefficient_fn = ca.Function("coef", [p], [dv.coefficients(p)])
    (out / "src").mkdir(parents=True, exist_ok=True)
    (out / "Cargo.toml").write_text('[package]\nname = "urdf_alternatives"\nversion = "0.1.0"\nedition = "2021"\n'
                                    '[dependencies]\nnalgebra = "0.33"\n[profile.release]\ncodegen-units = 1\n'
                                    '[workspace]\n')
    main_rs = MAIN.replace("@N@", str(n)).replace("@NK@", str(10 + n)).replace("@COUNTS@", ", ".join(f"{k} {v}" for k, v in counts.items()))
    (out / "src" / "main.rs").write_text(main_rs + "\n" + "\n\n".join(code) + "\n")
    trig = (HERE.parent / "src" / "trig.rs").read_text()
    (out / "src" / "trig.rs").write_text(trig)
    # The coefficients of a few tools, computed here (CasADi, double), for the timing inputs.
    import numpy as np
    rng = np.random.default_rng(1)
    tools = []
    for _ in range(16):
        t = _sample_tool(rng).ravel()
        tools.append(([float(v) for v in t], [float(v) for v in np.array(coefficient_fn(t)).ravel()]))
    (out / "src" / "tools.rs").write_text(
        "pub const TOOLS: [([f64; 7], [f64; " + str(10 + n) + "]); 16] = [\n"
        + "".join(f"    ({t!r}, {c!r}),\n" for t, c in tools) + "];\n")
    print(f"wrote {out}; instruction counts {counts}")
    return 0


MAIN = r'''
#![allow(clippy::all, unused_variables, unused_mut)]
mod trig;
mod tools;
use nalgebra::{SMatrix, SVector};
use std::hint::black_box;
use std::time::Instant;

const N: usize = @N@;
const NX: usize = 2 * N;
pub struct K { pub k: [f64; @NK@] }
pub struct P { pub k: [f64; 7] }

fn crba_nalgebra(x: &[f64; NX], u: &[f64; N], c: &K) -> [f64; NX] {
    let (m, rhs) = parts(x, u, c);
    let mat = SMatrix::<f64, N, N>::from_fn(|i, j| if i <= j { m[i * N + j] } else { m[j * N + i] });
    let a = mat.cholesky().expect("M is positive definite").solve(&SVector::<f64, N>::from_column_slice(&rhs));
    let mut out = [0.0; NX];
    for i in 0..N { out[i] = x[N + i]; out[N + i] = a[i]; }
    out
}

fn main() {
    // A population: 1000 states x 16 tools, drawn by a fixed LCG (no rand dependency).
    let mut seed: u64 = 23;
    let mut uniform = |lo: f64, hi: f64| {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((seed >> 11) as f64 / (1u64 << 53) as f64)
    };
    let points: Vec<([f64; NX], [f64; N], usize)> = (0..1000).map(|i| {
        let mut x = [0.0; NX];
        for j in 0..N { x[j] = uniform(-3.0, 3.0); x[N + j] = uniform(-2.0, 2.0); }
        let mut u = [0.0; N];
        for j in 0..N { u[j] = uniform(-5.0, 5.0); }
        (x, u, i % 16)
    }).collect();
    let ks: Vec<K> = tools::TOOLS.iter().map(|(_, c)| K { k: *c }).collect();
    let ps: Vec<P> = tools::TOOLS.iter().map(|(t, _)| P { k: *t }).collect();
    // Agreement with crba_ldl.
    let mut worst = [0.0f64; 3];
    for (x, u, t) in &points {
        let a = crba_ldl(x, u, &ks[*t]);
        let others = [aba(x, u, &ks[*t]), crba_nalgebra(x, u, &ks[*t]), inline(x, u, &ps[*t])];
        let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (w, o) in worst.iter_mut().zip(others) {
            *w = w.max(a.iter().zip(o).fold(0.0f64, |m, (p, q)| m.max((p - q).abs())) / scale);
        }
    }
    println!("normwise relative difference from crba_ldl: aba {:.1e}, crba_nalgebra {:.1e}, inline {:.1e}", worst[0], worst[1], worst[2]);
    println!("instructions: @COUNTS@");
    let time = |name: &str, f: &dyn Fn(&[f64; NX], &[f64; N], usize) -> [f64; NX]| {
        let mut per_call = Vec::new();
        for _ in 0..200 {
            let start = Instant::now();
            let mut s = 0.0;
            for (x, u, t) in &points { s += f(black_box(x), u, *t)[NX - 1]; }
            black_box(s);
            per_call.push(start.elapsed().as_secs_f64() / points.len() as f64 * 1e9);
        }
        per_call.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mean = per_call.iter().sum::<f64>() / per_call.len() as f64;
        println!("{name:14} ns per call over 1000 points: mean {mean:.0}, p50 {:.0}, p90 {:.0}, p99 {:.0} (200 repetitions)",
                 per_call[100], per_call[180], per_call[198]);
    };
    time("crba_ldl", &|x, u, t| crba_ldl(x, u, &ks[t]));
    time("aba", &|x, u, t| aba(x, u, &ks[t]));
    time("crba_nalgebra", &|x, u, t| crba_nalgebra(x, u, &ks[t]));
    time("inline", &|x, u, t| inline(x, u, &ps[t]));
}
'''


if __name__ == "__main__":
    sys.exit(main())
