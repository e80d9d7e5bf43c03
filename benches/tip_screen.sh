#!/usr/bin/env bash
# The screening target: the control confidence of N Panda tools with tips (default 10⁶) on
# a tip task, file reading included, on 2 threads. Writes target/tip_screen/panda_N.csv (N tools:
# mass 0.1-3 kg, centre of mass within 5 cm of the flange axis and up to 20 cm out, the principal
# moments of a solid box of 1-30 cm sides about it (so the triangle inequality holds), no products
# of inertia, the tip within 5 cm of the axis and 5-40 cm out; Python's random.Random(SEED), six
# significant digits), then runs `toolconf rank --screen K --screen-by confidence --json` (SCREEN_BY=predicted
# for the other screen; release) on the task and
# prints the confidence stage's wall time and throughput, with the load average around the run.
#   benches/tip_screen.sh [N=1000000] [K=100] [TASK=examples/tasks/panda_touch_point.toml] [THREADS=2] [SEED=1]
source "$(dirname "${BASH_SOURCE[0]}")/screen_lib.sh"
n="${1:-1000000}" k="${2:-100}" task="${3:-examples/tasks/panda_touch_point.toml}" threads="${4:-2}" seed="${5:-1}"
dir=target/tip_screen
tools="$dir/panda_${n}_seed${seed}.csv"
tools_file "$tools" "$n" "$seed" <<'PY'
columns = ("tool_mass,tool_com_x,tool_com_y,tool_com_z,tool_ixx,tool_iyy,tool_izz,"
           "tool_tip_x,tool_tip_y,tool_tip_z")
with open(path + ".part", "w") as f:
    f.write("name,model," + columns + "\n")
    for i in range(n):
        m = rng.uniform(0.1, 3.0)
        a, b, c = (rng.uniform(0.01, 0.3) for _ in range(3))
        p = [m, rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.2),
             m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12,
             rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), rng.uniform(0.05, 0.4)]
        f.write(f"t{i},panda," + ",".join(f"{v:.6g}" for v in p) + "\n")
import os
os.replace(path + ".part", path)
PY
echo "tools: $tools ($(($(wc -l < "$tools") - 1)) rows, $(du -h "$tools" | cut -f1)); task $task; --screen $k; RAYON_NUM_THREADS=$threads"
before="$(cut -d' ' -f1-3 /proc/loadavg)"
RAYON_NUM_THREADS="$threads" ./target/release/toolconf rank --tools "$tools" --task "$task" \
  --screen "$k" --screen-by "${SCREEN_BY:-confidence}" --json > "$dir/rank.json"
after="$(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$dir/rank.json" "$before" "$after" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))
c, s = v["timing"]["confidence_stage"], v["timing"]["simulation_stage"]
print(f"confidence stage {c['tools']} tools in {c['seconds']:.3f} s ({c['tools_per_second']:,.0f} tools/s, "
      f"{c['ns_per_tool']:.0f} ns/tool, reading included); simulation stage {s['episodes']} episodes in "
      f"{s['seconds']:.3f} s ({s['us_per_episode']:.0f} µs/episode); load {sys.argv[2]} -> {sys.argv[3]}")
PY
