# Sourced first by rank_screen.sh and tip_screen.sh: strict mode, the repository's root as the
# working folder, the release `toolconf` built (one job unless CARGO_BUILD_JOBS says otherwise),
# and `tools_file`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
cargo build --release --quiet --bin toolconf

# tools_file PATH N SEED: unless PATH is there and not empty, makes its folder and runs the
# Python on stdin, which writes PATH from `n`, `seed`, `path` and `rng = random.Random(seed)`.
tools_file() {
  if [[ -s "$1" ]]; then
    return
  fi
  mkdir -p "$(dirname "$1")"
  python3 -c 'import random, sys
n, seed, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rng = random.Random(seed)
exec(sys.stdin.read())' "$2" "$3" "$1"
}
