#!/usr/bin/env bash
# Ranking throughput on a population: the old path (ode45, Method::Explicit) and the
# new default (Method::Fast) side by side in one run of benches/timing/population.rs (one thread, the
# methods alternating tool by tool), with mean/p50/p90/p99/max per tool, mean RHS, Jacobians and
# LU factorisations, and the worst relative error and ranking swaps against an rtol-1e-10
# reference. Prints the table and rewrites the "Population throughput" block of
# docs/explanation/performance-population.md (date, machine, load average, commit). Arguments go to the example, e.g.
#   benches/population.sh --tools 500 --repeat 1      (a quick look; the default is 2000 tools, 3 rounds)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
cargo build --release --quiet --example population
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
table="$(./target/release/examples/population --markdown --methods explicit,auto,stiff,fast "$@")"
load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
echo "$table"
model="$(lscpu | sed -n 's/^Model name: *//p' | head -1)"
block="$(cat <<BLOCK
<!-- population:begin (written by benches/population.sh) -->

Measured $(date -u +%Y-%m-%d) on \`nproc\` = $(nproc), \`lscpu\` model name "$model", commit
$(git rev-parse --short HEAD)$(git diff --quiet || echo ' (with local changes)'), $(rustc --version | cut -d' ' -f1-2); load average $load_before before, $load_after after
(the machine is shared: compare the rows of one table, not tables of different runs).
Command: \`benches/population.sh $*\`. Each method's row: mean over tools of the per-tool time
(median of the timed rounds), its percentiles, work per tool, and for every tool the relative
difference of task error / ∫F dt / ∫J dt from DP5 at rtol 1e-10, atol 1e-12 (worst over the
tools), and the pairs of tools ranked the other way round from the reference by each objective
although their reference values differ by more than 1e-4 relative.

$table

<!-- population:end -->
BLOCK
)"
python3 - "$block" <<'PY'
import re, sys
path = "docs/explanation/performance-population.md"
text = open(path, encoding="utf-8").read()
block = sys.argv[1]
pattern = re.compile(r"<!-- population:begin.*?<!-- population:end -->", re.S)
if not pattern.search(text):
    sys.exit("docs/explanation/performance-population.md has no population:begin/end markers")
open(path, "w", encoding="utf-8").write(pattern.sub(lambda _: block, text))
PY
echo "docs/explanation/performance-population.md updated"
