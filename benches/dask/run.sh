#!/usr/bin/env bash
# toolconf.rank and toolconf.simulate_batch on one process against toolconf.dask on a
# distributed.LocalCluster of 2 worker processes (1 thread, RAYON_NUM_THREADS=1 each) on this
# machine, in one run (benches/dask/measure.py): throughput of both, the cluster's overhead per
# partition and per task. Builds a release wheel into benches/dask/.venv (with the pinned
# python/requirements-dev.txt), so nothing touches derive/.venv; prints a table and one JSON
# line. Nothing is written into docs/.
#   benches/dask/run.sh [--quick]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
venv="$root/benches/dask/.venv"
[[ -x "$venv/bin/python" ]] || python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check -r python/requirements-dev.txt
rm -rf target/bench-dask-wheel
"$venv/bin/maturin" build --quiet --release --manifest-path python/Cargo.toml \
  --interpreter "$venv/bin/python" --out target/bench-dask-wheel
"$venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps \
  target/bench-dask-wheel/toolconf-*.whl
cd benches/dask   # not the repository root: the wheel's toolconf, not python/toolconf
"$venv/bin/python" measure.py "$@"
