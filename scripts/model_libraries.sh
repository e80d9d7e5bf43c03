#!/usr/bin/env bash
# The model libraries the tests that load one use (the C example, the loaded-models tests, the
# MuJoCo example), built by make model's script:
#   scripts/model_libraries.sh PYTHON OUT [MODEL ...]
# A MODEL is a committed model, rendered and compiled from its IR (generated/MODEL.json), or
# xarm7, derived from the UFactory xArm7's unedited URDF (examples/robots/xarm7.toml); with none,
# every committed model and the xArm7. Each goes to OUT/MODEL/; a failed build prints its log.
# make test builds them once for all three tests; each test alone builds what it needs.
set -euo pipefail
cd "$(dirname "$0")/.."
py=$1 out=$2
shift 2
models=("$@")
if [ ${#models[@]} -eq 0 ]; then
  for ir in generated/*.json; do
    case $ir in *.vectors.json) continue ;; esac
    models+=("$(basename "$ir" .json)")
  done
  models+=(xarm7)
fi
for m in "${models[@]}"; do
  if [ "$m" = xarm7 ]; then from=(--desc examples/robots/xarm7.toml); else from=(--ir "generated/$m.json"); fi
  "$py" derive/make_model.py "${from[@]}" --out "$out/$m" 2>"$out/$m.log" >/dev/null || { cat "$out/$m.log" >&2; exit 1; }
done
echo "model libraries: ${#models[@]} built into $out"
