#!/bin/sh
# The claims table of docs/tutorials/evaluate-your-robot.md: `toolconf reproduce --model` on the Panda, the UR5 and
# the xArm7 (its library built from its unedited URDF by `make model`), every shipped tip task,
# absolute and relative goals, 1000 random tools each (the model's sampling box, seed 7), the
# paper's other counts. One row per run, each row's own command in its last column; every run's
# CSVs, figures and report stay under OUT (default: a temporary folder, printed at the end).
#
#     benches/claims.sh [XARM7_LIBRARY [OUT]]
#
# Without XARM7_LIBRARY, the xArm7's library is built first (about 3 minutes on 2 idle cores:
# derive/make_model.py, which needs `make venv`).
set -eu
cd "$(dirname "$0")/.."
cargo build --release --quiet --bin toolconf
bin=target/release/toolconf
lib=${1:-}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
if [ -z "$lib" ]; then
  lib=$out/xarm7-library
  derive/.venv/bin/python derive/make_model.py --desc examples/robots/xarm7.toml --out "$lib" >&2
fi

echo "| robot | task | goal | ρ(ln\|Π^U\|, task error) [95 %] | (a) | ρ(ln\|Π^U\|, \|Δ task error\|) [95 %] | (b) | J's − F's \|Δ\| (Wilcoxon p) | (c) | progress: median (min) | command |"
echo "|---|---|---|---:|---|---:|---|---:|---|---:|---|"
for robot in panda ur5 xarm7; do
  for task in touch_point draw_line push_off; do
    for variant in "" _relative; do
      file=examples/tasks/${robot}_${task}${variant}.toml
      dir=$out/${robot}_${task}${variant}
      prefix=""
      shown="toolconf"
      if [ "$robot" = xarm7 ]; then
        prefix="--model-path $lib"
        # LIB: the folder of `make model DESC=examples/robots/xarm7.toml OUT=LIB`.
        shown="toolconf --model-path LIB"
      fi
      command="$shown reproduce --model $robot --task-file $file --sample 1000 --seed 7 --out DIR"
      # shellcheck disable=SC2086
      $bin $prefix reproduce --model $robot --task-file "$file" --sample 1000 --seed 7 \
        --json --out "$dir" >"$dir.json"
      python3 - "$dir.json" "$command" <<'EOF'
import csv, json, statistics, sys
from pathlib import Path
summary = json.load(open(sys.argv[1]))
v = summary["verdicts"]
def rho(key):
    s = v[key]["statistic"]
    if "ci" not in s:
        return "undefined"
    return f"{s['rho']:+.2f} [{s['ci'][0]:+.2f}, {s['ci'][1]:+.2f}]".replace("-", "−")
c = v["free_energy_choices_less_sensitive"]["statistic"]
c_text = ("identical choices" if c.get("identical") else
          f"{c.get('mean_difference', 0):+.3g} (p = {c['wilcoxon_p']:.2g})".replace("-", "−") if "wilcoxon_p" in c
          else "undefined")
fig2 = Path(sys.argv[1]).with_suffix("") / "fig2_confidence_vs_error.csv"
progress = [float(r["progress"]) for r in csv.DictReader(open(fig2)) if r["progress"]]
moved = f"{statistics.median(progress):.3f} ({min(progress):.3f})" if progress else "–"
task = Path(summary["task_file"]).name
print(f"| {summary['model']} | `{task}` | {summary['goal']} | {rho('confidence_predicts_task_error')} | "
      f"{v['confidence_predicts_task_error']['verdict']} | {rho('confidence_predicts_reliability')} | "
      f"{v['confidence_predicts_reliability']['verdict']} | {c_text} | "
      f"{v['free_energy_choices_less_sensitive']['verdict']} | {moved} | `{sys.argv[2]}` |")
EOF
    done
  done
done
echo "runs (CSVs, figures, reports): $out" >&2
