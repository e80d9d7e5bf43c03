#!/bin/sh
# The prediction (toolconf::prediction) against episodes and ln|Pi^U| on random tools: one JSON line
# per model and task (benches/timing/prediction.rs), and the points of docs/prediction.md's figure;
# then design by the predicted task error against design by confidence and RANDOM random feasible
# tools on the touch task's design file (benches/timing/design_predicted.rs, $out/design_touch.json).
# The cost per tool side by side (prediction, ln|Pi^U|, episode): cargo bench --bench prediction_cost
# The xArm7 is loaded at run time: its model library is made once into $OUT_DIR/xarm7 (make model,
# several minutes), or taken from XARM7_LIBRARY. The touch task is also run on 10^4 tools.
# Usage: sh benches/prediction.sh [TOOLS] [OUT_DIR]   (from the repository root; 1000 tools by default)
set -eu
tools=${1:-1000}
out=${2:-target/prediction}
mkdir -p "$out"
cargo build --release --example prediction --example design_predicted
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
xarm7=${XARM7_LIBRARY:-$out/xarm7}
[ -e "$xarm7/toolconf_model.h" ] || make --no-print-directory model DESC=examples/robots/xarm7.toml OUT="$xarm7"
for task in touch_point draw_line push_off; do
    TOOLCONF_MODEL_PATH=$xarm7 run "xarm7_$task" --model xarm7 --task "examples/tasks/xarm7_$task.toml"
done
run panda_touch_10k --model panda --task examples/tasks/panda_touch_point.toml --tools "${MANY_TOOLS:-10000}"
run arm2_position --model arm2 --task position
run arm2_velocity --model arm2 --task velocity
run arm2_acceleration --model arm2 --task acceleration
target/release/examples/design_predicted --model panda --task examples/tasks/panda_touch_point.toml \
    --design examples/design/panda_tip_length.toml --random "${RANDOM_TOOLS:-10000}" > "$out/design_touch.json"
cat "$out/design_touch.json"
