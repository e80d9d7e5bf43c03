#!/usr/bin/env bash
# Peer comparison: toolconf vs SciPy solve_ivp(RK45) vs CasADi cvodes on the same 100 tools.
# Creates bench/peers/.venv from requirements.txt on first use, builds toolconf (release) and the
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
cargo build --release --quiet --bin toolconf --example peer_timing
exec "$venv/bin/python" "$here/compare.py" "$@"
