#!/usr/bin/env bash
# Both stages of `toolconf rank --screen K` on a large tools file: writes
# target/rank_screen/tools_N.csv (N arm2 tools, every parameter uniform on [0.1, 0.6) as
# draw_tools draws them, from Python's random.Random(SEED), six decimals), then runs
# `toolconf rank --screen K --screen-by confidence --json` (SCREEN_BY=predicted for the other
# screen; release) on each task and prints both stages' wall time and
# throughput, with the load average before and after each run. Nothing is written into docs/.
#   benches/rank_screen.sh [N=1000000] [K=1000] [TASKS=position,velocity] [THREADS=1] [SEED=1]
source "$(dirname "${BASH_SOURCE[0]}")/screen_lib.sh"
n="${1:-1000000}" k="${2:-1000}" tasks="${3:-position,velocity}" threads="${4:-1}" seed="${5:-1}"
dir=target/rank_screen
tools="$dir/tools_${n}_seed${seed}.csv"
tools_file "$tools" "$n" "$seed" <<'PY'
with open(path, "w") as f:
    f.write("name,model,m1,m2,l1,l2\n")
    for i in range(n):
        p = [0.1 + 0.5 * rng.random() for _ in range(4)]
        f.write(f"t{i},arm2," + ",".join(f"{v:.6f}" for v in p) + "\n")
PY
echo "tools: $tools ($(($(wc -l < "$tools") - 1)) rows, $(du -h "$tools" | cut -f1)); --screen $k; RAYON_NUM_THREADS=$threads"
for task in ${tasks//,/ }; do
  before="$(cut -d' ' -f1-3 /proc/loadavg)"
  RAYON_NUM_THREADS="$threads" ./target/release/toolconf rank --tools "$tools" --task "$task" \
    --screen "$k" --screen-by "${SCREEN_BY:-confidence}" --json > "$dir/rank_$task.json"
  after="$(cut -d' ' -f1-3 /proc/loadavg)"
  python3 - "$dir/rank_$task.json" "$task" "$before" "$after" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))
c, s = v["timing"]["confidence_stage"], v["timing"]["simulation_stage"]
print(f"{sys.argv[2]}: confidence stage {c['tools']} tools in {c['seconds']:.3f} s "
      f"({c['tools_per_second']:,.0f} tools/s, {c['ns_per_tool']:.0f} ns/tool); "
      f"simulation stage {s['episodes']} episodes in {s['seconds']:.3f} s on {s['threads']} thread(s) "
      f"({s['episodes_per_second']:,.0f} episodes/s, {s['us_per_episode']:.1f} µs/episode); "
      f"method {v['method'].split(':')[0]}; load average {sys.argv[3]} before, {sys.argv[4]} after")
PY
done
