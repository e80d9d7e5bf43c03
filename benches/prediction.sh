#!/bin/sh
# The prediction (toolconf::prediction) against episodes and ln|Pi^U| on random tools: one JSON line
# per model and task (benches/timing/prediction.rs), and the points of docs/prediction.md's figure.
# Usage: sh benches/prediction.sh [TOOLS] [OUT_DIR]   (from the repository root; 1000 tools by default)
set -eu
tools=${1:-1000}
out=${2:-target/prediction}
mkdir -p "$out"
cargo build --release --example prediction
run() {
    name=$1; shift
    target/release/examples/prediction --tools "$tools" --points "$out/$name.csv" "$@"
}
run panda_touch --model panda --task examples/tasks/panda_touch_point.toml
run panda_line --model panda --task examples/tasks/panda_draw_line.toml
run panda_push --model panda --task examples/tasks/panda_push_off.toml
run ur5_touch --model ur5 --task examples/tasks/ur5_touch_point.toml
run ur5_line --model ur5 --task examples/tasks/ur5_draw_line.toml
run ur5_push --model ur5 --task examples/tasks/ur5_push_off.toml
run arm2_position --model arm2 --task position
run arm2_velocity --model arm2 --task velocity
run arm2_acceleration --model arm2 --task acceleration
