#!/usr/bin/env bash
# Peer comparison: toolconf vs SciPy solve_ivp(RK45) vs CasADi cvodes on the same 100 tools;
# with --urdf, the Panda against SciPy solve_ivp with Pinocchio's aba (benches/peers/urdf_peers.py);
# with --sweep, a URDF robot's results against its impedance gains (benches/peers/impedance_sweep.py).
# Creates benches/peers/.venv from requirements.txt on first use, builds toolconf (release) and the
# peer_timing example, and writes docs/performance.md (extra arguments go to compare.py).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$here/.venv"
if [[ ! -x "$venv/bin/python" || "$here/requirements.txt" -nt "$venv/bin/python" ]]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
  touch "$venv/bin/python"
fi
cd "$root"
if [[ "${1:-}" == "--sweep" ]]; then
  # How a URDF robot's results depend on its impedance gains (impedance_sweep.py).
  shift
  exec "$venv/bin/python" "$here/impedance_sweep.py" "$@"
fi
if [[ "${1:-}" == "--urdf" ]]; then
  # The URDF arms: SciPy solve_ivp with Pinocchio's aba in the right-hand side (urdf_peers.py).
  shift
  cargo build --release --quiet --example model_timing
  exec "$venv/bin/python" "$here/urdf_peers.py" "$@"
fi
cargo build --release --quiet --bin toolconf --example peer_timing
exec "$venv/bin/python" "$here/compare.py" "$@"
