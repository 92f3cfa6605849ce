#!/usr/bin/env bash
# Renders each fit's stocking.glb in three.js (headless Chromium) and in Blender (Cycles) from one
# camera, then runs the pixel checks of tools/client_pixels.py on both (issue 23).
#
#   tools/client_check.sh OUT_DIR GLB...
#
# Each GLB is a fit's stocking.glb with its report.json beside it (the landmarks place the calf).
# OUT_DIR/<name of the GLB's folder>/ gets camera.json, threejs/*.png and blender/*.png. Exit 0
# when every check passed, 1 when one failed (one "FAIL case/client check: why" line each) or a
# client could not render, 2 on bad arguments.
#
# Needs (set up as .ci/run does): Debian's chromium (or $CHROMIUM), three and puppeteer-core from
# tools/client_render/package-lock.json in $CLIENT_NODE_MODULES (default
# target/client-render/node_modules), and the bpy venv tools/.venv-blender (or $BLENDER_PYTHON)
# with tools/blender_requirements.txt.
set -uo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  sed -n '2,16p' "$0" >&2
  exit 2
fi
out=$1
shift
python=${BLENDER_PYTHON:-tools/.venv-blender/bin/python}
node_modules=${CLIENT_NODE_MODULES:-target/client-render/node_modules}
status=0
cases=()
for glb in "$@"; do
  fit=$(dirname "$glb")
  case_dir="$out/$(basename "$(cd "$fit" && pwd)")"
  mkdir -p "$case_dir"
  if ! "$python" tools/client_pixels.py camera "$fit" "$case_dir/camera.json"; then
    echo "FAIL $case_dir: no camera from $glb"
    status=1
    continue
  fi
  start=$(date +%s.%N)
  if ! NODE_PATH="$node_modules" node tools/client_render/render.js "$case_dir/camera.json" "$glb" \
      "$case_dir/threejs"; then
    echo "FAIL $case_dir/threejs render: see above"
    status=1
  fi
  mid=$(date +%s.%N)
  if ! "$python" tools/blender_render.py "$case_dir/camera.json" "$glb" "$case_dir/blender"; then
    echo "FAIL $case_dir/blender render: see above"
    status=1
  fi
  end=$(date +%s.%N)
  printf '%s: three.js %.1f s, Blender %.1f s\n' "$case_dir" "$(echo "$mid - $start" | bc)" \
    "$(echo "$end - $mid" | bc)"
  cases+=("$case_dir")
done
if [ ${#cases[@]} -gt 0 ]; then
  "$python" tools/client_pixels.py check "${cases[@]}" || status=1
fi
exit $status
