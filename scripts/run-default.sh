#!/usr/bin/env bash
# The main job on the bundled default scene: sets up and builds (scripts/setup-debian.sh), then runs
# the whole pipeline — mesh, plan, replay, render, plots, exports — on scenes/barriers1.json (the
# paper's Fig. 1) and writes everything to out/default/ (a few minutes on a 2-core machine).
# Usage: scripts/run-default.sh [OUT_DIR] [SCENE]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/setup-debian.sh"
build="${SQUEEZE_BUILD_DIR:-$here/build}"
out="${1:-$here/out/default}"
scene="${2:-$here/scenes/barriers1.json}"
mkdir -p "$(dirname "$out")"
rc=0
"$build/squeeze" run "$scene" -o "$out" --seed 1 || rc=$?
if [ "$rc" -ne 0 ] && [ "$rc" -ne 3 ]; then exit "$rc"; fi
echo "squeeze: see $out/frames/frame_00040.png (a frame), $out/volume.png (volume change along the path)," \
     "$out/summary.json, $out/plan.json, $out/metrics.csv, $out/export/" >&2
exit "$rc"
